"""``sweep.rrd``: the work-precision plot as a 2D view of the recording, the figure, the text.

Rerun has no log axes and no x-y plot view besides the 2D spatial one, so the plot is drawn in
log coordinates in a ``Spatial2DView``: x = :data:`X_PER_DECADE` x log10(wall time per simulated second), y =
-log10(error) (the number of correct digits: the 2D view's y axis points down, so accuracy grows
downwards as in the PNG). Decade grid lines carry their values as labels. Entities, all static::

    /work_precision/axes                     decade grid and its labels
    /work_precision/floor                    the reference's floor
    /work_precision/{engine}/{method}        the series' line, its points (labelled with the
                                             setting) and timing bars (min to max)
    /work_precision/marks/{engine}/{method}  runs that are not ok, labelled
    /figure                                  work_precision.png
    /report                                  sweep.md without the link to the PNG file

The blueprint shows the plot (tabbed with the PNG) beside the text; there is no timeline.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from validation.recording.style import viewer_text
from validation.studies.sweep.config import Outcome
from validation.studies.sweep.figure import FigureData
from validation.studies.sweep.markdown import VIEW_NAME

X_PER_DECADE = 3.0
"""Width of a decade of wall time in the 2D view, in units of a decade of error (the view keeps
x and y at the same scale; wall times span a few decades, errors ten)."""

PALETTE = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
           (140, 86, 75), (227, 119, 194), (127, 127, 127))  # fmt: skip
"""matplotlib's tab10, so a method has the same colour in the PNG and the recording."""


def _xy(wall: float, error: float) -> tuple[float, float]:
    return X_PER_DECADE * math.log10(wall), -math.log10(error)


def _bounds(data: FigureData) -> tuple[tuple[float, float], tuple[float, float]]:
    """Decade-aligned ranges of log10 wall and log10 error covering every point and mark."""
    walls = [p.wall for ln in data.lines for p in ln.points] + [
        m.wall for m in data.marks if m.wall
    ]
    errs = [p.error for ln in data.lines for p in ln.points] + [
        m.error for m in data.marks if m.error
    ]
    if data.floor > 0:
        errs.append(data.floor)
    if not walls or not errs:
        return (-3.0, 1.0), (-12.0, 0.0)
    lw = (math.floor(math.log10(min(walls))), math.ceil(math.log10(max(walls))))
    le = (math.floor(math.log10(min(errs))), math.ceil(math.log10(max(errs))) + 1)
    return lw, le


def write_rrd(
    path: str | Path, data: FigureData, png: bytes, text: str, recording_id: str | None = None
) -> None:
    """Write ``sweep.rrd`` atomically (:func:`validation.recording.recording.atomic_stream`), with its
    blueprint."""
    # deferred: rerun ~0.25 s (python -X importtime), only when the recording is written
    from validation.runs.environment import import_rerun

    import_rerun()  # first: NO_COLOR for rerun's first import only
    import rerun as rr
    import rerun.blueprint as rrb

    from validation.recording.recording import AppId, atomic_stream

    (w0, w1), (e0, e1) = _bounds(data)
    x_range = (X_PER_DECADE * w0 - 0.5, X_PER_DECADE * w1 + 4.0)  # room for the labels
    y_range = (-e1 - 0.5, -e0 + 0.5)
    blueprint = rrb.Blueprint(
        rrb.Horizontal(
            rrb.Tabs(
                rrb.Spatial2DView(
                    origin="/work_precision",
                    name=viewer_text(VIEW_NAME),
                    visual_bounds=rrb.VisualBounds2D(x_range=x_range, y_range=y_range),
                ),
                rrb.Spatial2DView(origin="/figure", name="work_precision.png"),
            ),
            rrb.TextDocumentView(origin="/report", name="sweep.md"),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(state="collapsed"),
        collapse_panels=False,
    )
    methods = list(dict.fromkeys([ln.method for ln in data.lines] + [m.method for m in data.marks]))
    colour = {m: PALETTE[i % len(PALETTE)] for i, m in enumerate(methods)}
    with atomic_stream(path, AppId.SWEEP, blueprint=blueprint, recording_id=recording_id) as rec:
        grid, labels, label_pos = [], [], []
        for d in range(w0, w1 + 1):
            x = X_PER_DECADE * d
            grid.append([[x, -e1], [x, -e0]])
            labels.append(f"{10.0**d:g} s")
            label_pos.append([x, -e0 + 0.3])
        for d in range(e0, e1 + 1):
            grid.append([[X_PER_DECADE * w0, -d], [X_PER_DECADE * w1, -d]])
            labels.append(f"error 1e{d}")
            label_pos.append([X_PER_DECADE * w0 - 0.2, -d])
        rec.log(
            "work_precision/axes",
            rr.LineStrips2D(grid, colors=[(90, 90, 90)], radii=0.01),
            rr.Points2D(
                label_pos,
                labels=[viewer_text(x) for x in labels],
                radii=0.001,
                colors=[(160, 160, 160)],
            ),
            static=True,
        )
        if data.floor > 0:
            y = -math.log10(data.floor)
            rec.log(
                "work_precision/floor",
                rr.LineStrips2D(
                    [[[X_PER_DECADE * w0, y], [X_PER_DECADE * w1, y]]],
                    colors=[(128, 128, 128)],
                    radii=0.02,
                    labels=["reference floor"],
                ),
                static=True,
            )
        for ln in data.lines:
            xy = np.array([_xy(p.wall, p.error) for p in ln.points])
            bars = [
                [
                    [X_PER_DECADE * math.log10(p.wall_min), y],
                    [X_PER_DECADE * math.log10(p.wall_max), y],
                ]
                for p, (_, y) in zip(ln.points, xy, strict=True)
            ]
            c = colour[ln.method]
            rec.log(
                f"work_precision/{ln.engine}/{ln.method}",
                rr.LineStrips2D(
                    [xy], colors=[c], radii=0.03, labels=[viewer_text(f"{ln.engine} {ln.method}")]
                ),
                static=True,
            )
            rec.log(
                f"work_precision/{ln.engine}/{ln.method}/points",
                rr.Points2D(
                    xy,
                    radii=0.08,
                    colors=[c],
                    labels=[
                        viewer_text(
                            f"{ln.engine} {ln.method} #{p.run_id}: error {p.error:.2g}, "
                            f"{p.wall * 1e3:.3g} ms per simulated s (n = {p.n})"
                        )
                        for p in ln.points
                    ],
                    show_labels=False,
                ),
                static=True,
            )
            rec.log(
                f"work_precision/{ln.engine}/{ln.method}/timing_spread",
                rr.LineStrips2D(bars, colors=[c], radii=0.02),
                static=True,
            )
        by_series: dict[tuple[str, str], list] = {}
        for m in data.marks:
            by_series.setdefault((m.engine, m.method), []).append(m)
        for (engine, method), marks in by_series.items():
            pos = []
            for m in marks:
                x = X_PER_DECADE * (math.log10(m.wall) if m.wall else w0)
                y = -math.log10(m.error) if m.error else -e1
                pos.append([x, y])
            symbol = {Outcome.TOO_SLOW: "▷"}  # else ×: both in the viewer's fonts
            rec.log(
                f"work_precision/marks/{engine}/{method}",
                rr.Points2D(
                    pos,
                    radii=0.15,
                    colors=[colour[method]],
                    labels=[viewer_text(f"{symbol.get(m.outcome, '×')} {m.label}") for m in marks],
                ),
                static=True,
            )
        rec.log("figure", rr.EncodedImage(contents=png, media_type="image/png"), static=True)
        doc = rr.TextDocument(viewer_text(text, newlines=True), media_type=rr.MediaType.MARKDOWN)
        rec.log("report", doc, static=True)


__all__ = ["X_PER_DECADE", "write_rrd"]
