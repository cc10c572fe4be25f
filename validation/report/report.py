"""Reports of a validation run: ``report.md`` for people, ``report.json`` for machines, figures.

Every file is written atomically (a temporary file in the same directory, then :func:`os.replace`),
so an interrupted run never leaves a half-written report. A failed run still writes what it has;
its verdict is ``FAILED`` and the reason is stated first; a run a signal stopped is
``INTERRUPTED``, said the same way (:class:`RunVerdict`). A file that cannot be written (a full
disk) is an :class:`validation.runs.atomic.OutputError`, never a verdict. Every string a scene or an
error message brings into ``report.md`` is escaped to literal text on one line (:func:`_md`).

The figures are drawn by :mod:`validation.report.figures` (``errors``, ``tracking``, ``invariants``,
``control``), written in each format asked for (PNG by default; SVG or PDF for papers) and
embedded in ``report.md`` each with its caption; a figure that was not drawn (an uncontrolled scene
has no control figure) is named there with the reason.

"max" of a quantity over time is always its largest magnitude (:func:`validation.compare.summary.max_abs`):
the summaries' ``max_abs`` of a signed rod force is its largest ``|F_i|``, not its largest value.
"""

from __future__ import annotations

import errno
import json
import math
import platform
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from analytic.threshold import BoundPart
from analytic.trajectory import Trajectory
from validation.compare.checks import Check, CheckState, Comparison, Series
from validation.compare.referee import Verdict, rule_text, summary_lines
from validation.compare.summary import check_sentence, max_abs
from validation.report.figures import (
    DEFAULT_FORMATS,
    FIGURES,
    Drawing,
    FigureContext,
    FigureFormat,
    figure_control,
    figure_errors,
    figure_invariants,
    figure_tracking,
)
from validation.report.provenance import FileKind, code_origin, dumps, provenance
from validation.runs.atomic import OutputError, write_bytes


class RunVerdict(StrEnum):
    """A run's verdict, the first word of ``report.md`` after the scene's name and
    ``report.json``'s ``verdict``: PASSED only when every check passed and nothing failed or was
    left out (a plant, a figure, the recording); INTERRUPTED when a signal stopped the run."""

    PASSED = "PASSED"
    FAILED = "FAILED"
    INTERRUPTED = "INTERRUPTED"

    @classmethod
    def of(cls, cmp: Comparison | None, failure: str, interrupted: bool = False) -> RunVerdict:
        if interrupted:
            return cls.INTERRUPTED
        return cls.PASSED if cmp is not None and cmp.passed and not failure else cls.FAILED


def _stopped(verdict: RunVerdict) -> str:
    """How the failure line of ``report.md`` opens: ``The run failed`` / ``was interrupted``."""
    return "was interrupted" if verdict is RunVerdict.INTERRUPTED else "failed"


# ----------------------------------------------------------------------------------------------
# Atomic writes
# ----------------------------------------------------------------------------------------------


WRITE_FAILURES = frozenset(
    getattr(errno, name)
    for name in ("ENOSPC", "EDQUOT", "EIO", "EROFS", "EFBIG", "ENFILE", "EMFILE", "EACCES", "EPERM")
    if hasattr(errno, name)
)
"""The ``errno`` values of a filesystem that refuses a write (full, over quota, failing,
read-only, too many files open, no permission)."""


def is_write_failure(exc: BaseException) -> bool:
    """Whether ``exc`` is the filesystem refusing a write (:data:`WRITE_FAILURES`, or an
    :class:`validation.runs.atomic.OutputError`), as opposed to a bug."""
    return isinstance(exc, OutputError) or (
        isinstance(exc, OSError) and exc.errno in WRITE_FAILURES
    )


def write_atomic(path: str | Path, data: bytes | str) -> Path:
    """Write ``data`` (text as UTF-8) atomically and checked: :func:`validation.runs.atomic.write_bytes`."""
    return write_bytes(path, data.encode("utf-8") if isinstance(data, str) else data)


# ----------------------------------------------------------------------------------------------
# Metadata
# ----------------------------------------------------------------------------------------------


def versions() -> dict[str, str | None]:
    """Versions of Python, the platform and the packages that produce the numbers."""
    out = {"python": sys.version.split()[0], "platform": platform.platform()}
    for pkg in ("tumbling-testbed", "numpy", "scipy", "mujoco", "rerun-sdk", "matplotlib"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None  # not installed
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
    """Engine info without long per-sample lists: those belong in the trajectory files, so a
    list longer than ``longest`` is left out and its length given as ``<key>_length``."""
    out = {}
    for k, v in info.items():
        if isinstance(v, list | tuple | np.ndarray) and len(v) > longest:
            out[f"{k}_length"] = len(v)
        else:
            out[k] = v
    return out


# ----------------------------------------------------------------------------------------------
# report.md / report.json
# ----------------------------------------------------------------------------------------------


_MD_ESCAPES = str.maketrans(
    {
        "&": "&amp;",
        "<": "&lt;",
        ">": "&gt;",
        "\\": "\\\\",
        "`": "\\`",
        "*": "\\*",
        "[": "\\[",
        "]": "\\]",
        "|": "\\|",
        "\n": " ",
        "\r": " ",
        "\t": " ",
        "\v": " ",
        "\f": " ",
        "\x85": " ",
        "\u2028": " ",
        "\u2029": " ",
    }
)
_MD_LINE_START = ("#", "-", "+", "=", ">", "~")


def _md(text: Any) -> str:
    """``text`` as literal Markdown on one line, safe in a table cell or after a list marker: HTML
    special characters as entities (no tag or comment can open), the characters that make code,
    emphasis, links or table cells backslash-escaped, every line break a space, and a leading
    block marker (``#`` heading, ``-`` list, ``>`` quote ...) escaped. For every string a scene
    or an error message brings into ``report.md``."""
    out = str(text).translate(_MD_ESCAPES)
    if out.startswith(_MD_LINE_START):
        return "\\" + out
    return re.sub(r"^(\d+)([.)])", r"\1\\\2", out)  # "1." would start a numbered list


def _cell(text: Any) -> str:
    """A Markdown table cell's text (:func:`_md`: a literal ``|`` would end the cell)."""
    return _md(text)


def _fenced_json(meta: Mapping[str, Any]) -> str:
    """``meta`` as indented JSON for a fenced code block: a backtick (which could close the fence)
    is written as its JSON escape ``\\u0060``, so the block ends where the report ends it."""
    return json.dumps(_jsonable(meta), indent=2).replace("`", "\\u0060")


def _fmt(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.3e}" if x != 0 else "0"


def _bound_cell(c: Check) -> str:
    """Which part of a check's threshold decided: ``absolute``, ``relative (1e-07 × 1.6e+03)``
    (rtol × the quantity's scale, in the check's unit), or "" for a threshold without a relative
    part."""
    if not c.applicable or c.relative_part <= 0 or not c.magnitude:
        return ""
    if c.decided_by is BoundPart.RELATIVE:
        return f"relative ({c.relative_part / c.magnitude:.3g} × {c.magnitude:.3g})"
    return "absolute"


def _state_cell(c: Check) -> str:
    """A check's verdict cell: ``pass``, ``**FAIL**`` or ``not applicable``."""
    state = c.state
    return "**FAIL**" if state is CheckState.FAIL else state.value


def _referee_lines(verdicts: Sequence[Verdict], meta: Mapping[str, Any]) -> list[str]:
    """The referee's section: one sentence per quantity, then the pairwise table."""
    if not verdicts:
        note = meta.get("referee_note", "")
        return ["## Referee", "", f"No referee verdict: {_md(note)}.", ""] if note else []
    lines = ["## Referee", ""]
    plants = meta.get("plants", [])
    if plants:
        lines += ["Plants: " + "; ".join(_md(p["settings"]) for p in plants) + ".", ""]
    if meta.get("referee_note"):  # a plant of the run's set left out (it refused the scene)
        lines += [f"Note: {_md(meta['referee_note'])}.", ""]
    lines += [f"- {_md(t)}" for t in summary_lines(verdicts)]
    pairs = list(dict.fromkeys(p for v in verdicts for p in v.values))
    lines += [
        "",
        "| quantity | "
        + " | ".join(_cell(p) for p in pairs)
        + " | threshold | noise floor | floor set by | unit | verdict | decided by |",
        "|---|" + "---|" * (len(pairs) + 6),
    ]
    for v in verdicts:
        cells = " | ".join(_fmt(v.values.get(p, math.nan)) for p in pairs)
        who = v.kind.value
        if v.outliers:  # each outlier with its distance to the group
            who += ": " + ", ".join(f"{o.plant} ({_fmt(o.distance)})" for o in v.outliers)
        elif v.groups:
            who += ": " + " vs ".join(", ".join(g) for g in v.groups)
        by = v.clause.value if v.clause else "–"
        set_by = v.floor_set_by.value if v.floor_set_by else "–"
        lines.append(
            f"| {_cell(v.quantity)} | {cells} | {_fmt(v.threshold)} | {_fmt(v.floor)} | "
            f"{_cell(set_by)} | {_cell(v.unit)} | {_cell(who)} | {_cell(by)} |"
        )
    lines += ["", rule_text(), ""]
    return lines


@dataclass(frozen=True)
class SeriesSummary:
    """A series over time, summarised as the report states it.

    Attributes:
        max_abs: the largest magnitude ``max_t |x(t)|`` (for a signed rod force its largest
            ``|F_i|``; the series of vectors are already norms); ``inf`` with a non-finite sample.
        t_max_abs: the time of ``max_abs``, s.
        rms: root mean square over the samples.
        final: the last value (signed).
    """

    max_abs: float
    t_max_abs: float
    rms: float
    final: float

    @classmethod
    def of(cls, s: Series) -> SeriesSummary:
        v = np.asarray(s.values, float)
        peak, i = max_abs(v)
        if i < 0:
            return cls(math.nan, math.nan, math.nan, math.nan)
        rms = float(np.sqrt(np.mean(v * v))) if np.all(np.isfinite(v)) else math.inf
        return cls(peak, float(s.t[i]), rms, float(v[-1]))

    def to_dict(self) -> dict[str, float]:
        return {
            "max_abs": self.max_abs,
            "t_max_abs": self.t_max_abs,
            "rms": self.rms,
            "final": self.final,
        }


def summaries(cmp: Comparison | None) -> dict[str, dict[str, Any]]:
    """Series key -> label, unit and :class:`SeriesSummary` fields (report.json's ``summaries``)."""
    if cmp is None:
        return {}
    return {
        s.key: {"label": s.label, "unit": s.unit, **SeriesSummary.of(s).to_dict()}
        for s in cmp.series
    }


@dataclass(frozen=True)
class FigureEntry:
    """A figure as the report lists it: its name, caption, and the files written (none when it
    was not drawn; the caption then says why)."""

    name: str
    caption: str
    files: tuple[str, ...] = ()


def _figure_lines(figures: Sequence[FigureEntry]) -> list[str]:
    """The Figures section: each drawn figure embedded (PNG if written, else its first file) with
    its numbered caption below; each figure not drawn named with its reason."""
    if not figures:
        return []
    lines = ["## Figures", ""]
    number = 0
    for f in figures:
        if not f.files:
            lines += [
                f"*No {_md(f.name)} figure.* {_md(f.caption)}",
                "",
            ]
            continue
        number += 1
        shown = next((x for x in f.files if x.endswith(f".{FigureFormat.PNG.value}")), f.files[0])
        also = [x for x in f.files if x != shown]
        lines += [
            f"![Figure {number}: {f.name}]({shown})",
            "",
            f"*Figure {number} (`{shown}`).* {_md(f.caption)}"
            + (f" Also as {', '.join(f'[{x}]({x})' for x in also)}." if also else ""),
            "",
        ]
    return lines


def render_markdown(
    cmp: Comparison | None,
    verdict: RunVerdict | str,
    failure: str,
    figures: Sequence[FigureEntry],
    meta: Mapping[str, Any],
    verdicts: Sequence[Verdict] = (),
    code: str = "",
) -> str:
    """The text of ``report.md``: the verdict first, then the referee, checks, summaries,
    figures with their captions, thresholds and the run's metadata (after ``code``, the sentence
    naming the code that ran, :meth:`validation.report.provenance.CodeOrigin.sentence`)."""
    scene = meta.get("scene", {}).get("name", cmp.scene if cmp else "?")
    verdict = RunVerdict(getattr(verdict, "value", verdict))
    lines = [f"# {_md(scene)}: {verdict.value}", ""]
    if failure:
        lines += [f"**The run {_stopped(verdict)}:** {_md(failure)}", ""]
    for again in meta.get("redone", ()):
        lines += [f"**Redone:** {_md(again)}", ""]
    if cmp is not None:
        bad = cmp.failed_checks
        total = len(cmp.applicable_checks)
        idle: dict[str, list[str]] = {}  # why -> the checks that do not apply for that reason
        for c in cmp.checks:
            if not c.applicable:
                idle.setdefault(c.reason, []).append(c.label)
        also = (
            " Not applicable: "
            + "; ".join(f"{', '.join(map(_md, who))} ({_md(why)})" for why, who in idle.items())
            + "."
            if idle
            else ""
        )
        lines.append(
            f"{total - len(bad)} of {total} checks pass." + also + (" Failed:" if bad else "")
        )
        for c in bad:
            lines.append(f"- {_cell(check_sentence(c))}")
        lines.append("")
        for n in cmp.notes:
            lines.append(f"> {_md(n)}")
        if cmp.notes:
            lines.append("")
        lines += _referee_lines(verdicts, meta)
        lines += [
            "## Checks",
            "",
            "| check | value | threshold | threshold set by | unit | verdict | at t (s) |",
            "|---|---|---|---|---|---|---|",
        ]
        for c in cmp.checks:
            lines.append(
                f"| {_cell(c.label)} | {_fmt(c.value)} | {_fmt(c.threshold)} | {_bound_cell(c)} | "
                f"{_cell(c.unit)} | {_state_cell(c)} | {_fmt(c.t_max)} |"
            )
        lines += [
            "",
            "Relative checks are divided by the scale of the signal (see report.json). The "
            "states' and tracking laws' thresholds are the absolute part plus rtol × the "
            "quantity's largest magnitude over the run across the compared plants; *threshold set "
            "by* names the larger part (empty without a relative part). A "
            "`completed` check's value is the time the plant reached, its threshold the horizon.",
            "",
        ]
        lines += [
            "## Summaries over time",
            "",
            "| quantity | of | max \\|x\\| | t of max \\|x\\| (s) | RMS | final | unit |",
            "|---|---|---|---|---|---|---|",
        ]
        for s in cmp.series:
            m = SeriesSummary.of(s)
            lines.append(
                f"| {_cell(s.label)} | {s.subject.value} | {_fmt(m.max_abs)} | "
                f"{_fmt(m.t_max_abs)} | {_fmt(m.rms)} | {_fmt(m.final)} | {_cell(s.unit)} |"
            )
        lines += [
            "",
            "max |x| is the largest magnitude over time: of a signed quantity (a rod force) its "
            "largest absolute value; the vector quantities (|R_a − R_m|, |τ|, ...) are Euclidean "
            "norms ‖·‖₂, so max |τ| is max ‖τ‖₂. final is the last value, with its sign.",
            "",
        ]
    lines += _figure_lines(figures)
    lines += ["## Thresholds", ""]
    if cmp is not None:
        lines += ["| name | value | unit | source | reason |", "|---|---|---|---|---|"]
        for th in cmp.thresholds.values():
            kind = " (relative)" if th.relative else ""
            if th.rtol:
                kind = f" + {th.rtol:g} × scale"
            lines.append(
                f"| {_cell(th.name)} | {th.value:g}{kind} | {_cell(th.unit)} | {_cell(th.source)} | "
                f"{_cell(th.reason)} |"
            )
        lines.append("")
    lines += ["## Run", ""]
    if code:
        lines += [_md(code), ""]
    lines += ["```json", _fenced_json(meta), "```", ""]
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
    """Paths written by :func:`write_report` (figures only those that were drawn, in every format
    asked for), every figure's entry (captions, including the figures not drawn), and the
    verdict and failure the report states (a figure not drawn included)."""

    markdown: Path
    json: Path
    figures: tuple[Path, ...]
    entries: tuple[FigureEntry, ...] = ()
    verdict: RunVerdict = RunVerdict.FAILED
    failure: str = ""


def draw_figures(
    out: Path,
    cmp: Comparison | None,
    plants: Sequence[Trajectory],
    ctx: FigureContext,
    formats: Sequence[FigureFormat],
    names: Sequence[str] = FIGURES,
) -> tuple[list[Path], list[FigureEntry], list[str]]:
    """Draw every figure and write each drawn one in every format into ``out``; a figure that
    fails to draw is named in the returned errors (the report is still written, the run FAILED).
    A file that cannot be written, or a drawing stopped by the filesystem (``ENOSPC``, ``EIO``
    ... while matplotlib renders), raises :class:`validation.runs.atomic.OutputError`: a figure
    missing for want of disk is not a verdict.

    ``names``: which of :data:`validation.report.figures.FIGURES` to draw (all by default; workers
    share them). Returns the files written, every figure's entry (with its caption) and the
    errors."""
    makers = {
        "errors": (lambda: figure_errors(cmp, ctx)) if cmp else None,
        "tracking": (lambda: figure_tracking(cmp, ctx)) if cmp else None,
        "invariants": (lambda: figure_invariants(cmp, ctx)) if cmp else None,
        "control": lambda: figure_control(plants, ctx, cmp.thresholds if cmp else None),
    }
    paths: list[Path] = []
    entries: list[FigureEntry] = []
    errors: list[str] = []
    for name in FIGURES:
        if name not in names:
            continue
        make = makers[name]
        if make is None:
            continue
        try:
            drawing: Drawing = make()
            blobs = {f: drawing.render(f) for f in formats} if drawing.drawn else {}
        except OSError as exc:
            if not is_write_failure(exc):
                errors.append(f"{name}: {type(exc).__name__}: {exc}".splitlines()[0])
                continue
            raise OutputError(out / f"{name}.{formats[0].value}", exc) from exc
        except Exception as exc:  # a drawing bug: said in the report, the run FAILED
            errors.append(f"{name}: {type(exc).__name__}: {exc}".splitlines()[0])
            continue
        written = [write_atomic(out / f"{name}.{f.value}", b) for f, b in blobs.items()]
        paths += written
        entries.append(FigureEntry(name, drawing.caption, tuple(p.name for p in written)))
    return paths, entries, errors


def write_report(
    out_dir: str | Path,
    cmp: Comparison | None,
    plants: Sequence[Trajectory],
    meta: Mapping[str, Any],
    failure: str = "",
    verdicts: Sequence[Verdict] = (),
    formats: Sequence[FigureFormat | str] = DEFAULT_FORMATS,
    scene: Any = None,
    figures: tuple[Sequence[Path], Sequence[FigureEntry], Sequence[str]] | None = None,
    interrupted: bool = False,
) -> ReportFiles:
    """Write ``report.md``, ``report.json`` and the figures into ``out_dir`` (atomically).

    Args:
        out_dir: output directory (created).
        cmp: the comparison, or None when the run failed before one could be made.
        plants: the trajectories that exist (analytic first).
        meta: run metadata (scene, versions, solver settings, wall times ...), JSON-able.
        failure: why the run failed ("" when it did not); a failure makes the verdict FAILED.
        verdicts: the referee's rulings (three plants).
        formats: the figures' file formats (:class:`validation.report.figures.FigureFormat`), PNG by
            default; ValueError naming ``figure_format`` for an unknown one.
        scene: the resolved scene, dumped whole into ``report.json``'s provenance block
            (:mod:`validation.report.provenance`; None when the run has none).
        figures: what :func:`draw_figures` returned for this run when it was drawn already (in
            a worker, :mod:`validation.validate`); None draws them here. A figure that could
            not be drawn makes the run FAILED (its error joins ``failure``).
        interrupted: a signal stopped the run: the verdict is INTERRUPTED (``failure`` says
            where it stopped).

    Raises:
        OutputError: a file could not be written (a full disk ...): no verdict is given.
    """
    fmts = tuple(dict.fromkeys(_format(f) for f in formats))
    if not fmts:
        raise ValueError("figure_format: at least one format is needed (got none)")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ctx = FigureContext.from_meta(meta, cmp.scene if cmp is not None else "")
    if figures is None:
        figures = draw_figures(out, cmp, plants, ctx, fmts)
    figs, entries, fig_errors = (list(x) for x in figures)
    meta = dict(meta)
    if fig_errors:
        meta["figure_errors"] = fig_errors
        failure = "; ".join([*([failure] if failure else []), *(f"figure {e}" for e in fig_errors)])
    verdict = RunVerdict.of(cmp, failure, interrupted)
    doc = _report_doc(cmp, plants, meta, failure, verdicts, entries, verdict)
    origin = code_origin()
    block = provenance(FileKind.REPORT, scene, origin=origin)
    js = write_atomic(out / "report.json", dumps({"provenance": block, **doc}))
    md = write_atomic(
        out / "report.md",
        render_markdown(cmp, verdict, failure, entries, meta, verdicts, origin.sentence()),
    )
    return ReportFiles(md, js, tuple(figs), tuple(entries), verdict, failure)


def _format(f: FigureFormat | str) -> FigureFormat:
    try:
        return FigureFormat(str(getattr(f, "value", f)).strip().lower())
    except ValueError:
        known = ", ".join(x.value for x in FigureFormat)
        raise ValueError(f"figure_format: unknown format {f!r} (known: {known})") from None


def _report_doc(
    cmp: Comparison | None,
    plants: Sequence[Trajectory],
    meta: Mapping[str, Any],
    failure: str,
    verdicts: Sequence[Verdict],
    figures: Sequence[FigureEntry],
    verdict: RunVerdict,
) -> dict[str, Any]:
    """The content of ``report.json`` (every field is built here, in one place)."""
    passed = verdict is RunVerdict.PASSED
    comparison = cmp.to_dict() if cmp is not None else {"checks": [], "notes": []}
    comparison["summaries"] = summaries(cmp)  # largest magnitudes (max_abs), not signed maxima
    return {
        "verdict": verdict.value,
        **comparison,
        "passed": passed,  # cmp.to_dict() has its own; the failure overrides
        "failure": failure,
        "thresholds": {
            k: {
                "value": t.value,
                "unit": t.unit,
                "relative": t.relative,
                "floor": t.floor,
                "rtol": t.rtol,
                "source": t.source,
                "reason": t.reason,
            }
            for k, t in (cmp.thresholds.items() if cmp is not None else ())
        },
        "plants": [
            {
                "engine": p.engine,
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
        "figures": [name for f in figures for name in f.files],
        "captions": {f.name: f.caption for f in figures},
        "run": meta,
    }


__all__ = [
    "FIGURES",
    "FigureEntry",
    "ReportFiles",
    "RunVerdict",
    "SeriesSummary",
    "figure_control",
    "figure_errors",
    "figure_invariants",
    "figure_tracking",
    "is_write_failure",
    "render_markdown",
    "summaries",
    "versions",
    "write_atomic",
    "write_report",
]
