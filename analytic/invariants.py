"""Invariants of the tumbling system and their balances (Sec. V, Fig. 8; docs/errata.md, conventions C4-C5).

Computed from the state alone, in the paper's coordinates, for any engine's samples:

* quaternion norm error ``e_u = uᵀu - 1``;
* total linear momentum ``P = m_BR Ṙ + Σ m_i ṙ_i``;
* total angular momentum about the system centre of mass ``c``, inertial:
  ``L = S J ω + m_BR (R - c)×Ṙ + Σ m_i (r_i - c)×ṙ_i`` (J including the masses' own inertia
  when that effect is on, Remark 1);
* energy ``E = T + U`` with T of Eq. (45) and U of Eq. (46) restricted to the scene's effects.

The paper's S(u) (Eq. 11) is used throughout, so on the unit sphere these are the physical values.

The balances are judged in one place, :mod:`validation.compare.balances` (their residuals, scales
and relative figures); :class:`Balance` names them.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np

from analytic.effects import Effect
from analytic.kinematics import T_H, S_batch
from analytic.model import TumblingModel, dissipated_power, dissipated_power_rate, spring_energy
from analytic.trajectory import Invariants, Tracking


class Balance(StrEnum):
    """The balances of the invariants (values are the names of their thresholds)."""

    LINEAR_MOMENTUM = "linear_momentum"  # P - (P(0) + m_T g t + ∫F_C dt)
    ANGULAR_MOMENTUM = "angular_momentum"  # L - L(0) - ∫S τ dt, about the system CoM
    ENERGY = "energy"  # E - E(0) + D - W


def mass_kinematics(model: TumblingModel, q: np.ndarray, qdot: np.ndarray):
    """Inertial positions and velocities of the masses, shapes (N, n, 3) each, and S (N, 3, 3)."""
    u, ud = q[:, 3:7], qdot[:, 3:7]
    p, pd = q[:, 7:], qdot[:, 7:]
    Sm = S_batch(u)
    Sa = Sm @ model.a
    Sd = Sm @ model.d
    La_ud = np.einsum("rck,nk,nc->nr", model.T_a, u, ud)  # L_a u̇ = Ṡa
    Ld_ud = np.einsum("rck,nk,nc->nr", model.T_d, u, ud)  # L_d u̇ = Ṡd
    R, Rd = q[:, None, :3], qdot[:, None, :3]
    r = R + p[:, :, None] * Sa[:, None, :] + Sd[:, None, :]  # Eq. (21)
    rd = (
        Rd + pd[:, :, None] * Sa[:, None, :] + p[:, :, None] * La_ud[:, None, :] + Ld_ud[:, None, :]
    )
    return r, rd, Sm


def compute_invariants(
    model: TumblingModel,
    t: np.ndarray,
    q: np.ndarray,
    qdot: np.ndarray,
    work: np.ndarray,
    angular_impulse: np.ndarray,
    linear_impulse: np.ndarray,
    dissipated: np.ndarray | None = None,
) -> Invariants:
    """Invariants for N samples. ``work`` (N,), impulses (N, 3) and ``dissipated`` (N,; None:
    zeros, no dissipative effect) are integrals since t = 0."""
    m, m_BR, m_T = model.m, model.m_BR, model.m_T
    u, ud = q[:, 3:7], qdot[:, 3:7]
    R, Rd = q[:, :3], qdot[:, :3]
    r, rd, Sm = mass_kinematics(model, q, qdot)
    omega = np.einsum("rck,nk,nc->nr", T_H, u, ud)

    P = m_BR * Rd + np.einsum("i,nij->nj", m, rd)
    c = (m_BR * R + np.einsum("i,nij->nj", m, r)) / m_T
    L = np.einsum("nij,jk,nk->ni", Sm, model.J, omega)
    L += m_BR * np.cross(R - c, Rd)
    L += np.einsum("i,nij->nj", m, np.cross(r - c[:, None, :], rd))

    T = 0.5 * m_BR * np.sum(Rd * Rd, axis=1) + 0.5 * np.einsum("ni,ij,nj->n", omega, model.J, omega)
    T += 0.5 * np.einsum("i,nij,nij->n", m, rd, rd)
    U = spring_energy(model, q[:, 7:])
    P_expected = P[0] + linear_impulse
    if model.scene.has(Effect.GRAVITY):
        g = model.g
        U = U - m_BR * (R @ g) - np.einsum("i,nij,j->n", m, r, g)
        P_expected = P_expected + m_T * np.outer(t - t[0], g)
    return Invariants(
        quat_norm_error=np.sum(u * u, axis=1) - 1.0,
        linear_momentum=P,
        linear_momentum_expected=P_expected,
        angular_momentum=L,
        angular_impulse=angular_impulse,
        energy=T + U,
        work=work,
        dissipated=dissipated,
    )


def dissipated_from_samples(
    model: TumblingModel, t: np.ndarray, p: np.ndarray, pd: np.ndarray, pdd: np.ndarray
) -> np.ndarray:
    """``D(t) = ∫₀ᵗ Ḋ dt`` over a run's samples, for a plant that does not integrate it along its
    motion: per interval the two-point Hermite rule ``h/2 (Ḋ₀ + Ḋ₁) + h²/12 (D̈₀ − D̈₁)``, exact for
    cubics (fourth order in the sample interval), with ``Ḋ`` (:func:`analytic.model.
    dissipated_power`) and its rate ``D̈`` (:func:`analytic.model.dissipated_power_rate`) from
    the samples' ``p, ṗ, p̈`` (each (N, n)). Shape (N,), J."""
    rate = dissipated_power(model, p, pd)
    accel = dissipated_power_rate(model, p, pd, pdd)
    h = np.diff(np.asarray(t, float))
    steps = 0.5 * h * (rate[1:] + rate[:-1]) + h * h / 12.0 * (accel[:-1] - accel[1:])
    return np.concatenate([[0.0], np.cumsum(steps)])


def tracking_errors(
    model: TumblingModel, t: np.ndarray, q: np.ndarray, omega: np.ndarray
) -> Tracking:
    """Tracking errors of the scene's requirements for N samples, any engine.

    Args:
        t: times, s, shape (N,); q: coordinates (Eq. 44), shape (N, n+7); omega: body-axis angular
            velocity, rad/s, shape (N, 3).

    Returns:
        ``e_ω = ω - ω̄`` on the tracked axes (Eq. 82) and ``e_p = p - p̄`` for the tracked masses
        (Eq. 77); empty arrays for what is not tracked.
    """
    N = len(t)
    comps = tuple(model.omega_track.components) if model.omega_track else ()
    idx = tuple(model.mass_track.indices) if model.mass_track else ()
    e_w = np.zeros((N, len(comps)))
    e_p = np.zeros((N, len(idx)))
    for i in range(N):
        req = model.requirements(float(t[i]))
        if comps:
            e_w[i] = omega[i, list(comps)] - req["omega_bar"]
        if idx:
            e_p[i] = q[i, 7 + np.array(idx)] - req["p_bar"]
    return Tracking(omega_components=comps, e_omega=e_w, mass_indices=idx, e_p=e_p)
