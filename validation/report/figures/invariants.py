"""The ``invariants`` figure: each plant's quaternion norm error (absolute) and its balances of
linear momentum, angular momentum and energy divided by their scales (relative, as checked), log
axes, with thresholds."""

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
    as_checked,
    checks_by_series,
    figure_legend,
    log_panel,
    plant_rows,
    threshold_of,
)
from validation.report.figures.style import PANEL_TITLES


def figure_invariants(cmp: Comparison, ctx: FigureContext | None = None) -> Drawing:
    """Quaternion norm error and the relative balances of each plant, with their thresholds."""
    ctx = ctx or FigureContext(cmp.scene)
    rows = plant_rows(cmp, ("quat_norm", "linear_momentum", "angular_momentum", "energy"))
    if not rows:
        return Drawing("invariants", "No plant's trajectory was compared.")
    checks = checks_by_series(cmp)
    fig, axes = new_figure(len(rows), f"{ctx.scene}: invariants of each plant, as checked")
    zeros: list[tuple[str, list[Subject]]] = []
    for ax, (name, ss) in zip(axes, rows, strict=True):
        th = threshold_of(cmp, name)
        z = log_panel(
            ax, [(s.subject, s.t, as_checked(s, checks)) for s in ss], th.value if th else None
        )
        if z:
            zeros.append((name, z))
        ax.set_ylabel("1 (relative)" if th is not None and th.relative else ss[0].unit)
        limit = f"; threshold {th.value:g}" if th is not None else ""
        title_panel(ax, f"{PANEL_TITLES.get(name, ss[0].label)}{limit}")
    axes[-1].set_xlabel("t (s)")
    figure_legend(fig, axes)
    caption = join_sentences(
        "Invariants of each plant over time (log axes), drawn as they are checked: the "
        "quaternion norm error |uᵀu − 1| (absolute), and the balances of linear momentum "
        "(against gravity), angular momentum about the system's centre of mass (against the "
        "impulse of the control torque) and energy (against the work of the control), each "
        "divided by the largest magnitude of what it balances (relative; the divisor is named "
        "in each panel). Dotted black: the threshold.",
        zero_sentence(zeros),
        ctx.run_sentence(),
    )
    return Drawing("invariants", caption, fig)


__all__ = ["figure_invariants"]
