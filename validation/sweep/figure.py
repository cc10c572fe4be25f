"""The work-precision figure: what is drawn (:func:`figure_data`) and the PNG (:func:`render_png`).

One line per plant and solver / integrator through its settings, loose to tight. A point is one
setting: x its median wall time with the spread of its timings as a bar (min to max), y its error.
A run that is not ``ok`` is never dropped: a too-slow run is a ``▷`` mark where its series was cut
(at its measured or predicted wall time, at the last error the series reached), a failed or
diverged one an ``✕`` mark on the figure's top edge; each mark carries a label. The reference's
floor is a grey line.
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from validation.sweep.config import ANALYTIC, MUJOCO, PINOCCHIO, Outcome
from validation.sweep.metrics import ERROR_MEASURE

MARK_OUTCOMES = (Outcome.TOO_SLOW, Outcome.FAILED, Outcome.DIVERGED)
"""Outcomes drawn as a labelled mark (skipped settings are named by their series' mark)."""

STYLES = {ANALYTIC: ("-", "o"), MUJOCO: ("--", "s"), PINOCCHIO: (":", "^")}
"""Line style and marker per plant; colour is per solver / integrator."""


@dataclass(frozen=True)
class Point:
    """One ``ok`` setting: wall times in s (median, min, max of ``n`` timings), its error."""

    run_id: int
    setting: float
    wall: float
    wall_min: float
    wall_max: float
    n: int
    error: float
    at_floor: bool


@dataclass(frozen=True)
class Line:
    """The ``ok`` settings of one series, in grid order."""

    engine: str
    method: str
    points: tuple[Point, ...]


@dataclass(frozen=True)
class Mark:
    """A run that is not ``ok``, drawn as a labelled marker.

    ``wall`` (s) and ``error`` are where it is drawn; None: on the figure's edge (left for no wall
    time, top for no error).
    """

    engine: str
    method: str
    run_id: int
    outcome: Outcome
    wall: float | None
    error: float | None
    label: str


@dataclass(frozen=True)
class FigureData:
    """Everything the figure shows, and the words around it."""

    title: str
    t_end: float
    lines: tuple[Line, ...]
    marks: tuple[Mark, ...]
    floor: float
    error_measure: str = ERROR_MEASURE


def _finite_positive(v: Any) -> bool:
    return isinstance(v, int | float) and math.isfinite(v) and v > 0


def figure_data(
    runs: Sequence[Mapping[str, Any]], floor: float, scene: str, t_end: float
) -> FigureData:
    """The lines and marks of ``runs`` (rows of :data:`validation.sweep.rows.COLUMNS`).

    ``floor``: the error the reference resolves (drawn as a line).
    """
    series: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in runs:
        series.setdefault((str(r["engine"]), r["method"]), []).append(r)
    lines: list[Line] = []
    marks: list[Mark] = []
    for (engine, method), rows in series.items():
        pts = []
        for r in rows:
            ok = (
                r["status"] == Outcome.OK
                and _finite_positive(r["wall_time_s"])
                and _finite_positive(r["error"])
            )
            if ok:
                pts.append(
                    Point(
                        r["run_id"],
                        r["setting"],
                        r["wall_time_s"],
                        r["wall_time_min_s"],
                        r["wall_time_max_s"],
                        int(r["wall_time_repeats"] or 1),
                        r["error"],
                        bool(r["at_reference_floor"]),
                    )
                )
            elif r["status"] == Outcome.OK or r["status"] in MARK_OUTCOMES:
                marks.append(_mark(r, pts, rows))
        if pts:
            lines.append(Line(engine, method, tuple(pts)))
    return FigureData(
        f"work-precision: {scene}, horizon {t_end:g} s", t_end, tuple(lines), tuple(marks), floor
    )


def _mark(r: Mapping[str, Any], pts: list[Point], rows: Sequence[Mapping[str, Any]]) -> Mark:
    status = Outcome(r["status"])
    skipped = sum(1 for x in rows if x["status"] == Outcome.SKIPPED)
    what = f"{r['engine']} {r['method']} {r['setting_name']} {r['setting']:.2g}"
    if status is Outcome.TOO_SLOW:
        wall = r["wall_time_s"] if r["wall_time_s"] is not None else r["wall_time_predicted_s"]
        how = "predicted" if r["wall_time_s"] is None else "stopped at"  # its budget
        label = f"{what}: too slow ({how} {wall:.2g} s)" if wall else f"{what}: too slow"
        error = pts[-1].error if pts else None
    elif status is Outcome.OK:  # ok, but its wall time or error cannot be drawn on log axes
        wall = r["wall_time_s"]
        label = f"{what}: ok, error {r['error']!s}, wall {r['wall_time_s']!s} s (off the log axes)"
        error = None
    else:
        wall = r["wall_time_s"]
        label = f"{what}: {status.value}"
        error = None
    if skipped and status is not Outcome.OK:
        label += f", {skipped} skipped"
    return Mark(
        str(r["engine"]),
        r["method"],
        int(r["run_id"]),
        status,
        wall if _finite_positive(wall) else None,
        error if _finite_positive(error) else None,
        label,
    )


def render_png(data: FigureData) -> bytes:
    """The figure as PNG bytes (matplotlib, Agg; no global pyplot state)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.5, 6.4))
    ax = fig.add_subplot()
    ax.set_xscale("log")
    ax.set_yscale("log")
    methods = list(dict.fromkeys([ln.method for ln in data.lines] + [m.method for m in data.marks]))
    colours = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    ]  # fmt: skip
    colour = {m: colours[i % len(colours)] for i, m in enumerate(methods)}
    for ln in data.lines:
        ls, marker = STYLES.get(ln.engine, ("-.", "x"))
        c = colour[ln.method]
        x = [p.wall for p in ln.points]
        y = [p.error for p in ln.points]
        xerr = [[p.wall - p.wall_min for p in ln.points], [p.wall_max - p.wall for p in ln.points]]
        ax.errorbar(x, y, xerr=xerr, ls=ls, marker="none", capsize=2, lw=1.2, elinewidth=0.8,
                    color=c)  # fmt: skip
        ax.plot(x, y, ls=ls, lw=1.2, marker=marker, ms=5, color=c, label=f"{ln.engine} {ln.method}",
                markevery=[i for i, p in enumerate(ln.points) if p.n >= 2])  # fmt: skip
        single = [p for p in ln.points if p.n < 2]
        if single:  # one timing: no spread to show, drawn hollow
            ax.plot([p.wall for p in single], [p.error for p in single], ls="none", marker=marker,
                    ms=5, mfc="white", mec=c, zorder=3)  # fmt: skip
    if data.floor > 0:
        ax.axhline(data.floor, color="0.5", ls=":", lw=1, label="reference floor (3x its error)")
    xs = [p.wall for ln in data.lines for p in ln.points] + [m.wall for m in data.marks if m.wall]
    ys = [p.error for ln in data.lines for p in ln.points] + [
        m.error for m in data.marks if m.error
    ]
    if xs and ys:
        ax.set_xlim(min(xs) / 2, max(xs) * 8)  # room for the marks' labels
        ax.set_ylim(min(min(ys), data.floor or min(ys)) / 5, max(ys) * 50)
    trans_top = ax.get_xaxis_transform()  # x in data, y in axes fractions
    seen_kinds = set()
    for i, m in enumerate(data.marks):
        c = colour.get(m.method, "k")
        symbol = ">" if m.outcome is Outcome.TOO_SLOW else "X"
        kind_label = None
        if m.outcome not in seen_kinds:
            seen_kinds.add(m.outcome)
            kind_label = "too slow (series cut)" if symbol == ">" else "failed / diverged"
        if m.wall is not None and m.error is not None:
            xy, transform = (m.wall, m.error), ax.transData
        elif m.wall is not None:
            xy, transform = (m.wall, 0.96 - 0.04 * (i % 4)), trans_top
        else:
            xy, transform = (0.02, 0.96 - 0.04 * (i % 8)), ax.transAxes
        ax.plot(*xy, marker=symbol, ms=9, color=c, mec="k", ls="none", transform=transform,
                label=kind_label)  # fmt: skip
        ax.annotate(
            m.label, xy, xycoords=transform, xytext=(6, -3), textcoords="offset points",
            fontsize=6.5, color=c,
        )  # fmt: skip
    ax.set_xlabel(
        "wall time per run, s (integration only): median of the timings, bar min–max, "
        "hollow: one timing",
        fontsize=8.5,
    )
    ax.set_ylabel("error (max over the horizon; see below)", fontsize=9)
    ax.set_title(data.title, fontsize=11)
    fig.text(0.01, 0.005, f"error: {data.error_measure}", fontsize=7, color="0.25")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout(rect=(0, 0.025, 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


__all__ = ["FigureData", "Line", "Mark", "Point", "figure_data", "render_png"]
