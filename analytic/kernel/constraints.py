"""The constraint rows of the controlled system (Eq. 88), as kernel stages.

* :func:`modeling_row` (stage 5): the quaternion-norm constraint ``a_mᵀ q̈ = b_m`` with
  ``a_m = [0, u, 0]`` and ``b_m`` of Eq. (59), and the augmentation ``M_α = M + α a_m a_mᵀ``,
  ``Q_α = Q + α b_m a_m`` (``α = tr(M)/nq``) that keeps the solve valid when M is singular along u
  (:mod:`analytic.fundamental`; docs/errata.md item 15).
* :func:`control_rows` (stage 6): the right-hand sides ``b_c`` of the control constraints: the ω
  rows ``b_ω = ω̄̇ - P (H u̇ - ω̄)`` (Eqs. 76, 84-86 with the first-order stabilisation of
  docs/errata.md item 3, gain P of Eq. B6) and the tracked-mass rows
  ``b_p = p̄̈ - α (ṗ - p̄̇) - β (p - p̄)`` (Eqs. 75, 79-81; one α_i, β_i per mass, errata item 4).
  The rows of ``A_c`` themselves (``[0, H_ω, 0]`` and unit rows) are never formed.
"""

from __future__ import annotations

import math

from analytic.kernel.layout import (
    F_D1,
    F_D2,
    F_GAIN,
    F_MBR,
    F_MU0,
    F_WB,
    F_WS,
    I_COMP,
    I_TRACK,
    IX,
    WS_ALPHA,
    WS_BM,
    WS_BW,
    WS_EW,
    WS_MB,
    WS_OM,
    WS_QB,
    WS_S,
    WS_T0,
    WS_T1,
    WS_UU,
)
from analytic.runtime.jit import inner


@inner
def modeling_row(q, qd, fp, nq, w):
    """Stage 5: ``b_m = -δ1 uᵀu̇ - (δ2/2)(uᵀu - 1) - u̇ᵀu̇`` (Eq. 59), ``|u|²``, and
    ``α = tr(M)/nq``, added to the u rows of Q as ``Q_α = Q + α b_m a_m``. Reads the diagonal of
    ``M_bb`` and ``s`` from ``w``; writes ``|u|²``, ``b_m``, ``α``."""
    u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
    v0, v1, v2, v3 = qd[3], qd[4], qd[5], qd[6]
    mu0 = fp[F_MU0]
    m_T = fp[F_MBR] + mu0
    uu = u0 * u0 + u1 * u1 + u2 * u2 + u3 * u3
    uud = u0 * v0 + u1 * v1 + u2 * v2 + u3 * v3
    udud = v0 * v0 + v1 * v1 + v2 * v2 + v3 * v3
    b_m = -fp[F_D1] * uud - 0.5 * fp[F_D2] * (uu - 1.0) - udud
    trM = 3.0 * m_T + w[WS_S] * mu0
    for c in range(4):
        trM += w[WS_MB + 8 * (3 + c)]
    alpha = trM / nq
    for c in range(4):  # Q_α = Q + α b_m a_m (a_m = [0, u, 0])
        w[WS_QB + 3 + c] += alpha * b_m * q[3 + c]
    w[WS_UU] = uu
    w[WS_BM] = b_m
    w[WS_ALPHA] = alpha


@inner
def control_rows(t, q, qd, fp, ip, n, kw, kp, o, out, w):
    """Stage 6: ``b_c`` (module docstring). The ω rows go to ``w[WS_BW:]`` (tracking errors to
    ``w[WS_EW:]``); a tracked mass's ``b_i`` goes to ``out[7 + i]``, its q̈_i (Gauss: ``q̈_i = b_i``).
    Writes ``Σ_T m_i b_i`` and ``Σ_T m_i p_i b_i`` to ``w``. ``o``: the offsets of ``fp``'s tail
    (:class:`analytic.kernel.layout.FpTail`)."""
    o_m, o_pe, o_l, o_lam, o_alpha, o_beta = o.m, o.p_e, o.l, o.lam, o.alpha, o.beta
    ob = WS_BW
    for j in range(kw):  # (cos and sin of one argument in one block: a single sincos call)
        comp = ip[I_COMP + j] & IX
        arg = fp[F_WS + comp] * t
        cs = math.cos(arg)
        sn = math.sin(arg)
        w[WS_EW + j] = w[WS_OM + comp] - fp[F_WB + comp] * cs
        w[ob + j] = -fp[F_WB + comp] * fp[F_WS + comp] * sn
    for j in range(kw):
        v = w[ob + j]
        for c in range(kw):
            v -= fp[F_GAIN + kw * j + c] * w[WS_EW + c]
        w[ob + j] = v
    iidx = I_TRACK + n
    t0 = 0.0  # Σ_T m_i b_i
    t1 = 0.0  # Σ_T m_i p_i b_i
    lam_prev = math.nan  # cos, sin of λ t are reused while λ repeats (often one λ for all masses)
    cs = 0.0
    sn = 0.0
    for j in range(kp):
        i = ip[iidx + j] & IX
        lam = fp[o_lam + j]
        li = fp[o_l + j]
        if lam != lam_prev:
            cs = math.cos(lam * t)
            sn = math.sin(lam * t)
            lam_prev = lam
        pbar = fp[o_pe + i] + li * cs
        pbar_d = -li * lam * sn
        pbar_dd = -li * lam * lam * cs
        b = pbar_dd - fp[o_alpha + j] * (qd[7 + i] - pbar_d) - fp[o_beta + j] * (q[7 + i] - pbar)
        out[7 + i] = b  # q̈_i = b_i for a tracked mass
        mi = fp[o_m + i]
        t0 += mi * b
        t1 += mi * q[7 + i] * b
    w[WS_T0] = t0
    w[WS_T1] = t1
