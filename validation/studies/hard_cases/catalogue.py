"""What a hard case may measure, against what: the closed catalogue a ``[hard_case]`` table names.

Every ``(what, against)`` pair a scene file may name is a key of :data:`MEASURES`, with its unit,
its meaning and the plants it is made on (:class:`MeasureInfo`); :class:`Reference` lists the
independent references, :class:`Measure` the figures. ``docs/hard_cases.md`` lists every entry.
A new measure or reference costs an entry here and its computation in
:mod:`validation.studies.hard_cases.measures`; the file format that names them is
:mod:`validation.studies.hard_cases.criterion`'s.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum


class Reference(StrEnum):
    """What a figure is compared with (each is computed independently of the plant judged)."""

    RUN = "run"
    """The plant's own run: events it must show (a flip, a crossing)."""
    BALANCES = "balances"
    """The plant's own balances of energy and momenta (they hold exactly for the true motion)."""
    ANALYTIC = "analytic"
    """The analytic plant's run of the same scene, on the same samples (for the other plants)."""
    EULER = "euler"
    """A torque-free rigid body: Euler's equations integrated on their own
    (:mod:`validation.studies.hard_cases.references.euler`)."""
    CENTRE_OF_MASS = "centre_of_mass"
    """The closed-form motion of the system's centre of mass, ``c0 + ċ0 t + g t²/2``
    (:mod:`validation.studies.hard_cases.references.centre_of_mass`)."""
    TRACKING_LAWS = "tracking_laws"
    """The closed forms of the tracking errors (Eqs. 78, 84; :mod:`validation.compare.checks`)."""
    NORM_DECAY = "norm_decay"
    """The closed form of ``φ = uᵀu - 1`` under Eq. (58)
    (:mod:`validation.studies.hard_cases.references.off_manifold`)."""
    LOADER = "loader"
    """The scene loader, given the same file without its explicit allowance
    (:mod:`validation.studies.hard_cases.references.off_manifold`)."""
    MIRROR = "mirror"
    """The same plant's run of the mirrored scene ``[hard_case.mirror]``, u(0) negated
    (:mod:`validation.studies.hard_cases.references.double_cover`)."""
    ANALYTIC_MIRROR = "analytic_mirror"
    """The analytic plant's run of the mirrored scene (for the other plants)."""
    SOLVERS = "solvers"
    """The same plant integrated by the other scipy methods of ``[hard_case.solvers]``
    (:mod:`validation.studies.hard_cases.references.solvers`)."""
    PINV_LAW = "pinv_law"
    """The Moore-Penrose law with requirement rows duplicated as ``[hard_case.pinv_law]`` says
    (:mod:`validation.studies.hard_cases.references.pinv_law`)."""


class Measure(StrEnum):
    """What is measured (its meaning depends on the reference: :data:`MEASURES`)."""

    COMPLETED = "completed"
    FINITE = "finite"
    FLIPS = "flips"
    CROSSINGS = "crossings"
    INVARIANTS = "invariants"
    ENERGY = "energy"
    ANGULAR_MOMENTUM = "angular_momentum"
    LINEAR_MOMENTUM = "linear_momentum"
    QUAT_NORM = "quat_norm"
    INTERNAL_ENERGY = "internal_energy"
    COM_PATH = "com_path"
    COM_PATH_REL = "com_path_rel"
    ANGULAR_VELOCITY = "angular_velocity"
    ATTITUDE = "attitude"
    POSITION_C = "position_C"
    ROD_POSITIONS = "rod_positions"
    POSITIONS = "positions"
    QUATERNION = "quaternion"
    FLIP_TIMES = "flip_times"
    FIRST_CROSSING_TIME = "first_crossing_time"
    TRACKING = "tracking"
    REFUSED = "refused"
    REDUNDANT_ACCELERATION = "redundant_acceleration"
    REDUNDANT_RESIDUAL = "redundant_residual"
    CONFLICT_RESIDUAL = "conflict_residual"
    OTHER_RESIDUALS = "other_residuals"
    CONFLICT_TRACKING = "conflict_tracking"
    ENGINE_LAW = "engine_law"


class Applies(StrEnum):
    """Which plants a measure is made on (of those the case runs on)."""

    EVERY = "every plant"
    OTHERS = "every plant but the analytic one"
    ANALYTIC = "the analytic plant"
    SCIPY = "the plants integrated by scipy"
    ENGINE_LAW = "the engine plants whose own matrices give the law (MuJoCo, Pinocchio)"


@dataclass(frozen=True)
class MeasureInfo:
    """A measure against a reference: its unit, what it is, and who it is made on; an indicator
    is 1 when the property fails and 0 when it holds, judged against 0 (no bound named)."""

    unit: str
    meaning: str
    applies: Applies = Applies.EVERY
    indicator: bool = False


_M, _R = Measure, Reference
MEASURES: Mapping[tuple[Measure, Reference], MeasureInfo] = {
    (_M.COMPLETED, _R.RUN): MeasureInfo(
        "s", "the time the run reached, judged against its horizon (made on every run, implicitly)"
    ),
    (_M.FINITE, _R.RUN): MeasureInfo(
        "1",
        "1 when q, q̇ or q̈ has a NaN or an infinity (made on every run, implicitly)",
        indicator=True,
    ),
    (_M.FLIPS, _R.RUN): MeasureInfo(
        "1", "1 when ω about the intermediate principal axis never changes sign", indicator=True
    ),
    (_M.CROSSINGS, _R.RUN): MeasureInfo(
        "1", "1 when no two neighbouring masses pass through each other", indicator=True
    ),
    (_M.INVARIANTS, _R.BALANCES): MeasureInfo(
        "1",
        "the largest of the relative drifts of the energy, angular- and linear-momentum balances "
        "(validation.compare.summary.drift_figures)",
    ),
    (_M.ENERGY, _R.BALANCES): MeasureInfo("1", "max |E - E(0) + D - W| / max(|E|, |W|, |D|)"),
    (_M.ANGULAR_MOMENTUM, _R.BALANCES): MeasureInfo(
        "1", "max |L - L(0) - ∫Sτ dt| / max(|L|, |∫Sτ dt|), per component"
    ),
    (_M.LINEAR_MOMENTUM, _R.BALANCES): MeasureInfo(
        "1", "max |P - P(0) - m_T g t - ∫F_C dt| / max |P|, per component"
    ),
    (_M.QUAT_NORM, _R.BALANCES): MeasureInfo("1", "max |uᵀu - 1|"),
    (_M.QUAT_NORM, _R.NORM_DECAY): MeasureInfo(
        "1", "max |φ - φ_closed form| for φ = uᵀu - 1 (Eq. 58)"
    ),
    (_M.INTERNAL_ENERGY, _R.CENTRE_OF_MASS): MeasureInfo(
        "1",
        "max |E_int - E_int(0)| / max |E_int|, E_int the energy in the frame of the system's "
        "centre of mass",
    ),
    (_M.COM_PATH, _R.CENTRE_OF_MASS): MeasureInfo(
        "m", "max |c - (c0 + ċ0 t + g t²/2)|, c0 and ċ0 from the scene's initial state"
    ),
    (_M.COM_PATH_REL, _R.CENTRE_OF_MASS): MeasureInfo(
        "1", "max |c - (c(0) + ċ(0) t + g t²/2)| / max |c|, c(0), ċ(0) the run's first sample"
    ),
    (_M.ANGULAR_VELOCITY, _R.EULER): MeasureInfo("1", "max |ω - ω_E| / max |ω_E| (body axes)"),
    (_M.ATTITUDE, _R.EULER): MeasureInfo("rad", "max attitude angle between u and u_E"),
    (_M.ROD_POSITIONS, _R.EULER): MeasureInfo(
        "m", "max |p_i|: the rigid motion keeps every mass at C (p ≡ 0)"
    ),
    (_M.FLIP_TIMES, _R.EULER): MeasureInfo(
        "s",
        "max |Δt| between the sign changes of ω about the intermediate axis and the reference's "
        "(infinite when their numbers differ or there is none)",
    ),
    (_M.POSITION_C, _R.ANALYTIC): MeasureInfo("m", "max |R - R_a|", Applies.OTHERS),
    (_M.ROD_POSITIONS, _R.ANALYTIC): MeasureInfo("m", "max_i |p_i - p_a,i|", Applies.OTHERS),
    (_M.ATTITUDE, _R.ANALYTIC): MeasureInfo(
        "rad", "max attitude angle between u and u_a", Applies.OTHERS
    ),
    (_M.FLIP_TIMES, _R.ANALYTIC): MeasureInfo(
        "s", "max |Δt| between the plant's flips and the analytic plant's", Applies.OTHERS
    ),
    (_M.FIRST_CROSSING_TIME, _R.ANALYTIC): MeasureInfo(
        "s",
        "|Δt| between the first crossing of two masses and the analytic plant's",
        Applies.OTHERS,
    ),
    (_M.TRACKING, _R.TRACKING_LAWS): MeasureInfo(
        "1", "max |e - e_closed form| / max |e(0)| over the tracked ω components and masses"
    ),
    (_M.REFUSED, _R.LOADER): MeasureInfo(
        "1",
        "1 unless the loader refuses the file without initial.attitude.allow_off_manifold, naming "
        "initial.attitude.quaternion",
        Applies.ANALYTIC,
        indicator=True,
    ),
    (_M.QUATERNION, _R.MIRROR): MeasureInfo("1", "max |u + u_mirror| per component"),
    (_M.POSITIONS, _R.MIRROR): MeasureInfo(
        "m", "max over components of |R - R_mirror| and |p - p_mirror|"
    ),
    (_M.POSITION_C, _R.ANALYTIC_MIRROR): MeasureInfo("m", "max |R - R_a,mirror|", Applies.OTHERS),
    (_M.ROD_POSITIONS, _R.ANALYTIC_MIRROR): MeasureInfo(
        "m", "max_i |p_i - p_a,mirror,i|", Applies.OTHERS
    ),
    (_M.ATTITUDE, _R.ANALYTIC_MIRROR): MeasureInfo(
        "rad", "max attitude angle between u and u_a,mirror (sign-blind)", Applies.OTHERS
    ),
    (_M.POSITIONS, _R.SOLVERS): MeasureInfo(
        "m",
        "per method: max(max |ΔR|, max_i |Δp_i|) against the plant's run at the scene's method",
        Applies.SCIPY,
    ),
    (_M.REDUNDANT_ACCELERATION, _R.PINV_LAW): MeasureInfo(
        "1", "max |q̈_dup - q̈| / |q̈| at sampled states, one row duplicated", Applies.ANALYTIC
    ),
    (_M.REDUNDANT_RESIDUAL, _R.PINV_LAW): MeasureInfo(
        "1", "max |A q̈ - b| / max(1, max |q̈|) with the duplicated row", Applies.ANALYTIC
    ),
    (_M.CONFLICT_RESIDUAL, _R.PINV_LAW): MeasureInfo(
        "1", "max |residual - (+δ/2, -δ/2)| / δ on the conflicting pair", Applies.ANALYTIC
    ),
    (_M.OTHER_RESIDUALS, _R.PINV_LAW): MeasureInfo(
        "1", "max |residual| / δ of the other requirements", Applies.ANALYTIC
    ),
    (_M.CONFLICT_TRACKING, _R.PINV_LAW): MeasureInfo(
        "1",
        "max |e - (e0 exp(-γt) + δ/(2γ)(1 - exp(-γt)))| / max |e| of the conflicting component",
        Applies.ANALYTIC,
    ),
    (_M.ENGINE_LAW, _R.PINV_LAW): MeasureInfo(
        "1",
        "max |q̈_law - q̈_dup| / |q̈_dup|: the law from the engine's own M and forces",
        Applies.ENGINE_LAW,
    ),
}
"""The measures a scene file may name, per reference (``docs/hard_cases.md`` lists them)."""

IMPLICIT = frozenset({(_M.COMPLETED, _R.RUN), (_M.FINITE, _R.RUN)})
"""Made on every run a case makes; a scene file does not name them."""

UNTIL_REFERENCES = frozenset({_R.ANALYTIC, _R.ANALYTIC_MIRROR})
"""References whose checks may stop at ``until`` seconds."""


__all__ = [
    "IMPLICIT",
    "MEASURES",
    "UNTIL_REFERENCES",
    "Applies",
    "Measure",
    "MeasureInfo",
    "Reference",
]
