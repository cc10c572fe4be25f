"""The solve of a weighting that goes through ``M_α`` (M⁻², Eq. B13; identity, Eq. B10 with
W = I): everything but the control force itself, shared by :mod:`analytic.kernel.minv2` and
:mod:`analytic.kernel.identity`.

With ``M_α = M + α a_m a_mᵀ`` (:mod:`analytic.kernel.system` writes its body block, ``Q_α`` and
``b_m``), ``y = M_α⁻¹ a_m``, ``s_m = a_mᵀ y`` and ``K = M_α⁻¹ - y yᵀ/s_m`` (the norm-constrained
compliance of :mod:`analytic.fundamental`):

* the uncontrolled, norm-constrained acceleration ``a = M_α⁻¹ Q_α + λ_m y``,
  ``λ_m = (b_m - a_mᵀ M_α⁻¹ Q_α) / s_m`` (Eq. 60);
* the weighting's control force ``Q_c`` and ``v = M_α⁻¹ Q_c``: the weighting's own part, between
  :func:`prepare` (everything before) and :func:`finish` (everything after);
* then, for every weighting, ``q̈ = a + v - y (a_mᵀ v)/s_m`` (``= a + K Q_c``),
  ``Q^C = Q_c + a_m (λ_m - yᵀQ_c/s_m)``, ``τ = ¼ H Q_c,u`` (docs/errata.md C4) and the residual
  ``A_c q̈ - b_c``.

``M_α⁻¹ x`` is a structured solve (:func:`ma_solve`): the rods eliminated onto the 7x7 body block,
whose Schur complement has a Cholesky factor. Cost O(n) plus the weighting's, a few heap arrays.
"""

from __future__ import annotations

import math

import numpy as np

from analytic.kernel.calls import tail
from analytic.kernel.layout import (
    F_MU0,
    I_COMP,
    I_KP,
    I_KW,
    I_N,
    I_TRACK,
    IX,
    WS_ALPHA,
    WS_BM,
    WS_BW,
    WS_C1,
    WS_C2,
    WS_H,
    WS_MB,
    WS_MU1,
    WS_MU2,
    WS_QB,
    WS_S,
)
from analytic.runtime.jit import inner, jit


@jit
def chol(A, k):
    """In-place lower Cholesky of the leading k x k block of A. Returns False if not PD."""
    for j in range(k):
        d = A[j, j]
        for c in range(j):
            d -= A[j, c] * A[j, c]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        A[j, j] = d
        for i in range(j + 1, k):
            v = A[i, j]
            for c in range(j):
                v -= A[i, c] * A[j, c]
            A[i, j] = v / d
    return True


@jit
def chol_solve(L, k, b):
    """Solve (L Lᵀ) x = b in place (b of length >= k)."""
    for i in range(k):
        v = b[i]
        for c in range(i):
            v -= L[i, c] * b[c]
        b[i] = v / L[i, i]
    for i in range(k - 1, -1, -1):
        v = b[i]
        for c in range(i + 1, k):
            v -= L[c, i] * b[c]
        b[i] = v / L[i, i]


@jit
def ma_solve(SB, c1, c2, s, fp, om, p, n, x):
    """In place x <- M_α⁻¹ x by the Schur complement SB (Cholesky factor) on the body block."""
    s0 = 0.0
    s1 = 0.0
    for i in range(n):
        s0 += x[7 + i]
        s1 += p[i] * x[7 + i]
    xb = np.empty(7)
    for r in range(7):
        xb[r] = x[r] - (c1[r] * s0 + c2[r] * s1) / s
    chol_solve(SB, 7, xb)
    for r in range(7):
        x[r] = xb[r]
    for i in range(n):
        v = 0.0
        for r in range(7):
            v += (c1[r] + p[i] * c2[r]) * xb[r]
        x[7 + i] = (x[7 + i] / fp[om + i] - v) / s


@inner
def prepare(q, fp, ip, out, w):
    """The part before the control force, from what stages 1-6 wrote into ``w`` and the rod
    rows of ``out`` (module docstring; mirrors :func:`analytic.fundamental.solve`).

    Returns:
        ``(ok, SB, c1, c2, s, om, y, sm, lam_m, acc, bc, Hw)``: ``ok`` False when the Schur
        complement of ``M_α`` on the body block is not numerically positive definite (the rest is
        then unspecified), else its Cholesky factor ``SB`` and what :func:`ma_solve` needs with it
        (``c1, c2, s, om``: ``M_α⁻¹ x`` is ``ma_solve(SB, c1, c2, s, fp, om, q[7:], n, x)``),
        ``y = M_α⁻¹ a_m``, ``s_m``, ``λ_m``, the acceleration ``a`` (``acc``), ``b_c`` and the
        tracked rows ``H_ω`` of ``H(u)``.
    """
    n = ip[I_N] & IX
    kw = ip[I_KW] & IX
    kp = ip[I_KP] & IX
    s = w[WS_S]
    mu0 = fp[F_MU0]
    mu1 = w[WS_MU1]
    mu2 = w[WS_MU2]
    alpha = w[WS_ALPHA]
    b_m = w[WS_BM]
    nq = n + 7
    k = kw + kp
    om = tail(n, kp).m
    iidx = I_TRACK + n
    itr = I_TRACK
    p = q[7:]
    u = q[3:7]
    c1 = w[WS_C1 : WS_C1 + 7].copy()
    c2 = w[WS_C2 : WS_C2 + 7].copy()
    Qa = np.empty(nq)  # Q_α: body rows in w, rod rows in out (see forces.rod_pass)
    for i in range(7):
        Qa[i] = w[WS_QB + i]
    for i in range(n):
        Qa[7 + i] = out[nq + 7 + i] if ip[itr + i] else out[7 + i]
    bc = np.empty(k)
    for j in range(kw):
        bc[j] = w[WS_BW + j]
    for j in range(kp):
        bc[kw + j] = out[7 + (ip[iidx + j] & IX)]
    Hw = np.empty((kw, 4))  # the tracked rows of H(u), Eq. (85)
    for j in range(kw):
        for c in range(4):
            Hw[j, c] = w[WS_H + 4 * (ip[I_COMP + j] & IX) + c]

    SB = np.empty((7, 7))  # body block of M_α, then its Schur complement over all rods
    for i in range(7):
        for j in range(7):
            SB[i, j] = w[WS_MB + 7 * i + j]
    for i in range(4):
        for j in range(4):
            SB[3 + i, 3 + j] += alpha * u[i] * u[j]
    if s > 0.0:
        for i in range(7):
            for j in range(7):
                SB[i, j] -= (
                    mu0 * c1[i] * c1[j]
                    + mu1 * (c1[i] * c2[j] + c2[i] * c1[j])
                    + mu2 * c2[i] * c2[j]
                ) / s
    if not chol(SB, 7):
        return False, SB, c1, c2, s, om, Qa, 1.0, 0.0, Qa, bc, Hw
    a0 = Qa.copy()
    ma_solve(SB, c1, c2, s, fp, om, p, n, a0)
    y = np.zeros(nq)
    for c in range(4):
        y[3 + c] = u[c]
    ma_solve(SB, c1, c2, s, fp, om, p, n, y)
    sm = 0.0
    am_a0 = 0.0
    for c in range(4):
        sm += u[c] * y[3 + c]
        am_a0 += u[c] * a0[3 + c]
    lam_m = (b_m - am_a0) / sm
    acc = a0 + lam_m * y  # Eq. (60)
    return True, SB, c1, c2, s, om, y, sm, lam_m, acc, bc, Hw


@inner
def finish(q, ip, out, w, y, sm, lam_m, acc, bc, Hw, Qc, v):
    """The whole output ``[q̈, Q^C, τ, A_c q̈ - b_c]`` into ``out`` from the weighting's control
    force ``Q_c`` and ``v = M_α⁻¹ Q_c`` (length nq each) and what :func:`prepare` returned
    (module docstring)."""
    n = ip[I_N] & IX
    kw = ip[I_KW] & IX
    kp = ip[I_KP] & IX
    nq = n + 7
    k = kw + kp
    iidx = I_TRACK + n
    u = q[3:7]
    qdd = out[:nq]
    QC = out[nq : 2 * nq]
    tau = out[2 * nq : 2 * nq + 3]
    res = out[2 * nq + 3 : 2 * nq + 3 + k]
    am_v = 0.0  # q̈ = a + K Q_c = a + v - y (a_mᵀ v)/s_m
    yQc = 0.0
    for c in range(4):
        am_v += u[c] * v[3 + c]
    for i in range(nq):
        yQc += y[i] * Qc[i]
    for i in range(nq):
        qdd[i] = acc[i] + v[i] - y[i] * (am_v / sm)
    corr = lam_m - yQc / sm  # Q^C = Q_c + a_m (λ_m - yᵀQ_c/s_m)
    for i in range(nq):
        QC[i] = Qc[i]
    for c in range(4):
        QC[3 + c] += u[c] * corr
    # torque τ = ¼ H Q^C_u of the applied control force (docs/errata.md C4), residual A_c q̈ - b_c
    for rr in range(3):
        vv = 0.0
        for c in range(4):
            vv += w[WS_H + 4 * rr + c] * Qc[3 + c]
        tau[rr] = 0.25 * vv
    for j in range(kw):
        vv = 0.0
        for c in range(4):
            vv += Hw[j, c] * qdd[3 + c]
        res[j] = vv - bc[j]
    for j in range(kp):
        res[kw + j] = qdd[7 + (ip[iidx + j] & IX)] - bc[kw + j]


__all__ = ["chol", "chol_solve", "finish", "ma_solve", "prepare"]
