"""The accelerated plants in the sweep (MJX, MuJoCo Warp): their grid in words, and the floor of
each precision series.

A series of an accelerated plant is one plant and one precision (``method`` = ``float64`` or
``float32``) over time steps, large to small. Its **precision floor** is the smallest step beyond
which a smaller step stopped lowering the error (by less than
:data:`~validation.studies.sweep.config.PRECISION_FLOOR_GAIN` for a quartered step:
:func:`validation.studies.sweep.series.precision_floor` marks it ``at_precision_floor``); a
series that never showed one has none within its grid (its error was still falling, or it ended
at the reference's floor first). :func:`floors` reads them off the rows; the text, the JSON and
the figure all use it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from validation.studies.sweep.config import (
    ACCELERATED,
    MJWARP,
    MJX,
    PRECISION_FLOOR_GAIN,
    Outcome,
    SweepConfig,
)


@dataclass(frozen=True)
class Floor:
    """What one accelerated series showed of its precision's floor.

    Attributes:
        engine: ``mjx`` or ``mjwarp``; precision: the series' precision (its ``method``).
        horizon_s: the horizon of its runs, s.
        dt: the smallest step that lowered the error, s (None: no floor within the grid).
        error: that run's error (None with ``dt``).
        best_error: the smallest error of the series' ``ok`` runs (None: none ran ok).
        run_id: the floor run's id (None with ``dt``).
        words: one sentence saying what was found.
    """

    engine: str
    precision: str
    horizon_s: float
    dt: float | None
    error: float | None
    best_error: float | None
    run_id: int | None
    words: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "engine": self.engine,
            "precision": self.precision,
            "horizon_s": self.horizon_s,
            "floor_dt": self.dt,
            "floor_error": self.error,
            "best_error": self.best_error,
            "run_id": self.run_id,
            "words": self.words,
        }


def floors(runs: Sequence[Mapping[str, Any]]) -> list[Floor]:
    """One :class:`Floor` per accelerated series among ``runs``, in their order."""
    series: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in runs:
        if r["engine"] in ACCELERATED:
            series.setdefault((str(r["engine"]), str(r["method"])), []).append(r)
    out = []
    for (engine, precision), rows in series.items():
        ok = [r for r in rows if r["status"] == Outcome.OK and r["error"] is not None]
        best = min((float(r["error"]) for r in ok), default=None)
        at = next((r for r in rows if r.get("at_precision_floor")), None)
        horizon = float(rows[0]["horizon_s"] or 0.0)
        if at is not None:
            words = (
                f"{engine} {precision}: floor at dt {at['setting']:.3g} s, error "
                f"{at['error']:.2g} (a smaller step did not lower it)"
            )
            out.append(
                Floor(
                    engine,
                    precision,
                    horizon,
                    float(at["setting"]),
                    float(at["error"]),
                    best,
                    int(at["run_id"]),
                    words,
                )
            )
            continue
        if not ok:
            words = f"{engine} {precision}: no run ended ok, no floor measured"
        elif any(r.get("at_reference_floor") for r in ok):
            words = (
                f"{engine} {precision}: reached the reference's floor (error {best:.2g}) before "
                f"any precision floor"
            )
        else:
            words = (
                f"{engine} {precision}: no floor within the grid (smallest error {best:.2g}, "
                f"still falling)"
            )
        out.append(Floor(engine, precision, horizon, None, None, best, None, words))
    return out


def grid_words(cfg: SweepConfig, engine: str) -> str:
    """An accelerated plant's grid in words: its precisions, steps and horizon."""
    precisions = [str(p) for e, p in cfg.accelerated if e == engine]
    dts = ", ".join(f"{d:.3g}" for d in cfg.settings(engine)) + " s"
    horizon = cfg.horizon(engine)
    what = (
        "MJX (JAX) on the MJCF twin" if engine == MJX else "MuJoCo Warp on the MJCF twin"
    ) + ", RK4 stages run by the plant with the controller in every stage"
    text = f"{what}, {' and '.join(precisions)} over dt {dts}, over {horizon:g} s"
    if engine == MJWARP and horizon < cfg.t_end:
        text += (
            f" (not {cfg.t_end:g} s: Warp takes ~19 ms per step on a CPU, so its series is short "
            f"here; its errors are against the reference up to {horizon:g} s, scaled by that "
            f"part's own displacement)"
        )
    return text + "; each run is a process of its own, its compilation never timed"


def floors_markdown(runs: Sequence[Mapping[str, Any]], cfg: SweepConfig) -> list[str]:
    """The section of ``sweep.md`` on the precisions ([] without accelerated series)."""
    found = floors(runs)
    if not found:
        return []
    lines = [
        "",
        "## Precision: where a smaller step stops helping",
        "",
        "Each accelerated series is one plant and precision over time steps, a quarter per step. "
        f"Its floor is the smallest step beyond which a quartered step lowered the error by less "
        f"than {PRECISION_FLOOR_GAIN:g}x (RK4's truncation error alone falls 256x): below it the error is "
        "the precision's round-off, not the integration. The series stops after the run that "
        "showed it.",
        "",
        "| series | horizon | floor dt | error at the floor | smallest error | what was found |",
        "|---|---|---|---|---|---|",
    ]
    for f in found:
        dt = "–" if f.dt is None else f"{f.dt:.3g} s"
        err = "–" if f.error is None else f"{f.error:.2g}"
        best = "–" if f.best_error is None else f"{f.best_error:.2g}"
        lines.append(
            f"| {f.engine} {f.precision} | {f.horizon_s:g} s | {dt} | {err} | {best} | {f.words} |"
        )
    return lines


__all__ = ["Floor", "floors", "floors_markdown", "grid_words"]
