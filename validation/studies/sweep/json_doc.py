"""``sweep.json``: every number of the sweep as a JSON number, every array whole.

JSON has no NaN or infinity: a value that is not a finite number is written ``null`` (a row's
``status`` and ``note`` say why, e.g. ``diverged``). :func:`sweep_json` is the one place the
document is built, so that a shared block (provenance, a schema) is added here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from validation.report.provenance import FileKind, dumps, provenance
from validation.studies.sweep.accelerated import floors
from validation.studies.sweep.config import SweepConfig
from validation.studies.sweep.markdown import skipped_note
from validation.studies.sweep.result import SweepResult


def json_safe(x: Any) -> Any:
    """``x`` with every non-finite float as None, tuples and arrays as lists, paths as text."""
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, Mapping):
        return {str(k): json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_safe(v) for v in x]
    if isinstance(x, np.ndarray):
        return [json_safe(v) for v in x.tolist()]
    if isinstance(x, Path):
        return str(x)
    if isinstance(x, str):
        return str(x)  # a StrEnum as its plain value
    return x


def sweep_json(res: SweepResult, cfg: SweepConfig, scene: Any = None) -> str:
    """The text of ``sweep.json``: the provenance block (:mod:`validation.report.provenance`, with the
    resolved ``scene`` when given), then the sweep."""
    doc = {
        "provenance": provenance(FileKind.SWEEP, scene),
        "scene": res.scene,
        "config": cfg.to_dict(),
        "reference": res.reference,
        "levels": list(cfg.levels),
        "cheapest": {e: {repr(lv): rid for lv, rid in d.items()} for e, d in res.cheapest.items()},
        "series": [{"engine": e, "method": m} for e, m in res.series],
        "skipped_series": [
            {"engine": e, "reason": why, "note": skipped_note(e, why)}
            for e, why in res.skipped_series.items()
        ],
        "runs": list(res.runs),
        "precision_floors": [f.to_dict() for f in floors(res.runs)],
        "stabilization": list(res.stabilization),
        "effects": list(res.effects),
        "workers": res.workers,
        "wall_time_s": res.wall_time_s,
        "stage_wall_s": dict(res.stage_wall_s),
    }
    return dumps(json_safe(doc), indent=1)


__all__ = ["json_safe", "sweep_json"]
