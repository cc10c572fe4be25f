"""The figures of a validation run, each with its caption (matplotlib, Agg, no pyplot state).

:data:`FIGURES` names them in the report's order, each drawn by its own module:

* ``errors`` (:mod:`.errors`): the differences between each pair of plants over time, as checked,
  with the thresholds;
* ``tracking`` (:mod:`.tracking`): each plant's tracking errors and their deviations from the
  closed-form error dynamics (Eqs. 84 and 78);
* ``invariants`` (:mod:`.invariants`): each plant's quaternion norm error and its balances, as
  checked;
* ``control`` (:mod:`.control`): the reference plant's control torque and rod forces, and every
  other plant's relative distance from them.

A panel whose every curve is identically zero is left out (a log axis has no place for zero) and
the caption says which and why; a figure with nothing to show is not drawn, and its caption says
why (an uncontrolled scene has no control and no tracking figure). Curves that coincide are told
apart by their markers, staggered along the time axis (:mod:`.panels`). Legends stand outside the
data. The layout is fixed, in inches, from the figure's size (:mod:`.layout`); the colours, line
styles and panel titles are :mod:`.style`'s, the captions' shared sentences :mod:`.captions`'.
Every drawing renders to PNG, SVG or PDF (:class:`FigureFormat`, :mod:`.drawing`) without a time
stamp in the file.

A new figure is a module here with its ``figure_<name>`` function returning a :class:`Drawing`, its
name in :data:`FIGURES`, and its maker in :func:`validation.report.report.draw_figures`.
"""

from validation.report.figures.captions import FigureContext
from validation.report.figures.control import figure_control
from validation.report.figures.drawing import (
    DEFAULT_FORMATS,
    PNG_DPI,
    TEXT_RASTER,
    Drawing,
    FigureFormat,
    parse_formats,
)
from validation.report.figures.errors import figure_errors
from validation.report.figures.invariants import figure_invariants
from validation.report.figures.panels import prepare_drawing
from validation.report.figures.style import PLANT_STYLE, plant_style
from validation.report.figures.tracking import figure_tracking

FIGURES = ("errors", "tracking", "invariants", "control")
"""Every figure of a run, in the report's order."""

__all__ = [
    "DEFAULT_FORMATS",
    "FIGURES",
    "PLANT_STYLE",
    "PNG_DPI",
    "TEXT_RASTER",
    "Drawing",
    "FigureContext",
    "FigureFormat",
    "figure_control",
    "figure_errors",
    "figure_invariants",
    "figure_tracking",
    "parse_formats",
    "plant_style",
    "prepare_drawing",
]
