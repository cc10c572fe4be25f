"""The ``errors`` figure: the differences between each pair of plants over time, one panel per
compared quantity, log axes, drawn as they are checked: absolute for the state, and for the control
torque and rod forces divided by the reference plant's largest magnitude (relative); the thresholds
of :mod:`validation.compare.thresholds` as dotted lines. Not drawn when only one plant ran."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from validation.compare.checks import Comparison, Group, Series, Subject
from validation.report.figures.captions import (
    FigureContext,
    join_sentences,
    no_control_reason,
    subject_names,
    zero_sentence,
)
from validation.report.figures.drawing import Drawing
from validation.report.figures.layout import new_figure, title_panel
from validation.report.figures.panels import (
    as_checked,
    checks_by_series,
    figure_legend,
    log_panel,
    threshold_of,
)
from validation.report.figures.style import PANEL_TITLES


def figure_errors(cmp: Comparison, ctx: FigureContext | None = None) -> Drawing:
    """Differences between each pair of plants over time, as checked, with their thresholds."""
    ctx = ctx or FigureContext(cmp.scene)
    diffs = [s for s in cmp.series if s.group is Group.DIFFERENCE]
    if not diffs:
        return Drawing("errors", "Only one plant ran, so there is no pair to compare.")
    rows: dict[str, list[Series]] = {}
    for s in diffs:
        rows.setdefault(s.name, []).append(s)
    checks = checks_by_series(cmp)
    kept = {n: ss for n, ss in rows.items() if any(np.any(s.values) for s in ss)}
    left_out = [n for n in rows if n not in kept]
    control_out = [n for n in left_out if n in ("control_torque", "rod_forces")]
    if ctx.controlled is not False:
        control_out = []  # zero without a reason the scene gives: said as plain zeros below
    other_out = [n for n in left_out if n not in control_out]

    def names(ns: Sequence[str]) -> str:
        return ", ".join(PANEL_TITLES.get(n, n).split(":")[0] for n in ns)

    why_out = join_sentences(
        f"Left out: {names(control_out)} ({no_control_reason(ctx)})." if control_out else "",
        f"Left out, identically zero for every pair: {names(other_out)}." if other_out else "",
    )
    pairs = list(dict.fromkeys(s.subject for s in diffs))
    intro = (
        f"Differences between {'the plants' if len(pairs) == 1 else 'each pair of plants'} "
        f"({subject_names(pairs)}; a = the first-named plant of a pair, b = the second) over time, log "
        "axes, one panel per compared quantity, drawn as it is checked: the absolute distance "
        "for the state, and for the control torque and rod forces the distance divided by the "
        "first plant's largest magnitude (relative, dimensionless). Dotted black: the threshold "
        "(validation/compare/thresholds.py, or the scene's [thresholds])."
    )
    if not kept:
        return Drawing("errors", join_sentences(why_out, ctx.run_sentence()))
    fig, axes = new_figure(len(kept), f"{ctx.scene}: differences between the plants")
    zeros: list[tuple[str, list[Subject]]] = []
    for ax, (name, ss) in zip(axes, kept.items(), strict=True):
        th = threshold_of(cmp, name)
        z = log_panel(
            ax, [(s.subject, s.t, as_checked(s, checks)) for s in ss], th.value if th else None
        )
        if z:
            zeros.append((name, z))
        unit = "1 (relative)" if th is not None and th.relative else ss[0].unit
        ax.set_ylabel(unit)
        limit = f"; threshold {th.value:g}" if th is not None else ""
        title_panel(ax, f"{PANEL_TITLES.get(name, ss[0].label)}{limit}")
    axes[-1].set_xlabel("t (s)")
    figure_legend(fig, axes)
    return Drawing(
        "errors", join_sentences(intro, why_out, zero_sentence(zeros), ctx.run_sentence()), fig
    )


__all__ = ["figure_errors"]
