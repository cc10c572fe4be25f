"""Scene files: one TOML description drives every engine.

A scene is data only: it is parsed with :mod:`tomllib` and validated into frozen dataclasses; nothing
in it is ever evaluated. Every error is a :class:`ValueError` whose message starts with the dotted
name of the offending field and shows the offending value, e.g.
``masses.mass[1]: must be positive (got -3.0)``.

Units are SI. Frames: vectors marked *body* are in BR's principal axes at its centre of mass C
(the paper's xyz); vectors marked *inertial* are in XYZ with Z up. Quaternions are w-first.
Mass and control indices in files are 1-based, as in the paper (masses 1, 2, 4 of Example 2); the
loaded records hold 0-based indices.

Every key, with its type, unit, default and meaning, is declared in :mod:`analytic.scene_keys`
(rendered as ``docs/scene-format.md``); ``analytic/scenes/paper_example1.toml`` is a fully commented
example of every table, ``analytic/scenes/spacecraft_slosh.toml`` one of a system beyond the paper.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
import stat
import tomllib
import warnings
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from analytic.builtin_scenes import builtin_scene_names, builtin_scene_path
from analytic.effects import (
    CONTROL_EFFECTS,
    Effect,
    MjIntegrator,
    ShapeKind,
    SolverMethod,
    SpringModel,
    Weighting,
)
from analytic.kinematics import S, axis_angle_quat, matrix_quat, quat_mul, udot_of
from analytic.scene_keys import (
    DEFAULT_GRAVITY,
    NO_DEFAULT,
    Key,
    Kind,
    Need,
    declared_keys,
    generic_table,
    key_spec,
)

# Quaternion norm tolerances on load: silently exact below, renormalised with a warning up
# to the refusal bound, refused above it unless the scene asks to start off the manifold (Eq. 58).
QUAT_NORMALISE_TOL = 1e-12
QUAT_REFUSE_TOL = 1e-3
# A reference-frame matrix may be rounded (the paper prints Eq. 63 to 4 digits, orthogonal to ~1e-4);
# it is replaced by the nearest rotation, and refused when further than this from orthogonal.
ROTATION_REFUSE_TOL = 1e-2
# The rod axis a: a printed axis is rounded (Example 1's a has |a| = 0.99997); a norm within
# AXIS_REFUSE_TOL of 1 is normalised, with a one-line warning naming the norm when it is off 1 by
# more than AXIS_NORMALISE_TOL (round-off of a unit vector written with every digit, ~1e-16, is
# below it, so a normalised axis written back loads unchanged and without a warning); further off
# it is refused.
AXIS_REFUSE_TOL = 1e-3
AXIS_NORMALISE_TOL = 1e-12
# A rotation matrix orthonormal to this (max |MᵀM − I|, det > 0) is kept as given; otherwise the
# nearest rotation is taken. Round-off of a rotation written with every digit is ~1e-16, so a
# loaded matrix written back loads unchanged.
ROTATION_EXACT_TOL = 1e-12

# --- Sizes that can be held -------------------------------------------------------------------
# A scene file is a page of numbers: the largest built-in one (hard/many_masses, 200 masses) is
# about 10 KB. 1 MiB leaves a hundredfold margin and is still read at once; anything larger (a
# device such as /dev/zero, a log given by mistake) is refused before it is read.
MAX_SCENE_BYTES = 1 << 20
# The reference numpy model and MuJoCo's dense mass matrix hold (n+7)² doubles: 0.8 GB each at
# n = 10⁴ (ten times the largest benchmarked n = 1000); a longer list is a mistake, not a scene.
MAX_MASSES = 10_000
# Lists and tables nested in one another: the deepest value of the format is four levels below the
# document ([hard_case] checks, masses.inertia_body: a table, a list, a matrix, its rows). Python's
# TOML parser recurses once per level of brackets (its RecursionError comes near 300-1000 levels),
# and dotted keys build deeper tables without it (`a.a.a... = 1`), which every later walk of the
# document (repr, copies, JSON) would recurse through: deeper than this is refused at load.
MAX_SCENE_NESTING = 16
# Every output sample holds the state, accelerations, control and invariants of each plant (about
# 1 KB for the paper scenes, n + 7 ≤ 12): 10⁶ samples are ~1 GB per plant before the comparison,
# figures and recording, and a hundred times the largest built-in grid (1000 s at 10 Hz).
MAX_OUTPUT_SAMPLES = 1_000_000
# MuJoCo steps of one run: 10⁹ steps at the measured 10-17 µs per RK4 step with the controller
# are three to five hours; the longest built-in run is 2·10⁶ steps (hard/long_horizon).
MAX_MUJOCO_STEPS = 1_000_000_000
# t_end·rate within this distance of an integer (in sample intervals, so the last interval is never
# longer than 1/rate by more than this fraction) puts t_end on the output grid: decimal horizons
# and rates are not exact in binary (0.3 s x 10 Hz = 3.0000000000000004); the product's round-off,
# at most 2.2e-16 x MAX_OUTPUT_SAMPLES = 2.2e-10 intervals, stays below it. A sample interval must
# fit a whole number of MuJoCo steps to the same relative tolerance
# (mj_bridge.plan.STEP_FIT_RTOL).
GRID_RTOL = 1e-9

# --- What the MuJoCo twin can represent (checked here so that a scene is refused at load, naming
# its field, rather than by MuJoCo's compiler after the analytic plant has run) -----------------
# MuJoCo's mjMINVAL: its compiler refuses a moving body whose mass or any principal moment of
# inertia is below this (and one whose moments violate A + B >= C, checked exactly).
MJ_MINVAL = 1e-15
# model_xml gives each mass body without an inertia of its own an isotropic inertia
# eps = max(POINT_INERTIA_REL · min(J_BR), POINT_INERTIA_MIN) (MuJoCo refuses it without) and takes
# exactly that much off BR's principal moments, so the system's inertia is unchanged
# (model_xml.builder imports these two).
POINT_INERTIA_REL = 1e-9
POINT_INERTIA_MIN = 1e-12
# A mass's principal moments may violate A + B >= C by this much relative round-off (a ring's
# A + B = C after an eigen-decomposition); model_xml sets C = A + B then. Beyond it, MuJoCo refuses.
TRIANGLE_RTOL = 1e-12
# Upper bounds on masses (kg) and moments of inertia (kg·m²): the model forms squares and fourth
# powers of them (the M⁻² weighting and its Schur complement, energies, momenta times lever arms);
# at 1e30 kg (the mass of the Sun) and 1e40 kg·m² their fourth powers (1e120, 1e160) stay far
# inside the double range (1e308), where 1e300 overflows at once.
MAX_MASS = 1e30
MAX_INERTIA = 1e40


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


# ----------------------------------------------------------------------------------------------
# Records
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BodyShape:
    """Pictures of BR for viewers; massless, never used by the dynamics.

    ``box_center`` (body, m) and ``box_rotation`` (body-from-box rotation, 3x3) place the box;
    the hollow cylinder is centred on C with its axis along ``cylinder_axis`` (body). The rod runs
    along ``a`` from ``d + rod_start·a`` for ``rod_length`` metres.
    """

    kind: ShapeKind = ShapeKind.NONE
    box_half_sizes: np.ndarray = field(default_factory=lambda: _frozen(np.zeros(3)))
    box_center: np.ndarray = field(default_factory=lambda: _frozen(np.zeros(3)))
    box_rotation: np.ndarray = field(default_factory=lambda: _frozen(np.eye(3)))
    cylinder_radius: float = 0.0
    cylinder_length: float = 0.0
    cylinder_thickness: float = 0.0
    cylinder_axis: np.ndarray = field(default_factory=lambda: _frozen([1.0, 0.0, 0.0]))
    rod_radius: float = 0.05
    rod_start: float = 0.0
    rod_length: float = 1.0


@dataclass(frozen=True)
class Body:
    """The rigid body BR (body B plus rod R).

    Attributes:
        mass: ``m_BR``, kg.
        inertia: principal moments ``J = diag(J_x, J_y, J_z)`` about C, kg·m², shape (3,).
        shape: pictures only.
    """

    mass: float
    inertia: np.ndarray
    shape: BodyShape = field(default_factory=BodyShape)


@dataclass(frozen=True)
class Rod:
    """The rod line along which the masses slide.

    Attributes:
        axis: unit vector ``a`` in body axes, shape (3,).
        offset: ``d``, the vector from C to the reference point O' on the rod, body axes, m, shape (3,).
    """

    axis: np.ndarray
    offset: np.ndarray


@dataclass(frozen=True)
class Masses:
    """The n sliding masses.

    Attributes:
        mass: ``m``, kg, shape (n,).
        p_e: equilibrium positions along the rod from O', m, shape (n,).
        inertia: each mass's rotational inertia about its own centre, in body axes (the
            ``P_iᵀ J_i P_i`` of Remark 1, Eq. 54), kg·m², shape (n, 3, 3); zeros for point masses.
    """

    mass: np.ndarray
    p_e: np.ndarray
    inertia: np.ndarray

    @property
    def n(self) -> int:
        return int(self.mass.shape[0])


@dataclass(frozen=True)
class Springs:
    """The n+1 spring elements of Eq. (38): spring i joins mass i-1 and mass i (0-based: spring 0
    joins O'-side end and mass 0, spring n joins mass n-1 and the far end).

    Attributes:
        k_linear: ``k^l``, N/m, shape (n+1,).
        k_cubic: ``k^n``, N/m³, shape (n+1,).
    """

    k_linear: np.ndarray
    k_cubic: np.ndarray
    given: frozenset[str] = frozenset({"k_linear", "k_cubic"})
    """Which of ``k_linear``, ``k_cubic`` the scene gave (an effect needs its constants given)."""


@dataclass(frozen=True)
class InitialState:
    """State at t = 0 in the paper's coordinates.

    Attributes:
        R, Rdot: position (m) and velocity (m/s) of C, inertial, shape (3,).
        u: attitude quaternion (w first), body -> inertial, shape (4,).
        omega: body-axis angular velocity, rad/s, shape (3,).
        p, pdot: mass positions (m) and velocities (m/s) along the rod from O', shape (n,).
    """

    R: np.ndarray
    Rdot: np.ndarray
    u: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    pdot: np.ndarray

    @property
    def udot(self) -> np.ndarray:
        """``u̇(0)`` from ``ω(0)``: ``u̇ = Hᵀω / (4|u|²)`` (= ¼Hᵀω for unit u; Eq. 12 inverted)."""
        u = self.u
        H = np.array(
            [
                [-u[1], u[0], u[3], -u[2]],
                [-u[2], -u[3], u[0], u[1]],
                [-u[3], u[2], -u[1], u[0]],
            ]
        )
        return 2.0 * H.T @ self.omega / (4.0 * float(u @ u))

    def q0(self) -> np.ndarray:
        """``q(0) = [R, u, p]`` (Eq. 44), shape (n+7,)."""
        return np.concatenate([self.R, self.u, self.p])

    def qdot0(self) -> np.ndarray:
        """``q̇(0) = [Ṙ, u̇, ṗ]``, shape (n+7,)."""
        return np.concatenate([self.Rdot, self.udot, self.pdot])


@dataclass(frozen=True)
class Stabilization:
    """Baumgarte parameters of the quaternion-norm constraint, Eq. (58): ``φ̈ + δ1 φ̇ + δ2 φ = 0``."""

    delta1: float = 0.5
    delta2: float = 8.0


@dataclass(frozen=True)
class OmegaTrack:
    """Angular-velocity requirement ``ω̄_i(t) = b_i cos(σ_i t)`` (Eq. 76) on the chosen components.

    Attributes:
        components: 0-based body axes controlled (Remark 4), tuple of distinct ints in 0..2.
        b: amplitudes, rad/s, shape (3,) (all three stored; only ``components`` are enforced).
        sigma: frequencies, rad/s, shape (3,).
        gain: the matrix ``P`` of Eq. (B6) for the velocity-level error ``e = Hu̇ - ω̄``, restricted to
            ``components``, shape (k, k); ``γ I`` for the paper's Eq. (84).
    """

    components: tuple[int, ...]
    b: np.ndarray
    sigma: np.ndarray
    gain: np.ndarray


@dataclass(frozen=True)
class MassTrack:
    """Mass-position requirement ``p̄_i = p_e,i + l_i cos(λ_i t)`` (Eq. 75) for a subset of masses.

    Attributes:
        indices: 0-based indices of the controlled masses (Remark 4), shape (k,).
        l: amplitudes, m, shape (k,).
        lam: frequencies λ, rad/s, shape (k,).
        alpha, beta: error-dynamics gains of Eq. (78), 1/s and 1/s², shape (k,).
    """

    indices: tuple[int, ...]
    l: np.ndarray
    lam: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray


@dataclass(frozen=True)
class Control:
    """Control requirements and the cost weighting of Appendix B."""

    weighting: Weighting = Weighting.M_INV
    omega: OmegaTrack | None = None
    masses: MassTrack | None = None


@dataclass(frozen=True)
class ExternalTorque:
    """A given body-axis torque (Remark 2): ``τ_g(t) = constant + amplitude·cos(frequency·t)``, N·m."""

    constant: np.ndarray
    amplitude: np.ndarray
    frequency: float = 0.0

    def at(self, t: float) -> np.ndarray:
        return self.constant + self.amplitude * math.cos(self.frequency * t)


@dataclass(frozen=True)
class SolverSettings:
    """Analytic-engine integration settings (scipy ``solve_ivp``)."""

    method: SolverMethod = SolverMethod.DOP853
    rtol: float = 1e-12
    atol: float = 1e-13
    max_step: float = math.inf


@dataclass(frozen=True)
class OutputSettings:
    """Horizon and sampling shared by every engine.

    The output grid is ``0, 1/rate, 2/rate, ...`` up to ``t_end``, with ``t_end`` appended when it
    is not on that grid (:meth:`times`): a trajectory always starts with its t = 0 sample and ends
    at ``t_end`` exactly. At most :data:`MAX_OUTPUT_SAMPLES` samples.
    """

    t_end: float = 20.0
    rate: float = 100.0

    def __post_init__(self) -> None:
        _check_output(self.t_end, self.rate, "output.t_end", "output.rate", blame=None)

    def with_t_end(self, t_end: float | None, name: str = "t_end") -> OutputSettings:
        """These settings with another horizon (``self`` for None); a bad one is refused as ``name``."""
        if t_end is None:
            return self
        _check_output(t_end, self.rate, name, "output.rate", blame=name)
        return OutputSettings(t_end=float(t_end), rate=self.rate)

    def times(self) -> np.ndarray:
        """Output times ``0, 1/rate, ..., t_end`` (t_end included, and appended when it is not a
        multiple of ``1/rate``), s."""
        return output_times(self.t_end, self.rate)


def output_times(t_end: float, rate: float) -> np.ndarray:
    """The output grid ``0, 1/rate, 2/rate, ...``, ending at ``t_end`` exactly, s.

    ``t_end`` replaces the last grid point when ``t_end·rate`` is within :data:`GRID_RTOL` of an
    integer, else it is appended after the last grid point below it.
    """
    x = t_end * rate
    k = round(x)
    if k >= 1 and abs(x - k) <= GRID_RTOL:
        t = np.arange(k + 1) / rate
        t[-1] = t_end
        return t
    k = math.floor(x)
    return np.concatenate([np.arange(k + 1) / rate, [t_end]])


def _check_output(t_end: Any, rate: Any, t_name: str, rate_name: str, blame: str | None) -> None:
    """Horizon and rate positive and finite, at most MAX_OUTPUT_SAMPLES samples. ``blame`` names the
    field refused for too many samples (None: whichever is further from its default)."""
    t_end = _as_number(t_end, t_name, positive=True)
    rate = _as_number(rate, rate_name, positive=True)
    samples = t_end * rate + 2  # inf when the product overflows
    if samples > MAX_OUTPUT_SAMPLES:
        if blame is None:
            blame = t_name if t_end / 20.0 >= rate / 100.0 else rate_name
        value = t_end if blame == t_name else rate
        raise ValueError(
            f"{blame}: too large: {t_end:g} s at {rate:g} Hz makes {samples:.3g} output samples, "
            f"at most {MAX_OUTPUT_SAMPLES:,} (got {value!r})"
        )


@dataclass(frozen=True)
class MujocoSettings:
    """MuJoCo-twin settings."""

    integrator: MjIntegrator = MjIntegrator.RK4
    timestep: float = 2.5e-4
    spring_model: SpringModel = SpringModel.TENDON


@dataclass(frozen=True)
class Scene:
    """A validated scene. Build one with :func:`load_scene` or :func:`scene_from_dict`."""

    name: str
    description: str
    effects: frozenset[Effect]
    body: Body
    rod: Rod
    masses: Masses
    springs: Springs
    gravity: np.ndarray
    initial: InitialState
    stabilization: Stabilization
    control: Control
    external_torque: ExternalTorque | None
    solver: SolverSettings
    output: OutputSettings
    mujoco: MujocoSettings
    source: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of sliding masses."""
        return self.masses.n

    def has(self, effect: Effect) -> bool:
        return effect in self.effects

    @property
    def controlled(self) -> bool:
        return bool(self.effects & CONTROL_EFFECTS)

    def replace(self, **changes: Any) -> Scene:
        """A copy with top-level fields replaced (e.g. ``output=OutputSettings(t_end=60)``)."""
        return dataclasses.replace(self, **changes)

    def with_effects(self, effects: set[Effect] | frozenset[Effect]) -> Scene:
        """A copy with another effect set, validated like a loaded scene."""
        new = dataclasses.replace(self, effects=frozenset(effects))
        _check_effects_consistent(new)
        _check_initial_quantities(new)
        return new


# ----------------------------------------------------------------------------------------------
# Reading helpers: every value passes through one of these, so every error names its field.
# ----------------------------------------------------------------------------------------------


_VECTOR_KINDS = (Kind.VECTOR3, Kind.VECTOR4, Kind.VECTOR_N, Kind.VECTOR_N1, Kind.VECTOR_K)


class SceneText(str):
    """Text a scene file gives (its name, description, a threshold's reason), kept verbatim.

    A plain ``str`` in every respect; the JSON writers (``validation.report.provenance``) carry it as it
    is, where text the code writes itself may not be a placeholder such as ``"unknown"`` or
    ``"nan"``: a scene's description may well read "unknown"."""

    verbatim_text = True


class _Table:
    """A TOML table being read: tracks its dotted path and which keys were consumed.

    Every key is read through its declaration in :data:`analytic.scene_keys.KEYS` (``schema`` is
    the table's generic name there, e.g. ``thresholds.<name>``): reading an undeclared key, or a
    key as another kind than declared, is a programming error (``LookupError``, ``TypeError``),
    and a key's default is the declared one. A caller passes a default of its own only for a key
    declared without one (a default that depends on n, such as zeros of length n + 1).
    """

    def __init__(self, data: Any, path: str, schema: str | None = None):
        if not isinstance(data, Mapping):
            raise ValueError(f"{path or 'scene'}: must be a table (got {_show(data)})")
        self.data = data
        self.path = path
        self.schema = path if schema is None else schema
        self.used: set[str] = set()

    def name(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def spec(self, key: str, *kinds: Kind) -> Key:
        """The declaration of ``key``; ``kinds``: those the caller reads it as."""
        spec = key_spec(self.schema, key)
        if kinds and spec.kind not in kinds:
            raise TypeError(
                f"the loader reads {spec.dotted} as {' or '.join(kinds)}, declared {spec.kind}"
            )
        return spec

    def has(self, key: str) -> bool:
        self.spec(key)
        return key in self.data

    def raw(self, key: str, default: Any = ..., *, kinds: tuple[Kind, ...] = ()) -> Any:
        spec = self.spec(key, *kinds)
        if default is not ... and spec.default is not NO_DEFAULT:
            raise LookupError(
                f"{spec.dotted}: has a declared default; the loader must not pass one"
            )
        if default is ... and spec.default is not NO_DEFAULT:
            default = spec.default
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                raise ValueError(f"{self.name(key)}: missing required key")
            return default
        return self.data[key]

    def table(self, key: str) -> _Table | None:
        """The sub-table ``key``; None when it is absent and optional, refused when required."""
        spec = self.spec(key, Kind.TABLE)
        if key not in self.data:
            if spec.need is Need.REQUIRED:
                raise ValueError(f"{self.name(key)}: missing required table")
            self.used.add(key)
            return None
        return _Table(self.raw(key), self.name(key), generic_table(self.schema, key))

    def table_or_empty(self, key: str) -> _Table:
        """The sub-table ``key``, or an empty one (every key at its default) when it is absent."""
        t = self.table(key)
        return t if t is not None else _Table({}, self.name(key), generic_table(self.schema, key))

    def number(self, key: str, default: Any = ..., *, positive=False, nonneg=False) -> float:
        v = self.raw(key, default, kinds=(Kind.NUMBER,))
        return _as_number(v, self.name(key), positive=positive, nonneg=nonneg)

    def vector(self, key: str, length: int | None = None, default: Any = ..., **kw) -> np.ndarray:
        v = self.raw(key, default, kinds=_VECTOR_KINDS)
        return _as_vector(v, self.name(key), length, **kw)

    def string(self, key: str, default: Any = ...) -> str:
        v = self.raw(key, default, kinds=(Kind.STRING,))
        if not isinstance(v, str):
            raise ValueError(f"{self.name(key)}: must be a string (got {_show(v)})")
        return SceneText(v)

    def boolean(self, key: str, default: Any = ...) -> bool:
        v = self.raw(key, default, kinds=(Kind.BOOLEAN,))
        if not isinstance(v, bool):
            raise ValueError(f"{self.name(key)}: must be true or false (got {_show(v)})")
        return v

    def enum(self, key: str, kind: type, default: Any = ...):
        return as_enum(kind, self.raw(key, default, kinds=(Kind.CHOICE,)), self.name(key))

    def finish(self) -> None:
        """Refuse a key given here that the loader did not read: one not allowed in this case
        (the declaration's ``when``: ``box_center`` without a box), else an unknown one."""
        extra = sorted(set(self.data) - self.used)
        if not extra:
            return
        key = extra[0]
        got = _show(self.data[key])
        try:
            spec = key_spec(self.schema, key)
        except LookupError:
            message = _unknown_key_message(self.name(key), key, self.data[key], self.schema)
            raise ValueError(message) from None
        raise ValueError(
            f"{self.name(key)}: not used here: {spec.when or 'not allowed'} (got {got})"
        )


def _unknown_key_message(dotted: str, key: Any, value: Any, schema: str) -> str:
    """``dotted: unknown key (did you mean 'lambda'?; ...) (got ...)``: the closest declared name
    at that level (:func:`difflib.get_close_matches`), and every declared name there."""
    names = declared_keys(schema) or ()
    close = difflib.get_close_matches(str(key), names, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    where = f" in [{schema}]" if schema else ""
    known = f"known{where}: {', '.join(names)}"
    if isinstance(value, Mapping):  # its content is not the point: its name is
        return f"{dotted}: unknown table ({hint}{known}) (got a table of {len(value)} keys)"
    return f"{dotted}: unknown key ({hint}{known}) (got {_show(value)})"


def _refuse_unknown_keys(data: Mapping[str, Any]) -> None:
    """Refuse, before anything is read, a table or key that is not declared at its level
    (:data:`analytic.scene_keys.KEYS`), naming it and the closest declared name: a misspelt
    ``[mass]`` or ``lamda`` is named as such, never reported as the missing or mis-sized key it
    leaves behind. Tables are walked level by level in the document's order; a verbatim table
    (``[hard_case]``) and the names of ``[thresholds]`` are checked by the layers that own them;
    a value of the wrong type is left to the reader that names it."""
    queue: deque[tuple[Mapping[str, Any], str, str]] = deque([(data, "", "")])
    while queue:
        node, path, schema = queue.popleft()
        names = declared_keys(schema)
        for key, value in node.items():
            dotted = f"{path}.{key}" if path else str(key)
            if names is not None and key not in names:
                raise ValueError(_unknown_key_message(dotted, key, value, schema))
            if not isinstance(value, Mapping):
                continue
            try:
                sub = generic_table(schema, key)
            except LookupError:  # a verbatim table's own content
                continue
            if key_spec(schema, key).kind in (Kind.TABLE, Kind.NUMBER_OR_VALUE_TABLE):
                queue.append((value, dotted, sub))


def as_enum(kind: type, value: Any, name: str) -> Any:
    """``value`` as a member of the enum ``kind``, or ValueError naming ``name``, the value and
    the choices."""
    if isinstance(value, kind):
        return value
    try:
        return kind(value)
    except ValueError:
        allowed = ", ".join(repr(e.value) for e in kind)
        raise ValueError(f"{name}: unknown value {_show(value)} (allowed: {allowed})") from None


def _show(v: Any) -> str:
    """``repr(v)``, but an integer too long to read is shown by its number of digits."""
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 10**20:
        # (from its bit length: str() of an integer of more than 4300 digits raises)
        return f"an integer of about {int(abs(v).bit_length() * math.log10(2)) + 1} digits"
    try:
        r = repr(v)
    except ValueError:  # it holds an integer of more than 4300 digits
        return "a value holding an integer too long to show"
    if len(r) > _SHOW_MAX:  # a long list: its head and its length, so the message stays a line
        size = f"{len(v)} entries" if isinstance(v, list | tuple) else f"{len(r)} characters"
        return f"{r[: _SHOW_MAX // 2]}... ({size})"
    return r


_SHOW_MAX = 200  # characters of a bad value quoted in a message


def _as_number(v: Any, name: str, *, positive=False, nonneg=False) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ValueError(f"{name}: must be a number (got {_show(v)})")
    try:
        x = float(v)
    except OverflowError:  # an integer literal beyond the double range
        raise ValueError(f"{name}: must be finite (got {_show(v)})") from None
    if not math.isfinite(x):
        raise ValueError(f"{name}: must be finite (got {_show(v)})")
    if positive and not x > 0:
        raise ValueError(f"{name}: must be positive (got {_show(v)})")
    if nonneg and not x >= 0:
        raise ValueError(f"{name}: must be non-negative (got {_show(v)})")
    return x


def _as_vector(v: Any, name: str, length: int | None = None, *, positive=False, nonneg=False):
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, list | tuple):
        raise ValueError(f"{name}: must be a list of numbers (got {_show(v)})")
    if length is not None and len(v) != length:
        raise ValueError(f"{name}: must have {length} entries (got {len(v)}: {_show(v)})")
    out = [_as_number(x, f"{name}[{i}]", positive=positive, nonneg=nonneg) for i, x in enumerate(v)]
    return _frozen(np.array(out, dtype=float).reshape(len(out)))


def _as_matrix(v: Any, name: str, rows: int, cols: int) -> np.ndarray:
    if not isinstance(v, list | tuple) or len(v) != rows:
        raise ValueError(f"{name}: must be a {rows}x{cols} list of rows (got {_show(v)})")
    return _frozen(np.array([_as_vector(r, f"{name}[{i}]", cols) for i, r in enumerate(v)]))


def _unit(v: np.ndarray, name: str) -> np.ndarray:
    """A unit vector given with its norm within :data:`AXIS_REFUSE_TOL` of 1: kept as given
    within :data:`AXIS_NORMALISE_TOL`, else normalised with one warning naming the norm (a printed
    axis is rounded: Example 1's a has |a| = 0.99997); refused further off."""
    nrm = float(np.linalg.norm(v))
    if nrm == 0.0:
        raise ValueError(f"{name}: must be a nonzero vector (got {v.tolist()!r})")
    if abs(nrm - 1.0) > AXIS_REFUSE_TOL:
        raise ValueError(
            f"{name}: must be a unit vector, norm within {AXIS_REFUSE_TOL:g} of 1 "
            f"(got norm {nrm!r} for {v.tolist()!r})"
        )
    if abs(nrm - 1.0) <= AXIS_NORMALISE_TOL:
        return _frozen(v)
    warnings.warn(
        f"{name}: norm {nrm:.6g} normalised to 1 (got {v.tolist()!r})", UserWarning, stacklevel=5
    )
    return _frozen(v / nrm)


def _direction(v: np.ndarray, name: str) -> np.ndarray:
    """Any nonzero vector, scaled to unit length (rotation axes); kept as given when its norm is
    within :data:`AXIS_NORMALISE_TOL` of 1."""
    nrm = float(np.linalg.norm(v))
    if nrm == 0.0:
        raise ValueError(f"{name}: must be a nonzero vector (got {v.tolist()!r})")
    return _frozen(v if abs(nrm - 1.0) <= AXIS_NORMALISE_TOL else v / nrm)


def _nearest_rotation(m: np.ndarray, name: str) -> np.ndarray:
    """The rotation nearest ``m`` (polar decomposition); refuses a matrix far from one. A matrix
    orthonormal within :data:`ROTATION_EXACT_TOL` is kept as given."""
    if np.max(np.abs(m.T @ m - np.eye(3))) <= ROTATION_EXACT_TOL and np.linalg.det(m) > 0:
        return np.array(m, dtype=float)
    U, s, Vt = np.linalg.svd(m)
    if np.max(np.abs(s - 1.0)) > ROTATION_REFUSE_TOL or np.linalg.det(m) <= 0:
        raise ValueError(f"{name}: must be a rotation matrix (singular values {s.tolist()!r})")
    return U @ Vt


def _indices(v: Any, name: str, upper: int) -> tuple[int, ...]:
    """1-based indices in the file, 0-based in the record; distinct and in range."""
    if not isinstance(v, list | tuple) or not v:
        raise ValueError(f"{name}: must be a non-empty list of 1-based indices (got {_show(v)})")
    out = []
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, int) or not 1 <= x <= upper:
            raise ValueError(f"{name}[{i}]: must be an integer in 1..{upper} (got {_show(x)})")
        out.append(x - 1)
    if len(set(out)) != len(out):
        raise ValueError(f"{name}: indices must be distinct (got {_show(v)})")
    return tuple(out)


# ----------------------------------------------------------------------------------------------
# Parsing
# ----------------------------------------------------------------------------------------------


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (TOML), or a built-in scene by name. Raises ``ValueError``
    naming the field on bad input.

    ``path`` is a file when one exists there, else the name of a built-in scene
    (``"paper_example1"``, see :func:`analytic.builtin_scenes.builtin_scene_names`). Only a regular
    file of at most :data:`MAX_SCENE_BYTES` is read (a FIFO, a device such as ``/dev/zero`` or a
    directory is refused without reading it); messages name ``path`` as given.
    """
    p = Path(path)
    given = str(path)
    source = given
    try:
        st = os.stat(p)
    except FileNotFoundError:
        builtin = builtin_scene_path(given)
        if builtin is None:
            raise ValueError(
                f"scene: file not found and no built-in scene of that name (got {given!r}; "
                f"built-in: {', '.join(builtin_scene_names())})"
            ) from None
        p = builtin
        source = str(builtin)
        st = os.stat(p)
    except OSError as exc:
        raise ValueError(f"scene: cannot read {given!r} ({exc.strerror or exc})") from None
    except ValueError as exc:  # a NUL byte in the path
        raise ValueError(f"scene: cannot look up {given!r} ({exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"scene: is a directory, not a scene file (got {given!r})")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"scene: not a regular file (got {given!r})")
    too_big = f"scene: file larger than {MAX_SCENE_BYTES:,} bytes (got {given!r})"
    if st.st_size > MAX_SCENE_BYTES:
        raise ValueError(too_big)
    try:
        # O_NONBLOCK: should the path have become a FIFO since stat, opening it does not wait.
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                raise ValueError(f"scene: not a regular file (got {given!r})")
            raw = f.read(MAX_SCENE_BYTES + 1)  # at most this much, should the file be growing
    except OSError as exc:
        raise ValueError(f"scene: cannot read {given!r} ({exc.strerror or exc})") from None
    if len(raw) > MAX_SCENE_BYTES:
        raise ValueError(too_big)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"scene: not UTF-8 text (got {given!r})") from None
    _check_text_nesting(text, given)
    try:
        data = tomllib.loads(text)
    except RecursionError:  # (the scan above refuses such files first; kept as a safety net)
        raise ValueError(
            f"scene: nested deeper than {MAX_SCENE_NESTING} levels of lists and tables "
            f"(in {given!r})"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"scene: not valid TOML in {given!r} ({exc})") from None
    except ValueError as exc:  # e.g. an integer literal of more than 4300 digits
        msg = str(exc).splitlines()[0].split(";")[0] if str(exc) else type(exc).__name__
        raise ValueError(f"scene: cannot parse {given!r} ({msg})") from None
    return scene_from_dict(data, source=source)


# TOML tokens that can hold a bracket which is not one: strings (multi-line ones first) and
# comments; then the brackets themselves and newlines.
_TOML_TOKENS = re.compile(
    r'"""(?:\\.|[^\\])*?"""(?:"{1,2})?'
    r"|'''[\s\S]*?'''(?:'{1,2})?"
    r'|"(?:\\.|[^"\\\n])*"'
    r"|'[^'\n]*'"
    r"|#[^\n]*"
    r"|[\[\]{}\n]"
)
_TOML_HEADER = re.compile(r"\s*\[\[?\s*([^\]]*?)\s*\]")


def _check_text_nesting(text: str, given: str) -> None:
    """Refuse TOML text whose arrays and inline tables nest deeper than :data:`MAX_SCENE_NESTING`,
    before the parser (which recurses once per level) reads it; the message names the key (dotted,
    under the last table header) and the line. Strings and comments are skipped; the scan is
    linear in the text."""
    depth, line, line_start, table, key = 0, 1, 0, "", ""
    for tok in _TOML_TOKENS.finditer(text):
        c = tok.group()
        if c == "\n" or c[0] in "\"'#":
            if "\n" in c:
                line += c.count("\n")
                line_start = tok.start() + c.rindex("\n") + 1
            continue
        if c in "[{":
            if depth == 0:
                head = text[line_start : tok.start()]
                if not head.strip():  # a [table] header: its name is the table of what follows
                    m = _TOML_HEADER.match(text, line_start)
                    table, key = (m.group(1) if m else ""), ""
                elif "=" in head:
                    key = head.split("=", 1)[0].strip()
            depth += 1
            if depth > MAX_SCENE_NESTING:
                dotted = ".".join(x for x in (table, key) if x) or "scene"
                raise ValueError(
                    f"{dotted}: nested deeper than {MAX_SCENE_NESTING} levels of lists and tables "
                    f"(line {line} of {given!r})"
                )
        else:
            depth = max(depth - 1, 0)


def _check_nesting(data: Any, source: str = "") -> None:
    """Refuse a document whose lists and tables nest deeper than :data:`MAX_SCENE_NESTING` below
    it (dotted keys build deep tables without brackets), naming the dotted path of the first value
    beyond the limit. Iterative, so a document of any depth (or one that holds itself) is walked
    without recursion."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        node, path, depth = stack.pop()
        if isinstance(node, Mapping):
            children = ((f"{path}.{k}" if path else str(k), v) for k, v in node.items())
        elif isinstance(node, list | tuple):
            children = ((f"{path}[{i}]", v) for i, v in enumerate(node))
        else:
            continue
        if depth > MAX_SCENE_NESTING:
            where = f" (in {source!r})" if source else ""
            raise ValueError(
                f"{path or 'scene'}: nested deeper than {MAX_SCENE_NESTING} levels of lists and "
                f"tables{where}"
            )
        stack.extend((v, p, depth + 1) for p, v in children)


def scene_from_dict(data: Mapping[str, Any], source: str = "") -> Scene:
    """Validate a scene given as nested dicts (the parsed TOML)."""
    _check_nesting(data, source)
    if not isinstance(data, Mapping):
        raise ValueError(f"scene: must be a table (got {_show(data)})")
    _refuse_unknown_keys(data)
    top = _Table(data, "")

    meta = top.table("scene")
    name = meta.string("name")
    description = meta.string("description")
    effects_raw = meta.raw("effects", kinds=(Kind.CHOICES,))
    if not isinstance(effects_raw, list):
        raise ValueError(
            f"scene.effects: must be a list of effect names (got {_show(effects_raw)})"
        )
    effects = set()
    for i, e in enumerate(effects_raw):
        try:
            effects.add(Effect(e))
        except ValueError:
            allowed = ", ".join(repr(x.value) for x in Effect)
            raise ValueError(
                f"scene.effects[{i}]: unknown effect {_show(e)} (allowed: {allowed})"
            ) from None
    meta.finish()

    body = _parse_body(top.table("body"))
    rod = _parse_rod(top.table("rod"))
    masses = _parse_masses(top.table("masses"), rod.axis)
    n = masses.n
    springs = _parse_springs(top.table("springs"), n)

    g_tab = top.table("gravity")
    gravity = _frozen(np.array(DEFAULT_GRAVITY))
    if g_tab is not None:
        gravity = g_tab.vector("vector", 3)
        g_tab.finish()

    initial = _parse_initial(top.table_or_empty("initial"), n)

    s_tab = top.table_or_empty("stabilization")
    stab = Stabilization(
        delta1=s_tab.number("delta1", nonneg=True), delta2=s_tab.number("delta2", nonneg=True)
    )
    s_tab.finish()

    control = _parse_control(top.table_or_empty("control"), n)
    ext = _parse_external_torque(top.table("external_torque"))
    solver = _parse_solver(top.table_or_empty("solver"))
    output = _parse_output(top.table_or_empty("output"))
    mj = _parse_mujoco(top.table_or_empty("mujoco"))

    # [thresholds] belongs to later layers (the comparison's names are checked where they are
    # resolved, validation.compare.thresholds); here its shape: numbers, or {value, reason} tables.
    extra = {}
    th = top.table("thresholds")
    if th is not None:
        extra["thresholds"] = _parse_thresholds(th)
    # [hard_case] belongs to the hard-case suite, which validates it (validation/studies/hard_cases/
    # criterion.py); here only that it is a table, kept verbatim.
    hc = top.table("hard_case")
    if hc is not None:
        extra["hard_case"] = dict(hc.data)
    top.finish()

    scene = Scene(
        name=name,
        description=description,
        effects=frozenset(effects),
        body=body,
        rod=rod,
        masses=masses,
        springs=springs,
        gravity=gravity,
        initial=initial,
        stabilization=stab,
        control=control,
        external_torque=ext,
        solver=solver,
        output=output,
        mujoco=mj,
        source=source,
        extra=extra,
    )
    _check_effects_consistent(scene)
    _check_initial_quantities(scene)
    _check_horizon_fits_mujoco(scene)
    _warn_unused_tables(data, scene)
    _warn_masses_off_the_drawn_rod(scene)
    return scene


def _warn_masses_off_the_drawn_rod(scene: Scene) -> None:
    """One warning (one line) naming each ``masses.p_e`` and ``initial.p`` beyond the drawn rod.

    The rod of ``[body.shape]`` is a picture: the dynamics let the masses slide on an unbounded
    line (no end stops), so a mass beyond the drawing is allowed, but the picture would show it
    floating off the rod, which is usually a mistake in the scene (a length or a sign).
    """
    shape = scene.body.shape
    if shape.kind is ShapeKind.NONE or not scene.n:
        return
    lo, hi = shape.rod_start, shape.rod_start + shape.rod_length
    off = [
        f"{name}[{i}] = {x:g} m"
        for name, values in (("masses.p_e", scene.masses.p_e), ("initial.p", scene.initial.p))
        for i, x in enumerate(values.tolist())
        if not lo <= x <= hi
    ]
    if not off:
        return
    where = f"{lo:g} m to {hi:g} m from O'"
    warnings.warn(
        f"{', '.join(off)}: {'lies' if len(off) == 1 else 'lie'} beyond the drawn rod "
        f"(body.shape.rod_start = {lo:g} m, rod_length = {shape.rod_length:g} m: {where}); the "
        "rod's length is a picture only, the masses slide on an unbounded line",
        UserWarning,
        stacklevel=3,
    )


# Tables and keys that only an effect reads: given while the effect is off, they are ignored.
_EFFECT_DATA = (
    ("gravity", Effect.GRAVITY),
    ("external_torque", Effect.EXTERNAL_TORQUE),
    ("control.omega", Effect.CONTROL_OMEGA),
    ("control.masses", Effect.CONTROL_MASSES),
    ("springs.k_linear", Effect.SPRINGS_LINEAR),
    ("springs.k_cubic", Effect.SPRINGS_CUBIC),
    ("masses.ring_radius", Effect.MASS_INERTIA),
    ("masses.inertia_axial", Effect.MASS_INERTIA),
    ("masses.inertia_transverse", Effect.MASS_INERTIA),
    ("masses.inertia_body", Effect.MASS_INERTIA),
)


def _warn_unused_tables(data: Mapping[str, Any], scene: Scene) -> None:
    """One warning (one line) naming the tables and keys given for effects that are not listed."""
    unused: dict[str, Effect] = {}
    for dotted, effect in _EFFECT_DATA:
        node: Any = data
        for key in dotted.split("."):
            node = node.get(key) if isinstance(node, Mapping) else None
        if node is not None and effect not in scene.effects:
            unused[dotted] = effect
    if not unused:
        return
    effects = ", ".join(dict.fromkeys(repr(e.value) for e in unused.values()))
    one = len(set(unused.values())) == 1
    warnings.warn(
        f"{', '.join(unused)}: given but {'effect' if one else 'effects'} {effects} "
        f"{'is' if one else 'are'} not listed in scene.effects, so ignored",
        UserWarning,
        stacklevel=3,
    )


def _parse_thresholds(t: _Table) -> dict[str, Any]:
    """The ``[thresholds]`` table's shape: each entry a finite non-negative number or
    ``{value = number, reason = "..."}``; the hard-case suite's ``hard_*`` entries a number or,
    for its stated criterion, a sentence. Which names exist is for the layer that uses them."""
    out: dict[str, Any] = {}
    for key in list(t.data):
        name = t.name(key)
        v = t.raw(key, kinds=(Kind.NUMBER_OR_VALUE_TABLE, Kind.NUMBER_OR_STRING))
        if key.startswith("hard_"):
            out[key] = v if isinstance(v, str) else _as_number(v, name, nonneg=True)
        elif isinstance(v, Mapping):
            sub = _Table(v, name, generic_table(t.schema, key))
            sub.used.update(("value", "reason"))
            sub.finish()  # an unknown key first: a misspelt "value" is named as such
            entry = {"value": sub.number("value", nonneg=True)}
            if sub.has("reason"):
                entry["reason"] = sub.string("reason")
            sub.finish()
            out[key] = entry
        else:
            out[key] = _as_number(v, name, nonneg=True)
    return out


def _parse_body(t: _Table) -> Body:
    mass = _mass_in_range(t.number("mass", positive=True), t.name("mass"))
    inertia = t.vector("inertia", 3, positive=True)
    for i, x in enumerate(inertia.tolist()):
        if x > MAX_INERTIA:
            raise ValueError(
                f"{t.name('inertia')}[{i}]: must be at most {MAX_INERTIA:g} kg·m² (got {x!r})"
            )
    j = np.sort(inertia)
    if j[2] > j[0] + j[1] * (1 + 1e-12):
        raise ValueError(
            f"body.inertia: principal moments violate the triangle inequality (got {inertia.tolist()!r})"
        )
    shape = BodyShape()
    st = t.table("shape")
    if st is not None:
        shape = _parse_shape(st)
    t.finish()
    return Body(mass=mass, inertia=inertia, shape=shape)


def _parse_shape(t: _Table) -> BodyShape:
    kind = t.enum("kind", ShapeKind)
    kw: dict[str, Any] = {"kind": kind}
    if kind is ShapeKind.BOX_AND_ROD:
        kw["box_half_sizes"] = t.vector("box_half_sizes", 3, positive=True)
        kw["box_center"] = t.vector("box_center", 3)
        if t.has("box_rotation"):
            kw["box_rotation"] = _frozen(
                _nearest_rotation(
                    _as_matrix(
                        t.raw("box_rotation", kinds=(Kind.MATRIX3,)), t.name("box_rotation"), 3, 3
                    ),
                    t.name("box_rotation"),
                )
            )
    elif kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        kw["cylinder_radius"] = t.number("cylinder_radius", positive=True)
        kw["cylinder_length"] = t.number("cylinder_length", positive=True)
        kw["cylinder_thickness"] = t.number("cylinder_thickness", positive=True)
        kw["cylinder_axis"] = _direction(t.vector("cylinder_axis", 3), t.name("cylinder_axis"))
    if kind is not ShapeKind.NONE:
        kw["rod_radius"] = t.number("rod_radius", positive=True)
        kw["rod_start"] = t.number("rod_start")
        kw["rod_length"] = t.number("rod_length", positive=True)
    t.finish()
    return BodyShape(**kw)


def _parse_rod(t: _Table) -> Rod:
    axis = _unit(t.vector("axis", 3), t.name("axis"))
    offset = t.vector("offset", 3)
    t.finish()
    return Rod(axis=axis, offset=offset)


def _parse_masses(t: _Table | None, axis: np.ndarray) -> Masses:
    if t is None:
        z = _frozen(np.zeros(0))
        return Masses(mass=z, p_e=z, inertia=_frozen(np.zeros((0, 3, 3))))
    raw_m = t.raw("mass", kinds=(Kind.VECTOR_N,))
    if isinstance(raw_m, list | tuple) and len(raw_m) > MAX_MASSES:
        raise ValueError(
            f"{t.name('mass')}: at most {MAX_MASSES:,} masses (got a list of {len(raw_m):,})"
        )
    m = t.vector("mass", positive=True)
    for i, x in enumerate(m):
        _mass_in_range(float(x), f"{t.name('mass')}[{i}]")
    n = m.shape[0]
    p_e = t.vector("p_e", n)
    inertia = np.zeros((n, 3, 3))
    has_ring = t.has("ring_radius")
    has_axi = t.has("inertia_axial") or t.has("inertia_transverse")
    has_full = t.has("inertia_body")
    if has_ring + has_axi + has_full > 1:
        raise ValueError(
            f"{t.name('ring_radius')}: give one of ring_radius, inertia_axial/inertia_transverse, "
            f"inertia_body (got {sorted(k for k in t.data if k.startswith(('ring', 'inertia')))!r})"
        )
    aa = np.outer(axis, axis)
    if has_ring:
        # A thin ring about the rod: axial m r², transverse m r²/2 -> m r²/2 (I + a aᵀ) (Eq. 62;
        # docs/errata.md item 8).
        r = t.vector("ring_radius", n, nonneg=True)
        for i in range(n):
            if float(m[i]) * float(r[i]) * float(r[i]) > MAX_INERTIA:
                raise ValueError(
                    f"{t.name('ring_radius')}[{i}]: makes an axial moment m r² above "
                    f"{MAX_INERTIA:g} kg·m² (got {float(r[i])!r} m)"
                )
        inertia = (m * r**2 / 2)[:, None, None] * (np.eye(3) + aa)[None]
    elif has_axi:
        ia = t.vector("inertia_axial", n, nonneg=True)
        it = t.vector("inertia_transverse", n, nonneg=True)
        for key, vals in (("inertia_axial", ia), ("inertia_transverse", it)):
            for i, x in enumerate(vals.tolist()):
                if x > MAX_INERTIA:
                    raise ValueError(
                        f"{t.name(key)}[{i}]: must be at most {MAX_INERTIA:g} kg·m² (got {x!r})"
                    )
        for i in range(n):
            if ia[i] > 2 * it[i] * (1 + 1e-12):
                raise ValueError(
                    f"{t.name('inertia_axial')}[{i}]: exceeds twice the transverse moment "
                    f"(got {ia[i]!r} > 2 x {it[i]!r})"
                )
        inertia = it[:, None, None] * (np.eye(3) - aa)[None] + ia[:, None, None] * aa[None]
    elif has_full:
        raw = t.raw("inertia_body", kinds=(Kind.MATRICES_N,))
        if not isinstance(raw, list) or len(raw) != n:
            raise ValueError(
                f"{t.name('inertia_body')}: must hold {n} 3x3 matrices (got {_show(raw)})"
            )
        for i, mat in enumerate(raw):
            name = f"{t.name('inertia_body')}[{i}]"
            J = _as_matrix(mat, name, 3, 3)
            if not np.allclose(J, J.T, rtol=1e-12, atol=0):
                raise ValueError(f"{name}: must be symmetric (got {J.tolist()!r})")
            if np.max(np.abs(J)) > MAX_INERTIA:
                raise ValueError(
                    f"{name}: entries must be at most {MAX_INERTIA:g} kg·m² (got {J.tolist()!r})"
                )
            e = np.linalg.eigvalsh(J)
            if e[0] < 0:
                raise ValueError(f"{name}: must be positive semidefinite (got {J.tolist()!r})")
            # Principal moments of a rigid body satisfy A + B >= C (MuJoCo's compiler refuses
            # them otherwise); round-off up to TRIANGLE_RTOL is what model_xml repairs.
            if e[2] - e[0] - e[1] > TRIANGLE_RTOL * e[2]:
                raise ValueError(
                    f"{name}: principal moments {e.tolist()!r} violate the triangle inequality "
                    f"A + B >= C (got {J.tolist()!r})"
                )
            inertia[i] = J
    t.finish()
    return Masses(mass=m, p_e=p_e, inertia=_frozen(inertia))


def _parse_springs(t: _Table | None, n: int) -> Springs:
    if t is None:
        z = _frozen(np.zeros(n + 1))
        return Springs(k_linear=z, k_cubic=z, given=frozenset())
    given = frozenset(k for k in ("k_linear", "k_cubic") if t.has(k))
    kl = t.vector("k_linear", n + 1, _frozen(np.zeros(n + 1)), nonneg=True)
    kn = t.vector("k_cubic", n + 1, _frozen(np.zeros(n + 1)), nonneg=True)
    t.finish()
    return Springs(k_linear=kl, k_cubic=kn, given=given)


def _parse_initial(t: _Table, n: int) -> InitialState:
    R = t.vector("R", 3)
    Rdot = t.vector("Rdot", 3)
    omega = t.vector("omega", 3)
    p = t.vector("p", n) if n else t.vector("p", 0, _frozen(np.zeros(0)))
    pdot = t.vector("pdot", n, _frozen(np.zeros(n)))
    attitude = t.table("attitude")
    u = IDENTITY_QUATERNION if attitude is None else _parse_attitude(attitude)
    t.finish()
    return InitialState(R=R, Rdot=Rdot, u=u, omega=omega, p=p, pdot=pdot)


IDENTITY_QUATERNION = _frozen([1.0, 0.0, 0.0, 0.0])
"""``u(0)`` when ``[initial.attitude]`` is absent: body axes along XYZ."""


def _parse_attitude(t: _Table) -> np.ndarray:
    """Quaternion (w first) or axis-angle composed with a reference-from-principal rotation.

    ``S(u(0)) = Rot(axis, angle) · reference_from_principal`` (Example 1 needs the principal -> block
    rotation ``P`` of Eq. 63 here: ``docs/errata.md``, item 6).
    """
    allow_off = t.boolean("allow_off_manifold")
    if t.has("quaternion"):
        for k in ("axis", "angle", "angle_deg", "reference_from_principal"):
            if t.has(k):
                raise ValueError(f"{t.name(k)}: give either quaternion or axis-angle, not both")
        u = np.array(t.vector("quaternion", 4))
        nrm = float(np.linalg.norm(u))
        if nrm == 0.0:
            raise ValueError(f"{t.name('quaternion')}: must be nonzero (got {u.tolist()!r})")
        if not allow_off:
            if abs(nrm - 1.0) > QUAT_REFUSE_TOL:
                raise ValueError(
                    f"{t.name('quaternion')}: norm {nrm!r} is off the unit sphere by more than "
                    f"{QUAT_REFUSE_TOL} (set allow_off_manifold = true to start off it on purpose)"
                )
            if abs(nrm - 1.0) > QUAT_NORMALISE_TOL:
                warnings.warn(f"{t.name('quaternion')}: norm {nrm!r} normalised to 1", stacklevel=4)
                u = u / nrm
        t.finish()
        return _frozen(u)
    axis = _direction(t.vector("axis", 3), t.name("axis"))
    if t.has("angle") and t.has("angle_deg"):
        raise ValueError(f"{t.name('angle')}: give angle (rad) or angle_deg, not both")
    if t.has("angle_deg"):
        angle = math.radians(t.number("angle_deg"))
    else:
        angle = t.number("angle")
    ref = np.eye(3)
    if t.has("reference_from_principal"):
        name = t.name("reference_from_principal")
        raw_ref = t.raw("reference_from_principal", kinds=(Kind.MATRIX3,))
        ref = _nearest_rotation(_as_matrix(raw_ref, name, 3, 3), name)
    t.finish()
    if allow_off:
        raise ValueError(f"{t.name('allow_off_manifold')}: only meaningful with a quaternion")
    u = quat_mul(axis_angle_quat(axis, angle), matrix_quat(ref))
    return _frozen(u / np.linalg.norm(u))


def _parse_control(t: _Table, n: int) -> Control:
    weighting = t.enum("weighting", Weighting)
    omega = None
    ot = t.table("omega")
    if ot is not None:
        comps = _indices(ot.raw("components", kinds=(Kind.INDICES,)), ot.name("components"), 3)
        b = ot.vector("b", 3)
        sigma = ot.vector("sigma", 3)
        k = len(comps)
        if ot.has("gamma") and ot.has("gain"):
            raise ValueError(f"{ot.name('gain')}: give gamma or gain, not both")
        if ot.has("gain"):
            gain = _as_matrix(ot.raw("gain", kinds=(Kind.MATRIX_K,)), ot.name("gain"), k, k)
            if (
                not np.allclose(gain, gain.T, rtol=1e-12, atol=0)
                or np.min(np.linalg.eigvalsh(gain)) <= 0
            ):
                raise ValueError(
                    f"{ot.name('gain')}: must be symmetric positive definite (got {gain.tolist()!r})"
                )
        else:
            gain = _frozen(ot.number("gamma", positive=True) * np.eye(k))
        ot.finish()
        omega = OmegaTrack(components=comps, b=b, sigma=sigma, gain=_frozen(gain))
    masses = None
    mt = t.table("masses")
    if mt is not None:
        if n == 0:
            raise ValueError(f"{mt.path}: there are no masses to control (n = 0)")
        idx = (
            _indices(mt.raw("indices", kinds=(Kind.INDICES,)), mt.name("indices"), n)
            if mt.has("indices")
            else tuple(range(n))
        )
        k = len(idx)
        masses = MassTrack(
            indices=idx,
            l=mt.vector("l", k),
            lam=mt.vector("lambda", k),
            alpha=mt.vector("alpha", k, positive=True),
            beta=mt.vector("beta", k, positive=True),
        )
        mt.finish()
    t.finish()
    return Control(weighting=weighting, omega=omega, masses=masses)


def _parse_external_torque(t: _Table | None) -> ExternalTorque | None:
    if t is None:
        return None
    et = ExternalTorque(
        constant=t.vector("constant", 3),
        amplitude=t.vector("amplitude", 3),
        frequency=t.number("frequency"),
    )
    t.finish()
    return et


def _parse_solver(t: _Table) -> SolverSettings:
    s = SolverSettings(
        method=t.enum("method", SolverMethod),
        rtol=t.number("rtol", positive=True),
        atol=t.number("atol", positive=True),
        max_step=t.number("max_step", positive=True) if t.has("max_step") else math.inf,
    )
    t.finish()
    return s


def _parse_output(t: _Table) -> OutputSettings:
    o = OutputSettings(t_end=t.number("t_end", positive=True), rate=t.number("rate", positive=True))
    t.finish()
    return o


def _parse_mujoco(t: _Table) -> MujocoSettings:
    m = MujocoSettings(
        integrator=t.enum("integrator", MjIntegrator),
        timestep=t.number("timestep", positive=True),
        spring_model=t.enum("spring_model", SpringModel),
    )
    t.finish()
    return m


def _check_effects_consistent(scene: Scene) -> None:
    """An effect that is on must have its data; control indices must fit n."""
    e = scene.effects
    if Effect.CONTROL_OMEGA in e and scene.control.omega is None:
        raise ValueError(
            "control.omega: effect 'control.omega' is on but [control.omega] is missing"
        )
    if Effect.CONTROL_MASSES in e and scene.control.masses is None:
        raise ValueError(
            "control.masses: effect 'control.masses' is on but [control.masses] is missing"
        )
    if Effect.EXTERNAL_TORQUE in e and scene.external_torque is None:
        raise ValueError(
            "external_torque: effect 'external_torque' is on but [external_torque] is missing"
        )
    if scene.control.masses is not None and max(scene.control.masses.indices) >= scene.n:
        raise ValueError(
            f"control.masses.indices: refer to masses beyond n = {scene.n} "
            f"(got {[i + 1 for i in scene.control.masses.indices]!r})"
        )
    if scene.n:  # (with no masses there is nothing for a spring to act on)
        for key, effect in (("k_linear", Effect.SPRINGS_LINEAR), ("k_cubic", Effect.SPRINGS_CUBIC)):
            if effect in e and key not in scene.springs.given:
                raise ValueError(f"springs.{key}: required by effect {effect.value}")
    _check_body_for_mujoco(scene)


def _mass_in_range(x: float, name: str) -> float:
    if x < MJ_MINVAL:
        raise ValueError(
            f"{name}: must be at least {MJ_MINVAL:g} kg (MuJoCo's mjMINVAL: its compiler refuses "
            f"a lighter moving body) (got {x!r})"
        )
    if x > MAX_MASS:
        raise ValueError(f"{name}: must be at most {MAX_MASS:g} kg (got {x!r})")
    return x


def twin_point_inertia(scene: Scene) -> tuple[float, int]:
    """The isotropic inertia ``eps`` (kg·m²) that the MuJoCo twin gives each mass body without an
    inertia of its own, and how many masses get it (``model_xml.builder.mass_inertias``: the
    total ``count · eps`` is taken off BR's principal moments)."""
    eps = max(POINT_INERTIA_REL * float(np.min(scene.body.inertia)), POINT_INERTIA_MIN)
    if not scene.has(Effect.MASS_INERTIA):
        return eps, scene.n
    count = sum(1 for J in scene.masses.inertia if float(np.min(np.linalg.eigvalsh(J))) <= eps)
    return eps, count


def _check_body_for_mujoco(scene: Scene) -> None:
    """BR's principal moments as the MuJoCo twin compiles them (less the point masses' padding):
    at least mjMINVAL each and A + B >= C exactly, as MuJoCo's compiler requires."""
    eps, count = twin_point_inertia(scene)
    J = np.asarray(scene.body.inertia, float)
    pad = eps * count
    Jp = J - pad  # as model_xml.builder computes them
    for i in range(3):
        if not Jp[i] >= MJ_MINVAL:
            given = f"less the {pad:.3g} kg·m² given to {count} point masses, " if count else ""
            raise ValueError(
                f"body.inertia[{i}]: too small for the MuJoCo twin: {given}below "
                f"mjMINVAL = {MJ_MINVAL:g} kg·m², which MuJoCo's compiler refuses "
                f"(got {float(J[i])!r})"
            )
    a, b, c = np.sort(Jp)
    if a + b < c:
        raise ValueError(
            f"body.inertia: principal moments {J.tolist()!r} leave no room for the {pad:.3g} kg·m² "
            f"the MuJoCo twin gives {count} point masses (A + B - C must be at least that, so "
            "that MuJoCo's A + B >= C holds)"
        )


def _check_horizon_fits_mujoco(scene: Scene) -> None:
    """The scene's own horizon against its MuJoCo step: at least one step, at most
    MAX_MUJOCO_STEPS (the plants check overrides of t_end and dt themselves)."""
    t_end, dt = scene.output.t_end, scene.mujoco.timestep
    if t_end < dt * (1 - GRID_RTOL):
        raise ValueError(
            f"output.t_end: shorter than one MuJoCo step (mujoco.timestep = {dt!r} s) "
            f"(got {t_end!r})"
        )
    steps = t_end / dt
    if steps > MAX_MUJOCO_STEPS:
        field_name = "output.t_end" if t_end / 20.0 >= 2.5e-4 / dt else "mujoco.timestep"
        raise ValueError(
            f"{field_name}: {t_end:g} s at mujoco.timestep = {dt:g} s is {steps:.3g} MuJoCo steps, "
            f"at most {MAX_MUJOCO_STEPS:,} (got {t_end if field_name == 'output.t_end' else dt!r})"
        )


# ----------------------------------------------------------------------------------------------
# Derived initial quantities: finite numbers whose products overflow
# ----------------------------------------------------------------------------------------------
# Every field is checked finite on its own, but the plants and the comparison work with products
# of them: u̇(0) from ω, energies m v² and k x⁴, momenta, the generalized force (k^n x³, m ω² ρ),
# accelerations (force / mass) and the control's requirement (b σ, l λ², β e). A product beyond
# the double range (1.8e308) would surface late, as a solver's "initial state must be finite"
# after work was done; it is refused at load instead, naming the field that makes it overflow.


def _initial_fields(scene: Scene) -> dict[str, np.ndarray]:
    """The scene's numbers that the derived initial quantities use, by field name, as float
    arrays (zeros for an effect that is off, so it adds nothing)."""
    f = {
        "body.mass": np.array([scene.body.mass], float),
        "body.inertia": np.array(scene.body.inertia, float),
        "masses.mass": np.array(scene.masses.mass, float),
        "masses.p_e": np.array(scene.masses.p_e, float),
        "rod.offset": np.array(scene.rod.offset, float),
        "initial.R": np.array(scene.initial.R, float),
        "initial.Rdot": np.array(scene.initial.Rdot, float),
        "initial.omega": np.array(scene.initial.omega, float),
        "initial.p": np.array(scene.initial.p, float),
        "initial.pdot": np.array(scene.initial.pdot, float),
        "stabilization.delta1": np.array([scene.stabilization.delta1], float),
        "stabilization.delta2": np.array([scene.stabilization.delta2], float),
    }
    zeros3 = np.zeros(3)
    f["gravity.vector"] = np.array(scene.gravity, float) if scene.has(Effect.GRAVITY) else zeros3
    for key, effect in (("k_linear", Effect.SPRINGS_LINEAR), ("k_cubic", Effect.SPRINGS_CUBIC)):
        given = scene.has(effect)
        f[f"springs.{key}"] = np.array(getattr(scene.springs, key), float) * (1.0 if given else 0.0)
    ext = scene.external_torque if scene.has(Effect.EXTERNAL_TORQUE) else None
    f["external_torque.constant"] = np.array(ext.constant, float) if ext else zeros3
    f["external_torque.amplitude"] = np.array(ext.amplitude, float) if ext else zeros3
    w = scene.control.omega if scene.has(Effect.CONTROL_OMEGA) else None
    if w is not None:
        f["control.omega.b"] = np.array(w.b, float)
        f["control.omega.sigma"] = np.array(w.sigma, float)
        gain = np.array(w.gain, float)
        if np.array_equal(gain, gain[0, 0] * np.eye(len(gain))):
            f["control.omega.gamma"] = np.array([gain[0, 0]])
        else:
            f["control.omega.gain"] = gain
    mt = scene.control.masses if scene.has(Effect.CONTROL_MASSES) else None
    if mt is not None:
        for key, attr in (("l", "l"), ("lambda", "lam"), ("alpha", "alpha"), ("beta", "beta")):
            f[f"control.masses.{key}"] = np.array(getattr(mt, attr), float)
    return f


_MOTION = ("initial.Rdot", "initial.omega", "initial.p", "initial.pdot", "rod.offset")
_MASS = ("body.mass", "body.inertia", "masses.mass")


def _derived_quantities(
    scene: Scene, v: Mapping[str, np.ndarray]
) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
    """Each quantity derived at t = 0 from the fields ``v`` (:func:`_initial_fields`, possibly
    altered): ``name -> (the fields it is computed from, its value)``. Magnitudes matter, not
    exact values: the forces and accelerations are the terms of Eq. (52) and their ratios to the
    masses and moments, taken separately (a sum may cancel, a term that overflows is refused).
    Call under ``np.errstate(all="ignore")``."""
    n = scene.n
    a = np.array(scene.rod.axis, float)
    u = np.array(scene.initial.u, float)
    Sm = S(u)
    m_BR, m = v["body.mass"][0], v["masses.mass"]
    J = np.diag(v["body.inertia"])
    if scene.has(Effect.MASS_INERTIA) and n:
        J = J + np.asarray(scene.masses.inertia, float).sum(axis=0)
    w, p, pd = v["initial.omega"], v["initial.p"], v["initial.pdot"]
    rho = v["rod.offset"][None, :] + p[:, None] * a[None, :]  # masses from C, body axes (n, 3)
    rhod = np.cross(w[None, :], rho) + pd[:, None] * a[None, :]
    vel = (Sm.T @ v["initial.Rdot"])[None, :] + rhod  # mass velocities, body axes (n, 3)
    udot = udot_of(u, w)
    out: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    out["attitude rate u̇ = Hᵀω/4"] = (("initial.omega",), udot)
    kinetic = (
        0.5 * m_BR * (v["initial.Rdot"] @ v["initial.Rdot"])
        + 0.5 * (w @ J @ w)
        + 0.5 * float(np.sum(m[:, None] * vel * vel))
    )
    out["kinetic energy"] = (_MASS + _MOTION, np.array([kinetic]))
    out["linear momentum"] = (_MASS + _MOTION, m_BR * v["initial.Rdot"] + Sm @ (m @ vel))
    out["angular momentum"] = (
        _MASS + _MOTION,
        J @ w + np.sum(m[:, None] * np.cross(rho, vel), axis=0),
    )
    out["moment of inertia of the masses about C"] = (
        ("masses.mass", "initial.p", "rod.offset"),
        np.array([np.sum(m * np.sum(rho * rho, axis=1))]),
    )
    # gravity: U = -m_T g·R - Σ m_i g·Sρ_i; its force on C, torque on BR, force along the rod
    g = v["gravity.vector"]
    m_T = m_BR + float(np.sum(m))
    gb = Sm.T @ g
    grav_fields = (
        "gravity.vector",
        "body.mass",
        "masses.mass",
        "initial.R",
        "initial.p",
        "rod.offset",
    )
    u_grav = -m_T * (g @ v["initial.R"]) - float(np.sum(m * (rho @ gb)))
    out["gravitational energy"] = (grav_fields, np.array([u_grav]))
    f_grav_rod = m * (a @ gb)
    torque = np.sum(m[:, None] * np.cross(rho, np.broadcast_to(gb, rho.shape)), axis=0)
    # springs: extensions x (n + 1), energy ½k x² + ¼k^n x⁴, force along the rod on each mass
    spring_fields = ("springs.k_linear", "springs.k_cubic", "initial.p", "masses.p_e")
    k_l, k_n = v["springs.k_linear"], v["springs.k_cubic"]
    f_spring_rod = np.zeros(n)
    if n:
        x = p - v["masses.p_e"]
        ext = np.concatenate([x[:1], x[1:] - x[:-1], -x[-1:]])
        u_spring = np.sum(0.5 * k_l * ext**2 + 0.25 * k_n * ext**4)
        f = k_l * ext + k_n * ext**3
        f_spring_rod = f[1:] - f[:-1]
        out["spring energy"] = (spring_fields, np.array([u_spring]))
        out["spring forces"] = (spring_fields, f)
        out["energy"] = (
            _MASS + _MOTION + grav_fields + spring_fields,
            np.array([kinetic + u_grav + u_spring]),
        )
    # the inertial (centripetal and Coriolis) forces on the masses, Eq. (52)
    f_inertial = m[:, None] * (np.cross(w, np.cross(w, rho)) + 2.0 * np.cross(w, rhod))
    out["inertial forces on the masses"] = (("masses.mass", *_MOTION), f_inertial)
    tau = v["external_torque.constant"] + v["external_torque.amplitude"]
    out["given torque"] = (("external_torque.constant", "external_torque.amplitude"), tau)
    torque = torque + tau + np.sum(np.cross(rho, f_inertial), axis=0)
    force_fields = _MASS + _MOTION + grav_fields + spring_fields
    out["generalized force"] = (
        (*force_fields, "external_torque.constant", "external_torque.amplitude"),
        np.concatenate([m_T * g, torque, f_grav_rod, f_spring_rod]),
    )
    j_min = float(np.min(np.linalg.eigvalsh(J)))
    out["acceleration"] = (
        out["generalized force"][0],
        np.concatenate(
            [
                g,
                torque / j_min,
                (f_grav_rod + f_spring_rod) / m if n else np.zeros(0),
                np.sum(f_inertial, axis=1) / m if n else np.zeros(0),
            ]
        ),
    )
    out["quaternion-norm stabilisation"] = (
        ("stabilization.delta1", "stabilization.delta2", "initial.omega"),
        np.array([-v["stabilization.delta1"][0] * (u @ udot) - udot @ udot]),
    )
    out.update(_control_requirement(scene, v))
    return out


def _control_requirement(
    scene: Scene, v: Mapping[str, np.ndarray]
) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
    """The control's required accelerations at t = 0 and their amplitudes over time (Eqs. 81,
    84): ``b σ``, ``P (ω - b)``; ``l λ``, ``l λ²``, ``α ṗ``, ``β (p - p̄)``."""
    out: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    if "control.omega.b" in v:
        c = list(scene.control.omega.components)
        gain_key = "control.omega.gamma" if "control.omega.gamma" in v else "control.omega.gain"
        gain = v[gain_key]
        gain = gain[0] * np.eye(len(c)) if gain_key.endswith("gamma") else gain
        b, sigma = v["control.omega.b"][c], v["control.omega.sigma"][c]
        e = v["initial.omega"][c] - b
        out["angular-velocity requirement"] = (
            ("control.omega.b", "control.omega.sigma", gain_key, "initial.omega"),
            np.concatenate([b * sigma, gain @ e]),
        )
    if "control.masses.l" in v:
        i = list(scene.control.masses.indices)
        l, lam = v["control.masses.l"], v["control.masses.lambda"]
        err = v["initial.p"][i] - v["masses.p_e"][i] - l
        out["mass-position requirement"] = (
            (
                "control.masses.l",
                "control.masses.lambda",
                "control.masses.alpha",
                "control.masses.beta",
                "initial.p",
                "initial.pdot",
                "masses.p_e",
            ),
            np.concatenate(
                [
                    l * lam,
                    l * lam * lam,
                    v["control.masses.alpha"] * v["initial.pdot"][i],
                    v["control.masses.beta"] * err,
                ]
            ),
        )
    return out


def _blame(scene: Scene, fields: dict[str, np.ndarray], name: str, feeds: tuple[str, ...]) -> str:
    """The field that makes the quantity ``name`` overflow: the first (largest first) whose
    values, brought within [-1, 1], make it finite; else the largest."""
    order = sorted(dict.fromkeys(feeds), key=lambda k: -float(np.max(np.abs(fields[k]), initial=0)))
    for key in order:
        trial = dict(fields)
        trial[key] = np.clip(fields[key], -1.0, 1.0)
        if np.all(np.isfinite(_derived_quantities(scene, trial)[name][1])):
            return key
    return order[0]


def _check_initial_quantities(scene: Scene) -> None:
    """Refuse a scene whose initial state, energy, momenta, generalized force, acceleration or
    control requirement is not finite although every field is: ``ValueError`` naming the field
    that makes it overflow, its value, and the fields the quantity is computed from."""
    fields = _initial_fields(scene)
    with np.errstate(all="ignore"):
        for name, (feeds, value) in _derived_quantities(scene, fields).items():
            if np.all(np.isfinite(value)):
                continue
            key = _blame(scene, fields, name, feeds)
            got = fields[key].tolist()
            got = got[0] if len(got) == 1 and not isinstance(got[0], list) else got
            raise ValueError(
                f"{key}: makes the initial {name} overflow the double range (got {_show(got)}; "
                f"it is computed from {', '.join(dict.fromkeys(feeds))})"
            )
