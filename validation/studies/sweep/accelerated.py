"""The accelerated plants in the sweep (MJX, MuJoCo Warp): their grid in words, and the floor of
each precision series.

A series of an accelerated plant is one plant and one precision (``method`` = ``float64`` or
``float32``) over time steps, large to small. Its **precision floor** is the smallest step beyond
which a smaller step stopped lowering the error (by less than
:data:`~validation.studies.sweep.config.PRECISION_FLOOR_GAIN` for a quartered step:
:func:`validation.studies.sweep.series.precision_floor` marks it ``at_precision_floor``). A
float64 control of the same twin, step and horizon (the plant's float64 series, else MuJoCo's C
RK4) tells what the floor is: round-off when the control goes lower there, the model when it
stops too (MJX without the cubic stiffness it drops), unconfirmed without a control; a
series that never showed one has none within its grid (its error was still falling, or it ended
at the reference's floor first). :func:`floors` reads them off the rows; the text, the JSON and
the figure all use it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
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
        kind: what the floor is (:class:`FloorKind`; None without a floor).
    """

    engine: str
    precision: str
    horizon_s: float
    dt: float | None
    error: float | None
    best_error: float | None
    run_id: int | None
    words: str
    kind: FloorKind | None = None

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
            "kind": None if self.kind is None else self.kind.value,
        }


class FloorKind(StrEnum):
    """What a series' floor is, told by a float64 control series of the same twin and horizon
    (the same plant's float64 series, else MuJoCo's C RK4 series)."""

    ROUND_OFF = "round-off"
    """The control goes lower at the smaller step: the precision's round-off."""
    MODEL = "model"
    """The control stops there too: the model (or the reference) differs, not the round-off."""
    UNCONFIRMED = "unconfirmed"
    """No float64 control on the same horizon and step."""


def _control(
    runs: Sequence[Mapping[str, Any]], engine: str, precision: str, dt: float, horizon: float
) -> Mapping[str, Any] | None:
    """The float64 control run at step ``dt`` and the same horizon: the plant's own float64
    series, else MuJoCo's C RK4 (None when neither ran ok there)."""
    for e, m in ((engine, "float64"), ("mujoco", "RK4")):
        if e == engine and m == precision:
            continue
        for r in runs:
            if (
                str(r["engine"]) == e
                and str(r["method"]) == m
                and r["status"] == Outcome.OK
                and r["error"] is not None
                and abs(float(r["setting"]) - dt) <= 1e-12 * dt
                and abs(float(r["horizon_s"] or 0.0) - horizon) <= 1e-9
            ):
                return r
    return None


def _kind(runs, engine, precision, after: Mapping[str, Any], horizon: float):
    ctrl = _control(runs, engine, precision, float(after["setting"]), horizon)
    if ctrl is None:
        return FloorKind.UNCONFIRMED, (
            "no float64 run of the same twin at that step and horizon tells round-off from a "
            "model difference"
        )
    who = f"{ctrl['engine']} {ctrl['method']}"
    if float(ctrl["error"]) * PRECISION_FLOOR_GAIN <= float(after["error"]):
        return FloorKind.ROUND_OFF, (
            f"{who} reaches {float(ctrl['error']):.2g} at dt {float(after['setting']):.3g} s: "
            f"the {precision} round-off"
        )
    return FloorKind.MODEL, (
        f"{who} stops at {float(ctrl['error']):.2g} there too: the model (or the reference) "
        f"differs, not the round-off"
    )


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
            i = rows.index(at)
            after = next((r for r in rows[i + 1 :] if r["status"] == Outcome.OK), at)
            kind, why = _kind(runs, engine, precision, after, horizon)
            words = (
                f"{engine} {precision}: floor at dt {at['setting']:.3g} s, error "
                f"{at['error']:.2g} (a smaller step did not lower it); {why}"
            )
            dt, err, rid = float(at["setting"]), float(at["error"]), int(at["run_id"])
            out.append(Floor(engine, precision, horizon, dt, err, best, rid, words, kind))
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


__all__ = ["Floor", "FloorKind", "floors", "floors_markdown", "grid_words"]
