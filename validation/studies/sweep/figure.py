"""The work-precision figure: what is drawn (:func:`figure_data`) and the PNG (:func:`render_png`).

One line per plant and solver / integrator (an accelerated plant: per precision) through its
settings, loose to tight. A point is one setting: x its median wall time per simulated second (the
run's wall time over its horizon, so that a series with a shorter horizon, MuJoCo Warp's on a CPU,
is drawn on the same scale) with the spread of its timings as a bar (min to max), y its error.
The precision floor of an accelerated series (the smallest step beyond which a smaller one stopped
lowering the error) is ringed and labelled.
A run that is not ``ok`` is never dropped: a too-slow run is a ``▷`` mark where its series was cut
(at its measured or predicted wall time, at the last error the series reached), a failed or
diverged one an ``✕`` mark on the figure's top edge, a degraded one a ``+`` where it is; each mark
carries a label. Two series of a plant that draw the same errors (MuJoCo's Euler and implicitfast
on an undamped body) are both visible: the second thin and dotted with large hollow markers over
the first, and the legend says they coincide. The reference's floor is a grey line.
"""

from __future__ import annotations

import dataclasses
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from validation.studies.sweep.accelerated import floors
from validation.studies.sweep.config import (
    ACCELERATED,
    ANALYTIC,
    MJWARP,
    MJX,
    MUJOCO,
    PINOCCHIO,
    Outcome,
)
from validation.studies.sweep.metrics import ERROR_MEASURE

MARK_OUTCOMES = (Outcome.TOO_SLOW, Outcome.FAILED, Outcome.DIVERGED, Outcome.DEGRADED)
"""Outcomes drawn as a labelled mark (skipped settings are named by their series' mark)."""

SAME_ERROR_RTOL = 1e-12
"""Two series of one plant whose errors agree to this (relative) at every shared setting are
coincident: drawn so that both stay visible, and said so in the legend."""

STYLES = {
    ANALYTIC: ("-", "o"),
    MUJOCO: ("--", "s"),
    PINOCCHIO: (":", "^"),
    MJX: ("-.", "D"),
    MJWARP: ((0, (5, 1, 1, 1)), "v"),
}
"""Line style and marker per plant; colour is per solver / integrator (an accelerated plant's:
per plant and precision)."""


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
    at_precision_floor: bool = False


@dataclass(frozen=True)
class Line:
    """The ``ok`` settings of one series, in grid order."""

    engine: str
    method: str
    points: tuple[Point, ...]
    same_as: tuple[str, ...] = ()  # methods of the same plant drawing the same errors
    floor_kind: str = ""  # an accelerated series' floor: round-off, model or unconfirmed


def coincident(a: Line, b: Line) -> bool:
    """Same plant, the same settings, errors equal to :data:`SAME_ERROR_RTOL` at each."""
    if a.engine != b.engine or len(a.points) != len(b.points) or not a.points:
        return False
    return all(
        p.setting == q.setting and abs(p.error - q.error) <= SAME_ERROR_RTOL * max(p.error, q.error)
        for p, q in zip(a.points, b.points, strict=True)
    )


def _with_coincidences(lines: list[Line]) -> list[Line]:
    out = []
    for ln in lines:
        same = tuple(o.method for o in lines if o is not ln and coincident(ln, o))
        out.append(dataclasses.replace(ln, same_as=same) if same else ln)
    return out


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
    horizons: tuple[str, ...] = ()  # series whose horizon is not t_end, in words


def _finite_positive(v: Any) -> bool:
    return isinstance(v, int | float) and math.isfinite(v) and v > 0


def figure_data(
    runs: Sequence[Mapping[str, Any]], floor: float, scene: str, t_end: float
) -> FigureData:
    """The lines and marks of ``runs`` (rows of :data:`validation.studies.sweep.rows.COLUMNS`).

    ``floor``: the error the reference resolves (drawn as a line). Wall times are per simulated
    second: a row's over its ``horizon_s`` (``t_end`` when it has none).
    """
    series: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in runs:
        series.setdefault((str(r["engine"]), r["method"]), []).append(r)
    lines: list[Line] = []
    marks: list[Mark] = []
    horizons: list[str] = []
    kinds = {(f.engine, f.precision): f.kind for f in floors(runs)}
    for (engine, method), rows in series.items():
        pts = []
        horizon = float(rows[0].get("horizon_s") or t_end)
        if abs(horizon - t_end) > 1e-12:
            horizons.append(f"{engine} {method}: horizon {horizon:g} s")
        for r in rows:
            r = _per_second(r, horizon)
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
                        bool(r.get("at_precision_floor")),
                    )
                )
            elif r["status"] == Outcome.OK or r["status"] in MARK_OUTCOMES:
                marks.append(_mark(r, pts, rows))
        if pts:
            kind = kinds.get((engine, method))
            lines.append(Line(engine, method, tuple(pts), floor_kind=kind.value if kind else ""))
    lines = _with_coincidences(lines)
    return FigureData(
        f"work-precision: {scene}, horizon {t_end:g} s",
        t_end,
        tuple(lines),
        tuple(marks),
        floor,
        horizons=tuple(horizons),
    )


_WALL_KEYS = ("wall_time_s", "wall_time_min_s", "wall_time_max_s", "wall_time_predicted_s")


def _per_second(r: Mapping[str, Any], horizon: float) -> Mapping[str, Any]:
    """``r`` with its wall times per simulated second (over ``horizon`` s)."""
    out = dict(r)
    for k in _WALL_KEYS:
        if isinstance(out.get(k), int | float):
            out[k] = out[k] / horizon
    return out


def _series_colour_key(engine: str, method: str) -> str:
    """Colour is per solver / integrator, an accelerated plant's per plant and precision."""
    return f"{engine} {method}" if engine in ACCELERATED else method


def _mark(r: Mapping[str, Any], pts: list[Point], rows: Sequence[Mapping[str, Any]]) -> Mark:
    status = Outcome(r["status"])
    skipped = sum(1 for x in rows if x["status"] == Outcome.SKIPPED)
    what = f"{r['engine']} {r['method']} {r['setting_name']} {r['setting']:.2g}"
    if status is Outcome.TOO_SLOW:
        wall = r["wall_time_s"] if r["wall_time_s"] is not None else r["wall_time_predicted_s"]
        how = "predicted" if r["wall_time_s"] is None else "stopped at"  # its budget
        label = f"{what}: too slow ({how} {wall:.2g} s)" if wall else f"{what}: too slow"
        error = pts[-1].error if pts else None
    elif status is Outcome.DEGRADED:  # measured: drawn where it is, as a warning
        wall = r["wall_time_s"]
        label = f"{what}: degraded (a control dropped for a step)"
        error = r["error"]
    elif status is Outcome.OK:  # ok, but its wall time or error cannot be drawn on log axes
        wall = r["wall_time_s"]
        label = f"{what}: ok, error {r['error']!s}, wall {r['wall_time_s']!s} s (off the log axes)"
        error = None
    else:
        wall = r["wall_time_s"]
        label = f"{what}: {status.value}"
        error = None
    if skipped and status not in (Outcome.OK, Outcome.DEGRADED):
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


MARK_SYMBOLS = {
    Outcome.TOO_SLOW: (">", "too slow (series cut)"),
    Outcome.FAILED: ("X", "failed / diverged"),
    Outcome.DIVERGED: ("X", "failed / diverged"),
    Outcome.DEGRADED: ("P", "degraded (a control dropped)"),
}
"""Marker and legend words of each marked outcome."""


def render_png(data: FigureData) -> bytes:
    """The figure as PNG bytes (matplotlib, Agg; no global pyplot state)."""
    # deferred: matplotlib is imported only when the figure is drawn (docs/performance.md,
    # Import costs)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.5, 6.4))
    ax = fig.add_subplot()
    ax.set_xscale("log")
    ax.set_yscale("log")
    methods = list(
        dict.fromkeys(
            [_series_colour_key(ln.engine, ln.method) for ln in data.lines]
            + [_series_colour_key(m.engine, m.method) for m in data.marks]
        )
    )
    colours = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    ]  # fmt: skip
    colour = {m: colours[i % len(colours)] for i, m in enumerate(methods)}
    drawn: list[Line] = []
    for ln in data.lines:
        ls, marker = STYLES.get(ln.engine, ("-.", "x"))
        c = colour[_series_colour_key(ln.engine, ln.method)]
        x = [p.wall for p in ln.points]
        y = [p.error for p in ln.points]
        xerr = [[p.wall - p.wall_min for p in ln.points], [p.wall_max - p.wall for p in ln.points]]
        label = f"{ln.engine} {ln.method}"
        lw, ms, z = 1.2, 5, 2
        under = [o for o in drawn if o.method in ln.same_as]
        if ln.same_as:
            label += f" (≡ {', '.join(ln.same_as)} here: the same errors)"
        if under:  # drawn over a coincident series: thin, with large hollow markers around it
            ls, marker, lw, ms, z = (0, (1, 2)), "D", 2.4, 9, 1
        ax.errorbar(x, y, xerr=xerr, ls=ls, marker="none", capsize=2, lw=lw, elinewidth=0.8,
                    color=c, zorder=z)  # fmt: skip
        ax.plot(x, y, ls=ls, lw=lw, marker=marker, ms=ms, color=c, label=label, zorder=z,
                mfc="none" if under else c,
                markevery=[i for i, p in enumerate(ln.points) if p.n >= 2 or under])  # fmt: skip
        drawn.append(ln)
        for p in ln.points:
            if p.at_precision_floor:  # ringed and labelled: the smallest step that helped
                ax.plot(p.wall, p.error, marker="o", ms=16, mfc="none", mec=c, mew=1.6, zorder=4)
                ax.annotate(
                    f"{ln.engine} {ln.method} floor ({ln.floor_kind}): dt {p.setting:.2g} s",
                    (p.wall, p.error),
                    xytext=(10, -14), textcoords="offset points", fontsize=7, color=c,
                    fontweight="bold",
                )  # fmt: skip
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
        c = colour.get(_series_colour_key(m.engine, m.method), "k")
        symbol, kind_words = MARK_SYMBOLS[m.outcome]
        kind_label = None
        if kind_words not in seen_kinds:
            seen_kinds.add(kind_words)
            kind_label = kind_words
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
        "wall time per simulated second, s/s (integration only): median of the timings, bar "
        "min–max, hollow: one timing; ringed: a precision's floor",
        fontsize=8.5,
    )
    ax.set_ylabel("error (max over the horizon; see below)", fontsize=9)
    ax.set_title(data.title, fontsize=11)
    foot = f"error: {data.error_measure}"
    if data.horizons:
        foot += f". Other horizons: {'; '.join(data.horizons)}"
    fig.text(0.01, 0.005, foot, fontsize=7, color="0.25")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout(rect=(0, 0.025, 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


__all__ = ["FigureData", "Line", "Mark", "Point", "figure_data", "render_png"]
