"""The time-series part of a recording: one plot per quantity *and unit*, errors as ``log10``.

Rerun 0.41 has no logarithmic plot axis (rerun-io/rerun#6773 is open), so a difference, a
tracking error or a balance drift is logged as ``log10`` of its physical value and its plot says so
in its title (``log10 |Δ| (m)``: the axis reads −9 for 1 nm). An exact zero (two plants agreeing
to the last bit) has no logarithm and is left out, not drawn at an arbitrary floor. Each check's
threshold is drawn as a grey line in the same units: a curve passes while it stays below it.
Control forces are physical values on a linear axis.

Entity layout under ``{p0}``; ``{unit}`` is :func:`validation.recording.style.slug` of the unit::

    {p0}/plots/errors/{unit}/{name}/{pair}        log10 of each pair's difference (pair: a_vs_b)
    {p0}/plots/errors/{unit}/threshold/{name}     log10 of its threshold (one per pair when they
                                                  differ: …/threshold/{name}/{pair})
    {p0}/plots/tracking/{unit}/{name}/{plant}     log10 of each plant's tracking error
    {p0}/plots/tracking/{unit}/threshold/{name}
    {p0}/plots/invariants/{name}/{plant}          log10 of each plant's balance drift
    {p0}/plots/invariants/{name}/threshold        (a relative threshold that differs per plant:
                                                  one line each, …/threshold/{plant})
    {p0}/plots/control/torque/{plant}             τ_x, τ_y, τ_z (N·m, body axes)
    {p0}/plots/control/rod_forces/{plant}         F_1 … F_n (N)
    {p0}/key/{tab}                                what each colour and shade of the tab's plots
                                                  is (markdown, static; :func:`plot_keys`)

The layout hides the plots' legends (at the designed size they cover the curves); the series are
named by the tab's key instead (one colour per plant or pair, one shade per quantity, darkest
first) and by the viewer's tooltip on a curve.

:func:`plots_for` lists the plots (origin, title, tab) for the blueprint from the same rules, so the
layout and the logged entities cannot disagree.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison, Group, Series
from validation.recording.style import (
    THRESHOLD_RGBA,
    TIMELINE,
    color_word,
    entity_root,
    log10_nonzero,
    plant_color,
    shade,
    slug,
    unit_text,
    viewer_text,
)


class Tab(StrEnum):
    """The tabs of the plot column, in order."""

    DIFFERENCES = "differences between plants"
    TRACKING = "tracking errors"
    BALANCES = "invariant drifts"
    CONTROL = "control forces"


@dataclass(frozen=True)
class Plot:
    """One time-series view: its entity ``origin``, its ``title`` (with the unit, and ``log10``
    when its values are logarithms) and the ``tab`` it belongs to."""

    tab: Tab
    origin: str
    title: str


def plot_of(prefix: str, s: Series) -> Plot | None:
    """The plot a comparison series is drawn in (None for the control group, which is drawn
    from the trajectories)."""
    p0 = entity_root(prefix)
    if s.group is Group.DIFFERENCE:
        return Plot(
            Tab.DIFFERENCES, f"{p0}/plots/errors/{slug(s.unit)}", f"log10 |Δ|{unit_text(s.unit)}"
        )
    if s.group is Group.TRACKING:
        return Plot(
            Tab.TRACKING,
            f"{p0}/plots/tracking/{slug(s.unit)}",
            f"log10 tracking error{unit_text(s.unit)}",
        )
    if s.group is Group.INVARIANT:
        return Plot(
            Tab.BALANCES, f"{p0}/plots/invariants/{s.name}", f"log10 {s.label}{unit_text(s.unit)}"
        )
    return None


def series_path(prefix: str, s: Series) -> str | None:
    """The entity of a comparison series (see the module docstring)."""
    plot = plot_of(prefix, s)
    if plot is None:
        return None
    if s.group is Group.INVARIANT:
        return f"{plot.origin}/{s.subject.value}"
    who = s.subject.slug if s.subject.is_pair else s.subject.value
    return f"{plot.origin}/{s.name}/{who}"


def control_plots(prefix: str, n: int) -> list[Plot]:
    p0 = entity_root(prefix)
    out = [Plot(Tab.CONTROL, f"{p0}/plots/control/torque", "control torque τ (N·m, body axes)")]
    if n:
        out.append(Plot(Tab.CONTROL, f"{p0}/plots/control/rod_forces", "rod forces F_i (N)"))
    return out


def plots_for(prefix: str, scene: Any, comparison: Comparison | None) -> list[Plot]:
    """Every plot of a run, in tab order, each once."""
    plots: dict[str, Plot] = {}
    if comparison is not None:
        for s in comparison.series:
            plot = plot_of(prefix, s)
            if plot is not None and s.t.size:
                plots.setdefault(plot.origin, plot)
    for plot in control_plots(prefix, scene.n):
        plots[plot.origin] = plot
    order = list(Tab)
    return sorted(plots.values(), key=lambda p: order.index(p.tab))


def _send_scalars(rec, path: str, t: np.ndarray, values: np.ndarray, per_row: int = 1) -> bool:
    # deferred: rerun ~0.25 s (python -X importtime), only when a recording is made
    import rerun as rr

    if t.size == 0:
        return False
    col = rr.Scalars.columns(scalars=np.ravel(values))
    rec.send_columns(
        path,
        indexes=[rr.TimeColumn(TIMELINE, duration=t)],
        columns=col.partition([per_row] * t.shape[0]) if per_row > 1 else col,
    )
    return True


def _legend(s: Series) -> str:
    if s.group is Group.INVARIANT:
        return s.subject.value
    return f"{s.subject.value}: {s.label}"


THRESHOLD_SAME = 0.01
"""Two bounds of one quantity closer than this (relative) are drawn as one line: on a log axis
they are indistinguishable (relative thresholds differ slightly per plant or pair)."""


def _log_thresholds(rec, prefix: str, comparison: Comparison, logged: dict[str, Series]) -> None:
    """One grey line per distinct bound of each checked series, over the series' time span."""
    import rerun as rr

    bounds: dict[tuple[str, str], list[tuple[float, list[Series]]]] = {}
    for c in comparison.checks:
        s = logged.get(c.series)
        bound = c.threshold * c.scale
        if s is None or not (math.isfinite(bound) and bound > 0):
            continue
        plot = plot_of(prefix, s)
        if plot is None:
            continue
        groups = bounds.setdefault((plot.origin, s.name), [])
        same = next((g for g in groups if abs(g[0] - bound) <= THRESHOLD_SAME * g[0]), None)
        if same is None:
            groups.append((bound, [s]))
        else:
            same[1].append(s)
    for (origin, name), groups in bounds.items():
        own = origin.endswith(f"/{name}")  # a plot of one quantity (the balances)
        for bound, series in groups:
            path = f"{origin}/threshold" + ("" if own else f"/{name}")
            label = "threshold" + ("" if own else f" of {name}")
            if len(groups) > 1:  # relative thresholds that differ per plant or pair
                path += f"/{series[0].subject.slug}"
                label += f" ({', '.join(x.subject.value for x in series)})"
            t = series[0].t
            rec.log(
                path,
                rr.SeriesLines(names=[viewer_text(label)], colors=[THRESHOLD_RGBA], widths=[1.0]),
                static=True,
            )
            _send_scalars(rec, path, np.array([t[0], t[-1]]), np.full(2, math.log10(bound)))


_FORMULA = re.compile(r"\s+(max_\w+\s*)?(\||conj\().*$")


def _short(label: str) -> str:
    """A series' label without its formula (``position of C |R_a − R_m|`` -> ``position of C``)."""
    return _FORMULA.sub("", label) or label


def key_path(prefix: str, tab: Tab) -> str:
    """The entity of tab ``tab``'s key (:func:`plot_keys`)."""
    return f"{entity_root(prefix)}/key/{slug(tab.name.lower())}"


def _unique_add(items: list[str], item: str) -> None:
    if item not in items:
        items.append(item)


def plot_keys(
    prefix: str, plants: Sequence[Trajectory], comparison: Comparison | None
) -> dict[Tab, str]:
    """Per tab, the text that names its series in place of the plots' legends: the colour of each
    plant or pair, the threshold's grey, and each plot's quantities in shade order (darkest first),
    from the same rules as :func:`log_plots` draws them."""
    colours: dict[Tab, list[str]] = {}
    shades: dict[Tab, dict[str, list[str]]] = {}
    for s in comparison.series if comparison is not None else ():
        plot = plot_of(prefix, s)
        if plot is None or s.t.size == 0:
            continue
        _unique_add(colours.setdefault(plot.tab, []), s.subject.value)
        if s.group is not Group.INVARIANT:  # a balance plot is one quantity, named in its title
            _unique_add(shades.setdefault(plot.tab, {}).setdefault(plot.title, []), _short(s.label))
    n = plants[0].n if plants else 0
    for plot in control_plots(prefix, n):
        for tr in plants:
            _unique_add(colours.setdefault(Tab.CONTROL, []), tr.engine)
        comps = (
            ["τ_x", "τ_y", "τ_z"]
            if plot.origin.endswith("torque")
            else [f"F_{i + 1}" for i in range(n)]
        )
        shades.setdefault(Tab.CONTROL, {})[plot.title] = comps
    keys: dict[Tab, str] = {}
    for tab, who in colours.items():
        named = ", ".join(f"{color_word(plant_color(x))}: {x}" for x in who)
        grey = "" if tab is Tab.CONTROL else "; grey: the threshold (a curve passes below it)"
        lines = [f"Colours: {named}{grey}. Hover a curve for its name."]
        per_plot = [(t, q) for t, q in shades.get(tab, {}).items() if len(q) > 1]
        if per_plot:
            lines.append("Shades, darkest first:")
            lines += [f"- {title}: {', '.join(q)}" for title, q in per_plot]
        keys[tab] = "\n".join(lines)
    return keys


def _log_keys(rec, prefix: str, plants: Sequence[Trajectory], comparison: Comparison | None):
    import rerun as rr

    for tab, text in plot_keys(prefix, plants, comparison).items():
        doc = rr.TextDocument(viewer_text(text, newlines=True), media_type=rr.MediaType.MARKDOWN)
        rec.log(key_path(prefix, tab), doc, static=True)


def log_plots(
    rec, prefix: str, plants: Sequence[Trajectory], comparison: Comparison | None
) -> list[str]:
    """Log the control forces of every plant and, with a comparison, every difference, tracking
    error and balance drift as log10 (exact zeros left out) with their thresholds; returns the
    entity paths that received time series."""
    import rerun as rr

    entities: list[str] = []
    for plot in control_plots(prefix, plants[0].n if plants else 0):
        for tr in plants:
            name = tr.engine
            if plot.origin.endswith("torque"):
                values, comps = tr.torque, ["τ_x", "τ_y", "τ_z"]
            else:
                values, comps = tr.rod_forces, [f"F_{i + 1}" for i in range(tr.n)]
            path = f"{plot.origin}/{name}"
            rec.log(
                path,
                rr.SeriesLines(
                    names=[viewer_text(f"{name} {c}") for c in comps],
                    colors=[shade(plant_color(name), j) for j in range(len(comps))],
                ),
                static=True,
            )
            if _send_scalars(rec, path, tr.t, values, per_row=len(comps)):
                entities.append(path)
    _log_keys(rec, prefix, plants, comparison)
    if comparison is None:
        return entities

    quantity: dict[str, list[str]] = {}  # plot origin -> names in it (a shade per name)
    logged: dict[str, Series] = {}
    for s in comparison.series:
        path, plot = series_path(prefix, s), plot_of(prefix, s)
        if path is None or plot is None or s.t.size == 0:
            continue
        names = quantity.setdefault(plot.origin, [])
        if s.name not in names:
            names.append(s.name)
        color = shade(plant_color(s.subject.value), names.index(s.name))
        rec.log(path, rr.SeriesLines(names=[viewer_text(_legend(s))], colors=[color]), static=True)
        t, v = log10_nonzero(s.t, s.values)
        if _send_scalars(rec, path, t, v):
            entities.append(path)
        logged[s.key] = s
    _log_thresholds(rec, prefix, comparison, logged)
    return entities


__all__ = [
    "Plot",
    "Tab",
    "control_plots",
    "key_path",
    "log_plots",
    "plot_keys",
    "plot_of",
    "plots_for",
    "series_path",
]
