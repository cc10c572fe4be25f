"""A validation's evidence step: the recording (``run.rrd``) and the figures, made by two helpers
of the job's :class:`~validation.runs.stages.StagePool` (worker processes that import rerun and
matplotlib while the plants run, or this process), and what they made as the report's files.

:data:`EVIDENCE_HELPERS` are the helpers the job's pool starts; :func:`make_evidence` gives them
their inputs and collects an :class:`Evidence`. A recording or a figure that could not be made is
an error the report states (the run FAILED); a file that could not be written raises
:class:`~validation.runs.atomic.OutputError` (no verdict); a helper whose worker was lost is redone
here (:class:`Evidence` ``redone`` says so).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.scene import Scene
from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison
from validation.report.figures import (
    FIGURES,
    FigureContext,
    FigureFormat,
    prepare_drawing,
)
from validation.report.report import FigureEntry, draw_figures, is_write_failure
from validation.runs.atomic import OutputError
from validation.runs.stages import Helper, StagePool
from validation.validate.request import one_line

RECORDING = "run.rrd"

EVIDENCE_SHARES: tuple[tuple[str, ...], ...] = (
    (RECORDING, "errors"),
    ("tracking", "invariants", "control"),
)
"""How the recording and the figures (:data:`validation.report.figures.FIGURES`) are shared between
the two evidence helpers, balanced by their measured costs (``docs/performance.md``)."""


def _recording_task(
    path: Path, sc: Scene, plants, cmp, run_id: str, *, report
) -> tuple[Any, float]:
    # deferred: rerun and scipy.spatial, ~0.25 s (python -X importtime), in the worker
    from validation.recording.recording import write_recording

    t0 = time.perf_counter()
    info = write_recording(path, sc, plants, cmp, recording_id=run_id)
    return info, time.perf_counter() - t0


def evidence_task(share: Sequence[str], rec_args, fig_args, *, report) -> dict[str, Any]:
    """The recording (when ``share`` names it and there are trajectories) and the figures named
    in ``share``: ``{"recording": (info, wall), "figures": ((paths, entries, errors), wall)}``."""
    done: dict[str, Any] = {}
    if RECORDING in share and rec_args is not None:
        try:
            done["recording"] = _recording_task(*rec_args, report=report)
        except Exception as exc:  # a bug: said in the report (FAILED); the figures are still drawn
            if is_write_failure(exc):
                raise _as_output_error(exc, rec_args[0]) from exc
            done["recording_error"] = one_line(exc)
    names = [n for n in share if n != RECORDING]
    if names:
        t0 = time.perf_counter()
        drawn = draw_figures(*fig_args, names=names)
        done["figures"] = (drawn, time.perf_counter() - t0)
    return done


def _as_output_error(exc: BaseException, path: Path) -> OutputError:
    """``exc`` (a filesystem's refusal to write, :func:`validation.report.report.is_write_failure`) as
    the :class:`OutputError` it means: the run's set cannot be completed."""
    return exc if isinstance(exc, OutputError) else OutputError(path, exc)


def _import_rerun() -> None:
    from validation.runs.environment import import_rerun

    import_rerun()  # first: NO_COLOR for rerun's first import only
    import rerun.blueprint  # noqa: F401

    import validation.recording.recording  # noqa: F401  (scipy.spatial)


def _prepare_rerun_and_figures() -> None:
    _import_rerun()
    _prepare_figures()


def _prepare_figures() -> None:
    """matplotlib imported and one throw-away figure drawn (:func:`validation.report.figures.prepare_drawing`):
    the fonts and caches the first figure needs are loaded (in an evidence worker, before it is
    given its inputs)."""
    try:
        prepare_drawing()
    except Exception:  # an optimisation only: the figures, drawn later, report their own errors
        pass


def prepare_comparison() -> None:
    """What the comparison needs imported here, while the evidence helpers start (scipy.linalg:
    its exponentials)."""
    import scipy.linalg  # noqa: F401


EVIDENCE_HELPERS: tuple[Helper, ...] = tuple(
    Helper(
        f"evidence {k + 1}",
        evidence_task,
        _prepare_rerun_and_figures if RECORDING in share else _prepare_figures,
    )
    for k, share in enumerate(EVIDENCE_SHARES)
)
"""The job's evidence helpers, one per share of :data:`EVIDENCE_SHARES`."""


@dataclass(frozen=True)
class Evidence:
    """What the evidence helpers made.

    Attributes:
        figures: ``(paths, entries, errors)`` of the figures drawn, as
            :func:`validation.report.report.write_report` takes them.
        files: name -> path of the recording, when it was written.
        failures: one line for each piece of evidence that could not be made.
        redone: one line for each helper redone here (its worker was lost).
    """

    figures: tuple[list, list, list] = field(default_factory=lambda: ([], [], []))
    files: Mapping[str, Path] = field(default_factory=dict)
    failures: tuple[str, ...] = ()
    redone: tuple[str, ...] = ()


def make_evidence(
    pool: StagePool,
    out: Path,
    run_id: str,
    sc: Scene,
    trajectories: Sequence[Trajectory],
    cmp: Comparison | None,
    meta: dict[str, Any],
    formats: Sequence[FigureFormat],
    walls: dict[str, float],
) -> Evidence:
    """The recording and the figures of a run into the staging directory ``out``, by ``pool``'s
    evidence helpers (module docstring); their wall times go into ``walls``."""
    ctx = FigureContext.from_meta(meta, cmp.scene if cmp is not None else "")
    rec_args = (out / RECORDING, sc, trajectories, cmp, run_id) if trajectories else None
    fig_args = (out, cmp, trajectories, ctx, formats)
    inputs = [(share, rec_args, fig_args) for share in EVIDENCE_SHARES]
    # The helper without a recording first: the other may still be importing rerun.
    order = sorted(range(len(EVIDENCE_SHARES)), key=lambda k: RECORDING in EVIDENCE_SHARES[k])
    got = pool.run_helpers(inputs, order)
    files: dict[str, Path] = {}
    paths: list[Path] = []
    entries: dict[str, FigureEntry] = {}
    fig_errors: list[str] = []
    failures: list[str] = []
    walls["figures"] = 0.0
    for share, done in zip(EVIDENCE_SHARES, got.results, strict=True):
        if isinstance(done, Exception):  # a bug: said in the report, the run FAILED
            fig_errors.append(f"{', '.join(share)}: {one_line(done)}")
            continue
        if "recording" in done:
            rinfo, walls["recording"] = done["recording"]
            files[RECORDING] = rinfo.path
        if "recording_error" in done:
            failures.append(f"recording: {done['recording_error']}")
        if "figures" in done:
            (got_paths, got_entries, got_errors), wall = done["figures"]
            paths += got_paths
            entries.update({e.name: e for e in got_entries})
            fig_errors += got_errors
            walls["figures"] += wall
    if trajectories and RECORDING not in files and not failures:
        failures.append("recording: not written")
    ordered = [entries[n] for n in FIGURES if n in entries]
    return Evidence((paths, ordered, fig_errors), files, tuple(failures), got.redone)


__all__ = ["EVIDENCE_HELPERS", "EVIDENCE_SHARES", "RECORDING", "Evidence", "make_evidence"]
