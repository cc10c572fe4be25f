"""Named agreement thresholds of the side-by-side validation, each with the reason for its number.

One module holds the defaults; a scene may override any of them in a ``[thresholds]`` table, which
the scene loader keeps verbatim in ``scene.extra["thresholds"]``::

    [thresholds]
    position_C = 1e-7                                   # a number is the whole bound
    attitude = { value = 1e-7, reason = "tighter dt" }  # or a table with a value and a reason
    rod_velocities = { value = 1e-5, rtol = 1e-8 }      # and, for a scaled one, its rtol

An override without an ``rtol`` has none: its value is the whole bound (give ``rtol`` to keep a
relative part).

Two kinds of threshold:

* **absolute** (``relative = False``): the checked value is a maximum over time in the threshold's
  unit (m, rad, m/s, rad/s, or the dimensionless quaternion norm error). The states' differences
  and the tracking laws are bounded by ``value + rtol · scale``, as scipy's ``atol + rtol·|y|``:
  ``scale`` is the quantity's own magnitude over the run, the largest over time and over the
  compared plants (the names in :data:`SCALED`; the others, the attitude among them, have
  ``rtol = 0``);
* **relative** (``relative = True``): the checked value is a maximum over time divided by a scale,
  ``max(scale, floor)``, where the scale is the maximum magnitude of the reference signal (for
  forces: the analytic plant's; for balances: the quantity balanced) and ``floor`` (in the signal's
  unit) keeps an identically-zero signal (an uncontrolled run's torque) from dividing by zero.

The numbers are set for the paper scenes with the analytic plant at its scene or quick-run
tolerance and MuJoCo's RK4 at its scene step: two to three decades above both integrators' global
errors over a tumbling 20 s run (the free motion is sensitive to initial conditions) and well below
a modelling difference (a missing inertia term, a wrong spring force, a sign). The figures behind
each number are in ``docs/performance.md`` (section *Comparison thresholds and the referee's noise
floor*); each threshold's ``reason`` states its own in every report.

Each bound is an :class:`analytic.threshold.Threshold` (value, unit, reason), the one record type
of the project; the tolerances only the tests use are records of the same type in
``tests/support/tolerances.py``.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from analytic.threshold import Threshold, ThresholdSource

_RK4_DOP = (
    "both integrators' global errors are ~1e-9 or smaller at the scene settings (DOP853 rtol "
    "1e-10..1e-12, RK4 dt 2.5e-4 s); two to three decades of margin for the growth over a tumbling "
    "20 s run, while a modelling difference shows at 1e-3 or larger"
)

STATE_RTOL = 1e-7
"""The relative part of the state and tracking bounds (``rtol`` in ``value + rtol · scale``),
dimensionless. Both integrators' errors are relative to the state's magnitude (DOP853 holds each
step's local error to ``rtol · |y|``; RK4's error per unit time is ``O((ω h)^4)`` of the state), so
the bound's relative part follows the state; the absolute bounds' margin (``_RK4_DOP``) put above
their global errors over a run gives this value, four decades below a modelling difference. A
velocity's error and its scale are both its position's times the rate of the motion, so one rtol
serves positions and velocities. The absolute parts keep deciding at the scales they were set for:
at 10 m (or 10 m/s, 10 rad/s) the relative part is at most the absolute one; it decides where the
motion is larger (masses running away at hundreds of m/s). For the position and velocity of C the
scale is C's departure from its uniformly accelerated motion ``R(0) + Ṙ(0) t + ½ g t²``, not
``|R|``: that polynomial is reproduced to round-off by both integrators, so a long free fall does
not loosen their bound. Stiff scenes are the exception the absolute part covers: RK4 on springs of
high frequency errs by more than this fraction of the state, within the absolute part. The
figures: ``docs/performance.md``, *Comparison thresholds and the referee's noise floor*."""

SCALED = frozenset(
    (
        "position_C",
        "rod_positions",
        "velocity_C",
        "rod_velocities",
        "angular_velocity",
        "tracking_omega",
        "tracking_p",
    )
)
"""The thresholds whose bound may have a relative part (``rtol`` > 0): those of a quantity with a
magnitude of its own that grows with the motion (a position, a velocity; the tracking laws through
the state they are errors of). The attitude is not among them: its magnitude is a unit
quaternion's, the same in every run, so ``rtol`` × 1 would be a constant added to the value; nor
the relative thresholds (their value is already a fraction of a scale) and the quaternion norm
(dimensionless, of a unit quaternion). A scene's ``rtol`` for any other name is refused."""

_SCALED_BY = (
    "; plus rtol × the largest {of} over the run across the compared plants (both integrators' "
    "errors are relative to the state: STATE_RTOL)"
)

DEFAULTS: Mapping[str, Threshold] = {
    t.name: t
    for t in (
        # ---- analytic vs MuJoCo: the state ----
        Threshold(
            "position_C",
            1e-6,
            "m",
            f"max |R_a - R_m| (position of C, inertial): {_RK4_DOP}"
            + _SCALED_BY.format(of="|R - (R(0) + Ṙ(0) t + ½ g t²)|"),
            rtol=STATE_RTOL,
        ),
        Threshold(
            "attitude",
            1e-6,
            "rad",
            "max angle of the relative quaternion conj(u_a) ⊗ u_m (q and -q agree): "
            + _RK4_DOP
            + "; no relative part: the attitude's scale is a unit quaternion's, so rtol × 1 "
            "would only add a constant 1e-7 rad below this value",
        ),
        Threshold(
            "rod_positions",
            1e-6,
            "m",
            f"max over masses of |p_a - p_m|: {_RK4_DOP}" + _SCALED_BY.format(of="|p_i|"),
            rtol=STATE_RTOL,
        ),
        Threshold(
            "velocity_C",
            1e-5,
            "m/s",
            "max |Ṙ_a - Ṙ_m|: a velocity error is the position error times the fastest rate of the "
            "motion (~10 rad/s), hence one decade above the position bound"
            + _SCALED_BY.format(of="|Ṙ - (Ṙ(0) + g t)|"),
            rtol=STATE_RTOL,
        ),
        Threshold(
            "rod_velocities",
            1e-5,
            "m/s",
            "max over masses of |ṗ_a - ṗ_m|: one decade above the position bound (rates up to 2π rad/s)"
            + _SCALED_BY.format(of="|ṗ_i|"),
            rtol=STATE_RTOL,
        ),
        Threshold(
            "angular_velocity",
            1e-5,
            "rad/s",
            "max |ω_a - ω_m| (body axes): one decade above the attitude bound (rates ~10 rad/s)"
            + _SCALED_BY.format(of="|ω|"),
            rtol=STATE_RTOL,
        ),
        # ---- analytic vs MuJoCo: the control (same controller, so same forces up to state error) ----
        Threshold(
            "control_torque",
            1e-6,
            "1",
            "max |τ_a - τ_m| / max |τ_a|: the same controller evaluated on states that agree to ~1e-9 "
            "relative; the control's gains amplify the state error by at most ~100",
            relative=True,
            floor=1.0,  # N·m
        ),
        Threshold(
            "rod_forces",
            1e-6,
            "1",
            "max over masses |F_a - F_m| / max |F_a|: as for the torque",
            relative=True,
            floor=1.0,  # N
        ),
        # ---- each plant against the requirement (closed-form error dynamics, docs/errata.md item 3) ----
        Threshold(
            "tracking_omega",
            1e-6,
            "rad/s",
            "max |e_ω(t) - exp(-P t) e_ω(0)|: Eq. (84) makes the error decay exactly as exp(-P t) "
            "(γ = 0.6 1/s for the paper); an error of O(10) rad/s integrated to ~1e-9 relative; "
            "plus rtol × the plant's largest |ω| over the run (e_ω inherits the integration error "
            "of ω: STATE_RTOL)",
            rtol=STATE_RTOL,
        ),
        Threshold(
            "tracking_p",
            1e-6,
            "m",
            "max over controlled masses |e_p(t) - e_ref(t)|, e_ref solving ë + α ė + β e = 0 "
            "(Eq. 78) from e_p(0), ė_p(0): an error of O(1) m integrated to ~1e-9 relative; plus "
            "rtol × the plant's largest |p_i| over the run among the controlled masses (e_p "
            "inherits the integration error of p_i: STATE_RTOL)",
            rtol=STATE_RTOL,
        ),
        # ---- each plant: invariants and their balances ----
        Threshold(
            "quat_norm",
            1e-9,
            "1",
            "max |uᵀu - 1|: the paper reports O(1e-13) (controlled) at rtol 1e-12; Baumgarte "
            "stabilisation (Eq. 58) holds the norm at the tolerance level, so 1e-9 admits the quick "
            "tolerance rtol 1e-10 (measured ~3e-10) and MuJoCo's renormalised quaternion",
        ),
        Threshold(
            "linear_momentum",
            1e-8,
            "1",
            "max |P - (P(0) + m_T g t + ∫F_C dt)| / max |P|: linear momentum changes only by gravity "
            "(and a force at C, zero for the Gauss cost); integration error ~1e-10 relative",
            relative=True,
            floor=1.0,  # kg·m/s
        ),
        Threshold(
            "angular_momentum",
            1e-8,
            "1",
            "max |L - L(0) - ∫S τ dt| / max(|L|, |∫S τ dt|): angular momentum about the system CoM changes only "
            "by the impulse of the control torque; integration error ~1e-10 relative",
            relative=True,
            floor=1.0,  # kg·m²/s
        ),
        Threshold(
            "energy",
            1e-8,
            "1",
            "max |E - E(0) + D - W| / max(|E|, |W|, |D|): energy changes only by the work of the "
            "control and the given torque, less what the dampers dissipate; integration error "
            "~1e-10 relative",
            relative=True,
            floor=1.0,  # J
        ),
    )
}


REFEREE_SEPARATION = 10.0
"""The referee names plant X the outlier of a quantity when X's distances to the other two are at
least this many times the distance between those two. A decade: two independent engines that
model the same body agree to their integration error, so a factor of ten between "X vs the
others" and "the others vs each other" is a difference of kind (a coarser step, a modelling slip),
not the scatter of three errors of one size (which stay within a factor of ~3 of each other)."""

REFEREE_NOISE_FRACTION = 1e-3
"""Pairwise differences below this fraction of the quantity's threshold count as agreement: three
plants that all agree a thousand times better than the threshold asks have no outlier worth
naming, and round-off-level differences (1e-12 m beside a 1e-6 m bound) do not decide verdicts.
It is the threshold part of the referee's noise floor; the round-off part below takes over where a
quantity's own scale makes its round-off larger (:class:`validation.compare.noise_floor.NoiseFloor`).
The fraction is of the threshold's absolute part (its ``value``), not of the effective bound
``value + rtol · scale``: the relative part is a margin for the integrators' relative error
(:data:`STATE_RTOL`, 1e-7 of the scale), and a thousandth of it (1e-10 of the scale) would call
agreement what is an integrator's own error, the difference the referee is there to attribute
(MuJoCo's RK4 away from two DOP853 plants in ``paper_example2``: ``docs/performance.md``). Where
a state's size makes round-off matter, the round-off part scales it."""

REFEREE_ROUNDOFF_FORCE = 1e5
"""The round-off part of the noise floor of the control torque and rod forces, in float64 epsilons
(2.2e-16) of the largest control force of the run, of the median plant (``|τ|`` in N·m and ``|F_i|``
in N as one SI vector, as the controller's solve computes them together, analytic/fundamental.py).
A force zero in exact arithmetic comes out of that solve as a cancellation residue of the large
ones: with the rod through C and only the masses controlled (identity weighting) the torque is zero,
yet each plant gives a residue of some ε × max |F|, which under the absolute part alone would name
a plant the outlier of runs where every check passed. 1e5 ε (2.2e-11 relative) sits above the
largest residue measured (``docs/performance.md``, *Comparison thresholds and the referee's noise
floor*); it decides only when the torque is over 45 times smaller than the rod forces (or they
than it), where a difference below 2.2e-11 of the largest force is round-off, not a modelling
slip."""

REFEREE_ROUNDOFF_STATE = 1e3
"""The round-off part of the noise floor of a state (position of C, rod positions, velocities,
angular velocity, attitude), in float64 epsilons of its largest magnitude over the run across the
plants (``max |R|``, ``max |p_i|``, ...; 1 for the attitude's unit quaternion). Each step of an
integrator rounds the state at ε/2 of its magnitude; over the 1e4-1e6 steps of a run those
roundings add up like a random walk to about sqrt(1e6) = 1e3 of them. It decides only for large
magnitudes (|R| over 4.5 km against the default 1e-6 m threshold's floor of 1e-9 m): no built-in
scene reaches it."""


POINTWISE_ROUNDOFF = 1e4
"""The least bound of the pointwise check (:mod:`validation.compare.pointwise`), in epsilons of the
checked plant's precision (``numpy.finfo(precision).eps``: 2.2e-16 for float64, 1.19e-7 for
float32), as a fraction of ``max |q̈|`` at the state. One ``q̈`` is one forward-dynamics evaluation:
a few hundred operations and a solve with the mass matrix, whose rounding is a few ε times the
solve's amplification. MuJoCo C and the analytic model, two float64 implementations by different
algorithms, agree to 3-50 ε on the built-in scenes at their initial and random states
(``docs/accelerated-engines.md``); 1e4 ε leaves two decades above that and, at float32 (1.2e-3),
still sits a decade below the smallest modelling term of a built-in scene's ``q̈`` (the cubic
springs, 1.1e-2 of it in ``paper_example2``). A state whose own rounding is larger raises the
bound (:data:`POINTWISE_MARGIN`)."""

POINTWISE_MARGIN = 10.0
"""How far above a state's measured float64 rounding the pointwise bound sits, scaled to the
checked precision: the bound at a state is ``ε_P · max(POINTWISE_ROUNDOFF, POINTWISE_MARGIN ·
d/ε64)``, ``d`` the relative difference of MuJoCo C's and the analytic model's ``q̈`` there (two
float64 implementations of the same body differ by their rounding, which the cancellations of an
ill-conditioned state amplify: 4e5 ε in ``hard/heavy_masses``). A decade: rounding of one size in
two codes stays within a factor of a few of each other, a difference of model does not. A
precision P rounds ``ε_P/ε64`` times coarser, so its bound is that many times the float64 one;
where it reaches 1 the state cannot be judged at P."""

POINTWISE_AGREEMENT = 1e-8
"""Above this relative difference MuJoCo C and the analytic model disagree on the model at a state
(an off-manifold quaternion the analytic model stabilises and MuJoCo normalises), so their
difference measures no rounding and does not raise the pointwise bound
(:data:`POINTWISE_MARGIN`): 4.5e7 float64 ε, two decades above the largest rounding measured
between them (9e-11, ``hard/heavy_masses``)."""

POINTWISE_FLOOR = 1e-9
"""The smallest ``max |q̈|`` a pointwise difference is divided by (m/s² and 1/s²: the
accelerations of ``q = [R, u, p]``), so a state at rest without forces gives no division by zero;
far below any built-in scene's ``max |q̈|`` (1e-2 to 1e3)."""


def pointwise_threshold(precision: Any) -> Threshold:
    """The pointwise check's least bound (:data:`POINTWISE_ROUNDOFF` ε) for a plant computing in
    ``precision`` (``"float32"``, ``"float64"``, a :class:`numpy.dtype` or an enum of those
    names), named ``pointwise_<precision>``, relative to ``max |q̈|``.

    Raises:
        ValueError: naming ``settings.precision`` for anything but a floating-point type.
    """
    name = str(getattr(precision, "value", precision))
    try:
        dtype = np.dtype(name)
    except TypeError:
        dtype = None
    if dtype is None or dtype.kind != "f":
        raise ValueError(
            f"settings.precision: not a floating-point precision (got {precision!r}; "
            "e.g. float32, float64)"
        )
    eps = float(np.finfo(dtype).eps)
    return Threshold(
        f"pointwise_{dtype.name}",
        POINTWISE_ROUNDOFF * eps,
        "1",
        f"max |q̈_plant - q̈_ref| / max |q̈_ref| at a state, the plant computing in {dtype.name} "
        f"(ε = {eps:.3g}): {POINTWISE_ROUNDOFF:g} ε, two decades above the rounding of one "
        "forward-dynamics evaluation (MuJoCo C and the analytic model agree to 3-50 ε64), raised "
        f"to {POINTWISE_MARGIN:g} × a state's own measured rounding scaled to {dtype.name}",
        relative=True,
        floor=POINTWISE_FLOOR,
    )


# Keys of a scene's [thresholds] table that belong to the hard-case suite, not to the comparison.
HARD_CASE_PREFIX = "hard_"


def thresholds_for(
    scene: Any = None, overrides: Mapping[str, Any] | None = None
) -> dict[str, Threshold]:
    """The thresholds in force for ``scene``: the defaults, replaced by the scene's ``[thresholds]``.

    Args:
        scene: a :class:`analytic.scene.Scene` (or None for the defaults); its
            ``extra["thresholds"]`` maps names to a number (the whole bound: rtol 0) or to
            ``{value = ..., rtol = ..., reason = ...}`` (rtol optional, default 0, positive only
            for the names in :data:`SCALED`).
        overrides: further overrides in the same form (applied after the scene's).

    Raises:
        ValueError: naming ``thresholds.<name>`` (or ``thresholds.<name>.rtol``) for an unknown
            name, a bad value or rtol, or an rtol for a name outside :data:`SCALED`.
    """
    out = dict(DEFAULTS)
    tables = []
    if scene is not None:
        tables.append(dict(getattr(scene, "extra", {}) or {}).get("thresholds", {}) or {})
    if overrides:
        tables.append(overrides)
    for table in tables:
        if not isinstance(table, Mapping):
            raise ValueError(f"thresholds: must be a table (got {table!r})")
        for name, spec in table.items():
            if name.startswith(HARD_CASE_PREFIX):
                continue  # criteria of the hard-case suite (validation/hard_cases.py reads them)
            if name not in DEFAULTS:
                known = ", ".join(sorted(DEFAULTS))
                close = difflib.get_close_matches(str(name), list(DEFAULTS), n=1)
                hint = f"did you mean {close[0]!r}? " if close else ""
                raise ValueError(f"thresholds.{name}: unknown threshold ({hint}known: {known})")
            out[name] = _override(out[name], spec)
    return out


def _number(spec: Any, name: str) -> float:
    """``spec`` as a finite non-negative float, else a ValueError naming ``name``."""
    if isinstance(spec, bool) or not isinstance(spec, int | float):
        raise ValueError(f"{name}: must be a number (got {spec!r})")
    if not (math.isfinite(spec) and spec >= 0):
        raise ValueError(f"{name}: must be a finite non-negative number (got {spec!r})")
    return float(spec)


def _override(base: Threshold, spec: Any) -> Threshold:
    name = f"thresholds.{base.name}"
    reason = "set by the scene"
    # An override states the whole bound unless it gives an rtol: a value alone means what it
    # meant before bounds had a relative part (a scene's 1e-15 is 1e-15 at every scale).
    rtol = 0.0
    if isinstance(spec, Mapping):
        unknown = sorted(set(spec) - {"value", "reason", "rtol"})
        if unknown:
            raise ValueError(f"{name}.{unknown[0]}: unknown key (allowed: value, rtol, reason)")
        if "value" not in spec:
            raise ValueError(f"{name}.value: missing required key")
        reason = spec.get("reason", reason)
        if not isinstance(reason, str):
            raise ValueError(f"{name}.reason: must be a string (got {reason!r})")
        if "rtol" in spec:
            rtol = _number(spec["rtol"], f"{name}.rtol")
            if rtol and base.name not in SCALED:
                raise ValueError(
                    f"{name}.rtol: {base.name} has no relative part (a scale of its own only "
                    f"{', '.join(sorted(SCALED))} have; got {spec['rtol']!r})"
                )
        spec = spec["value"]
    value = _number(spec, name)
    default = f"{base.value:g}" + (f" + {base.rtol:g} × scale" if base.rtol else "")
    return replace(
        base,
        value=value,
        rtol=rtol,
        reason=f"{reason} (default {default}: {base.reason})",
        source=ThresholdSource.SCENE,
    )


__all__ = [
    "DEFAULTS",
    "POINTWISE_AGREEMENT",
    "POINTWISE_FLOOR",
    "POINTWISE_MARGIN",
    "POINTWISE_ROUNDOFF",
    "REFEREE_NOISE_FRACTION",
    "REFEREE_ROUNDOFF_FORCE",
    "REFEREE_ROUNDOFF_STATE",
    "REFEREE_SEPARATION",
    "SCALED",
    "STATE_RTOL",
    "Threshold",
    "ThresholdSource",
    "pointwise_threshold",
    "thresholds_for",
]
