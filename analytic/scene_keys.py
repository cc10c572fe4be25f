"""Every key of the scene format, with its type, unit, default and meaning: the one place they live.

The loader (:mod:`analytic.scene`) reads a key only through this table: a key it reads that is
not declared here is a programming error (``LookupError``), a default it applies is the one
declared here, and the kind of value it reads (a number, a list of n numbers, ...) must be the
declared kind. The reference ``docs/scene-format.md`` is rendered from this table
(``python -m validation scene-reference``), so the documentation and the loader cannot drift apart;
``tests/validation/report/test_scene_reference.py`` checks both directions.

Conventions (as in the loader): units SI; *body* vectors are in BR's principal axes at its centre
of mass C (the paper's xyz), *inertial* vectors in XYZ with Z up; quaternions are w first; mass and
axis indices in files are 1-based, as in the paper. ``n`` is the number of masses (the length of
``masses.mass``), ``k`` the number of controlled masses or axes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum, StrEnum
from typing import Any

from analytic.effects import (
    Effect,
    MjIntegrator,
    ShapeKind,
    SolverMethod,
    SpringModel,
    Weighting,
)


class Kind(StrEnum):
    """The kind of TOML value a key holds (as the documentation shows it)."""

    TABLE = "table"
    STRING = "string"
    BOOLEAN = "boolean"
    NUMBER = "number"
    VECTOR3 = "list of 3 numbers"
    VECTOR4 = "list of 4 numbers"
    VECTOR_N = "list of n numbers, one per mass"
    VECTOR_N1 = "list of n + 1 numbers, one per spring"
    VECTOR_K = "list of k numbers, one per controlled mass (in the order of `indices`)"
    MATRIX3 = "3×3 matrix (list of 3 rows)"
    MATRIX_K = "k×k matrix (list of k rows), k = the number of `components`"
    MATRICES_N = "list of n 3×3 matrices, one per mass"
    INDICES = "list of distinct 1-based integers"
    CHOICE = "string, one of the choices"
    CHOICES = "list of strings, each one of the choices"
    NUMBER_OR_VALUE_TABLE = "number, or table { value, reason }"
    NUMBER_OR_STRING = "number or string"


class Need(StrEnum):
    """Whether a key must be given."""

    REQUIRED = "required"
    OPTIONAL = "optional"
    CONDITIONAL = "conditional"
    """Required, or allowed, only in the case that :attr:`Key.when` states."""


class _NoDefault(Enum):
    NO_DEFAULT = "no default"


NO_DEFAULT = _NoDefault.NO_DEFAULT
"""The :attr:`Key.default` of a key without one (required, or computed when absent)."""


@dataclass(frozen=True)
class Key:
    """One key of the scene format.

    Attributes:
        table: the dotted table the key sits in (``"body.shape"``; ``""`` for the top-level tables);
            ``<name>`` stands for any name (the ``[thresholds]`` entries).
        key: the key (``"rod_length"``), or the table's own name for a table.
        kind: the kind of value.
        unit: SI unit of the value(s), ``""`` for none.
        meaning: what it is, in a sentence or two. ``meaning``, ``bounds`` and ``when`` may name
            a bound of :mod:`analytic.scene` in braces (``{MAX_MASS}``), filled in from its
            constant when the reference is rendered (so the number lives in one place); a literal
            brace is doubled.
        need: required, optional (with a default) or conditional (see ``when``).
        default: the TOML value the loader uses when the key is absent (:data:`NO_DEFAULT`: none).
        default_text: the default in words, when it is not a TOML value (``"no limit"``).
        when: for a conditional key, when it is required or allowed.
        bounds: what the loader refuses, in short (``"> 0"``).
        choices: the enum of the allowed strings, for ``CHOICE`` and ``CHOICES`` keys.
    """

    table: str
    key: str
    kind: Kind
    unit: str
    meaning: str
    need: Need = Need.OPTIONAL
    default: Any = NO_DEFAULT
    default_text: str = ""
    when: str = ""
    bounds: str = ""
    choices: type[StrEnum] | None = None

    @property
    def dotted(self) -> str:
        """``table.key`` (``body.shape.rod_length``)."""
        return f"{self.table}.{self.key}" if self.table else self.key

    def __post_init__(self) -> None:
        if self.need is Need.REQUIRED and self.default is not NO_DEFAULT:
            raise ValueError(f"{self.dotted}: a required key has no default")
        if (self.kind in (Kind.CHOICE, Kind.CHOICES)) != (self.choices is not None):
            raise ValueError(f"{self.dotted}: choices go with the CHOICE kinds only")
        if self.need is Need.CONDITIONAL and not self.when:
            raise ValueError(f"{self.dotted}: a conditional key says when")


DEFAULT_GRAVITY: tuple[float, float, float] = (0.0, 0.0, -9.81)
"""``[gravity] vector`` when the table is absent, m/s², inertial (Z up)."""

_R = Need.REQUIRED
_C = Need.CONDITIONAL

_SHAPE_ROD = 'kind is not "none"'
_BOX = 'kind = "box_and_rod"'
_CYL = 'kind = "hollow_cylinder_and_rod"'

KEYS: tuple[Key, ...] = (
    # ---- [scene] -------------------------------------------------------------------------------
    Key(
        "", "scene", Kind.TABLE, "", "What the scene is called and which effects it simulates.", _R
    ),
    Key(
        "scene",
        "name",
        Kind.STRING,
        "",
        "The scene's name, shown in reports; default output directories are named after it, "
        "reduced to `[A-Za-z0-9._-]` (a name never chooses a path).",
        _R,
    ),
    Key("scene", "description", Kind.STRING, "", "One line for reports.", default=""),
    Key(
        "scene",
        "effects",
        Kind.CHOICES,
        "",
        "What is simulated, from the effects listed above. An effect that is not listed is not "
        "computed at all, and data given for it is ignored with one warning.",
        _R,
        choices=Effect,
    ),
    # ---- [body] --------------------------------------------------------------------------------
    Key(
        "",
        "body",
        Kind.TABLE,
        "",
        "The rigid body BR (body B plus rod R): its mass and principal moments of inertia. Its "
        "principal axes at its centre of mass C are the body axes of every other table.",
        _R,
    ),
    Key(
        "body",
        "mass",
        Kind.NUMBER,
        "kg",
        "`m_BR`, the mass of BR.",
        _R,
        bounds="{MJ_MINVAL} … {MAX_MASS} kg",
    ),
    Key(
        "body",
        "inertia",
        Kind.VECTOR3,
        "kg·m²",
        "Principal moments `J = diag(J_x, J_y, J_z)` of BR about C.",
        _R,
        bounds="> 0, at most {MAX_INERTIA} kg·m²; A + B ≥ C",
    ),
    Key(
        "body",
        "shape",
        Kind.TABLE,
        "",
        "Pictures of BR for the viewers; massless, never used by the dynamics.",
        default_text="no picture",
    ),
    # ---- [body.shape] --------------------------------------------------------------------------
    Key("body.shape", "kind", Kind.CHOICE, "", "What to draw.", _R, choices=ShapeKind),
    Key(
        "body.shape",
        "box_half_sizes",
        Kind.VECTOR3,
        "m",
        "Half the box's edge lengths, along the box's own axes.",
        _C,
        when=f"required with {_BOX}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "box_center",
        Kind.VECTOR3,
        "m",
        "The box's centre, body axes (from C).",
        _C,
        default=[0.0, 0.0, 0.0],
        when=f"only with {_BOX}",
    ),
    Key(
        "body.shape",
        "box_rotation",
        Kind.MATRIX3,
        "",
        "Body-from-box rotation (columns: the box's axes in body axes); the nearest rotation is "
        "taken.",
        _C,
        default_text="identity",
        when=f"only with {_BOX}",
        bounds="within {ROTATION_REFUSE_TOL} of a rotation",
    ),
    Key(
        "body.shape",
        "cylinder_radius",
        Kind.NUMBER,
        "m",
        "Outer radius of the hollow cylinder (centred on C).",
        _C,
        when=f"required with {_CYL}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "cylinder_length",
        Kind.NUMBER,
        "m",
        "Outer length of the cylinder, end plates included.",
        _C,
        when=f"required with {_CYL}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "cylinder_thickness",
        Kind.NUMBER,
        "m",
        "Thickness of the cylinder's wall and end plates.",
        _C,
        when=f"required with {_CYL}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "cylinder_axis",
        Kind.VECTOR3,
        "",
        "Direction of the cylinder's axis, body axes (any nonzero length).",
        _C,
        when=f"required with {_CYL}",
    ),
    Key(
        "body.shape",
        "rod_radius",
        Kind.NUMBER,
        "m",
        "Radius of the drawn rod.",
        _C,
        default=0.05,
        when=f"only with {_SHAPE_ROD}",
        bounds="> 0",
    ),
    Key(
        "body.shape",
        "rod_start",
        Kind.NUMBER,
        "m",
        "Where the drawn rod starts, along `a` from O' (negative: behind O').",
        _C,
        default=0.0,
        when=f"only with {_SHAPE_ROD}",
    ),
    Key(
        "body.shape",
        "rod_length",
        Kind.NUMBER,
        "m",
        "Length of the drawn rod, from `rod_start` along `a`. A picture only: the masses slide on "
        "an unbounded line; a `masses.p_e` or `initial.p` off the drawn rod gets one warning.",
        _C,
        default=1.0,
        when=f"only with {_SHAPE_ROD}",
        bounds="> 0",
    ),
    # ---- [rod] ---------------------------------------------------------------------------------
    Key(
        "",
        "rod",
        Kind.TABLE,
        "",
        "The line fixed in BR along which the masses slide: through O' along `a`.",
        _R,
    ),
    Key(
        "rod",
        "axis",
        Kind.VECTOR3,
        "",
        "The unit vector `a` along the rod, body axes; positions `p` count along it from O'.",
        _R,
        bounds="unit length within {AXIS_REFUSE_TOL}; one off 1 by more than "
        "{AXIS_NORMALISE_TOL} is normalised with a one-line warning naming its norm",
    ),
    Key(
        "rod",
        "offset",
        Kind.VECTOR3,
        "m",
        "`d`, the vector from C to the rod's reference point O', body axes (zero: the rod passes "
        "through C).",
        _R,
    ),
    # ---- [masses] ------------------------------------------------------------------------------
    Key(
        "",
        "masses",
        Kind.TABLE,
        "",
        "The n masses sliding along the rod (mass i is `m_i` of the paper, 1-based).",
        default_text="no masses (n = 0)",
    ),
    Key(
        "masses",
        "mass",
        Kind.VECTOR_N,
        "kg",
        "`m_i`; the length of this list is n.",
        _R,
        bounds="each {MJ_MINVAL} … {MAX_MASS} kg; n ≤ {MAX_MASSES}",
    ),
    Key(
        "masses",
        "p_e",
        Kind.VECTOR_N,
        "m",
        "The springs' rest positions `p_e,i`: where each mass sits, along `a` from O', when every "
        "spring is at its rest length (Eq. 38). Any order; masses may pass each other.",
        _R,
    ),
    Key(
        "masses",
        "ring_radius",
        Kind.VECTOR_N,
        "m",
        "Each mass a thin ring of this radius about the rod: axial moment `m r²`, transverse "
        "`m r²/2` (Remark 1, Eq. 62). One of `ring_radius`, `inertia_axial` + "
        "`inertia_transverse`, `inertia_body`; used with the effect `mass_inertia`.",
        _C,
        when="optional; not with the other inertia keys",
        bounds="≥ 0",
    ),
    Key(
        "masses",
        "inertia_axial",
        Kind.VECTOR_N,
        "kg·m²",
        "Each mass's moment of inertia about the rod through its own centre (axisymmetric mass); "
        "given with `inertia_transverse`.",
        _C,
        when="optional, with inertia_transverse; not with the other inertia keys",
        bounds="≥ 0, at most twice the transverse moment",
    ),
    Key(
        "masses",
        "inertia_transverse",
        Kind.VECTOR_N,
        "kg·m²",
        "Each mass's moment of inertia about any axis perpendicular to the rod through its centre.",
        _C,
        when="optional, with inertia_axial; not with the other inertia keys",
        bounds="≥ 0",
    ),
    Key(
        "masses",
        "inertia_body",
        Kind.MATRICES_N,
        "kg·m²",
        "Each mass's full inertia matrix about its own centre, body axes (`P_iᵀ J_i P_i` of "
        "Remark 1, Eq. 54).",
        _C,
        when="optional; not with the other inertia keys",
        bounds="symmetric, positive semidefinite, A + B ≥ C",
    ),
    # ---- [springs] -----------------------------------------------------------------------------
    Key(
        "",
        "springs",
        Kind.TABLE,
        "",
        "The n + 1 spring elements wall – m_1 – m_2 – … – m_n – wall (Eq. 38); see *Springs* above.",
        default_text="no springs",
    ),
    Key(
        "springs",
        "k_linear",
        Kind.VECTOR_N1,
        "N/m",
        "Linear stiffnesses `k_i^l`; spring 1 joins the near wall and m_1, spring i joins m_(i-1) "
        "and m_i, spring n + 1 joins m_n and the far wall.",
        _C,
        default_text="zeros",
        when="required by the effect springs.linear (n > 0)",
        bounds="≥ 0",
    ),
    Key(
        "springs",
        "k_cubic",
        Kind.VECTOR_N1,
        "N/m³",
        "Cubic stiffnesses `k_i^n`, the same springs in parallel (force `k^n x³` at extension x).",
        _C,
        default_text="zeros",
        when="required by the effect springs.cubic (n > 0)",
        bounds="≥ 0",
    ),
    # ---- [gravity] -----------------------------------------------------------------------------
    Key(
        "",
        "gravity",
        Kind.TABLE,
        "",
        "Uniform gravity on BR and every mass (Eq. 46), acting only with the effect `gravity`.",
        default_text=f"vector = [{', '.join(f'{g:g}' for g in DEFAULT_GRAVITY)}]",
    ),
    Key("gravity", "vector", Kind.VECTOR3, "m/s²", "The acceleration of gravity, inertial.", _R),
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
    # ---- [external_torque] ---------------------------------------------------------------------
    Key(
        "",
        "external_torque",
        Kind.TABLE,
        "",
        "A given torque on BR, body axes (Remark 2): `τ_g(t) = constant + amplitude · "
        "cos(frequency · t)`. Acts with the effect `external_torque`.",
        _C,
        when="required by the effect external_torque",
    ),
    Key(
        "external_torque",
        "constant",
        Kind.VECTOR3,
        "N·m",
        "Constant part, body axes.",
        default=[0.0, 0.0, 0.0],
    ),
    Key(
        "external_torque",
        "amplitude",
        Kind.VECTOR3,
        "N·m",
        "Amplitude of the cosine part, body axes.",
        default=[0.0, 0.0, 0.0],
    ),
    Key("external_torque", "frequency", Kind.NUMBER, "rad/s", "Its frequency.", default=0.0),
    # ---- [solver] ------------------------------------------------------------------------------
    Key(
        "",
        "solver",
        Kind.TABLE,
        "",
        "How the analytic plant (and Pinocchio) integrate: scipy `solve_ivp`.",
        default_text="the defaults below",
    ),
    Key(
        "solver",
        "method",
        Kind.CHOICE,
        "",
        "The scipy integrator.",
        default=SolverMethod.DOP853.value,
        choices=SolverMethod,
    ),
    Key("solver", "rtol", Kind.NUMBER, "", "Relative tolerance.", default=1e-12, bounds="> 0"),
    Key(
        "solver",
        "atol",
        Kind.NUMBER,
        "",
        "Absolute tolerance, in each coordinate's unit (m, 1, m).",
        default=1e-13,
        bounds="> 0",
    ),
    Key(
        "solver",
        "max_step",
        Kind.NUMBER,
        "s",
        "Largest step the integrator may take.",
        default_text="no limit",
        bounds="> 0",
    ),
    # ---- [output] ------------------------------------------------------------------------------
    Key(
        "",
        "output",
        Kind.TABLE,
        "",
        "Horizon and sampling, shared by every plant: samples at `0, 1/rate, 2/rate, …` and at "
        "`t_end` exactly.",
        default_text="the defaults below",
    ),
    Key(
        "output",
        "t_end",
        Kind.NUMBER,
        "s",
        "The horizon.",
        default=20.0,
        bounds="> 0, at least one MuJoCo step; ≤ {MAX_OUTPUT_SAMPLES} samples",
    ),
    Key(
        "output",
        "rate",
        Kind.NUMBER,
        "Hz",
        "Samples per second; `1/rate` a whole number of MuJoCo steps.",
        default=100.0,
        bounds="> 0",
    ),
    # ---- [mujoco] ------------------------------------------------------------------------------
    Key(
        "",
        "mujoco",
        Kind.TABLE,
        "",
        "The MuJoCo twin's settings.",
        default_text="the defaults below",
    ),
    Key(
        "mujoco",
        "integrator",
        Kind.CHOICE,
        "",
        "MuJoCo's integrator.",
        default=MjIntegrator.RK4.value,
        choices=MjIntegrator,
    ),
    Key(
        "mujoco",
        "timestep",
        Kind.NUMBER,
        "s",
        "MuJoCo's fixed step.",
        default=2.5e-4,
        bounds="> 0; ≤ {MAX_MUJOCO_STEPS} steps per run",
    ),
    Key(
        "mujoco",
        "spring_model",
        Kind.CHOICE,
        "",
        "How MuJoCo represents the springs.",
        default=SpringModel.TENDON.value,
        choices=SpringModel,
    ),
    # ---- [hard_case] ---------------------------------------------------------------------------
    Key(
        "",
        "hard_case",
        Kind.TABLE,
        "",
        "The criterion of a hard case (`validation/scenes/hard/*.toml`): the checks, their "
        "references, bounds and reasons. The loader keeps the table verbatim; the hard-case suite "
        "validates it (format: `docs/hard_cases.md`).",
        default_text="none (not a hard case)",
    ),
    # ---- [thresholds] --------------------------------------------------------------------------
    Key(
        "",
        "thresholds",
        Kind.TABLE,
        "",
        "Overrides of the comparison's named thresholds (`tumble validate`, the pytest plugin), "
        "by the names listed below. The loader checks the entries' shape, the comparison their names.",
        default_text="the defaults",
    ),
    Key(
        "thresholds",
        "<name>",
        Kind.NUMBER_OR_VALUE_TABLE,
        "the threshold's",
        'A new bound for the named threshold: a number, or `{{ value = …, reason = "…" }}`.',
        bounds="finite, ≥ 0; a known name",
    ),
    Key(
        "thresholds",
        "hard_<criterion>",
        Kind.NUMBER_OR_STRING,
        "the criterion's",
        "A criterion of the hard-case suite (`validation/scenes/hard/*.toml`): a bound, or "
        "`hard_criterion`, the criterion in a sentence.",
        bounds="a number ≥ 0 or a string",
    ),
    Key(
        "thresholds.<name>", "value", Kind.NUMBER, "the threshold's", "The bound.", _R, bounds="≥ 0"
    ),
    Key(
        "thresholds.<name>",
        "reason",
        Kind.STRING,
        "",
        "Why this bound; shown in reports.",
        default_text='"set by the scene"',
    ),
)
"""Every key, in the order of the reference."""

KEY_INDEX: Mapping[tuple[str, str], Key] = {(k.table, k.key): k for k in KEYS}
"""``(table, key) -> Key``."""

TABLES: tuple[str, ...] = tuple(k.dotted for k in KEYS if k.kind is Kind.TABLE)
"""Every table, in the order of the reference (``scene``, ``body``, ``body.shape``, ...)."""

_WILDCARDS: Mapping[str, tuple[tuple[str, str], ...]] = {
    "thresholds": (("hard_", "hard_<criterion>"), ("", "<name>")),
}


def key_spec(table: str, key: str) -> Key:
    """The declaration of ``key`` in ``table`` (generic table names: ``thresholds.<name>``).

    Raises:
        LookupError: the key is not declared (a loader reading it is a programming error).
    """
    spec = KEY_INDEX.get((table, key))
    if spec is not None:
        return spec
    for prefix, generic in _WILDCARDS.get(table, ()):
        if key.startswith(prefix):
            return KEY_INDEX[table, generic]
    raise LookupError(f"scene key {table + '.' if table else ''}{key} is not declared in KEYS")


VERBATIM_TABLES: frozenset[str] = frozenset({"hard_case"})
"""Tables kept verbatim for a later layer: their keys are not declared here (the hard-case suite
declares and checks ``[hard_case]``)."""


def declared_keys(table: str) -> tuple[str, ...] | None:
    """The keys and sub-tables declared in ``table`` (generic name, ``""`` for the document), in
    the order of the reference; None for a table whose keys are not declared here (a verbatim
    table, or one of any names such as ``[thresholds]``)."""
    if table in VERBATIM_TABLES or table in _WILDCARDS:
        return None
    return tuple(k.key for k in KEYS if k.table == table)


def generic_table(table: str, key: str) -> str:
    """The generic name of the sub-table ``key`` of ``table`` (``thresholds.<name>``)."""
    spec = key_spec(table, key)
    return spec.dotted


CHOICE_MEANINGS: Mapping[StrEnum, str] = {
    Effect.GRAVITY: "Uniform gravity on BR and every mass (Eq. 46), from `[gravity]`.",
    Effect.SPRINGS_LINEAR: "The linear spring elements `k^l` (Eq. 38), from `springs.k_linear`.",
    Effect.SPRINGS_CUBIC: "The cubic spring elements `k^n` (Eq. 38), from `springs.k_cubic`.",
    Effect.MASS_INERTIA: "The masses' own rotational inertia (Remark 1, Eq. 54), from "
    "`masses.ring_radius`, `inertia_axial` + `inertia_transverse` or `inertia_body`; without "
    "it the masses are points.",
    Effect.CONTROL_OMEGA: "Track the angular-velocity requirement `[control.omega]` (Eqs. 82–86).",
    Effect.CONTROL_MASSES: "Track the mass-position requirement `[control.masses]` (Eqs. 77–81).",
    Effect.EXTERNAL_TORQUE: "The given torque `[external_torque]` on BR (Remark 2, Eq. 61).",
    ShapeKind.NONE: "No picture.",
    ShapeKind.BOX_AND_ROD: "A box (`box_*`) and the rod: Example 1's block with a corner rod.",
    ShapeKind.HOLLOW_CYLINDER_AND_ROD: "A closed hollow cylinder (`cylinder_*`) centred on C "
    "and the rod: Example 2.",
    Weighting.M_INV: "`N = M⁻¹`: Gauss's principle, the paper's choice (Eqs. 74, B12).",
    Weighting.M_INV2: "`N = M⁻²` (Eq. B13).",
    Weighting.IDENTITY: "`N = I`: the plain Euclidean norm of the generalized control force.",
    SolverMethod.DOP853: "Explicit Runge-Kutta of order 8 (the paper used MATLAB's ode113).",
    SolverMethod.RK45: "Explicit Runge-Kutta of order 5(4).",
    SolverMethod.RK23: "Explicit Runge-Kutta of order 3(2).",
    SolverMethod.RADAU: "Implicit Runge-Kutta (Radau IIA) of order 5.",
    SolverMethod.BDF: "Implicit multistep (backward differentiation).",
    SolverMethod.LSODA: "Adams/BDF with automatic stiffness detection.",
    MjIntegrator.EULER: "Semi-implicit Euler.",
    MjIntegrator.RK4: "Fourth-order Runge-Kutta, the controller evaluated in every stage.",
    MjIntegrator.IMPLICIT: "Implicit in velocity.",
    MjIntegrator.IMPLICITFAST: "Implicit in velocity, without the Coriolis derivatives.",
    SpringModel.TENDON: "Fixed tendons with MuJoCo's polynomial stiffness (energy counted by "
    "MuJoCo).",
    SpringModel.ACTUATOR: "One general actuator per spring (affine bias plus a cubic term).",
}
"""What each allowed string of a ``CHOICE`` key means."""


__all__ = [
    "CHOICE_MEANINGS",
    "DEFAULT_GRAVITY",
    "KEYS",
    "KEY_INDEX",
    "NO_DEFAULT",
    "TABLES",
    "VERBATIM_TABLES",
    "Key",
    "Kind",
    "Need",
    "declared_keys",
    "generic_table",
    "key_spec",
]
