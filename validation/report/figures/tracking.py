"""The ``tracking`` figure: each plant's tracking errors and their deviations from the closed-form
error dynamics (Eq. 84 with ``docs/errata.md`` item 3, and Eq. 78), log axes, with thresholds. Not
drawn without a control requirement."""

from __future__ import annotations

from validation.compare.checks import Comparison, Subject
from validation.report.figures.captions import (
    FigureContext,
    join_sentences,
    zero_sentence,
)
from validation.report.figures.drawing import Drawing
from validation.report.figures.layout import new_figure, title_panel
from validation.report.figures.panels import (
    figure_legend,
    log_panel,
    plant_rows,
    threshold_of,
)
from validation.report.figures.style import PANEL_TITLES


def figure_tracking(cmp: Comparison, ctx: FigureContext | None = None) -> Drawing:
    """Each plant's tracking errors and their deviation from the closed-form laws; log axes."""
    ctx = ctx or FigureContext(cmp.scene)
    rows = plant_rows(cmp, ("e_omega", "e_omega_law", "e_p", "e_p_law"))
    if not rows:
        why = (
            "the scene has no control requirement"
            if ctx.controlled is False
            else "no plant tracks a requirement"
        )
        return Drawing(
            "tracking", f"{why[0].upper()}{why[1:]}, so there is no tracking error to draw."
        )
    limits = {"e_omega_law": "tracking_omega", "e_p_law": "tracking_p"}
    fig, axes = new_figure(len(rows), f"{ctx.scene}: tracking errors of each plant")
    zeros: list[tuple[str, list[Subject]]] = []
    for ax, (name, ss) in zip(axes, rows, strict=True):
        th = threshold_of(cmp, limits[name]) if name in limits else None
        z = log_panel(ax, [(s.subject, s.t, s.values) for s in ss], th.value if th else None)
        if z:
            zeros.append((name, z))
        ax.set_ylabel(ss[0].unit)
        limit = f"; threshold {th.value:g} {th.unit}" if th is not None else ""
        title_panel(ax, f"{PANEL_TITLES.get(name, ss[0].label)}{limit}")
    axes[-1].set_xlabel("t (s)")
    figure_legend(fig, axes)
    caption = join_sentences(
        "Tracking errors of each plant over time (log axes): the angular-velocity error "
        "e_ω = ω − ω̄ (rad/s, body axes) and the largest position error of the controlled masses "
        "(m), each followed by its deviation from the closed-form error dynamics the controller "
        "imposes, e_ω(t) = exp(−γt) e_ω(0) (Eq. 84; docs/errata.md, item 3) and ë + αė + βe = 0 "
        "(Eq. 78). Dotted black: the threshold. Where the plants' curves coincide, the markers "
        "(staggered in time) tell them apart.",
        zero_sentence(zeros),
        ctx.run_sentence(),
    )
    return Drawing("tracking", caption, fig)


__all__ = ["figure_tracking"]
