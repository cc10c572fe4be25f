"""The scene format's keys of the initial state, stabilisation and control: one :class:`~analytic.scene.key.Key` each (type, unit, default,
bounds, meaning, the effect that reads it), in the order of the reference.

Part of :data:`analytic.scene.schema.KEYS`, the one table the loader, its cross-field rules and
``docs/scene-format.md`` read.
"""

from __future__ import annotations

from analytic.effects import Effect, Weighting
from analytic.scene.key import Key, Kind, Need

_R = Need.REQUIRED
_C = Need.CONDITIONAL

MOTION_KEYS: tuple[Key, ...] = (
    # ---- [initial] -----------------------------------------------------------------------------
    Key(
        "",
        "initial",
        Kind.TABLE,
        "",
        "The state at t = 0 in the paper's coordinates, `q(0) = [R, u, p]` and `q̇(0)` (Eq. 44).",
        _C,
        default_text="at rest at the origin, identity attitude (only without masses)",
        when="required when n > 0 (for `p`)",
    ),
    Key("initial", "R", Kind.VECTOR3, "m", "Position of C, inertial.", default=[0.0, 0.0, 0.0]),
    Key(
        "initial",
        "Rdot",
        Kind.VECTOR3,
        "m/s",
        "Velocity of C, inertial.",
        default=[0.0, 0.0, 0.0],
    ),
    Key(
        "initial",
        "omega",
        Kind.VECTOR3,
        "rad/s",
        "Angular velocity ω of BR, body axes; `u̇(0)` follows from it (Eq. 12).",
        default=[0.0, 0.0, 0.0],
    ),
    Key(
        "initial",
        "p",
        Kind.VECTOR_N,
        "m",
        "Mass positions `p_i(0)` along `a` from O' (the `p` of `q`, Eq. 44).",
        _C,
        when="required when n > 0",
    ),
    Key(
        "initial",
        "pdot",
        Kind.VECTOR_N,
        "m/s",
        "Mass velocities along the rod.",
        default_text="zeros",
    ),
    Key(
        "initial",
        "attitude",
        Kind.TABLE,
        "",
        "The attitude `u(0)` (Eq. 44): a quaternion, or an axis and an angle.",
        default_text="identity: `quaternion = [1, 0, 0, 0]` (body axes along XYZ)",
    ),
    # ---- [initial.attitude] --------------------------------------------------------------------
    Key(
        "initial.attitude",
        "quaternion",
        Kind.VECTOR4,
        "",
        "`u(0) = [w, x, y, z]`, body → inertial, w first. A norm off 1 by more than "
        "{QUAT_NORMALISE_TOL} is normalised with a warning.",
        _C,
        when="either this or axis + angle",
        bounds="norm within {QUAT_REFUSE_TOL} of 1",
    ),
    Key(
        "initial.attitude",
        "axis",
        Kind.VECTOR3,
        "",
        "Rotation axis (any nonzero length): `S(u(0)) = Rot(axis, angle) · "
        "reference_from_principal`.",
        _C,
        when="required without quaternion",
    ),
    Key(
        "initial.attitude",
        "angle",
        Kind.NUMBER,
        "rad",
        "Rotation angle about `axis`.",
        _C,
        when="with axis: angle or angle_deg",
    ),
    Key(
        "initial.attitude",
        "angle_deg",
        Kind.NUMBER,
        "deg",
        "Rotation angle about `axis`, in degrees.",
        _C,
        when="with axis: angle or angle_deg",
    ),
    Key(
        "initial.attitude",
        "reference_from_principal",
        Kind.MATRIX3,
        "",
        "A rotation applied before `Rot(axis, angle)`, e.g. from BR's principal axes to the axes "
        "of a drawing (Example 1's `P` of Eq. 63); the nearest rotation is taken.",
        _C,
        default_text="identity",
        when="only with axis",
        bounds="within {ROTATION_REFUSE_TOL} of a rotation",
    ),
    Key(
        "initial.attitude",
        "allow_off_manifold",
        Kind.BOOLEAN,
        "",
        "Start from a quaternion of norm ≠ 1 on purpose (the stabilisation of Eq. 58 pulls it "
        "back).",
        _C,
        default=False,
        when="only with quaternion",
    ),
    # ---- [stabilization] -----------------------------------------------------------------------
    Key(
        "",
        "stabilization",
        Kind.TABLE,
        "",
        "Baumgarte stabilisation of the quaternion's norm, Eq. (58): "
        "`φ̈ + δ1 φ̇ + δ2 φ = 0` with `φ = uᵀu − 1`.",
        default_text="δ1 = 0.5, δ2 = 8",
    ),
    Key("stabilization", "delta1", Kind.NUMBER, "1/s", "`δ1`.", default=0.5, bounds="≥ 0"),
    Key("stabilization", "delta2", Kind.NUMBER, "1/s²", "`δ2`.", default=8.0, bounds="≥ 0"),
    # ---- [control] -----------------------------------------------------------------------------
    Key(
        "",
        "control",
        Kind.TABLE,
        "",
        "The closed-form tracking control (Sec. VI): requirements on ω and on mass positions, met "
        "exactly by the force of least cost.",
        default_text="no control",
    ),
    Key(
        "control",
        "weighting",
        Kind.CHOICE,
        "",
        "The weighting `N` of the control cost `Q^Cᵀ N Q^C` (Appendix B).",
        default=Weighting.M_INV.value,
        choices=Weighting,
    ),
    Key(
        "control",
        "omega",
        Kind.TABLE,
        "",
        "Angular-velocity requirement `ω̄_i(t) = b_i cos(σ_i t)` (Eq. 76); the error "
        "`e_ω = ω − ω̄` decays as `exp(−P t) e_ω(0)` (Eqs. 82–86). Acts with the effect "
        "`control.omega`.",
        _C,
        when="required by the effect control.omega",
        effect=Effect.CONTROL_OMEGA,
        effect_needs=True,
    ),
    Key(
        "control",
        "masses",
        Kind.TABLE,
        "",
        "Mass-position requirement `p̄_i(t) = p_e,i + l_i cos(λ_i t)` (Eq. 75); the error "
        "`e_p = p − p̄` solves `ë + α ė + β e = 0` (Eq. 78). Acts with the effect "
        "`control.masses`.",
        _C,
        when="required by the effect control.masses",
        effect=Effect.CONTROL_MASSES,
        effect_needs=True,
    ),
    # ---- [control.omega] -----------------------------------------------------------------------
    Key(
        "control.omega",
        "components",
        Kind.INDICES,
        "",
        "The body axes whose ω is controlled, 1-based (1 = x, 2 = y, 3 = z; Remark 4); the others "
        "move freely.",
        default=[1, 2, 3],
        bounds="distinct, in 1..3",
    ),
    Key(
        "control.omega",
        "b",
        Kind.VECTOR3,
        "rad/s",
        "Amplitudes `b_i` of `ω̄_i(t) = b_i cos(σ_i t)` for x, y, z (Eq. 76; all three given, "
        "only `components` are enforced). With `sigma = 0` a constant rate.",
        _R,
    ),
    Key(
        "control.omega",
        "sigma",
        Kind.VECTOR3,
        "rad/s",
        "Angular frequencies `σ_i` of `ω̄_i(t) = b_i cos(σ_i t)` for x, y, z (Eq. 76).",
        _R,
    ),
    Key(
        "control.omega",
        "gamma",
        Kind.NUMBER,
        "1/s",
        "The gain `P = γ I` (Eq. 84): the error decays as `exp(−γ t)`.",
        _C,
        when="gamma or gain",
        bounds="> 0",
    ),
    Key(
        "control.omega",
        "gain",
        Kind.MATRIX_K,
        "1/s",
        "The gain matrix `P` (Eq. B6) over `components`, k = their number.",
        _C,
        when="gamma or gain",
        bounds="symmetric positive definite",
    ),
    # ---- [control.masses] ----------------------------------------------------------------------
    Key(
        "control.masses",
        "indices",
        Kind.INDICES,
        "",
        "The controlled masses, 1-based as in the paper (Remark 4); k = their number. The others "
        "feel no control force.",
        default_text="all masses",
        bounds="distinct, in 1..n",
    ),
    Key(
        "control.masses",
        "l",
        Kind.VECTOR_K,
        "m",
        "Amplitudes `l_i` of the required motion `p̄_i(t) = p_e,i + l_i cos(λ_i t)` about the rest "
        "position `p_e,i` (Eq. 75).",
        _R,
    ),
    Key(
        "control.masses",
        "lambda",
        Kind.VECTOR_K,
        "rad/s",
        "Angular frequencies `λ_i` of the required motion (Eq. 75); 0 holds the mass at "
        "`p_e,i + l_i`.",
        _R,
    ),
    Key(
        "control.masses",
        "alpha",
        Kind.VECTOR_K,
        "1/s",
        "Damping gains `α_i` of the error dynamics `ë_i + α_i ė_i + β_i e_i = 0` (Eq. 78), "
        "`e_i = p_i − p̄_i`.",
        _R,
        bounds="> 0",
    ),
    Key(
        "control.masses",
        "beta",
        Kind.VECTOR_K,
        "1/s²",
        "Stiffness gains `β_i` of the error dynamics (Eq. 78): with `α_i² ≥ 4β_i` the error "
        "decays without oscillating.",
        _R,
        bounds="> 0",
    ),
)
"""``[initial]``, ``[initial.attitude]``, ``[stabilization]``, ``[control]``, ``[control.omega]``, ``[control.masses]``."""
