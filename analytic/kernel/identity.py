"""The kernel for the identity weighting (N = W = I, the plain Euclidean norm of the control force,
Appendix B's Eq. B10 with ``W = I``): :func:`evaluate`, compiled only when a scene asks for it.

With ``K`` the norm-constrained compliance of :mod:`analytic.fundamental` (``K = M_α⁻¹ - y yᵀ/s_m``,
``y = M_α⁻¹ a_m``, ``s_m = a_mᵀ y``), ``Z = K A_cᵀ`` (nq x k) and ``r = b_c - A_c a`` (``a`` the
uncontrolled, norm-constrained acceleration, Eq. 60), the control force of least Euclidean norm is
``Q_c = Z (ZᵀZ)⁻¹ r``: the minimum-norm solution of ``Zᵀ Q_c = r``. It is computed from a thin
Householder QR of ``Z`` with its columns scaled to unit length (``Z D = Q̂ R̃``, ``D`` diagonal):
``Q_c = Q̂ R̃⁻ᵀ D r``. The Gram matrix ``ZᵀZ`` is never formed (it squares the conditioning, which
the dense numpy path pays; ``docs/performance.md``). Then, as for every
weighting, ``q̈ = a + K Q_c`` and ``Q^C = Q_c + a_m (λ_m - yᵀQ_c/s_m)``.

Rank: ``Z`` has full column rank in exact arithmetic (:mod:`analytic.fast`, "Rank of the control
rows"). A scaled column whose distance to the span of the others, ``|R̃_jj|``, is at most
:data:`~analytic.kernel.layout.IDENTITY_RANK_TOL` (the square root of the numpy path's Moore-Penrose
cut-off on the Gram matrix) makes the kernel decline (``STATUS_NOT_PD``): the numpy path then
applies its own rank decision.

Cost ``O(n k²)`` (k control rows; ``M_α`` solves by the Schur complement on the body block), a
few heap arrays. Stages: :func:`analytic.kernel.system.make_build_system` (1-6, shared with every weighting), then
:func:`make_solve_identity`: :func:`analytic.kernel.norm_constrained.prepare` and ``finish``
(shared with the other weighting through ``M_α``) around this weighting's own part,
:func:`control_force`. Entry points :data:`evaluate`, :data:`qddot_into`
(:mod:`analytic.kernel.weighting`).
"""

from __future__ import annotations

import math

import numpy as np

from analytic.kernel.calls import arrays
from analytic.kernel.layout import (
    I_KP,
    I_KW,
    I_N,
    I_TRACK,
    IDENTITY_RANK_TOL,
    IX,
    STATUS_NOT_PD,
    STATUS_OK,
    STATUS_UNSUPPORTED,
    W_IDENTITY,
)
from analytic.kernel.norm_constrained import finish, ma_solve, prepare
from analytic.kernel.weighting import make_evaluate, make_qddot_into
from analytic.runtime.jit import inner, jit


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


@inner
def control_force(q, fp, ip, w, SB, c1, c2, s, om, y, sm, acc, bc, Hw, Qc, v):
    """This weighting's ``Q_c`` and ``M_α⁻¹ Q_c`` (between
    :func:`analytic.kernel.norm_constrained.prepare`, whose results it takes, and ``finish``):
    ``Z = K A_cᵀ`` column by column, ``r = b_c - A_c a``, ``Q_c = Z (ZᵀZ)⁻¹ r``
    (:func:`min_norm_solve`), then ``v = M_α⁻¹ Q_c``. False when ``Z`` is numerically rank
    deficient (module docstring)."""
    n = ip[I_N] & IX
    kw = ip[I_KW] & IX
    kp = ip[I_KP] & IX
    nq = n + 7
    k = kw + kp
    iidx = I_TRACK + n
    p = q[7:]
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
    if not min_norm_solve(Z, nq, k, r, Qc):
        return False
    for i in range(nq):  # q̈ = a + K Q_c needs M_α⁻¹ Q_c
        v[i] = Qc[i]
    ma_solve(SB, c1, c2, s, fp, om, p, n, v)
    return True


def make_solve_identity(deps: int):
    """The C callback body of stage 7 under the identity weighting (:data:`analytic.runtime.abi.
    SOLVE_SIG`; ``full`` is always 1 here), closing over the kernel's source fingerprint;
    :mod:`analytic.kernel.halves` compiles it once."""

    def solve_identity(q_p, fp_p, ip_p, out_p, len_out, w_p, full):
        """Stage 7 (W = I): ``q̈``, ``Q^C``, ``τ`` and the residual into ``out``
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

    return solve_identity


evaluate = make_evaluate(W_IDENTITY)
"""One evaluation under the identity weighting: ``evaluate(t, q, qd, fp, ip, out) -> status``
(:func:`analytic.kernel.weighting.make_evaluate`; the full output only)."""

qddot_into = make_qddot_into(W_IDENTITY)
"""``qddot_into(t, q, qd, fp, ip, qdd) -> status``: :data:`evaluate` reduced to ``q̈``."""
