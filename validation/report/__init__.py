"""The report wing: what a run leaves to be read.

* :mod:`.report`: ``write_report`` (``report.md``, ``report.json``, the figures);
* :mod:`.figures`: the figures and their captions (PNG, SVG or PDF);
* :mod:`.provenance`: the provenance block of every JSON file, ``dumps`` and the JSON Schemas in
  ``schemas/``;
* :mod:`.scene_reference`: ``docs/scene-format.md`` rendered from the key declarations;
* :mod:`.scene_schema`: the scene format's JSON Schema for editors, from the same declarations.
"""

from typing import TYPE_CHECKING

from validation._lazy import lazy_exports

_PUBLIC = {
    "write_report": "validation.report.report",
    "RunVerdict": "validation.report.report",
    "ReportFiles": "validation.report.report",
    "FigureFormat": "validation.report.figures",
    "FileKind": "validation.report.provenance",
    "dumps": "validation.report.provenance",
    "SCHEMA_DIR": "validation.report.provenance",
    "render": "validation.report.scene_reference",
}

if TYPE_CHECKING:  # the same names, typed for a type checker (never run: imports stay lazy)
    from validation.report.figures import FigureFormat as FigureFormat
    from validation.report.provenance import SCHEMA_DIR as SCHEMA_DIR
    from validation.report.provenance import FileKind as FileKind
    from validation.report.provenance import dumps as dumps
    from validation.report.report import ReportFiles as ReportFiles
    from validation.report.report import RunVerdict as RunVerdict
    from validation.report.report import write_report as write_report
    from validation.report.scene_reference import render as render

__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
