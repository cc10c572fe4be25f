"""The kernel for the weighting N = M⁻² (Eq. B13): :func:`evaluate`, O(n), compiled only when a
scene asks for it.

With ``Z = K A_cᵀ`` (``K`` the norm-constrained compliance of :mod:`analytic.fundamental`) one has
``M Z = A_cᵀ - a_m wᵀ``, ``w = A_c y / s_m``, and since ``H(u) u = 0``,
``Zᵀ M² Z = A_c A_cᵀ + |u|² w wᵀ = diag(4|u|² I_kω, I_kp) + |u|² w wᵀ`` (Sherman-Morrison); the rest
are structured solves with ``M_α`` (a Cholesky factor of its Schur complement on the body block),
one product with ``M`` (for ``Q^C``) and ``M_α⁻¹ M v = v - α y (a_mᵀ v)`` (``y = M_α⁻¹ a_m``) in place
of a product with ``M`` followed by a solve, which would cost about cond(M) in accuracy. Cost O(n)
(a few heap arrays of size n + 7, unlike the Gauss kernel).

Stages: :func:`analytic.kernel.system.make_build_system` (1-6, shared with every weighting), then
:func:`make_solve_minv2`: :func:`analytic.kernel.norm_constrained.prepare` and ``finish``
(shared with the other weighting through ``M_α``) around this weighting's own part,
:func:`control_force`. Entry points :data:`evaluate`, :data:`qddot_into`
(:mod:`analytic.kernel.weighting`).
"""

from __future__ import annotations

import numpy as np

from analytic.kernel.calls import arrays
from analytic.kernel.layout import (
    I_KP,
    I_KW,
    I_N,
    I_TRACK,
    IX,
    STATUS_NOT_PD,
    STATUS_OK,
    STATUS_UNSUPPORTED,
    W_MINV2,
    WS_ALPHA,
    WS_MB,
    WS_UU,
)
from analytic.kernel.norm_constrained import finish, prepare
from analytic.kernel.weighting import make_evaluate, make_qddot_into
from analytic.runtime.jit import inner, jit


@inner
def control_force(q, fp, ip, w, SB, c1, c2, s, om, y, sm, acc, bc, Hw, Qc, v2):
    """This weighting's ``Q_c`` and ``M_α⁻¹ Q_c`` (between
    :func:`analytic.kernel.norm_constrained.prepare`, whose results it takes, and ``finish``): the
    multipliers ``μ`` of ``Zᵀ M² Z μ = r`` by Sherman-Morrison (module docstring), ``Q_c = M Z μ``
    by one product with ``M`` (:func:`m_mul`), and ``M_α⁻¹ Q_c = v - α y (a_mᵀ v)`` with
    ``v = Z μ``. Never declines (returns True)."""
    n = ip[I_N] & IX
    kw = ip[I_KW] & IX
    kp = ip[I_KP] & IX
    nq = n + 7
    k = kw + kp
    iidx = I_TRACK + n
    p = q[7:]
    u = q[3:7]
    uu = w[WS_UU]
    alpha = w[WS_ALPHA]
    Mbb = np.empty((7, 7))
    for i in range(7):
        for j in range(7):
            Mbb[i, j] = w[WS_MB + 7 * i + j]
    # r = b_c - A acc; w = A y / s_m; G = diag(4|u|², 1) + |u|² w wᵀ
    r = np.empty(k)
    wv = np.empty(k)
    dg = np.empty(k)
    for j in range(kw):
        va = 0.0
        vy = 0.0
        for c in range(4):
            va += Hw[j, c] * acc[3 + c]
            vy += Hw[j, c] * y[3 + c]
        r[j] = bc[j] - va
        wv[j] = vy / sm
        dg[j] = 4.0 * uu
    for j in range(kp):
        i = ip[iidx + j] & IX
        r[kw + j] = bc[kw + j] - acc[7 + i]
        wv[kw + j] = y[7 + i] / sm
        dg[kw + j] = 1.0
    wDr = 0.0
    wDw = 0.0
    for j in range(k):
        wDr += wv[j] * r[j] / dg[j]
        wDw += wv[j] * wv[j] / dg[j]
    f = uu * wDr / (1.0 + uu * wDw)
    mu = np.empty(k)
    wmu = 0.0
    for j in range(k):
        mu[j] = (r[j] - wv[j] * f) / dg[j]
        wmu += wv[j] * mu[j]
    # v = A_cᵀ μ - a_m (w·μ) (= M Z μ); Q_c = M v
    v = np.zeros(nq)
    for j in range(kw):
        for c in range(4):
            v[3 + c] += Hw[j, c] * mu[j]
    for c in range(4):
        v[3 + c] -= u[c] * wmu
    for j in range(kp):
        v[7 + (ip[iidx + j] & IX)] = mu[kw + j]
    m_mul(Mbb, c1, c2, s, fp, om, p, n, v, Qc)
    # v2 = M_α⁻¹ Q_c = M_α⁻¹ M v = v - α y (a_mᵀ v) exactly (M = M_α - α a_m a_mᵀ, y = M_α⁻¹ a_m):
    # no product with M followed by a solve, which would cost about cond(M) in accuracy
    am_v = 0.0
    for c in range(4):
        am_v += u[c] * v[3 + c]
    for i in range(nq):
        v2[i] = v[i] - alpha * am_v * y[i]
    return True


def make_solve_minv2(deps: int):
    """The C callback body of stage 7 under M⁻² (:data:`analytic.runtime.abi.SOLVE_SIG`; ``full``
    is always 1 here), closing over the kernel's source fingerprint; :mod:`analytic.kernel.halves`
    compiles it once."""

    def solve_minv2(q_p, fp_p, ip_p, out_p, len_out, w_p, full):
        """Stage 7 (M⁻²): ``q̈``, ``Q^C``, ``τ`` and the residual into ``out``
        (the shared :func:`analytic.kernel.norm_constrained.prepare` and ``finish`` around
        :func:`control_force`),
        from what :func:`analytic.kernel.system.make_build_system` wrote; its status."""
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return STATUS_UNSUPPORTED
        q, fp, ip, out, w = arrays(q_p, fp_p, ip_p, out_p, len_out, w_p)
        ok, SB, c1, c2, s, om, y, sm, lam_m, acc, bc, Hw = prepare(q, fp, ip, out, w)
        if not ok:
            return STATUS_NOT_PD
        nq = (ip[I_N] & IX) + 7
        Qc = np.empty(nq)
        v = np.empty(nq)
        if not control_force(q, fp, ip, w, SB, c1, c2, s, om, y, sm, acc, bc, Hw, Qc, v):
            return STATUS_NOT_PD
        finish(q, ip, out, w, y, sm, lam_m, acc, bc, Hw, Qc, v)
        return STATUS_OK

    return solve_minv2


@jit
def m_mul(Mbb, c1, c2, s, fp, om, p, n, v, out):
    """out = M v (M without the α term) using M_bp columns m_i (c1 + p_i c2), M_pp = s diag(m)."""
    t0 = 0.0
    t1 = 0.0
    for i in range(n):
        mv = fp[om + i] * v[7 + i]
        t0 += mv
        t1 += mv * p[i]
    for r in range(7):
        acc = c1[r] * t0 + c2[r] * t1
        for c in range(7):
            acc += Mbb[r, c] * v[c]
        out[r] = acc
    for i in range(n):
        acc = 0.0
        for r in range(7):
            acc += (c1[r] + p[i] * c2[r]) * v[r]
        out[7 + i] = fp[om + i] * (acc + s * v[7 + i])


evaluate = make_evaluate(W_MINV2)
"""One evaluation under M⁻²: ``evaluate(t, q, qd, fp, ip, out) -> status``
(:func:`analytic.kernel.weighting.make_evaluate`; the full output only)."""

qddot_into = make_qddot_into(W_MINV2)
"""``qddot_into(t, q, qd, fp, ip, qdd) -> status``: :data:`evaluate` reduced to ``q̈``."""
