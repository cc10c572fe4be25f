"""Which of a case's checks a plant's precision can judge (:mod:`validation.studies.roundoff`).

A check's bound B on a plant of precision P is judged only when ``B >= EPS[P] x S``, S the
magnitude of the checked quantity in that plant's run (:func:`magnitude`):

* a length (unit m): the largest magnitude of the coordinates it is made of, over the plant's run:
  ``|R|`` for the position of C, ``|p_i|`` for the rod positions (``|R|`` when every mass stays at
  C), the larger of the two for a figure over both, ``|c|`` (``|R|``) for the centre of mass;
* an angle (rad): 1, the magnitude of a unit quaternion's components (an attitude angle is
  ``2 asin`` of a difference of unit quaternions);
* an instant (s): the horizon (the largest time the plant's clock holds);
* a relative figure (unit 1): 1.

An indicator (judged against 0, no bound) and the implicit checks are always judgeable; on a
float64 plant every shipped bound is (the smallest, 1e-15 relative, is above 2.2e-16). A check
below the round-off is made with ``applicable = False`` (it passes nothing and fails nothing)
and its reason says why; :class:`NotJudgeable` is the record the table and its JSON show.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from analytic.effects import Precision
from analytic.trajectory import Trajectory
from validation.studies.hard_cases.catalogue import MEASURES, Measure, Reference
from validation.studies.hard_cases.criterion import CheckSpec
from validation.studies.roundoff import EPS, judgeable, not_judgeable_reason, round_off


@dataclass(frozen=True)
class NotJudgeable:
    """A check a plant's precision cannot judge.

    Attributes:
        plant: the plant; check: the check's label (``analytic_vs_mjx.position_C``).
        precision: the plant's precision.
        bound: the bound's name and value, in ``unit``.
        scale: the quantity's magnitude S, in ``unit``; round_off: ``EPS x S``.
        value: what was measured (reported, not judged).
        reason: the sentence the report gives.
    """

    plant: str
    check: str
    precision: Precision
    bound_name: str
    bound: float
    unit: str
    scale: float
    round_off: float
    value: float
    reason: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "plant": self.plant,
            "check": self.check,
            "precision": self.precision.value,
            "verdict": f"not judgeable at {self.precision.value}",
            "bound_name": self.bound_name,
            "bound": self.bound,
            "unit": self.unit,
            "eps": EPS[self.precision],
            "scale": self.scale,
            "round_off": self.round_off,
            "value": self.value,
            "reason": self.reason,
        }


@dataclass(frozen=True)
class _Samples:
    """The part of a run a magnitude is taken over: ``t`` (N,), ``R`` (N, 3), ``p`` (N, n)."""

    t: np.ndarray
    R: np.ndarray
    p: np.ndarray


def _largest(a: np.ndarray) -> float:
    a = np.asarray(a, float)
    return float(np.max(np.abs(a))) if a.size else 0.0


def _position_scale(tr: Trajectory) -> float:
    return float(np.max(np.linalg.norm(np.asarray(tr.R, float), axis=1))) if tr.t.size else 0.0


def _rod_scale(tr: Trajectory) -> float:
    p = _largest(tr.p)
    return p if p > 0 else _position_scale(tr)


def _length_scale(tr: Trajectory) -> float:
    return max(_position_scale(tr), _largest(tr.p))


_M, _R = Measure, Reference
_LENGTHS: dict[tuple[Measure, Reference], Callable[[Trajectory], float]] = {
    (_M.POSITION_C, _R.ANALYTIC): _position_scale,
    (_M.POSITION_C, _R.ANALYTIC_MIRROR): _position_scale,
    (_M.COM_PATH, _R.CENTRE_OF_MASS): _position_scale,
    (_M.ROD_POSITIONS, _R.ANALYTIC): _rod_scale,
    (_M.ROD_POSITIONS, _R.ANALYTIC_MIRROR): _rod_scale,
    (_M.ROD_POSITIONS, _R.EULER): _rod_scale,
}
"""The magnitude of each length measure in a run; any other length: the largest coordinate."""

UNIT_SCALES = {"1": 1.0, "rad": 1.0}
"""The magnitude of a relative figure and of an angle from unit quaternions."""


def magnitude(spec: CheckSpec, tr: Trajectory, t_end: float) -> float:
    """S of :mod:`this module <validation.studies.hard_cases.judgeable>` for ``spec`` on the
    plant's run ``tr`` over ``t_end`` s, in the measure's unit; a check with ``until`` takes the
    samples up to then only (the magnitude of what it compares)."""
    unit = MEASURES[(spec.what, spec.against)].unit
    if spec.until is not None:
        t_end = min(float(t_end), spec.until)
        k = int(np.searchsorted(np.asarray(tr.t, float), spec.until, side="right"))
        tr = _Samples(np.asarray(tr.t)[:k], np.asarray(tr.R)[:k], np.asarray(tr.p)[:k])
    if unit == "m":
        return _LENGTHS.get((spec.what, spec.against), _length_scale)(tr)
    if unit == "s":
        return float(t_end)
    if unit in UNIT_SCALES:
        return UNIT_SCALES[unit]
    raise ValueError(f"hard_case.check.what: no magnitude for unit {unit!r} ({spec.name})")


def assess(
    spec: CheckSpec,
    plant: str,
    label: str,
    precision: Precision,
    bound_name: str,
    bound: float,
    value: float,
    tr: Trajectory,
    t_end: float,
) -> NotJudgeable | None:
    """The :class:`NotJudgeable` record of a check below ``precision``'s round-off, else None
    (judgeable; an indicator always is)."""
    info = MEASURES[(spec.what, spec.against)]
    if info.indicator or not bound_name:
        return None
    scale = magnitude(spec, tr, t_end)
    if judgeable(bound, scale, precision):
        return None
    return NotJudgeable(
        plant=plant,
        check=label,
        precision=Precision(precision),
        bound_name=bound_name,
        bound=float(bound),
        unit=info.unit,
        scale=scale,
        round_off=round_off(scale, precision),
        value=float(value),
        reason=not_judgeable_reason(bound, scale, info.unit, precision),
    )


__all__ = ["UNIT_SCALES", "NotJudgeable", "assess", "magnitude"]
