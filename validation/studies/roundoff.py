"""The round-off of a plant's floating-point precision: which bounds it can resolve.

A plant integrates in one precision (:class:`analytic.effects.Precision`): its settings'
``precision`` attribute where it has one (MJX: either; MuJoCo Warp: float32 only), float64
otherwise. The rule every study applies:

    a bound B on a quantity of magnitude S (in the bound's unit: m, rad, s, or 1 for a relative
    figure) can be judged at precision P only when B >= EPS[P] x S,

``EPS[P]`` the machine epsilon of P (float32: 2**-23 = 1.19e-7; float64: 2**-52 = 2.22e-16):
one unit in the last place of S. Below it the plant's own state cannot represent the difference
the bound asks about, so a PASS or a FAIL there would judge the number format, not the engine.
Such a check is "not judgeable at float32" (never a PASS or a FAIL). ``S`` is the quantity's
magnitude in the plant's state over the run (the largest ``|R|`` for the position of C, the
largest ``|p_i|`` for the rod positions, the horizon for an instant, 1 for an angle from a unit
quaternion and for a relative figure).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analytic.effects import Precision

EPS: dict[Precision, float] = {
    Precision.FLOAT32: float(np.finfo(np.float32).eps),  # 2**-23 = 1.19e-7
    Precision.FLOAT64: float(np.finfo(np.float64).eps),  # 2**-52 = 2.22e-16
}
"""Machine epsilon of each precision: the relative spacing of its numbers at 1."""


def precision_of(settings: Any) -> Precision:
    """The precision a plant with these settings integrates in: ``settings.precision`` where
    the settings have one (a :class:`Precision` or its value), else float64 (every built-in
    plant). ``ValueError`` naming ``precision`` for a value that is neither."""
    value = getattr(settings, "precision", Precision.FLOAT64)
    try:
        return Precision(value)
    except ValueError:
        allowed = ", ".join(p.value for p in Precision)
        raise ValueError(f"precision: unknown value {value!r} (allowed: {allowed})") from None


def round_off(scale: float, precision: Precision) -> float:
    """``EPS[precision] x |scale|``: the smallest difference a quantity of magnitude ``scale``
    resolves at ``precision`` (same unit as ``scale``)."""
    return EPS[Precision(precision)] * abs(float(scale))


def judgeable(bound: float, scale: float, precision: Precision) -> bool:
    """Whether ``bound`` can be judged at ``precision`` on a quantity of magnitude ``scale``:
    ``bound >= EPS x scale`` (a non-finite scale: never)."""
    if not math.isfinite(scale):
        return False
    return float(bound) >= round_off(scale, precision)


def not_judgeable_reason(bound: float, scale: float, unit: str, precision: Precision) -> str:
    """The sentence a report gives for a bound below ``precision``'s round-off."""
    p = Precision(precision)
    floor = round_off(scale, p)
    u = "" if unit == "1" else f" {unit}"
    return (
        f"not judgeable at {p.value}: the bound {bound:.2g}{u} is below {p.value} round-off "
        f"for this quantity, eps {EPS[p]:.3g} x its magnitude {abs(scale):.3g}{u} = "
        f"{floor:.2g}{u}"
    )


__all__ = ["EPS", "judgeable", "not_judgeable_reason", "precision_of", "round_off"]
