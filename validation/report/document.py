"""The content of ``report.json`` (:func:`report_document`: every field is built here, in one
place; its provenance block is added by :func:`validation.report.report.write_report`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison
from validation.compare.referee import Verdict
from validation.report.records import FigureEntry, RunVerdict, summaries


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


def _pairwise(cmp: Comparison | None) -> dict[str, dict[str, float]]:
    """Quantity -> pair (``analytic vs mujoco``) -> the pair's checked value."""
    out: dict[str, dict[str, float]] = {}
    for c in cmp.checks if cmp is not None else ():
        if c.subject.is_pair:
            out.setdefault(c.name, {})[c.subject.value] = c.value
    return out


def report_document(
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
    pointwise = meta.get("pointwise")  # the check before the run: a field of its own
    run = {k: v for k, v in meta.items() if k != "pointwise"}
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
        "run": run,
        **({"pointwise": pointwise} if pointwise else {}),
    }


__all__ = ["report_document"]
