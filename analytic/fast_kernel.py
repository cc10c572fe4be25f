"""Compiled O(n) kernel of the controlled dynamics (Eqs. 51-53, 59, 80-89, B10): the numba side of
:mod:`analytic.fast`.

Everything the kernel needs is packed by :func:`analytic.fast.pack` into one float array ``fp`` and
one int array ``ip`` (layout constants below), so a call unboxes six arguments only. The kernel writes
``[q̈ (nq), Q^C (nq), τ (3), residual (k)]`` into ``out`` and returns a status (0 = done).

Structure used (coordinates ``q = [R (3), u (4), p (n)]``, body block ``b = [R, u]`` of size 7):

* ``M_pp = s diag(m)`` with ``s = (Sa)ᵀSa`` (Eq. 51), and column i of ``M_bp`` is
  ``m_i (c1 + p_i c2)`` with ``c1 = [Sa; L_dᵀSa]``, ``c2 = [0; L_aᵀSa]`` (7-vectors). Eliminating any
  set F of rod rows onto the body block gives the 7x7 Schur complement
  ``M_bb - (1/s) Σ_F m_i (c1 + p_i c2)(c1 + p_i c2)ᵀ``, i.e. three moments ``Σ_F m_i p_iʲ``.
* Gauss weighting (N = M⁻¹, Eq. 89): the control is the KKT system of Gauss's principle
  ``M_α q̈ = Q_α + a_m λ + A_cᵀ μ``, ``a_mᵀq̈ = b_m``, ``A_c q̈ = b_c``. Tracked-mass rows of ``A_c`` are
  unit rows, so ``q̈_p,i = b_c,i`` for a tracked mass, the free rod rows are eliminated by the Schur
  complement, and what is left is a 7x7 body system bordered by ``1 + k_ω`` rows (≤ 4). ``μ_i`` of a
  tracked mass is its row of ``M_α q̈ - Q_α``. Cost O(n), no (n+7)² matrix is formed.
* N = M⁻² (Eq. B13): with ``Z = K A_cᵀ`` (``K`` the norm-constrained compliance) one has
  ``M Z = A_cᵀ - a_m wᵀ``, ``w = A_c y / s_m``, and since ``H(u) u = 0``,
  ``Zᵀ M² Z = A_c A_cᵀ + |u|² w wᵀ = diag(4|u|² I_kω, I_kp) + |u|² w wᵀ`` (Sherman-Morrison); the rest
  are structured solves with ``M_α`` and products with ``M``. Cost O(n).

The identity weighting is not in this kernel (:mod:`analytic.fast` uses the numpy path for it).
"""

from __future__ import annotations

import math
import os

import numpy as np

try:  # numba is optional: without it analytic.fast falls back to the numpy model
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None
    HAVE_NUMBA = False


def _jit(fn):
    """``numba.njit(cache=True)``, or without the on-disk cache when no cache directory is usable.

    numba looks for a writable cache directory in this order: ``$NUMBA_CACHE_DIR`` (when set),
    ``__pycache__`` beside this file, then the user-wide cache dir (``~/.cache/numba/...`` on Linux;
    the route taken when the package is installed in a read-only site-packages). If none of them is
    writable, ``njit(cache=True)`` raises ``RuntimeError`` at decoration time; the kernel is then
    compiled in memory on every process start instead (slower first call, same results).
    """
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    try:
        return numba.njit(cache=True, fastmath=False, nogil=True)(fn)
    except RuntimeError:  # no usable cache locator
        return numba.njit(cache=False, fastmath=False, nogil=True)(fn)


# ----------------------------------------------------------------------------------------------
# Packed-parameter layout (shared with analytic.fast.pack)
# ----------------------------------------------------------------------------------------------
F_MBR, F_MU0, F_D1, F_D2, F_TFREQ = 0, 1, 2, 3, 4
F_J = 5  # 9, row-major, body axes
F_G = 14  # 3, inertial
F_TC = 17  # 3, external torque constant, body
F_TA = 20  # 3, external torque amplitude, body
F_WB = 23  # 3, omega amplitudes b
F_WS = 26  # 3, omega frequencies sigma
F_GAIN = 29  # kw*kw row-major (9 slots)
F_TAT = 38  # 48: T_a (3, 4, 4) row-major, L_a(u) = T_a @ u (Eq. 29)
F_TDT = 86  # 48: T_d, L_d(u) = T_d @ u (Eq. 34)
F_ARR = 134  # then m (n), p_e (n), k_l (n+1), k_n (n+1), l, lam, alpha, beta (kp each)

I_N, I_KW, I_KP, I_GRAV, I_SLIN, I_SCUB, I_TORQ, I_WEIGHT = 0, 1, 2, 3, 4, 5, 6, 7
I_COMP = 8  # 3 slots: omega components
I_TRACK = 11  # n: 1 for a tracked mass, then the kp tracked indices

W_GAUSS, W_MINV2 = 0, 1
STATUS_OK, STATUS_NOT_PD, STATUS_UNSUPPORTED = 0, 1, 2


# ----------------------------------------------------------------------------------------------
# Small dense helpers (fixed tiny sizes; no LAPACK call overhead)
# ----------------------------------------------------------------------------------------------


@_jit
def _chol(A, k):
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


@_jit
def _chol_solve(L, k, b):
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


@_jit
def _Hmat(u, Hm):
    """H(u) of Eq. (13), shape (3, 4)."""
    u0, u1, u2, u3 = u[0], u[1], u[2], u[3]
    Hm[0, 0] = -2 * u1
    Hm[0, 1] = 2 * u0
    Hm[0, 2] = 2 * u3
    Hm[0, 3] = -2 * u2
    Hm[1, 0] = -2 * u2
    Hm[1, 1] = -2 * u3
    Hm[1, 2] = 2 * u0
    Hm[1, 3] = 2 * u1
    Hm[2, 0] = -2 * u3
    Hm[2, 1] = 2 * u2
    Hm[2, 2] = -2 * u1
    Hm[2, 3] = 2 * u0


@_jit
def _Lmat(fp, off, u, L):
    """L(u) = T @ u for the tensor T stored at fp[off:off+48] (Eqs. 29, 34), shape (3, 4)."""
    for r in range(3):
        for c in range(4):
            base = off + 16 * r + 4 * c
            L[r, c] = (
                fp[base] * u[0] + fp[base + 1] * u[1] + fp[base + 2] * u[2] + fp[base + 3] * u[3]
            )


# ----------------------------------------------------------------------------------------------
# The kernel
# ----------------------------------------------------------------------------------------------


@_jit
def evaluate(t, q, qd, fp, ip, out):
    """One evaluation of the controlled dynamics; see the module docstring.

    Args:
        t: time, s.
        q, qd: state ``[R, u, p]`` and its rate, shape (nq,).
        fp, ip: packed parameters (:func:`analytic.fast.pack`).
        out: float array of length ``2 nq + 3 + k``; receives ``[q̈, Q^C, τ, A_c q̈ - b_c]``.

    Returns:
        status: 0 done; 1 a Schur complement was not numerically positive definite (the caller
        falls back); 2 weighting not supported by this kernel.
    """
    n = ip[I_N]
    kw = ip[I_KW]
    kp = ip[I_KP]
    k = kw + kp
    nq = n + 7
    wt = ip[I_WEIGHT]
    if k > 0 and wt != W_GAUSS and wt != W_MINV2:
        return STATUS_UNSUPPORTED
    om = F_ARR
    ope = om + n
    okl = ope + n
    okn = okl + n + 1
    oml = okn + n + 1
    omlam = oml + kp
    omal = omlam + kp
    ombe = omal + kp
    itr = I_TRACK
    iidx = I_TRACK + n

    m_BR = fp[F_MBR]
    mu0 = fp[F_MU0]
    m_T = m_BR + mu0
    u = q[3:7]
    ud = qd[3:7]
    p = q[7:]
    pd = qd[7:]

    # --- kinematics (Eqs. 11-13, 29, 34) ---
    u0, u1, u2, u3 = u[0], u[1], u[2], u[3]
    Sm = np.empty((3, 3))
    Sm[0, 0] = 2 * u0 * u0 - 1 + 2 * u1 * u1
    Sm[0, 1] = 2 * u1 * u2 - 2 * u0 * u3
    Sm[0, 2] = 2 * u1 * u3 + 2 * u0 * u2
    Sm[1, 0] = 2 * u1 * u2 + 2 * u0 * u3
    Sm[1, 1] = 2 * u0 * u0 - 1 + 2 * u2 * u2
    Sm[1, 2] = 2 * u2 * u3 - 2 * u0 * u1
    Sm[2, 0] = 2 * u1 * u3 - 2 * u0 * u2
    Sm[2, 1] = 2 * u2 * u3 + 2 * u0 * u1
    Sm[2, 2] = 2 * u0 * u0 - 1 + 2 * u3 * u3
    Hm = np.empty((3, 4))
    _Hmat(u, Hm)
    Hd = np.empty((3, 4))
    _Hmat(ud, Hd)
    La = np.empty((3, 4))
    Ld = np.empty((3, 4))
    _Lmat(fp, F_TAT, u, La)
    _Lmat(fp, F_TDT, u, Ld)
    Lad = np.empty((3, 4))
    Ldd = np.empty((3, 4))
    _Lmat(fp, F_TAT, ud, Lad)
    _Lmat(fp, F_TDT, ud, Ldd)
    oa = ombe + kp  # a (3), d (3) appended after the mass-track arrays
    Sa = np.zeros(3)
    Sd = np.zeros(3)
    for r in range(3):
        for c in range(3):
            Sa[r] += Sm[r, c] * fp[oa + c]
            Sd[r] += Sm[r, c] * fp[oa + 3 + c]
    s = Sa[0] * Sa[0] + Sa[1] * Sa[1] + Sa[2] * Sa[2]

    mu1 = 0.0
    mu2 = 0.0
    mpd = 0.0
    mppd = 0.0
    for i in range(n):
        mi = fp[om + i]
        mp = mi * p[i]
        mu1 += mp
        mu2 += mp * p[i]
        mpd += mi * pd[i]
        mppd += mp * pd[i]

    omega = np.zeros(3)
    for r in range(3):
        for c in range(4):
            omega[r] += Hm[r, c] * ud[c]
    Jw = np.zeros(3)
    for r in range(3):
        for c in range(3):
            Jw[r] += fp[F_J + 3 * r + c] * omega[c]

    # --- M body block (Eq. 51) ---
    Mbb = np.zeros((7, 7))
    for r in range(3):
        Mbb[r, r] = m_T
        for c in range(4):
            b = mu1 * La[r, c] + mu0 * Ld[r, c]
            Mbb[r, 3 + c] = b
            Mbb[3 + c, r] = b
    HJ = np.zeros((3, 4))  # J H
    for r in range(3):
        for c in range(4):
            v = 0.0
            for j in range(3):
                v += fp[F_J + 3 * r + j] * Hm[j, c]
            HJ[r, c] = v
    for i in range(4):
        for j in range(i, 4):
            v = 0.0
            for r in range(3):
                v += (
                    Hm[r, i] * HJ[r, j]
                    + mu2 * La[r, i] * La[r, j]
                    + mu1 * (La[r, i] * Ld[r, j] + Ld[r, i] * La[r, j])
                    + mu0 * Ld[r, i] * Ld[r, j]
                )
            Mbb[3 + i, 3 + j] = v
            Mbb[3 + j, 3 + i] = v
    c1 = np.zeros(7)
    c2 = np.zeros(7)
    for r in range(3):
        c1[r] = Sa[r]
    for c in range(4):
        va = 0.0
        vd = 0.0
        for r in range(3):
            va += La[r, c] * Sa[r]
            vd += Ld[r, c] * Sa[r]
        c1[3 + c] = vd
        c2[3 + c] = va

    # --- Q (Eq. 52 with the effect-gated terms) ---
    Lau = np.zeros(3)
    Lad_u = np.zeros(3)
    Ldd_u = np.zeros(3)
    for r in range(3):
        for c in range(4):
            Lau[r] += La[r, c] * ud[c]
            Lad_u[r] += Lad[r, c] * ud[c]
            Ldd_u[r] += Ldd[r, c] * ud[c]
    smk = np.empty(3)
    smpk = np.empty(3)
    for r in range(3):
        smk[r] = 2.0 * mpd * Lau[r] + mu1 * Lad_u[r] + mu0 * Ldd_u[r]
        smpk[r] = 2.0 * mppd * Lau[r] + mu2 * Lad_u[r] + mu1 * Ldd_u[r]
    Q = np.empty(nq)
    for r in range(3):
        Q[r] = -smk[r]
    for c in range(4):
        v = 0.0
        for r in range(3):
            v += -2.0 * Hd[r, c] * Jw[r] - La[r, c] * smpk[r] - Ld[r, c] * smk[r]
        Q[3 + c] = v
    sLau = Sa[0] * Lau[0] + Sa[1] * Lau[1] + Sa[2] * Lau[2]
    sLad = Sa[0] * Lad_u[0] + Sa[1] * Lad_u[1] + Sa[2] * Lad_u[2]
    sLdd = Sa[0] * Ldd_u[0] + Sa[1] * Ldd_u[1] + Sa[2] * Ldd_u[2]
    for i in range(n):
        Q[7 + i] = -fp[om + i] * ((2.0 * sLau) * pd[i] + sLad * p[i] + sLdd)
    if ip[I_GRAV]:
        g0, g1, g2 = fp[F_G], fp[F_G + 1], fp[F_G + 2]
        Q[0] += m_T * g0
        Q[1] += m_T * g1
        Q[2] += m_T * g2
        for c in range(4):
            Q[3 + c] += (
                (mu1 * La[0, c] + mu0 * Ld[0, c]) * g0
                + (mu1 * La[1, c] + mu0 * Ld[1, c]) * g1
                + (mu1 * La[2, c] + mu0 * Ld[2, c]) * g2
            )
        sg = Sa[0] * g0 + Sa[1] * g1 + Sa[2] * g2
        for i in range(n):
            Q[7 + i] += sg * fp[om + i]
    if n > 0 and (ip[I_SLIN] or ip[I_SCUB]):
        # spring forces F^S = -∂U_s/∂p (Eq. 38, ERRATA 2): f_j on spring j, Q_p,i += f_{i+1} - f_i
        lin = ip[I_SLIN]
        cub = ip[I_SCUB]
        prev = 0.0  # x_{i-1}, with x_{-1} = 0
        f_prev = 0.0
        for j in range(n + 1):
            x = p[j] - fp[ope + j] if j < n else 0.0
            e = x - prev
            f = 0.0
            if lin:
                f += fp[okl + j] * e
            if cub:
                f += fp[okn + j] * (e * e * e)
            if j > 0:
                Q[7 + j - 1] += f - f_prev
            f_prev = f
            prev = x
    if ip[I_TORQ]:
        ct = math.cos(fp[F_TFREQ] * t)
        for c in range(4):
            v = 0.0
            for r in range(3):
                v += Hm[r, c] * (fp[F_TC + r] + fp[F_TA + r] * ct)
            Q[3 + c] += v

    # --- modeling constraint (Eq. 59) and M_α = M + α a_m a_mᵀ (fundamental.py) ---
    uu = u0 * u0 + u1 * u1 + u2 * u2 + u3 * u3
    uud = u0 * ud[0] + u1 * ud[1] + u2 * ud[2] + u3 * ud[3]
    udud = ud[0] * ud[0] + ud[1] * ud[1] + ud[2] * ud[2] + ud[3] * ud[3]
    b_m = -fp[F_D1] * uud - 0.5 * fp[F_D2] * (uu - 1.0) - udud
    trM = 3.0 * m_T + s * mu0
    for c in range(4):
        trM += Mbb[3 + c, 3 + c]
    alpha = trM / nq
    Mab = Mbb.copy()  # body block of M_α
    for i in range(4):
        for j in range(4):
            Mab[3 + i, 3 + j] += alpha * u[i] * u[j]
    Qa = Q.copy()
    for c in range(4):
        Qa[3 + c] += alpha * b_m * u[c]

    # --- control requirements (Eqs. 75-76, 81, 84) ---
    bc = np.empty(k)
    Hw = np.zeros((kw, 4))
    for j in range(kw):
        comp = ip[I_COMP + j]
        for c in range(4):
            Hw[j, c] = Hm[comp, c]
    ew = np.empty(kw)
    for j in range(kw):
        comp = ip[I_COMP + j]
        ew[j] = omega[comp] - fp[F_WB + comp] * math.cos(fp[F_WS + comp] * t)
    for j in range(kw):
        comp = ip[I_COMP + j]
        v = -fp[F_WB + comp] * fp[F_WS + comp] * math.sin(fp[F_WS + comp] * t)
        for c in range(kw):
            v -= fp[F_GAIN + kw * j + c] * ew[c]
        bc[j] = v
    for j in range(kp):
        i = ip[iidx + j]
        lam = fp[omlam + j]
        li = fp[oml + j]
        cs = math.cos(lam * t)
        sn = math.sin(lam * t)
        pbar = fp[ope + i] + li * cs
        pbar_d = -li * lam * sn
        pbar_dd = -li * lam * lam * cs
        bc[kw + j] = pbar_dd - fp[omal + j] * (pd[i] - pbar_d) - fp[ombe + j] * (p[i] - pbar)

    qdd = out[:nq]
    QC = out[nq : 2 * nq]
    tau = out[2 * nq : 2 * nq + 3]
    res = out[2 * nq + 3 : 2 * nq + 3 + k]

    if wt == W_GAUSS or k == 0:
        # ---- Gauss: KKT of Gauss's principle, tracked rod rows fixed, free rod rows eliminated ----
        n0 = 0.0
        n1 = 0.0
        n2 = 0.0
        sq = 0.0  # Σ_F Q_i
        spq = 0.0  # Σ_F p_i Q_i
        t0 = 0.0  # Σ_T m_i b_i
        t1 = 0.0  # Σ_T m_i p_i b_i
        for i in range(n):
            mi = fp[om + i]
            if ip[itr + i] == 0:
                n0 += mi
                n1 += mi * p[i]
                n2 += mi * p[i] * p[i]
                sq += Qa[7 + i]
                spq += p[i] * Qa[7 + i]
        for j in range(kp):
            i = ip[iidx + j]
            mi = fp[om + i]
            t0 += mi * bc[kw + j]
            t1 += mi * p[i] * bc[kw + j]
        SF = Mab.copy()
        if s > 0.0:
            for i in range(7):
                for j in range(7):
                    SF[i, j] -= (
                        n0 * c1[i] * c1[j]
                        + n1 * (c1[i] * c2[j] + c2[i] * c1[j])
                        + n2 * c2[i] * c2[j]
                    ) / s
        rb = np.empty(7)
        for i in range(7):
            rb[i] = Qa[i] - (c1[i] * sq + c2[i] * spq) / s - c1[i] * t0 - c2[i] * t1
        if not _chol(SF, 7):
            return STATUS_NOT_PD
        nc = 1 + kw
        Y = np.zeros((7, nc))  # S_F⁻¹ Cᵀ, C = [a_bᵀ; H_w] on the body block
        for c in range(4):
            Y[3 + c, 0] = u[c]
        for j in range(kw):
            for c in range(4):
                Y[3 + c, 1 + j] = Hw[j, c]
        Ct = Y.copy()
        col = np.empty(7)
        for j in range(nc):
            for i in range(7):
                col[i] = Y[i, j]
            _chol_solve(SF, 7, col)
            for i in range(7):
                Y[i, j] = col[i]
        _chol_solve(SF, 7, rb)  # x0
        Gc = np.zeros((nc, nc))
        dv = np.empty(nc)
        for i in range(nc):
            for j in range(nc):
                v = 0.0
                for r in range(7):
                    v += Ct[r, i] * Y[r, j]
                Gc[i, j] = v
            v = 0.0
            for r in range(7):
                v += Ct[r, i] * rb[r]
            dv[i] = (b_m if i == 0 else bc[i - 1]) - v
        for i in range(nc):  # symmetrise
            for j in range(i + 1, nc):
                v = 0.5 * (Gc[i, j] + Gc[j, i])
                Gc[i, j] = v
                Gc[j, i] = v
        if not _chol(Gc, nc):
            return STATUS_NOT_PD
        _chol_solve(Gc, nc, dv)  # ν = [λ, μ_ω]
        for i in range(7):
            v = rb[i]
            for j in range(nc):
                v += Y[i, j] * dv[j]
            qdd[i] = v
        for i in range(n):
            QC[7 + i] = 0.0
        for i in range(n):
            if ip[itr + i] == 0:
                v = 0.0
                for r in range(7):
                    v += (c1[r] + p[i] * c2[r]) * qdd[r]
                qdd[7 + i] = (Qa[7 + i] / fp[om + i] - v) / s
        for j in range(kp):
            i = ip[iidx + j]
            qdd[7 + i] = bc[kw + j]
            v = 0.0
            for r in range(7):
                v += (c1[r] + p[i] * c2[r]) * qdd[r]
            QC[7 + i] = fp[om + i] * (s * bc[kw + j] + v) - Qa[7 + i]  # μ_i
        QC[0] = 0.0
        QC[1] = 0.0
        QC[2] = 0.0
        Qcu = np.zeros(4)  # applied control torque part H_wᵀ μ_ω
        for j in range(kw):
            for c in range(4):
                Qcu[c] += Hw[j, c] * dv[1 + j]
        for c in range(4):
            QC[3 + c] = Qcu[c] + u[c] * dv[0]
    else:
        # ---- N = M⁻² (Eq. B13), mirroring fundamental.solve with the closed forms above ----
        SB = Mab.copy()
        if s > 0.0:
            for i in range(7):
                for j in range(7):
                    SB[i, j] -= (
                        mu0 * c1[i] * c1[j]
                        + mu1 * (c1[i] * c2[j] + c2[i] * c1[j])
                        + mu2 * c2[i] * c2[j]
                    ) / s
        if not _chol(SB, 7):
            return STATUS_NOT_PD
        a0 = Qa.copy()
        _ma_solve(SB, c1, c2, s, fp, om, p, n, a0)
        y = np.zeros(nq)
        for c in range(4):
            y[3 + c] = u[c]
        _ma_solve(SB, c1, c2, s, fp, om, p, n, y)
        sm = 0.0
        am_a0 = 0.0
        for c in range(4):
            sm += u[c] * y[3 + c]
            am_a0 += u[c] * a0[3 + c]
        lam_m = (b_m - am_a0) / sm
        acc = a0 + lam_m * y
        # r = b_c - A acc; w = A y / s_m; G = diag(4|u|², 1) + |u|² w wᵀ
        r = np.empty(k)
        w = np.empty(k)
        dg = np.empty(k)
        for j in range(kw):
            va = 0.0
            vy = 0.0
            for c in range(4):
                va += Hw[j, c] * acc[3 + c]
                vy += Hw[j, c] * y[3 + c]
            r[j] = bc[j] - va
            w[j] = vy / sm
            dg[j] = 4.0 * uu
        for j in range(kp):
            i = ip[iidx + j]
            r[kw + j] = bc[kw + j] - acc[7 + i]
            w[kw + j] = y[7 + i] / sm
            dg[kw + j] = 1.0
        wDr = 0.0
        wDw = 0.0
        for j in range(k):
            wDr += w[j] * r[j] / dg[j]
            wDw += w[j] * w[j] / dg[j]
        f = uu * wDr / (1.0 + uu * wDw)
        mu = np.empty(k)
        wmu = 0.0
        for j in range(k):
            mu[j] = (r[j] - w[j] * f) / dg[j]
            wmu += w[j] * mu[j]
        # v = A_cᵀ μ - a_m (w·μ) (= M Z μ); Q_c = M v
        v = np.zeros(nq)
        for j in range(kw):
            for c in range(4):
                v[3 + c] += Hw[j, c] * mu[j]
        for c in range(4):
            v[3 + c] -= u[c] * wmu
        for j in range(kp):
            v[7 + ip[iidx + j]] = mu[kw + j]
        Qc = np.zeros(nq)
        _m_mul(Mbb, c1, c2, s, fp, om, p, n, v, Qc)
        v2 = Qc.copy()
        _ma_solve(SB, c1, c2, s, fp, om, p, n, v2)
        am_v2 = 0.0
        yQc = 0.0
        for c in range(4):
            am_v2 += u[c] * v2[3 + c]
        for i in range(nq):
            yQc += y[i] * Qc[i]
        for i in range(nq):
            qdd[i] = acc[i] + v2[i] - y[i] * (am_v2 / sm)
        corr = lam_m - yQc / sm
        for i in range(nq):
            QC[i] = Qc[i]
        for c in range(4):
            QC[3 + c] += u[c] * corr
        Qcu = np.empty(4)
        for c in range(4):
            Qcu[c] = Qc[3 + c]

    # torque τ = ¼ H Q^C_u of the applied control force (ERRATA), residual A_c q̈ - b_c
    for r in range(3):
        v = 0.0
        for c in range(4):
            v += Hm[r, c] * Qcu[c]
        tau[r] = 0.25 * v
    for j in range(kw):
        v = 0.0
        for c in range(4):
            v += Hw[j, c] * qdd[3 + c]
        res[j] = v - bc[j]
    for j in range(kp):
        res[kw + j] = qdd[7 + ip[iidx + j]] - bc[kw + j]
    return STATUS_OK


@_jit
def _ma_solve(SB, c1, c2, s, fp, om, p, n, x):
    """In place x <- M_α⁻¹ x by the Schur complement SB (Cholesky factor) on the body block."""
    s0 = 0.0
    s1 = 0.0
    for i in range(n):
        s0 += x[7 + i]
        s1 += p[i] * x[7 + i]
    xb = np.empty(7)
    for r in range(7):
        xb[r] = x[r] - (c1[r] * s0 + c2[r] * s1) / s
    _chol_solve(SB, 7, xb)
    for r in range(7):
        x[r] = xb[r]
    for i in range(n):
        v = 0.0
        for r in range(7):
            v += (c1[r] + p[i] * c2[r]) * xb[r]
        x[7 + i] = (x[7 + i] / fp[om + i] - v) / s


@_jit
def _m_mul(Mbb, c1, c2, s, fp, om, p, n, v, out):
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


def cache_dir_note() -> str:
    """Where numba caches this kernel in this process (for messages)."""
    if not HAVE_NUMBA:
        return "numba not installed"
    env = os.environ.get("NUMBA_CACHE_DIR")
    return f"NUMBA_CACHE_DIR={env}" if env else "__pycache__ beside analytic/ or the user cache dir"
