"""Reports of a validation run: ``report.md`` for people, ``report.json`` for machines, PNG figures.

Every file is written atomically (a temporary file in the same directory, then :func:`os.replace`),
so an interrupted run never leaves a half-written report. A failed run still writes what it has;
its verdict is ``FAILED`` and the reason is stated first.

Figures (matplotlib, Agg, no pyplot state):

* ``errors.png``: the differences between the plants against time, log axes;
* ``tracking.png``: each plant's tracking errors and their deviation from the closed-form error
  dynamics, log axes;
* ``invariants.png``: each plant's quaternion norm error and balances of linear momentum, angular
  momentum and energy, log axes;
* ``control.png``: control torque (body axes) and rod forces of both plants, linear axes.
"""

from __future__ import annotations

import io
import json
import math
import platform
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from analytic.trajectory import Trajectory
from validation.atomic import write_bytes
from validation.compare import Comparison, Group, Series, Subject
from validation.referee import LABELS, Verdict, summary_lines

PLANT_STYLE = {
    Subject.ANALYTIC: {"color": "tab:blue", "linestyle": "-"},
    Subject.MUJOCO: {"color": "tab:orange", "linestyle": "--"},
    Subject.PINOCCHIO: {"color": "tab:green", "linestyle": ":"},
    Subject.BOTH: {"color": "tab:red", "linestyle": "-"},
    Subject.ANALYTIC_PINOCCHIO: {"color": "tab:purple", "linestyle": "-"},
    Subject.MUJOCO_PINOCCHIO: {"color": "tab:brown", "linestyle": "--"},
}
FIGURES = ("errors", "tracking", "invariants", "control")
_LINESTYLE_NAME = {"-": "solid", "--": "dashed", ":": "dotted"}


# ----------------------------------------------------------------------------------------------
# Atomic writes
# ----------------------------------------------------------------------------------------------


def write_atomic(path: str | Path, data: bytes | str) -> Path:
    """Write ``data`` (text as UTF-8) atomically and checked: :func:`validation.atomic.write_bytes`."""
    return write_bytes(path, data.encode("utf-8") if isinstance(data, str) else data)


# ----------------------------------------------------------------------------------------------
# Metadata
# ----------------------------------------------------------------------------------------------


def versions() -> dict[str, str]:
    """Versions of Python, the platform and the packages that produce the numbers."""
    out = {"python": sys.version.split()[0], "platform": platform.platform()}
    for pkg in ("tumbling-testbed", "numpy", "scipy", "mujoco", "rerun-sdk", "matplotlib"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def _jsonable(x: Any) -> Any:
    if isinstance(x, Mapping):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        return _jsonable(x.item())
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)  # JSON has no inf/nan
    if isinstance(x, str | int | float | bool) or x is None:
        return x
    return str(x)


def _short(info: Mapping[str, Any], longest: int = 20) -> dict[str, Any]:
    """Engine info without long per-sample lists (those belong in the trajectory files)."""
    out = {}
    for k, v in info.items():
        if isinstance(v, list | tuple | np.ndarray) and len(v) > longest:
            out[k] = f"<{len(v)} values>"
        else:
            out[k] = v
    return out


# ----------------------------------------------------------------------------------------------
# Figures
# ----------------------------------------------------------------------------------------------


def _figure(nrows: int, title: str):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 2.2 * nrows + 0.8))
    fig.subplots_adjust(
        left=0.09,
        right=0.98,
        top=1 - 0.75 / (2.2 * nrows + 0.8),
        bottom=0.45 / (2.2 * nrows + 0.8),
        hspace=0.45,
    )
    axes = fig.subplots(nrows, 1, sharex=True, squeeze=False)[:, 0]
    fig.suptitle(title)
    return fig, axes


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def _log_plot(ax, series: Sequence[Series], threshold: float | None = None) -> None:
    """Plot positive values on a log axis; zeros (exact agreement) are stated, not drawn."""
    ax.set_yscale("log")
    drawn = False
    for s in series:
        v = np.where(s.values > 0, s.values, np.nan)
        style = PLANT_STYLE[s.subject]
        label = s.subject.value
        if np.any(np.isfinite(v)):
            ax.plot(s.t, v, label=label, linewidth=1.2, **style)
            drawn = True
        else:
            ax.plot([], [], label=f"{label}: identically zero", **style)
    if threshold is not None and threshold > 0:
        ax.axhline(
            threshold, color="k", linestyle=":", linewidth=1.0, label=f"threshold {threshold:.3g}"
        )
        drawn = True
    pos = [s.values[s.values > 0] for s in series]
    pos = np.concatenate(pos) if pos else np.zeros(0)
    if threshold is not None and threshold > 0:
        pos = np.append(pos, threshold)
    pos = pos[np.isfinite(pos)]
    if not drawn or pos.size == 0:
        ax.set_ylim(1e-16, 1.0)
    else:  # explicit limits: matplotlib's autoscale warns on a constant series
        ax.set_ylim(pos.min() / 5, pos.max() * 5)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def _abs_threshold(cmp: Comparison, name: str, scale: float = 1.0) -> float | None:
    th = cmp.thresholds.get(name)
    if th is None:
        return None
    return th.value * max(scale, th.floor) if th.relative else th.value


def figure_errors(cmp: Comparison) -> bytes | None:
    """Differences between the plants against time (one panel per quantity, one line per pair),
    log axes; None without a second plant."""
    diffs = [s for s in cmp.series if s.group is Group.DIFFERENCE]
    if not diffs:
        return None
    rows: dict[str, list[Series]] = {}
    for s in diffs:
        rows.setdefault(s.name, []).append(s)
    first = {c.name: c.scale for c in reversed(cmp.checks) if c.subject.is_pair}
    pairs = list(dict.fromkeys(s.subject.value for s in diffs))
    fig, axes = _figure(len(rows), f"{cmp.scene}: {', '.join(pairs)}")
    for ax, (name, ss) in zip(axes, rows.items(), strict=True):
        _log_plot(ax, ss, _abs_threshold(cmp, name, first.get(name, 1.0)))
        ax.set_ylabel(ss[0].unit)
        title = ss[0].label if len(ss) == 1 else f"{LABELS.get(name, name)} ({ss[0].unit})"
        ax.set_title(title, fontsize=9)
    axes[-1].set_xlabel("t (s)")
    return _png(fig)


def _plant_rows(cmp: Comparison, names: Sequence[str]) -> list[tuple[str, list[Series]]]:
    rows = []
    for name in names:
        ss = [s for s in cmp.series if not s.subject.is_pair and s.name == name]
        if ss:
            rows.append((name, ss))
    return rows


def figure_tracking(cmp: Comparison) -> bytes | None:
    """Tracking errors of each plant and their deviation from the closed-form law; log axes."""
    rows = _plant_rows(cmp, ("e_omega", "e_omega_law", "e_p", "e_p_law"))
    if not rows:
        return None
    limits = {"e_omega_law": "tracking_omega", "e_p_law": "tracking_p"}
    fig, axes = _figure(len(rows), f"{cmp.scene}: tracking errors of each plant")
    for ax, (name, ss) in zip(axes, rows, strict=True):
        _log_plot(ax, ss, _abs_threshold(cmp, limits[name]) if name in limits else None)
        ax.set_ylabel(ss[0].unit)
        ax.set_title(ss[0].label, fontsize=9)
    axes[-1].set_xlabel("t (s)")
    return _png(fig)


def figure_invariants(cmp: Comparison) -> bytes | None:
    """Quaternion norm error, momentum and energy balances of each plant; log axes."""
    rows = _plant_rows(cmp, ("quat_norm", "linear_momentum", "angular_momentum", "energy"))
    if not rows:
        return None
    fig, axes = _figure(len(rows), f"{cmp.scene}: invariants (drift of each balance)")
    for ax, (_name, ss) in zip(axes, rows, strict=True):
        _log_plot(ax, ss)
        ax.set_ylabel(ss[0].unit)
        ax.set_title(ss[0].label, fontsize=9)
    axes[-1].set_xlabel("t (s)")
    return _png(fig)


def figure_control(plants: Sequence[Trajectory]) -> bytes | None:
    """Control torque components (body axes, N·m) and rod forces (N) of every plant."""
    if not plants:
        return None
    n = plants[0].n
    fig, axes = _figure(2 if n else 1, f"{plants[0].scene}: control forces of every plant")
    for tr in plants:
        style = PLANT_STYLE[Subject(tr.engine.value)]
        for j in range(3):
            axes[0].plot(
                tr.t,
                tr.torque[:, j],
                linestyle=style["linestyle"],
                linewidth=1.1,
                label=f"{tr.engine.value} τ_{'xyz'[j]}",
                color=f"C{j}",
            )
        for i in range(n):
            axes[1].plot(
                tr.t,
                tr.rod_forces[:, i],
                linestyle=style["linestyle"],
                linewidth=1.1,
                label=f"{tr.engine.value} F_{i + 1}",
                color=f"C{i + 3}",
            )
    axes[0].set_ylabel("N·m")
    styles = ", ".join(
        f"{_LINESTYLE_NAME[PLANT_STYLE[Subject(tr.engine.value)]['linestyle']]}: {tr.engine.value}"
        for tr in plants
    )
    axes[0].set_title(f"control torque, body axes ({styles})", fontsize=9)
    if n:
        axes[1].set_ylabel("N")
        axes[1].set_title("rod forces on the masses", fontsize=9)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=2, loc="best")
    axes[-1].set_xlabel("t (s)")
    return _png(fig)


# ----------------------------------------------------------------------------------------------
# report.md / report.json
# ----------------------------------------------------------------------------------------------


def _cell(text: str) -> str:
    """Markdown table cell: a literal ``|`` would end the cell."""
    return str(text).replace("|", "\\|")


def _fmt(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.3e}" if x != 0 else "0"


def _referee_lines(verdicts: Sequence[Verdict], meta: Mapping[str, Any]) -> list[str]:
    """The referee's section: one sentence per quantity, then the pairwise table."""
    if not verdicts:
        note = meta.get("referee_note", "")
        return ["## Referee", "", f"No referee verdict: {note}.", ""] if note else []
    lines = ["## Referee", ""]
    plants = meta.get("plants", [])
    if plants:
        lines += ["Plants: " + "; ".join(p["settings"] for p in plants) + ".", ""]
    lines += [f"- {t}" for t in summary_lines(verdicts)]
    pairs = list(verdicts[0].values)
    lines += [
        "",
        "| quantity | " + " | ".join(pairs) + " | threshold | unit | verdict |",
        "|---|" + "---|" * (len(pairs) + 3),
    ]
    for v in verdicts:
        cells = " | ".join(_fmt(v.values.get(p, math.nan)) for p in pairs)
        who = f"{v.kind.value}: {v.outlier}" if v.outlier else v.kind.value
        lines.append(f"| {v.quantity} | {cells} | {_fmt(v.threshold)} | {v.unit} | {who} |")
    lines += [
        "",
        "Values are each pair's maximum over time (relative for the forces). A plant is the "
        "outlier when its distances to the other two exceed theirs to each other tenfold "
        "(`validation.thresholds.REFEREE_SEPARATION`).",
        "",
    ]
    return lines


def render_markdown(
    cmp: Comparison | None,
    verdict: str,
    failure: str,
    figures: Sequence[str],
    meta: Mapping[str, Any],
    verdicts: Sequence[Verdict] = (),
) -> str:
    """The text of ``report.md``: the verdict first, then the referee, checks, summaries,
    figures, thresholds and the run's metadata."""
    scene = meta.get("scene", {}).get("name", cmp.scene if cmp else "?")
    lines = [f"# {scene}: {verdict}", ""]
    if failure:
        lines += [f"**The run failed:** {failure}", ""]
    if cmp is not None:
        bad = cmp.failed_checks
        total = len(cmp.checks)
        lines.append(f"{total - len(bad)} of {total} checks pass." + (" Failed:" if bad else ""))
        for c in bad:
            lines.append(
                f"- **{c.label}** = {_fmt(c.value)} {c.unit} > {_fmt(c.threshold)} ({c.reason})"
            )
        lines.append("")
        for n in cmp.notes:
            lines.append(f"> {n}")
        if cmp.notes:
            lines.append("")
        lines += _referee_lines(verdicts, meta)
        lines += [
            "## Checks",
            "",
            "| check | value | threshold | unit | verdict | at t (s) |",
            "|---|---|---|---|---|---|",
        ]
        for c in cmp.checks:
            lines.append(
                f"| {c.label} | {_fmt(c.value)} | {_fmt(c.threshold)} | {c.unit} | "
                f"{'pass' if c.passed else '**FAIL**'} | {_fmt(c.t_max)} |"
            )
        lines += [
            "",
            "Relative checks are divided by the scale of the signal (see report.json).",
            "",
        ]
        lines += [
            "## Summaries over time",
            "",
            "| quantity | of | max | RMS | final | t of max (s) | unit |",
            "|---|---|---|---|---|---|---|",
        ]
        for s in cmp.series:
            m = s.summary
            lines.append(
                f"| {_cell(s.label)} | {s.subject.value} | {_fmt(m.max)} | {_fmt(m.rms)} | {_fmt(m.final)} | "
                f"{_fmt(m.t_max)} | {s.unit} |"
            )
        lines.append("")
    if figures:
        lines += ["## Figures", ""]
        for f in figures:
            lines += [f"![{Path(f).stem}]({f})", ""]
    lines += ["## Thresholds", ""]
    if cmp is not None:
        lines += ["| name | value | unit | source | reason |", "|---|---|---|---|---|"]
        for th in cmp.thresholds.values():
            kind = " (relative)" if th.relative else ""
            lines.append(
                f"| {th.name} | {th.value:g}{kind} | {th.unit} | {th.source} | {_cell(th.reason)} |"
            )
        lines.append("")
    lines += ["## Run", "", "```json", json.dumps(_jsonable(meta), indent=2), "```", ""]
    return "\n".join(lines)


def _pairwise(cmp: Comparison | None) -> dict[str, dict[str, float]]:
    """Quantity -> pair (``analytic vs mujoco``) -> the pair's checked value."""
    out: dict[str, dict[str, float]] = {}
    for c in cmp.checks if cmp is not None else ():
        if c.subject.is_pair:
            out.setdefault(c.name, {})[c.subject.value] = c.value
    return out


@dataclass(frozen=True)
class ReportFiles:
    """Paths written by :func:`write_report` (figures only those that were drawn)."""

    markdown: Path
    json: Path
    figures: tuple[Path, ...]


def write_report(
    out_dir: str | Path,
    cmp: Comparison | None,
    plants: Sequence[Trajectory],
    meta: Mapping[str, Any],
    failure: str = "",
    verdicts: Sequence[Verdict] = (),
) -> ReportFiles:
    """Write ``report.md``, ``report.json`` and the figures into ``out_dir`` (atomically).

    Args:
        out_dir: output directory (created).
        cmp: the comparison, or None when the run failed before one could be made.
        plants: the trajectories that exist (analytic first).
        meta: run metadata (scene, versions, solver settings, wall times ...), JSON-able.
        failure: why the run failed ("" when it did not); a failure makes the verdict FAILED.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    passed = cmp is not None and cmp.passed and not failure
    verdict = "PASSED" if passed else "FAILED"
    figs: list[Path] = []
    makers = {
        "errors": (lambda: figure_errors(cmp)) if cmp else None,
        "tracking": (lambda: figure_tracking(cmp)) if cmp else None,
        "invariants": (lambda: figure_invariants(cmp)) if cmp else None,
        "control": lambda: figure_control(plants),
    }
    fig_errors: list[str] = []
    for name in FIGURES:
        make = makers[name]
        if make is None:
            continue
        try:
            with warnings.catch_warnings():
                # matplotlib's autoscale of a constant series on a log axis: harmless
                warnings.filterwarnings("ignore", message="Attempting to set identical")
                png = make()
        except Exception as exc:  # a figure must not cost the report
            fig_errors.append(f"{name}.png: {type(exc).__name__}: {exc}")
            continue
        if png is not None:
            figs.append(write_atomic(out / f"{name}.png", png))
    meta = dict(meta)
    if fig_errors:
        meta["figure_errors"] = fig_errors
    doc = {
        "verdict": verdict,
        "passed": passed,
        "failure": failure,
        **(cmp.to_dict() if cmp is not None else {"checks": [], "summaries": {}, "notes": []}),
        "thresholds": {
            k: {
                "value": t.value,
                "unit": t.unit,
                "relative": t.relative,
                "floor": t.floor,
                "source": t.source,
                "reason": t.reason,
            }
            for k, t in (cmp.thresholds.items() if cmp is not None else ())
        },
        "plants": [
            {
                "engine": p.engine.value,
                "status": p.status.value,
                "message": p.message,
                "samples": int(p.t.shape[0]),
                "t_reached": float(p.t[-1]) if p.t.size else None,
                "info": _short(p.info),
            }
            for p in plants
        ],
        "referee": [v.to_dict() for v in verdicts],
        "pairwise": _pairwise(cmp),
        "figures": [f.name for f in figs],
        "run": meta,
    }
    doc["passed"] = passed  # cmp.to_dict() has its own; the failure overrides
    js = write_atomic(out / "report.json", json.dumps(_jsonable(doc), indent=2) + "\n")
    md = write_atomic(
        out / "report.md",
        render_markdown(cmp, verdict, failure, [f.name for f in figs], meta, verdicts),
    )
    return ReportFiles(md, js, tuple(figs))


__all__ = [
    "FIGURES",
    "ReportFiles",
    "figure_control",
    "figure_errors",
    "figure_invariants",
    "figure_tracking",
    "render_markdown",
    "versions",
    "write_atomic",
    "write_report",
]
