"""The referee's noise floor: the distance below which plants' differences decide nothing.

A quantity's floor (:class:`NoiseFloor`) is the larger of two parts, each in the quantity's unit:
``REFEREE_NOISE_FRACTION × threshold`` (distances a thousand times inside the threshold decide
nothing; the threshold's absolute part, its ``value``, not the effective bound ``value + rtol ·
scale`` of a state's check: a thousandth of the relative part would be an integrator's own
error, which is what the referee attributes) and the quantity's **round-off**,
``ε_round × ε × scale`` with ``ε`` the float64 machine epsilon: for a state (position of C, rod
positions, velocities, angular velocity, attitude) its largest magnitude over the run, of the
median plant (:func:`typical`: an outlier running away does not raise the others' floor), with
``ε_round = REFEREE_ROUNDOFF_STATE``; for the control torque and rod forces the largest control
force, of the median plant too (torque in N·m and rod forces in N, one vector in SI as
the controller's solve handles them) with ``ε_round = REFEREE_ROUNDOFF_FORCE``, divided by the
relative check's scale (:func:`roundoff_scales`). A quantity zero in exact arithmetic (the torque
of a rod through C with only the masses controlled) thus keeps its round-off residue below the
floor. Each verdict records its floor and which part decided it (:class:`FloorPart`), and its
sentence states it (:meth:`NoiseFloor.phrase`, :func:`floor_rule_text`). A change to what counts
as noise costs this module only; the constants are :mod:`validation.compare.thresholds`'.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from validation.compare.checks import Comparison, Group
from validation.compare.reductions import largest
from validation.compare.thresholds import (
    REFEREE_NOISE_FRACTION,
    REFEREE_ROUNDOFF_FORCE,
    REFEREE_ROUNDOFF_STATE,
)

EPS = float(np.finfo(float).eps)
"""float64 machine epsilon (2.2e-16): the unit of the round-off part of the noise floor."""

FORCE_QUANTITIES = frozenset({"control_torque", "rod_forces"})
"""The quantities whose round-off follows the largest control force (``REFEREE_ROUNDOFF_FORCE``)."""


def sci(x: float) -> str:
    """``1e5`` for 1e5, ``0.001`` for 1e-3: a constant as the rule's text writes it."""
    return f"{x:.0e}".replace("e+0", "e").replace("e+", "e") if x >= 1e3 else f"{x:g}"


def fmt(x: float, unit: str) -> str:
    """``1e-09 m``: a distance or floor as the verdicts write it, two significant digits."""
    u = "" if unit in ("", "1") else f" {unit}"
    return f"{x:.2g}{u}"


class FloorPart(StrEnum):
    """Which part of the noise floor decided its value."""

    THRESHOLD = "threshold"  # REFEREE_NOISE_FRACTION × threshold
    ROUND_OFF = "round-off"  # ε_round × ε × the quantity's scale


@dataclass(frozen=True)
class RoundoffScale:
    """The magnitude whose round-off a quantity carries.

    Attributes:
        value: the largest magnitude over the run of the median plant (:func:`typical`), in
            ``unit`` (0: unknown).
        unit: its unit (``m``; ``N·m, N`` for the control forces).
        what: what it is, for people (``largest |R|``).
        multiplier: ``ε_round`` (``REFEREE_ROUNDOFF_STATE`` or ``REFEREE_ROUNDOFF_FORCE``).
    """

    value: float
    unit: str
    what: str
    multiplier: float


@dataclass(frozen=True)
class NoiseFloor:
    """A quantity's noise floor and its two parts, in the quantity's unit.

    Attributes:
        threshold_part: ``REFEREE_NOISE_FRACTION × threshold``.
        roundoff_part: ``multiplier × ε × scale / divisor`` (0 when the scale is unknown).
        scale: the magnitude whose round-off it is (None: not known, no round-off part).
        divisor: a relative check's scale (its reference signal's largest magnitude, in
            ``scale.unit``); 1.0 for an absolute quantity.
    """

    threshold_part: float
    roundoff_part: float = 0.0
    scale: RoundoffScale | None = None
    divisor: float = 1.0

    @classmethod
    def of(
        cls, threshold: float, scale: RoundoffScale | None = None, divisor: float = 1.0
    ) -> NoiseFloor:
        """The floor of a quantity with this threshold and round-off scale."""
        part = 0.0
        if scale is not None and math.isfinite(scale.value) and scale.value > 0:
            d = divisor if math.isfinite(divisor) and divisor > 0 else 1.0
            part = scale.multiplier * EPS * scale.value / d
        return cls(REFEREE_NOISE_FRACTION * threshold, part, scale, divisor)

    @property
    def value(self) -> float:
        """``max(threshold_part, roundoff_part)``."""
        return max(self.threshold_part, self.roundoff_part)

    @property
    def decided_by(self) -> FloorPart:
        if self.roundoff_part > self.threshold_part:
            return FloorPart.ROUND_OFF
        return FloorPart.THRESHOLD

    def phrase(self, unit: str) -> str:
        """``1e-09 m = 0.001 × threshold``, or the round-off that decided it."""
        head = f"{fmt(self.value, unit)} = "
        if self.decided_by is FloorPart.THRESHOLD or self.scale is None:
            return head + f"{REFEREE_NOISE_FRACTION:g} × threshold"
        s = self.scale
        out = f"round-off, {sci(s.multiplier)} ε × {s.what} {s.value:.2g} {s.unit}"
        if self.divisor != 1.0:
            out += f" / the check's scale {self.divisor:.2g}"
        return head + out

    def to_dict(self) -> dict[str, Any]:
        s = self.scale
        return {
            "value": self.value,
            "decided_by": self.decided_by.value,
            "threshold_part": self.threshold_part,
            "roundoff_part": self.roundoff_part,
            "scale": s.value if s else None,
            "scale_unit": s.unit if s else "",
            "scale_of": s.what if s else "",
            "multiplier": s.multiplier if s else None,
            "divisor": self.divisor,
        }


def noise_floor(threshold: float) -> float:
    """The threshold part of the referee's noise floor (same unit as the threshold)."""
    return REFEREE_NOISE_FRACTION * threshold


def floor_rule_text() -> str:
    """The noise floor in words, with its constants, as the rule under the report's table states
    it."""
    return (
        f"The noise floor is the larger of {REFEREE_NOISE_FRACTION:g} × the threshold (its "
        "absolute part) and the "
        f"quantity's round-off, {sci(REFEREE_ROUNDOFF_STATE)} ε × its largest magnitude over the run "
        f"for a state, {sci(REFEREE_ROUNDOFF_FORCE)} ε × the largest control force "
        "(relative to the check's scale) for the torque and rod forces, of the median plant (a "
        "plant that runs away does not raise it), ε = 2.2e-16 (column *floor set by*). "
    )


_STATE_SCALES: Mapping[str, tuple[str, str, Any]] = {
    # quantity -> (what, unit, largest magnitude of one trajectory)
    "position_C": ("largest |R|", "m", lambda tr: largest(tr.q[:, :3], True)),
    "attitude": ("|u|", "1", lambda tr: 1.0),  # a unit quaternion's components are O(1)
    "rod_positions": ("largest |p_i|", "m", lambda tr: largest(tr.q[:, 7:], False)),
    "velocity_C": ("largest |Ṙ|", "m/s", lambda tr: largest(tr.qdot[:, :3], True)),
    "rod_velocities": ("largest |ṗ_i|", "m/s", lambda tr: largest(tr.qdot[:, 7:], False)),
    "angular_velocity": ("largest |ω|", "rad/s", lambda tr: largest(tr.omega, True)),
}


def typical(values: Sequence[float]) -> float:
    """The lower median of the plants' magnitudes: the magnitude of a plant of the majority, so
    that one plant running away (an outlier whose state or force grows by decades before it
    stops) does not raise the round-off floor the others are judged by; with two plants, the
    smaller."""
    ordered = sorted(values)
    return ordered[(len(ordered) - 1) // 2]


def roundoff_scales(cmp: Comparison, trajectories: Sequence[Any] = ()) -> dict[str, RoundoffScale]:
    """Quantity -> the magnitude whose round-off it carries, over the run, of a typical plant
    (:func:`typical`: the lower median over the plants of each plant's largest magnitude).

    The control torque and rod forces: each plant's largest control force, ``max(|τ|, |F_i|)``
    over its control series in ``cmp`` (N·m and N as one SI vector, as the controller's solve
    computes them together). The states: each trajectory's largest magnitude (none given: no
    round-off part for them). Non-finite samples are left out."""
    out: dict[str, RoundoffScale] = {}
    per_plant: dict[str, float] = {}
    for s in cmp.series:
        if s.group is Group.CONTROL and not s.subject.is_pair:
            key = str(s.subject.value)
            per_plant[key] = max(per_plant.get(key, 0.0), largest(s.values, False))
    if per_plant:
        f = RoundoffScale(
            typical(list(per_plant.values())),
            "N·m, N",
            "largest control force",
            REFEREE_ROUNDOFF_FORCE,
        )
        for q in FORCE_QUANTITIES:
            out[q] = f
    if trajectories:
        for q, (what, unit, of) in _STATE_SCALES.items():
            out[q] = RoundoffScale(
                typical([of(tr) for tr in trajectories]), unit, what, REFEREE_ROUNDOFF_STATE
            )
    return out


__all__ = [
    "EPS",
    "FORCE_QUANTITIES",
    "FloorPart",
    "NoiseFloor",
    "RoundoffScale",
    "floor_rule_text",
    "fmt",
    "noise_floor",
    "roundoff_scales",
    "sci",
    "typical",
]
