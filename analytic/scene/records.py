"""The records a scene loads to: frozen dataclasses, one per table of the file.

Units are SI. Frames: vectors marked *body* are in BR's principal axes at its centre of mass C
(the paper's xyz); vectors marked *inertial* are in XYZ with Z up. Quaternions are w-first.
Mass and control indices are 0-based here (1-based in files, as in the paper). Every array is a
read-only float array. Build a :class:`Scene` with :func:`analytic.scene.load_scene` or
:func:`analytic.scene.scene_from_dict`, which validate it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Self

import numpy as np

from analytic.effects import (
    CONTROL_EFFECTS,
    Effect,
    MjIntegrator,
    ShapeKind,
    SolverMethod,
    SpringModel,
    Weighting,
)
from analytic.effects.declaration import SpringLaw
from analytic.scene.limits import GRID_RTOL, MAX_OUTPUT_SAMPLES
from analytic.scene.values import as_number, frozen


@dataclass(frozen=True)
class BodyShape:
    """Pictures of BR for viewers; massless, never used by the dynamics.

    ``box_center`` (body, m) and ``box_rotation`` (body-from-box rotation, 3x3) place the box;
    the hollow cylinder is centred on C with its axis along ``cylinder_axis`` (body). The rod runs
    along ``a`` from ``d + rod_start·a`` for ``rod_length`` metres.
    """

    kind: ShapeKind = ShapeKind.NONE
    box_half_sizes: np.ndarray = field(default_factory=lambda: frozen(np.zeros(3)))
    box_center: np.ndarray = field(default_factory=lambda: frozen(np.zeros(3)))
    box_rotation: np.ndarray = field(default_factory=lambda: frozen(np.eye(3)))
    cylinder_radius: float = 0.0
    cylinder_length: float = 0.0
    cylinder_thickness: float = 0.0
    cylinder_axis: np.ndarray = field(default_factory=lambda: frozen([1.0, 0.0, 0.0]))
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

    One coefficient vector per spring law (:data:`analytic.effects.registry.SPRING_LAWS`), read
    by its key's name as an attribute: ``k_linear`` (``k^l``, N/m), ``k_cubic`` (``k^n``, N/m³),
    each shape (n+1,), zeros when not given.

    Attributes:
        coefficients: ``key name -> coefficients``, every spring law's.
        given: which of them the scene gave (an effect needs its constants given).
    """

    coefficients: Mapping[str, np.ndarray]
    given: frozenset[str] = frozenset()

    def __getattr__(self, name: str) -> np.ndarray:
        if name.startswith("__") or name in ("coefficients", "given"):
            raise AttributeError(name)
        try:
            return self.coefficients[name]
        except KeyError:
            raise AttributeError(f"Springs has no coefficients {name!r}") from None

    def of(self, law: SpringLaw) -> np.ndarray:
        """The coefficients of ``law``, N/m-like (its key's unit), shape (n+1,)."""
        return self.coefficients[law.key.key]


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
        check_output(self.t_end, self.rate, "output.t_end", "output.rate", blame=None)

    def with_t_end(self, t_end: float | None, name: str = "t_end") -> OutputSettings:
        """These settings with another horizon (``self`` for None); a bad one is refused as ``name``."""
        if t_end is None:
            return self
        check_output(t_end, self.rate, name, "output.rate", blame=name)
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


def check_output(t_end: Any, rate: Any, t_name: str, rate_name: str, blame: str | None) -> None:
    """Horizon and rate positive and finite, at most MAX_OUTPUT_SAMPLES samples. ``blame`` names the
    field refused for too many samples (None: whichever is further from its default)."""
    t_end = as_number(t_end, t_name, positive=True)
    rate = as_number(rate, rate_name, positive=True)
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
class SceneRecord:
    """Every table of a scene, as records. A validated one is an :class:`analytic.scene.Scene`
    (this record with :meth:`~analytic.scene.Scene.with_effects`), built by
    :func:`~analytic.scene.load_scene` or :func:`~analytic.scene.scene_from_dict`; the cross-field
    rules read this record."""

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

    def replace(self, **changes: Any) -> Self:
        """A copy with top-level fields replaced (e.g. ``output=OutputSettings(t_end=60)``),
        checked by nothing: a modified *valid* scene is :func:`analytic.scene.modified_scene`."""
        return dataclasses.replace(self, **changes)


__all__ = [
    "Body",
    "BodyShape",
    "Control",
    "ExternalTorque",
    "InitialState",
    "MassTrack",
    "Masses",
    "MujocoSettings",
    "OmegaTrack",
    "OutputSettings",
    "Rod",
    "SceneRecord",
    "SolverSettings",
    "Springs",
    "Stabilization",
    "output_times",
]
