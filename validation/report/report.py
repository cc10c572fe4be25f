"""Reports of a validation run: ``report.md`` and ``report.html`` for people, ``report.json`` for
machines, figures.

:func:`write_report` writes them all. Every file is written atomically (a temporary file in the same
directory, then :func:`os.replace`), so an interrupted run never leaves a half-written report. A
failed run still writes what it has; its verdict is ``FAILED`` and the reason is stated first; a run
a signal stopped is ``INTERRUPTED``, said the same way (:class:`RunVerdict`). A file that cannot be
written (a full disk) is an :class:`validation.runs.atomic.OutputError`, never a verdict.

What each file says is built elsewhere, one job each: ``report.md``'s sections in
:mod:`validation.report.markdown`, ``report.html`` from the same records in
:mod:`validation.report.html_report`, ``report.json``'s fields in :mod:`validation.report.document`,
the figures in :mod:`validation.report.figures` (drawn by :func:`draw_figures`, in each format asked
for: PNG by default; SVG or PDF for papers; a figure that was not drawn, as an uncontrolled scene's
control figure, is named in ``report.md`` with the reason).
"""

from __future__ import annotations

import errno
import platform
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison
from validation.compare.referee import Verdict
from validation.report.document import report_document
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
from validation.report.html_report import HTML_NAME, figure_images, render_html
from validation.report.markdown import Page, render_markdown
from validation.report.md_text import md_literal as _md  # noqa: F401  # escaping's name in the fault tests
from validation.report.provenance import FileKind, code_origin, dumps, provenance
from validation.report.records import FigureEntry, RunVerdict
from validation.runs.atomic import OutputError, write_bytes

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


def versions() -> dict[str, str | None]:
    """Versions of Python, the platform and the packages that produce the numbers."""
    out = {"python": sys.version.split()[0], "platform": platform.platform()}
    for pkg in ("tumbling-testbed", "numpy", "scipy", "mujoco", "rerun-sdk", "matplotlib"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None  # not installed
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
    html: Path | None = None


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
    recording: str | None = None,
) -> ReportFiles:
    """Write ``report.md``, ``report.html``, ``report.json`` and the figures into ``out_dir``
    (atomically).

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
        recording: the recording's file name beside the report (``run.rrd``), linked from
            ``report.html``; None when the run wrote none.

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
    doc = report_document(cmp, plants, meta, failure, verdicts, entries, verdict)
    origin = code_origin()
    block = provenance(FileKind.REPORT, scene, origin=origin)
    js = write_atomic(out / "report.json", dumps({"provenance": block, **doc}))
    md = write_atomic(
        out / "report.md",
        render_markdown(cmp, verdict, failure, entries, meta, verdicts, origin.sentence()),
    )
    page = Page(cmp, verdict, failure, entries, meta, verdicts, origin.sentence())
    html = write_atomic(out / HTML_NAME, render_html(page, figure_images(out, entries), recording))
    return ReportFiles(md, js, tuple(figs), tuple(entries), verdict, failure, html)


def _format(f: FigureFormat | str) -> FigureFormat:
    try:
        return FigureFormat(str(getattr(f, "value", f)).strip().lower())
    except ValueError:
        known = ", ".join(x.value for x in FigureFormat)
        raise ValueError(f"figure_format: unknown format {f!r} (known: {known})") from None


__all__ = [
    "FIGURES",
    "FigureEntry",
    "ReportFiles",
    "RunVerdict",
    "draw_figures",
    "figure_control",
    "figure_errors",
    "figure_invariants",
    "figure_tracking",
    "is_write_failure",
    "render_markdown",
    "versions",
    "write_atomic",
    "write_report",
]
