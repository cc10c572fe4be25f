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

The model is assembled from the scene's effects: a force term whose effect is off is not in the
term list and is never evaluated.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from analytic import fundamental
from analytic.effects import Effect
from analytic.effects.declaration import SpringLaw
from analytic.effects.registry import SPRING_LAWS
from analytic.kinematics import T_H, S, tensor_along
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


class _Kin:
    """Kinematic quantities shared by M, Q and the constraints at one state (no copies)."""

    __slots__ = (
        "Hd",
        "Hm",
        "La",
        "Ld",
        "Sa",
        "Sd",
        "Sm",
        "mu1",
        "mu2",
        "omega",
        "p",
        "pd",
        "u",
        "ud",
    )


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

        terms: list[tuple[str, Callable]] = []
        if scene.has(Effect.GRAVITY):
            terms.append((Effect.GRAVITY.value, self._q_gravity))
        for law in self.spring_laws:
            terms.append((law.effect.value, partial(self._q_spring_law, law)))
        if scene.has(Effect.EXTERNAL_TORQUE):
            terms.append((Effect.EXTERNAL_TORQUE.value, self._q_external_torque))
        self._terms = tuple(f for _, f in terms)
        self.force_terms = tuple(name for name, _ in terms)

        self.omega_track = scene.control.omega if scene.has(Effect.CONTROL_OMEGA) else None
        self.mass_track = scene.control.masses if scene.has(Effect.CONTROL_MASSES) else None
        k_w = len(self.omega_track.components) if self.omega_track else 0
        k_p = len(self.mass_track.indices) if self.mass_track else 0
        self.k = k_w + k_p
        # Constant part of A_c: the mass rows [0, 0, E] (Eq. 80, Remark 4).
        self._A_c_template = np.zeros((self.k, self.nq))
        if self.mass_track:
            idx = np.array(self.mass_track.indices)
            self._A_c_template[k_w + np.arange(k_p), 7 + idx] = 1.0
            self._p_idx = idx
        if self.omega_track:
            self._w_comps = np.array(self.omega_track.components)

    # ------------------------------------------------------------------------------------------
    # Kinematics
    # ------------------------------------------------------------------------------------------

    def _kin(self, q: np.ndarray, qdot: np.ndarray | None) -> _Kin:
        k = _Kin()
        k.u = u = q[3:7]
        k.p = p = q[7:]
        k.Sm = Sm = S(u)
        k.Sa = Sm @ self.a
        k.Sd = Sm @ self.d
        k.Hm = T_H @ u  # Eq. (13)
        k.La = self.T_a @ u  # Eq. (29)
        k.Ld = self.T_d @ u  # Eq. (34)
        k.mu1 = float(self.m @ p)
        k.mu2 = float((self.m * p) @ p)
        if qdot is not None:
            k.ud = qdot[3:7]
            k.pd = qdot[7:]
            k.omega = k.Hm @ k.ud  # Eq. (12)
            k.Hd = T_H @ k.ud  # Ḣ = H(u̇)
        return k

    # ------------------------------------------------------------------------------------------
    # M and Q
    # ------------------------------------------------------------------------------------------

    def _mass_matrix(self, k: _Kin) -> np.ndarray:
        n, m = self.n, self.m
        La, Ld, Sa = k.La, k.Ld, k.Sa
        M = np.zeros((self.nq, self.nq))
        M[0, 0] = M[1, 1] = M[2, 2] = self.m_T
        B = k.mu1 * La + self.mu0 * Ld  # {mᵀp}L_a + {mᵀ1}L_d, Eq. (51)
        M[:3, 3:7] = B
        M[3:7, :3] = B.T
        LaLd = La.T @ Ld
        # HᵀJH + {(p∘m)ᵀp}L_aᵀL_a + A_d, Eq. (51)
        M[3:7, 3:7] = (
            k.Hm.T @ self.J @ k.Hm
            + k.mu2 * (La.T @ La)
            + k.mu1 * (LaLd + LaLd.T)
            + self.mu0 * (Ld.T @ Ld)
        )
        if n:
            M[:3, 7:] = np.outer(Sa, m)  # (Sa)mᵀ
            M[7:, :3] = M[:3, 7:].T
            Mup = np.outer(La.T @ Sa, k.p * m) + np.outer(Ld.T @ Sa, m)  # L_aᵀSa(p∘m)ᵀ + L_dᵀSa mᵀ
            M[3:7, 7:] = Mup
            M[7:, 3:7] = Mup.T
            M[7:, 7:] = np.diag((Sa @ Sa) * m)  # {(Sa)ᵀSa} diag(m)
        return M

    def _inertial_force(self, k: _Kin) -> np.ndarray:
        """Velocity-dependent part of Q (Eq. 52 without gravity and springs)."""
        m = self.m
        ud, pd = k.ud, k.pd
        Q = np.empty(self.nq)
        Lau = k.La @ ud  # L_a u̇ = Ṡa
        Lad_u = (self.T_a @ ud) @ ud  # L̇_a u̇
        Ldd_u = (self.T_d @ ud) @ ud  # L̇_d u̇
        mpd = float(m @ pd)  # mᵀṗ
        mppd = float((m * k.p) @ pd)  # (p∘m)ᵀṗ
        sum_m_kappa = (2.0 * mpd) * Lau + k.mu1 * Lad_u + self.mu0 * Ldd_u  # Σ m_i κ_i
        sum_mp_kappa = (2.0 * mppd) * Lau + k.mu2 * Lad_u + k.mu1 * Ldd_u  # Σ m_i p_i κ_i
        Q[:3] = -sum_m_kappa
        # -2ḢᵀJHu̇ - L_aᵀ Σ m_i p_i κ_i - L_dᵀ Σ m_i κ_i  (= Eq. 52 second row with B_d)
        Q[3:7] = -2.0 * (k.Hd.T @ (self.J @ k.omega)) - k.La.T @ sum_mp_kappa - k.Ld.T @ sum_m_kappa
        if self.n:
            Sa = k.Sa
            # -{(Sa)ᵀL̇_a u̇}(p∘m) - 2{(Sa)ᵀL_a u̇}(m∘ṗ) - {(Sa)ᵀL̇_d u̇}m, Eq. (52) third row
            Q[7:] = -m * (
                (2.0 * float(Sa @ Lau)) * pd + float(Sa @ Lad_u) * k.p + float(Sa @ Ldd_u)
            )
        return Q

    def _q_gravity(self, t: float, k: _Kin, Q: np.ndarray) -> None:
        g = self.g  # inertial acceleration vector (paper: -g e3)
        Q[:3] += self.m_T * g
        Q[3:7] += (k.mu1 * k.La + self.mu0 * k.Ld).T @ g
        if self.n:
            Q[7:] += float(k.Sa @ g) * self.m

    def _q_spring_law(self, law: SpringLaw, t: float, k: _Kin, Q: np.ndarray) -> None:
        """One spring law's term of Q: tensions ``f = c φ(e, ė)`` of the n + 1 elements, and
        ``Q_i = f_{i+1} - f_i`` (F^S = -∂U_s/∂p for a conservative law; Eq. 53 corrected,
        docs/errata.md item 2)."""
        e = _element_differences(k.p - self.p_e)
        ed = _element_differences(k.pd) if law.dissipation is not None else None
        f = self.spring_coefficients[law.effect] * law.force(e, ed)
        Q[7:] += f[1:] - f[:-1]

    def _q_external_torque(self, t: float, k: _Kin, Q: np.ndarray) -> None:
        Q[3:7] += k.Hm.T @ self.scene.external_torque.at(t)  # Q_τ = Hᵀτ, Remark 2 (Eq. 61)

    def _force(self, t: float, k: _Kin) -> np.ndarray:
        Q = self._inertial_force(k)
        for term in self._terms:
            term(t, k, Q)
        return Q

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """``M(q)`` of Eq. (51) (with Remark 1's inertia when the effect is on), shape (nq, nq)."""
        return self._mass_matrix(self._kin(np.asarray(q, float), None))

    def generalized_force(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """``Q(q, q̇)`` of Eq. (52) for the scene's effects (Remark 2 included), shape (nq,)."""
        return self._force(t, self._kin(np.asarray(q, float), np.asarray(qdot, float)))

    # ------------------------------------------------------------------------------------------
    # Constraints
    # ------------------------------------------------------------------------------------------

    def modeling_constraint(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, float]:
        """``a_m = [0, u, 0]`` and ``b_m`` of Eq. (59): ``φ̈ + δ1 φ̇ + δ2 φ = 0`` for ``φ = uᵀu - 1``."""
        u, ud = q[3:7], qdot[3:7]
        a_m = np.zeros(self.nq)
        a_m[3:7] = u
        b_m = (
            -self.delta1 * float(u @ ud) - 0.5 * self.delta2 * (float(u @ u) - 1.0) - float(ud @ ud)
        )
        return a_m, b_m

    def requirements(self, t: float) -> dict[str, np.ndarray]:
        """The required ``ω̄, ω̄̇`` (Eq. 76) and ``p̄, p̄̇, p̄̈`` (Eq. 75) at time t, for the tracked
        components/masses only."""
        out: dict[str, np.ndarray] = {}
        if self.omega_track:
            w = self.omega_track
            c = self._w_comps
            out["omega_bar"] = w.b[c] * np.cos(w.sigma[c] * t)
            out["omega_bar_dot"] = -w.b[c] * w.sigma[c] * np.sin(w.sigma[c] * t)
        if self.mass_track:
            mt = self.mass_track
            cos, sin = np.cos(mt.lam * t), np.sin(mt.lam * t)
            out["p_bar"] = self.p_e[self._p_idx] + mt.l * cos
            out["p_bar_dot"] = -mt.l * mt.lam * sin
            out["p_bar_ddot"] = -mt.l * mt.lam**2 * cos
        return out

    def control_constraints(
        self, t: float, q: np.ndarray, qdot: np.ndarray, k: _Kin | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``A_c`` (k, nq) and ``b_c`` (k,) of Eqs. (80), (85) (subsets per Remark 4; gain P of
        Eq. B6 in place of γI when given)."""
        if k is None:
            k = self._kin(q, qdot)
        A = self._A_c_template.copy()
        b = np.empty(self.k)
        req = self.requirements(t)
        k_w = 0
        if self.omega_track:
            c = self._w_comps
            k_w = len(c)
            A[:k_w, 3:7] = k.Hm[c]  # [0, H, 0], Eq. (86)
            e = k.omega[c] - req["omega_bar"]
            b[:k_w] = req["omega_bar_dot"] - self.omega_track.gain @ e  # Eq. (84) / (B8)
        if self.mass_track:
            mt = self.mass_track
            i = self._p_idx
            b[k_w:] = (
                req["p_bar_ddot"]
                - mt.alpha * (k.pd[i] - req["p_bar_dot"])
                - mt.beta * (k.p[i] - req["p_bar"])
            )  # Eq. (81)
        return A, b

    # ------------------------------------------------------------------------------------------
    # Motion
    # ------------------------------------------------------------------------------------------

    def acceleration(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, ControlOutput]:
        """Constrained, controlled acceleration ``q̈`` (Eq. 89) and the control that produces it.

        Args:
            t: time, s.
            q, qdot: state in the paper's coordinates, shape (nq,) each.

        Returns:
            ``(qddot, control)``: shape (nq,) and a :class:`ControlOutput`.
        """
        q = np.asarray(q, float)
        qdot = np.asarray(qdot, float)
        k = self._kin(q, qdot)
        M = self._mass_matrix(k)
        Q = self._force(t, k)
        a_m, b_m = self.modeling_constraint(q, qdot)
        if self.k:
            A_c, b_c = self.control_constraints(t, q, qdot, k)
        else:
            A_c, b_c = np.zeros((0, self.nq)), np.zeros(0)
        sol = fundamental.solve(M, Q, a_m, b_m, A_c, b_c, self.weighting)
        Qc = sol.control_force  # = Q^C up to the norm-constraint reaction along [0, u, 0] (H u = 0)
        ctrl = ControlOutput(
            QC=sol.constraint_force,
            torque=0.25 * (k.Hm @ Qc[3:7]),  # τ = ¼ H Q^C_u (docs/errata.md C4: Q^C_u = Hᵀτ + c u)
            rod_forces=Qc[7:].copy(),
            force_at_C=Qc[:3].copy(),
            residual=sol.residual,
            rank=sol.rank,
        )
        return sol.qddot, ctrl

    def given_torque(self, t: float) -> np.ndarray:
        """The given body-axis torque of Remark 2 at time t (zeros when the effect is off), N·m."""
        if self.scene.has(Effect.EXTERNAL_TORQUE):
            return self.scene.external_torque.at(t)
        return np.zeros(3)

    def positions(self, q: np.ndarray) -> np.ndarray:
        """Inertial positions of the masses ``r_i = R + p_i Sa + Sd`` (Eq. 21), shape (n, 3)."""
        k = self._kin(np.asarray(q, float), None)
        return q[:3] + np.outer(k.p, k.Sa) + k.Sd


MODEL_EFFECTS: frozenset[Effect] = frozenset(
    {
        Effect.GRAVITY,  # _q_gravity
        Effect.EXTERNAL_TORQUE,  # _q_external_torque
        Effect.MASS_INERTIA,  # J + Σ J_i (Remark 1)
        Effect.CONTROL_OMEGA,  # control_constraints
        Effect.CONTROL_MASSES,
        *(law.effect for law in SPRING_LAWS),  # _q_spring_law, from each law's declaration
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
