"""The kernel for the weighting N = M⁻² (Eq. B13): :func:`evaluate`, O(n), compiled only when a
scene asks for it.

With ``Z = K A_cᵀ`` (``K`` the norm-constrained compliance of :mod:`analytic.fundamental`) one has
``M Z = A_cᵀ - a_m wᵀ``, ``w = A_c y / s_m``, and since ``H(u) u = 0``,
``Zᵀ M² Z = A_c A_cᵀ + |u|² w wᵀ = diag(4|u|² I_kω, I_kp) + |u|² w wᵀ`` (Sherman-Morrison); the rest
are structured solves with ``M_α`` (a Cholesky factor of its Schur complement on the body block),
one product with ``M`` (for ``Q^C``) and ``M_α⁻¹ M v = v - α y (a_mᵀ v)`` (``y = M_α⁻¹ a_m``) in place
of a product with ``M`` followed by a solve, which would cost about cond(M) in accuracy. Cost O(n)
(a few heap arrays of size n + 7, unlike the Gauss kernel).

Stages: :func:`analytic.kernel.system.make_build_system` (1-6, shared with Gauss), then
:func:`solve_minv2`.
"""

from __future__ import annotations

import math

import numpy as np

from analytic.kernel.abi import arrays, call_halves, tail
from analytic.kernel.jit import inner, jit, jit_entry
from analytic.kernel.layout import (
    F_MU0,
    I_COMP,
    I_KP,
    I_KW,
    I_N,
    I_TRACK,
    I_WEIGHT,
    IX,
    STATUS_NOT_PD,
    STATUS_OK,
    STATUS_UNSUPPORTED,
    W_MINV2,
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
    WS_UU,
)


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


def make_solve_minv2(deps: int):
    """The C callback body of stage 7 under M⁻² (:data:`analytic.kernel.abi.SOLVE_SIG`; ``full``
    is always 1 here), closing over the kernel's source fingerprint; :mod:`analytic.kernel.halves`
    compiles it once."""

    def solve_minv2(q_p, fp_p, ip_p, out_p, len_out, w_p, full):
        """Stage 7 (M⁻²): ``q̈``, ``Q^C``, ``τ`` and the residual into ``out`` (Eq. B13, with the
        closed forms of the module docstring), mirroring :func:`analytic.fundamental.solve`. ``w`` and
        the rod rows of ``out`` hold what :func:`analytic.kernel.system.make_build_system` wrote.

        Returns:
            ``STATUS_NOT_PD`` when the Schur complement of ``M_α`` is not numerically positive
            definite, else ``STATUS_OK``.

        Compiled once, as the C callback :data:`analytic.kernel.halves.SOLVE_MINV2` (cached on its
        own), which the kernel's callers call by address (:mod:`analytic.kernel.abi`).
        """
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return STATUS_UNSUPPORTED
        q, fp, ip, out, w = arrays(q_p, fp_p, ip_p, out_p, len_out, w_p)
        n = ip[I_N] & IX
        kw = ip[I_KW] & IX
        kp = ip[I_KP] & IX
        s = w[WS_S]
        mu0 = fp[F_MU0]
        mu1 = w[WS_MU1]
        mu2 = w[WS_MU2]
        alpha = w[WS_ALPHA]
        b_m = w[WS_BM]
        uu = w[WS_UU]
        nq = n + 7
        k = kw + kp
        om = tail(n, kp).m
        iidx = I_TRACK + n
        itr = I_TRACK
        p = q[7:]
        u = q[3:7]
        Mbb = np.empty((7, 7))
        for i in range(7):
            for j in range(7):
                Mbb[i, j] = w[WS_MB + 7 * i + j]
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
            bc[kw + j] = out[7 + ip[iidx + j]]
        Hm = np.empty((3, 4))  # H(u), Eq. (13), as kinematics.kinematic_terms wrote it
        for row in range(3):
            for c in range(4):
                Hm[row, c] = w[WS_H + 4 * row + c]
        Hw = np.empty((kw, 4))
        for j in range(kw):
            for c in range(4):
                Hw[j, c] = Hm[ip[I_COMP + j], c]
        qdd = out[:nq]
        QC = out[nq : 2 * nq]
        tau = out[2 * nq : 2 * nq + 3]
        res = out[2 * nq + 3 : 2 * nq + 3 + k]

        SB = Mbb.copy()  # body block of M_α, then its Schur complement over all rods
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
            return STATUS_NOT_PD
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
        acc = a0 + lam_m * y
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
            i = ip[iidx + j]
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
            v[7 + ip[iidx + j]] = mu[kw + j]
        Qc = np.zeros(nq)
        m_mul(Mbb, c1, c2, s, fp, om, p, n, v, Qc)
        # v2 = M_α⁻¹ Q_c = M_α⁻¹ M v = v - α y (a_mᵀ v) exactly (M = M_α - α a_m a_mᵀ, y = M_α⁻¹ a_m):
        # no product with M followed by a solve, which would cost about cond(M) in accuracy
        am_v = 0.0
        for c in range(4):
            am_v += u[c] * v[3 + c]
        v2 = np.empty(nq)
        for i in range(nq):
            v2[i] = v[i] - alpha * am_v * y[i]
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
        # torque τ = ¼ H Q^C_u of the applied control force (docs/errata.md C4), residual A_c q̈ - b_c
        for rr in range(3):
            vv = 0.0
            for c in range(4):
                vv += Hm[rr, c] * Qc[3 + c]
            tau[rr] = 0.25 * vv
        for j in range(kw):
            vv = 0.0
            for c in range(4):
                vv += Hw[j, c] * qdd[3 + c]
            res[j] = vv - bc[j]
        for j in range(kp):
            res[kw + j] = qdd[7 + ip[iidx + j]] - bc[kw + j]
        return STATUS_OK

    return solve_minv2


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


def _make_evaluate(deps: int):
    """:func:`evaluate` closing over the kernel's source fingerprint (see
    :func:`analytic.kernel.jit.jit_entry`)."""

    def evaluate(t, q, qd, fp, ip, out):
        """One evaluation of the controlled dynamics under the weighting N = M⁻².

        Args:
            t: time, s. q, qd: state ``[R, u, p]`` and its rate, shape (nq,).
            fp, ip: packed parameters (:func:`analytic.fast.pack`).
            out: ``[q̈, Q^C, τ, A_c q̈ - b_c]``, length ``2 nq + 3 + k`` (the full output).

        Returns:
            status: 0 done; 1 not numerically positive definite (the caller falls back); 2 the
            scene is not controlled under M⁻², or ``out`` is shorter than the full output. With a
            nonzero status ``out`` is unspecified.
        """
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return STATUS_UNSUPPORTED
        return join(t, q, qd, fp, ip, out)

    return evaluate


@inner
def join(t, q, qd, fp, ip, out):
    """:func:`evaluate`'s body, called by compiled callers (``analytic.kernel.entry.evaluate_as``):
    the two compiled halves called by the addresses in ``ip`` (:mod:`analytic.kernel.abi`;
    ``STATUS_UNSUPPORTED`` when they are not set)."""
    n = ip[I_N] & IX
    kw = ip[I_KW] & IX
    kp = ip[I_KP] & IX
    if kw + kp == 0 or ip[I_WEIGHT] != W_MINV2:
        return STATUS_UNSUPPORTED
    full = out.shape[0] >= 2 * (n + 7) + 3 + kw + kp
    if not full:  # this weighting needs Q^C on the way to q̈: the whole output
        return STATUS_UNSUPPORTED
    return call_halves(t, q, qd, fp, ip, out, full)


evaluate = jit_entry(_make_evaluate)


def _make_qddot_into(deps: int):
    def qddot_into(t, q, qd, fp, ip, qdd):
        """:func:`evaluate` reduced to ``q̈`` (written into ``qdd``, shape (nq,)): the same numbers,
        computed through the full output (this weighting needs ``Q^C`` on the way)."""
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return STATUS_UNSUPPORTED
        nq = (ip[I_N] & IX) + 7
        out = np.empty(2 * nq + 3 + (ip[I_KW] & IX) + (ip[I_KP] & IX))
        status = evaluate(t, q, qd, fp, ip, out)
        if status == STATUS_OK:
            qdd[:] = out[:nq]
        return status

    return qddot_into


qddot_into = jit_entry(_make_qddot_into)
