"""Rates of the quantities integrated along with the motion (work and impulses), one call per
right-hand side: ``Ẇ = (τ + τ_g)·ω + F·ṗ + F_C·Ṙ``, ``İ_L = S(u)(τ + τ_g) + (R - c)×F_C`` and
``İ_P = F_C``, with ``ω = H(u)u̇`` (Eq. 12), S of Eq. (11) and ``R - c = -(μ1 Sa + μ0 Sd)/m_T`` (the
arm of a force at C about the system centre of mass c).

Scalar code, compiled with numba when it is installed (the numpy version of the same lines runs
otherwise): on small vectors ``np.cross`` and friends cost far more than the arithmetic. ``S`` and
``ω`` are the kernel's (:mod:`analytic.kernel.kinematics`).
"""

from __future__ import annotations

import numpy as np

from analytic.kernel.kinematics import omega, rotation
from analytic.runtime.jit import inner, jit_entry


def _make(deps: int):
    """:func:`aux_rates` closing over the kernel's source fingerprint (it embeds
    :func:`analytic.kernel.kinematics.rotation`; see :func:`analytic.runtime.jit.jit_entry`)."""

    def aux_rates(q, qd, tau, rod, fC, a, d, m, mu0, m_T, out):  # pragma: no cover - compiled
        """Fill ``out[0] = Ẇ``, ``out[1:4] = İ_L``, ``out[4:7] = İ_P`` (see the module docstring).

        Args: q, qd (n+7,); tau = τ + τ_g (3,), body axes, N·m; rod (n,), N; fC (3,), inertial,
        N; a, d (3,), body axes; m (n,), kg; mu0 = Σm, m_T = m_BR + Σm, kg; out (7,).
        """
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return
        rates(q, qd, tau, rod, fC, a, d, m, mu0, m_T, out)

    return aux_rates


@inner
def rates(q, qd, tau, rod, fC, a, d, m, mu0, m_T, out):  # pragma: no cover - compiled
    """:func:`aux_rates`'s body, called by compiled callers (the analytic plant's right-hand
    side, :mod:`analytic.fast_rhs`), which then need no separately compiled function."""
    u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
    v0, v1, v2, v3 = qd[3], qd[4], qd[5], qd[6]
    w0, w1, w2 = omega(u0, u1, u2, u3, v0, v1, v2, v3)  # ω = H(u) u̇, Eqs. (12)-(13)
    power = tau[0] * w0 + tau[1] * w1 + tau[2] * w2
    power += fC[0] * qd[0] + fC[1] * qd[1] + fC[2] * qd[2]
    mu1 = 0.0
    for i in range(m.shape[0]):
        power += rod[i] * qd[7 + i]
        mu1 += m[i] * q[7 + i]
    s00, s01, s02, s10, s11, s12, s20, s21, s22 = rotation(u0, u1, u2, u3)  # S(u), Eq. (11)
    # arm R - c = -(μ1 a + μ0 d) rotated by S, over m_T
    e0 = mu1 * a[0] + mu0 * d[0]
    e1 = mu1 * a[1] + mu0 * d[1]
    e2 = mu1 * a[2] + mu0 * d[2]
    r0 = -(s00 * e0 + s01 * e1 + s02 * e2) / m_T
    r1 = -(s10 * e0 + s11 * e1 + s12 * e2) / m_T
    r2 = -(s20 * e0 + s21 * e1 + s22 * e2) / m_T
    out[0] = power
    out[1] = s00 * tau[0] + s01 * tau[1] + s02 * tau[2] + (r1 * fC[2] - r2 * fC[1])
    out[2] = s10 * tau[0] + s11 * tau[1] + s12 * tau[2] + (r2 * fC[0] - r0 * fC[2])
    out[3] = s20 * tau[0] + s21 * tau[1] + s22 * tau[2] + (r0 * fC[1] - r1 * fC[0])
    out[4] = fC[0]
    out[5] = fC[1]
    out[6] = fC[2]


aux_rates = jit_entry(_make)


def aux_rates_reference(q, qd, tau, rod, fC, a, d, m, mu0, m_T) -> np.ndarray:
    """The same rates with numpy's vector operations (for tests)."""
    from analytic.kinematics import S, omega_of

    u = q[3:7]
    omega = omega_of(u, qd[3:7])
    Sm = S(u)
    arm = -(float(m @ q[7:]) * (Sm @ a) + mu0 * (Sm @ d)) / m_T
    out = np.empty(7)
    out[0] = float(tau @ omega) + float(rod @ qd[7:]) + float(fC @ qd[:3])
    out[1:4] = Sm @ tau + np.cross(arm, fC)
    out[4:7] = fC
    return out
