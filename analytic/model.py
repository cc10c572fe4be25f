"""The tumbling multibody model of the paper: ``M(q) q̈ = Q(q, q̇)`` (Eqs. 50-53), the modeling
constraint (Eqs. 55-59), the control constraints (Eqs. 77-88, Remark 4, Appendix B) and the
fundamental equation (Eqs. 48, 74, 89, B10).

Coordinates (Eq. 44): ``q = [R (3), u (4, w first), p (n)]``, ``nq = n + 7``.

Every mass term derives from one identity (Appendix A): the inertial acceleration of mass i is
``r̈_i = J_i q̈ + κ_i`` with ``J_i = [I₃, p_i L_a + L_d, Sa e_iᵀ]`` and
``κ_i = 2 ṗ_i L_a u̇ + p_i L̇_a u̇ + L̇_d u̇`` (Eq. 40), so ``M = M_BR + Σ m_i J_iᵀJ_i`` (Eq. 51) and
``Q = Q_BR - Σ m_i J_iᵀ κ_i + (given forces)`` (Eq. 52). The sums over masses reduce to the moments
``μ0 = Σm``, ``μ1 = mᵀp``, ``μ2 = (p∘m)ᵀp`` and two weighted sums of κ, so one evaluation costs O(n)
plus the dense solve (no Python loop over masses).

The formulas are written once, in :mod:`analytic.array_model` (an array form that numpy and
jax.numpy both run); :class:`TumblingModel` is that form evaluated with numpy in float64 at one
state, with scipy's Cholesky in the fundamental equation (:func:`analytic.fundamental.solve`). The
model is assembled from the scene's effects: a force term whose effect is off is skipped by a branch
on the scene's :class:`~analytic.array_model.Structure` and never evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analytic import array_model, fundamental
from analytic.effects import Effect
from analytic.effects.registry import SPRING_LAWS
from analytic.kinematics import tensor_along
from analytic.scene import Scene


@dataclass(frozen=True)
class ControlOutput:
    """The control at one instant, in physical terms.

    Attributes:
        QC: generalized control force ``Q^C`` of Eq. (89), shape (n+7,): ``[Q^C_R, Q^C_u, Q^C_p]``.
            It includes the (tiny) part along u that enforces the quaternion norm.
        torque: body-axis control torque ``τ = ¼ H Q^C_u``, N·m, shape (3,).
        rod_forces: force along the rod between the rod and mass i, ``F_i = Q^C_p,i``, N, shape (n,).
        force_at_C: force at C, ``Q^C_R``, inertial, N, shape (3,) (zero for the paper's cost).
        residual: unattainable part of the control requirements ``A_c q̈ - b_c``, shape (k,).
        rank: rank of the control requirements (k when all are independent).
    """

    QC: np.ndarray
    torque: np.ndarray
    rod_forces: np.ndarray
    force_at_C: np.ndarray
    residual: np.ndarray
    rank: int


class TumblingModel:
    """The paper's model for one scene.

    Args:
        scene: a validated :class:`~analytic.scene.Scene`.

    Attributes:
        n: number of masses; nq = n + 7 coordinates.
        J: inertia used in Eq. (51), ``J_BR + Σ P_iᵀ J_i P_i`` with the mass_inertia effect
            (Remark 1, Eq. 54), else ``J_BR``; body axes, kg·m², shape (3, 3).
        force_terms: the names of the generalized-force terms assembled for this scene.
    """

    def __init__(self, scene: Scene):
        self.scene = scene
        self.n = n = scene.n
        self.nq = n + 7
        self.m_BR = float(scene.body.mass)
        self.m = np.array(scene.masses.mass)
        self.mu0 = float(self.m.sum())
        self.m_T = self.m_BR + self.mu0
        J = np.diag(scene.body.inertia).astype(float)
        if scene.has(Effect.MASS_INERTIA) and n:
            J = J + scene.masses.inertia.sum(axis=0)  # Remark 1, Eq. (54)
        self.J = J
        self.a = np.array(scene.rod.axis)
        self.d = np.array(scene.rod.offset)
        self.T_a = tensor_along(self.a)  # L_a(u) = T_a @ u, Eq. (29)
        self.T_d = tensor_along(self.d)  # L_d(u) = T_d @ u, Eq. (34)
        self.p_e = np.array(scene.masses.p_e)
        self.g = np.array(scene.gravity)
        self.spring_laws = tuple(
            law for law in SPRING_LAWS if n and scene.has(law.effect)
        )  # the spring elements' laws that are on (Eq. 38; analytic.effects)
        self.spring_coefficients = {
            law.effect: np.array(scene.springs.of(law)) for law in SPRING_LAWS
        }
        self.delta1 = scene.stabilization.delta1
        self.delta2 = scene.stabilization.delta2
        self.weighting = scene.control.weighting

        self.force_terms = tuple(
            name
            for name, on in (
                (Effect.GRAVITY.value, scene.has(Effect.GRAVITY)),
                *((law.effect.value, True) for law in self.spring_laws),
                (Effect.EXTERNAL_TORQUE.value, scene.has(Effect.EXTERNAL_TORQUE)),
            )
            if on
        )

        self.omega_track = scene.control.omega if scene.has(Effect.CONTROL_OMEGA) else None
        self.mass_track = scene.control.masses if scene.has(Effect.CONTROL_MASSES) else None
        self.structure = array_model.structure_of(scene)
        self.params = array_model.parameters(scene, np, np.float64)
        self.k = self.structure.k

    # ------------------------------------------------------------------------------------------
    # M, Q and the constraints: the array form (analytic.array_model) with numpy, one state
    # ------------------------------------------------------------------------------------------

    def _kin(self, q: np.ndarray, qdot: np.ndarray | None) -> array_model.Kinematics:
        return array_model.kinematics(np, self.structure, self.params, q, qdot)

    def _mass_matrix(self, k: array_model.Kinematics) -> np.ndarray:
        return array_model.mass_matrix(np, self.structure, self.params, k)

    def _force(self, t: float, k: array_model.Kinematics) -> np.ndarray:
        return array_model.generalized_force(np, self.structure, self.params, t, k)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """``M(q)`` of Eq. (51) (with Remark 1's inertia when the effect is on), shape (nq, nq)."""
        return self._mass_matrix(self._kin(np.asarray(q, float), None))

    def generalized_force(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """``Q(q, q̇)`` of Eq. (52) for the scene's effects (Remark 2 included), shape (nq,)."""
        return self._force(t, self._kin(np.asarray(q, float), np.asarray(qdot, float)))

    def modeling_constraint(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, float]:
        """``a_m = [0, u, 0]`` and ``b_m`` of Eq. (59): ``φ̈ + δ1 φ̇ + δ2 φ = 0`` for ``φ = uᵀu - 1``."""
        a_m, b_m = array_model.modeling_constraint(
            np, self.structure, self.params, np.asarray(q, float), np.asarray(qdot, float)
        )
        return a_m, float(b_m)

    def requirements(self, t: float) -> dict[str, np.ndarray]:
        """The required ``ω̄, ω̄̇`` (Eq. 76) and ``p̄, p̄̇, p̄̈`` (Eq. 75) at time t, for the tracked
        components/masses only."""
        return array_model.requirements(np, self.structure, self.params, float(t))

    def control_constraints(
        self, t: float, q: np.ndarray, qdot: np.ndarray, k: array_model.Kinematics | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``A_c`` (k, nq) and ``b_c`` (k,) of Eqs. (80), (85) (subsets per Remark 4; gain P of
        Eq. B6 in place of γI when given)."""
        if not self.k:
            return np.zeros((0, self.nq)), np.zeros(0)
        if k is None:
            k = self._kin(np.asarray(q, float), np.asarray(qdot, float))
        return array_model.control_constraints(np, self.structure, self.params, t, k)

    # ------------------------------------------------------------------------------------------
    # Motion
    # ------------------------------------------------------------------------------------------

    def acceleration(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, ControlOutput]:
        """Constrained, controlled acceleration ``q̈`` (Eq. 89) and the control that produces it.

        The array form's system and fundamental equation (:func:`analytic.array_model.solution`)
        with numpy, scipy's Cholesky of ``M_α`` (which raises when the motion is not unique) and
        :func:`analytic.fundamental.pinv_psd` (the rank decided by a branch, one eigen-decomposition
        at full rank).

        Args:
            t: time, s.
            q, qdot: state in the paper's coordinates, shape (nq,) each.

        Returns:
            ``(qddot, control)``: shape (nq,) and a :class:`ControlOutput`.
        """
        q = np.asarray(q, float)
        qdot = np.asarray(qdot, float)
        kin, sol = array_model.solution(
            np,
            self.structure,
            self.params,
            t,
            q,
            qdot,
            factor=fundamental.cholesky_factor,
            pinv=fundamental.pinv_psd,
        )
        c = array_model.control_of(np, kin, sol)
        ctrl = ControlOutput(
            QC=c.QC,
            torque=c.torque,
            rod_forces=c.rod_forces,
            force_at_C=c.force_at_C,
            residual=c.residual,
            rank=int(sol.rank),
        )
        return c.qddot, ctrl

    def given_torque(self, t: float) -> np.ndarray:
        """The given body-axis torque of Remark 2 at time t (zeros when the effect is off), N·m."""
        return array_model.given_torque(np, self.structure, self.params, float(t))

    def positions(self, q: np.ndarray) -> np.ndarray:
        """Inertial positions of the masses ``r_i = R + p_i Sa + Sd`` (Eq. 21), shape (n, 3)."""
        return array_model.positions(np, self.structure, self.params, np.asarray(q, float))


MODEL_EFFECTS: frozenset[Effect] = frozenset(
    {
        Effect.GRAVITY,  # array_model.generalized_force
        Effect.EXTERNAL_TORQUE,  # array_model.given_torque
        Effect.MASS_INERTIA,  # J + Σ J_i (Remark 1), array_model.parameters
        Effect.CONTROL_OMEGA,  # array_model.control_constraints
        Effect.CONTROL_MASSES,
        *(law.effect for law in SPRING_LAWS),  # each law's declaration, array_model
    }
)
"""The effects :class:`TumblingModel` assembles: those written here, and every spring law (its
force, energy and dissipation are its declaration's)."""


def _element_differences(x: np.ndarray) -> np.ndarray:
    """``x_j - x_{j-1}`` for the n + 1 spring elements, with ``x_{-1} = x_n = 0``: their
    extensions from ``x = p - p_e``, their extension rates from ``ṗ`` (Eq. 38); x shape (..., n)
    -> (..., n + 1)."""
    x = np.asarray(x, float)
    out = np.empty((*x.shape[:-1], x.shape[-1] + 1))
    out[..., 0] = x[..., 0]
    out[..., 1:-1] = x[..., 1:] - x[..., :-1]
    out[..., -1] = -x[..., -1]
    return out


def spring_energy(model: TumblingModel, p: np.ndarray) -> np.ndarray:
    """``U_s`` of Eq. (38) for the scene's conservative spring laws; p shape (N, n) -> (N,), J."""
    U = np.zeros(p.shape[0])
    if model.n == 0:
        return U
    ext = _element_differences(p - model.p_e)
    for law in model.spring_laws:
        if law.potential is not None:
            U += law.potential(ext) @ model.spring_coefficients[law.effect]
    return U


def dissipated_power(model: TumblingModel, p: np.ndarray, pd: np.ndarray) -> np.ndarray:
    """``Ḋ = Σ c δ(e, ė) ≥ 0``, the power the scene's dissipative spring laws take out of the
    motion (the rate of the energy balance's ``D``); p, pd shape (..., n) -> (...), W."""
    shape = np.shape(p)[:-1]
    D = np.zeros(shape)
    if model.n == 0:
        return D
    ext = _element_differences(np.asarray(p) - model.p_e)
    rate = _element_differences(pd)
    for law in model.spring_laws:
        if law.dissipation is not None:
            D = D + law.dissipation(ext, rate) @ model.spring_coefficients[law.effect]
    return D


def dissipated_power_rate(
    model: TumblingModel, p: np.ndarray, pd: np.ndarray, pdd: np.ndarray
) -> np.ndarray:
    """``d Ḋ / dt``, W/s: the rate of :func:`dissipated_power` along a motion with ``p̈``, by the
    chain rule through each dissipative law's ``δ(e, ė)`` (a central difference of ``δ`` in each
    argument, exact for the quadratic ``δ`` of a viscous law); shapes (..., n) -> (...)."""
    D = np.zeros(np.shape(p)[:-1])
    if model.n == 0:
        return D
    e = _element_differences(np.asarray(p) - model.p_e)
    ed = _element_differences(pd)
    edd = _element_differences(pdd)
    for law in model.spring_laws:
        if law.dissipation is None:
            continue
        c = model.spring_coefficients[law.effect]
        he = 1e-3 * (1.0 + np.abs(e))
        hd = 1e-3 * (1.0 + np.abs(ed))
        d_e = (law.dissipation(e + he, ed) - law.dissipation(e - he, ed)) / (2 * he)
        d_ed = (law.dissipation(e, ed + hd) - law.dissipation(e, ed - hd)) / (2 * hd)
        D = D + (d_e * ed + d_ed * edd) @ c
    return D


def dissipates(model: TumblingModel) -> bool:
    """Whether a law that is on takes energy out of the motion (the run then integrates ``D``)."""
    return any(law.dissipation is not None for law in model.spring_laws)


__all__ = [
    "MODEL_EFFECTS",
    "ControlOutput",
    "TumblingModel",
    "dissipated_power",
    "dissipated_power_rate",
    "dissipates",
    "spring_energy",
]
