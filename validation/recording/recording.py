"""Rerun recordings (``run.rrd``, the demo's ``demo.rrd``) of finished trajectories.

Everything is logged in columns (``send_columns``) from the finished trajectories through an
explicit :class:`rerun.RecordingStream` encoded in memory, on one timeline ``sim_time`` (s),
without the wall-clock timeline, so one process can write several files and a file depends only
on the trajectories; the file is written by :mod:`validation.runs.atomic` after it reads back whole.

The parts, one module each:

* :mod:`validation.recording.stream`: the in-memory streams, :func:`check_rrd`, :func:`atomic_stream`;
* :mod:`validation.recording.world`: the 3D views' entities (every plant's body, arrows and path of C;
  each other plant's difference from the reference, exaggerated by a stated power of ten), Z up;
* :mod:`validation.recording.plots`: the time series (one plot per unit; errors as log10, exact zeros
  left out; thresholds), and the list of plots the blueprint shows;
* :mod:`validation.recording.layout`: the blueprint and the narrative (what each view shows, with the
  arrow scales and the exaggeration factors);
* :mod:`validation.recording.style`: the timeline, one colour per plant, entity-path slugs.

Entity layout for a run logged under ``prefix`` (``""`` for ``run.rrd``, ``stepN`` in the demo):
``{prefix}/world/…`` and ``{prefix}/difference/…`` (:mod:`validation.recording.world`),
``{prefix}/plots/…`` (:mod:`validation.recording.plots`), ``{prefix}/narrative`` (markdown, static).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison
from validation.recording.layout import (
    Legend,
    blueprint_for,
    default_narrative,
    legend_for,
    legend_markdown,
    narrative_for,
    with_legend,
)
from validation.recording.plots import log_plots
from validation.recording.stream import (
    RRD_FLUSH_TIMEOUT_S,
    AppId,
    atomic_stream,
    binary_stream,
    check_rrd,
    new_stream,
    rrd_bytes,
)
from validation.recording.style import PLANT_COLOR, TIMELINE, entity_root, viewer_text
from validation.recording.world import ArrowScales, arrow_scales, log_world


@dataclass(frozen=True)
class RecordingInfo:
    """What :func:`write_recording` wrote: ``path``, its time-series ``entities``, the number of
    ``samples`` of the longest plant, the ``wall_time_s`` it took and the :class:`Legend` (arrow
    scales, difference factors) its narrative states."""

    path: Path
    entities: tuple[str, ...]
    samples: int
    wall_time_s: float
    legend: Legend | None = None


def log_run(
    rec,
    scene: Any,
    plants: Sequence[Trajectory],
    comparison: Comparison | None = None,
    narrative: str = "",
    prefix: str = "",
) -> tuple[list[str], Legend]:
    """Log one run (one plant or several) into ``rec`` under ``prefix``.

    The first plant is the reference, drawn solid; the others are drawn over it in their own
    colours, and each in a view of its own with its difference from the reference exaggerated.
    ``narrative`` (markdown; default :func:`default_narrative`) is logged followed by
    :func:`legend_markdown`, which states the arrow scales and the exaggeration factors, spelled
    in the viewer's characters (:func:`validation.recording.style.viewer_text`).

    Returns:
        the entity paths that received time series (plus the narrative's), and the run's
        :class:`Legend` (``legend.arrows`` are the arrow scales; ``legend_markdown(legend)`` the
        text appended to the narrative).
    """
    # deferred: rerun ~0.25 s (python -X importtime), only when a recording is made
    import rerun as rr

    p0 = entity_root(prefix)
    legend = legend_for(scene, plants, comparison)
    entities = log_world(rec, p0, scene, plants, legend.arrows, legend.factors)
    entities += log_plots(rec, prefix, plants, comparison)
    text = (
        with_legend(narrative, legend)
        if narrative
        else default_narrative(scene, plants, comparison, legend=legend)
    )
    doc = rr.TextDocument(viewer_text(text, newlines=True), media_type=rr.MediaType.MARKDOWN)
    rec.log(f"{p0}/narrative", doc, static=True)
    entities.append(f"{p0}/narrative")
    return entities, legend


def write_recording(
    path: str | Path,
    scene: Any,
    plants: Sequence[Trajectory],
    comparison: Comparison | None = None,
    narrative: str = "",
    recording_id: str | None = None,
) -> RecordingInfo:
    """Write ``run.rrd`` for one run (blueprint included); atomically, checked (:func:`atomic_stream`).

    ``recording_id``: Rerun's recording id (the run id of the output directory, when there is one).
    """
    from validation.runs.environment import import_rerun

    import_rerun()  # first: NO_COLOR for rerun's first import only
    import rerun.blueprint as rrb

    path = Path(path)
    t0 = time.perf_counter()
    legend = legend_for(scene, plants, comparison)
    bp = rrb.Blueprint(
        blueprint_for(
            "",
            scene,
            comparison,
            len(legend.plants) > 1,
            plants=legend.plants,
            factors=legend.factors,
        ),
        rrb.TimePanel(state="expanded"),
        collapse_panels=False,
    )
    with atomic_stream(path, AppId.VALIDATE, blueprint=bp, recording_id=recording_id) as rec:
        entities, legend = log_run(rec, scene, plants, comparison, narrative)
    samples = max((p.t.shape[0] for p in plants), default=0)
    return RecordingInfo(
        path, tuple(dict.fromkeys(entities)), samples, time.perf_counter() - t0, legend
    )


__all__ = [
    "PLANT_COLOR",
    "RRD_FLUSH_TIMEOUT_S",
    "TIMELINE",
    "AppId",
    "ArrowScales",
    "Legend",
    "RecordingInfo",
    "arrow_scales",
    "atomic_stream",
    "binary_stream",
    "blueprint_for",
    "check_rrd",
    "default_narrative",
    "legend_for",
    "legend_markdown",
    "log_run",
    "narrative_for",
    "new_stream",
    "rrd_bytes",
    "with_legend",
    "write_recording",
]
