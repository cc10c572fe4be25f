"""The kernel for the identity weighting (N = W = I, the plain Euclidean norm of the control force,
Appendix B's Eq. B10 with ``W = I``): :func:`evaluate`, compiled only when a scene asks for it.

With ``K`` the norm-constrained compliance of :mod:`analytic.fundamental` (``K = M_α⁻¹ - y yᵀ/s_m``,
``y = M_α⁻¹ a_m``, ``s_m = a_mᵀ y``), ``Z = K A_cᵀ`` (nq x k) and ``r = b_c - A_c a`` (``a`` the
uncontrolled, norm-constrained acceleration, Eq. 60), the control force of least Euclidean norm is
``Q_c = Z (ZᵀZ)⁻¹ r``: the minimum-norm solution of ``Zᵀ Q_c = r``. It is computed from a thin
Householder QR of ``Z`` with its columns scaled to unit length (``Z D = Q̂ R̃``, ``D`` diagonal):
``Q_c = Q̂ R̃⁻ᵀ D r``. The Gram matrix ``ZᵀZ`` is never formed (it squares the conditioning: that
is what costs the dense numpy path ~1e-7 on masses spread over six decades). Then, as for every
weighting, ``q̈ = a + K Q_c`` and ``Q^C = Q_c + a_m (λ_m - yᵀQ_c/s_m)``.

Rank: ``Z`` has full column rank in exact arithmetic (:mod:`analytic.fast`, "Rank of the control
rows"). A scaled column whose distance to the span of the others, ``|R̃_jj|``, is at most
:data:`~analytic.kernel.layout.IDENTITY_RANK_TOL` (the square root of the numpy path's Moore-Penrose
cut-off on the Gram matrix) makes the kernel decline (``STATUS_NOT_PD``): the numpy path then
applies its own rank decision.

Cost ``O(n k²)`` (k control rows; ``M_α`` solves by the Schur complement on the body block, as
:mod:`analytic.kernel.minv2`), a few heap arrays. Stages: :func:`analytic.kernel.system.
make_build_system` (1-6, shared with the other weightings), then :func:`make_solve_identity`.
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
    IDENTITY_RANK_TOL,
    IX,
    STATUS_NOT_PD,
    STATUS_OK,
    STATUS_UNSUPPORTED,
    W_IDENTITY,
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
from analytic.kernel.minv2 import chol, ma_solve


@jit
def min_norm_solve(Z, nq, k, r, qc):
    """``qc <- Z (ZᵀZ)⁻¹ r``, the minimum-norm solution of ``Zᵀ qc = r`` (``Z`` (nq, k), k ≤ nq,
    overwritten; ``r`` (k,) overwritten), by a Householder QR of ``Z`` with unit columns.

    Returns:
        False when a scaled column lies within :data:`IDENTITY_RANK_TOL` of the span of the ones
        before it, or is zero or not finite (nothing useful is then in ``qc``), else True.
    """
    for j in range(k):  # Z D: unit columns, r <- D r
        nrm = 0.0
        for i in range(nq):
            nrm += Z[i, j] * Z[i, j]
        nrm = math.sqrt(nrm)
        if not (nrm > 0.0 and nrm < math.inf):
            return False
        inv = 1.0 / nrm
        for i in range(nq):
            Z[i, j] *= inv
        r[j] *= inv
    beta = np.empty(k)  # Householder reflectors I - β v vᵀ, v stored below the diagonal (v_j = 1)
    rdiag = np.empty(k)
    for j in range(k):
        sig = 0.0
        for i in range(j + 1, nq):
            sig += Z[i, j] * Z[i, j]
        x0 = Z[j, j]
        nx = math.sqrt(x0 * x0 + sig)
        if not nx > IDENTITY_RANK_TOL:  # |R̃_jj| = distance to the span of columns 0..j-1
            return False
        alpha = -nx if x0 >= 0.0 else nx  # R̃_jj, of the sign that avoids cancellation in v_0
        v0 = x0 - alpha
        for i in range(j + 1, nq):
            Z[i, j] /= v0
        beta[j] = -v0 / alpha  # = 2 / (vᵀv) with v_0 = 1
        rdiag[j] = alpha
        for c in range(j + 1, k):  # apply the reflector to the remaining columns
            dot = Z[j, c]
            for i in range(j + 1, nq):
                dot += Z[i, j] * Z[i, c]
            dot *= beta[j]
            Z[j, c] -= dot
            for i in range(j + 1, nq):
                Z[i, c] -= dot * Z[i, j]
    for j in range(k):  # R̃ᵀ g = D r (forward substitution; R̃ above the diagonal of Z)
        v = r[j]
        for c in range(j):
            v -= Z[c, j] * r[c]
        r[j] = v / rdiag[j]
    for i in range(nq):  # qc = Q̂ [g; 0]: the reflectors applied in reverse order
        qc[i] = r[i] if i < k else 0.0
    for j in range(k - 1, -1, -1):
        dot = qc[j]
        for i in range(j + 1, nq):
            dot += Z[i, j] * qc[i]
        dot *= beta[j]
        qc[j] -= dot
        for i in range(j + 1, nq):
            qc[i] -= dot * Z[i, j]
    return True


def make_solve_identity(deps: int):
    """The C callback body of stage 7 under the identity weighting (:data:`analytic.kernel.abi.
    SOLVE_SIG`; ``full`` is always 1 here), closing over the kernel's source fingerprint;
    :mod:`analytic.kernel.halves` compiles it once."""

    def solve_identity(q_p, fp_p, ip_p, out_p, len_out, w_p, full):
        """Stage 7 (W = I): ``q̈``, ``Q^C``, ``τ`` and the residual into ``out`` (module docstring),
        mirroring :func:`analytic.fundamental.solve`. ``w`` and the rod rows of ``out`` hold what
        :func:`analytic.kernel.system.make_build_system` wrote.

        Returns:
            ``STATUS_NOT_PD`` when the Schur complement of ``M_α`` is not numerically positive
            definite or ``Z`` is numerically rank deficient, else ``STATUS_OK``.
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
        qdd = out[:nq]
        QC = out[nq : 2 * nq]
        tau = out[2 * nq : 2 * nq + 3]
        res = out[2 * nq + 3 : 2 * nq + 3 + k]

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
        acc = a0 + lam_m * y  # Eq. (60)
        # Z = K A_cᵀ column by column: x = M_α⁻¹ A_c[j]ᵀ, z_j = x - y (A_c[j] y)/s_m; r = b_c - A_c a
        Z = np.empty((nq, k))
        r = np.empty(k)
        x = np.empty(nq)
        for j in range(k):
            for i in range(nq):
                x[i] = 0.0
            if j < kw:
                ay = 0.0
                aa = 0.0
                for c in range(4):
                    x[3 + c] = Hw[j, c]
                    ay += Hw[j, c] * y[3 + c]
                    aa += Hw[j, c] * acc[3 + c]
            else:
                i_m = ip[iidx + j - kw] & IX
                x[7 + i_m] = 1.0
                ay = y[7 + i_m]
                aa = acc[7 + i_m]
            r[j] = bc[j] - aa
            ma_solve(SB, c1, c2, s, fp, om, p, n, x)
            f = ay / sm
            for i in range(nq):
                Z[i, j] = x[i] - y[i] * f
        Qc = np.empty(nq)
        if not min_norm_solve(Z, nq, k, r, Qc):
            return STATUS_NOT_PD
        v = Qc.copy()  # q̈ = a + K Q_c
        ma_solve(SB, c1, c2, s, fp, om, p, n, v)
        am_v = 0.0
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
        return STATUS_OK

    return solve_identity


def _make_evaluate(deps: int):
    """:func:`evaluate` closing over the kernel's source fingerprint (see
    :func:`analytic.kernel.jit.jit_entry`)."""

    def evaluate(t, q, qd, fp, ip, out):
        """One evaluation of the controlled dynamics under the identity weighting.

        Args:
            t: time, s. q, qd: state ``[R, u, p]`` and its rate, shape (nq,).
            fp, ip: packed parameters (:func:`analytic.fast.pack`).
            out: ``[q̈, Q^C, τ, A_c q̈ - b_c]``, length ``2 nq + 3 + k`` (the full output).

        Returns:
            status: 0 done; 1 not numerically positive definite, or ``Z`` numerically rank
            deficient (the caller falls back); 2 the scene is not controlled under this weighting,
            or ``out`` is shorter than the full output. With a nonzero status ``out`` is
            unspecified.
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
    if kw + kp == 0 or ip[I_WEIGHT] != W_IDENTITY:
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
