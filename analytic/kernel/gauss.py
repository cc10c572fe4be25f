"""The kernel for Gauss weighting (N = M⁻¹, the paper's Eq. 89) and for uncontrolled scenes:
:func:`evaluate`, O(n), no heap allocation.

Stages: :func:`analytic.kernel.system.make_build_system` (1-6: M, Q, b_m, b_c), then :func:`make_solve_gauss`:
:func:`analytic.kernel.schur.schur_complement` (7: rods and R eliminated),
:func:`analytic.kernel.bordered.bordered_solve` (8: the bordered 4x4 system on u, q̈_b), and
:func:`control_outputs` (9: q̈ of the free rods, ``Q^C``, ``τ``, the residual). The two halves are
compiled and cached on their own (:mod:`analytic.kernel.halves`), so two processes can compile
them at once, and every caller calls them by address (:mod:`analytic.runtime.abi`). Entry point:
:data:`evaluate` (:mod:`analytic.kernel.weighting`).
"""

from __future__ import annotations

from analytic.kernel.bordered import bordered_solve
from analytic.kernel.calls import tail
from analytic.kernel.layout import (
    I_COMP,
    I_KP,
    I_KW,
    I_N,
    I_TRACK,
    IX,
    STATUS_OK,
    STATUS_UNSUPPORTED,
    W_GAUSS,
    WS_BW,
    WS_C1,
    WS_C2,
    WS_H,
    WS_NU,
    WS_PM,
    WS_S,
)
from analytic.kernel.schur import schur_complement
from analytic.kernel.weighting import make_evaluate
from analytic.runtime.jit import inner


@inner
def control_outputs(q, fp, ip, n, kw, kp, out, full, w):
    """Stage 9: the rod rows and the control force.

    * free rods: ``q̈_i = (Q_i/m_i - (c1 + p_i c2)ᵀ q̈_b) / s`` (row i of ``M q̈ = Q``, Eq. 51);
    * tracked rods: ``μ_i``, row i of ``M_α q̈ - Q_α``, the rod force ``Q^C_p,i``;
    * ``Q^C_u = H_ωᵀ μ_ω + u λ`` (Eq. 89; ``Q^C_R = 0`` for Gauss, docs/errata.md C4);
    * ``τ = ¼ H H_ωᵀ μ_ω``, the torque of the applied control force (C4);
    * residual ``A_c q̈ - b_c``.

    With ``full`` False only the free rods' ``q̈_i`` are written.
    """
    nq = n + 7
    om = tail(n, kp).m
    itr = I_TRACK
    iidx = I_TRACK + n
    s = w[WS_S]
    inv_s = 1.0 / s
    # rod rows: (c1 + p_i c2)ᵀ q̈_b = e1 + p_i e2
    e1 = 0.0
    e2 = 0.0
    for r in range(7):
        e1 += w[WS_C1 + r] * out[r]
        e2 += w[WS_C2 + r] * out[r]
    for i in range(n):
        if ip[itr + i] == 0:
            out[7 + i] = (out[7 + i] / fp[om + i] - (e1 + q[7 + i] * e2)) * inv_s
            if full:
                out[nq + 7 + i] = 0.0
    if not full:
        return
    for j in range(kp):  # μ_i: the tracked row of M_α q̈ - Q_α (q̈_i = b_i, Q_i stored in Q^C_i)
        i = ip[iidx + j] & IX
        out[nq + 7 + i] = fp[om + i] * (s * out[7 + i] + (e1 + q[7 + i] * e2)) - out[nq + 7 + i]
    oc = nq  # Q^C
    out[oc] = 0.0
    out[oc + 1] = 0.0
    out[oc + 2] = 0.0
    lam_m = w[WS_NU]
    for c in range(4):
        v = 0.0  # applied control torque part H_wᵀ μ_ω
        for j in range(kw):
            v += w[WS_H + 4 * (ip[I_COMP + j] & IX) + c] * w[WS_NU + 1 + j]
        w[WS_PM + c] = v
        out[oc + 3 + c] = v + q[3 + c] * lam_m
    # torque τ = ¼ H Q^C_u of the applied control force (docs/errata.md C4), residual A_c q̈ - b_c
    ot = 2 * nq
    for r in range(3):
        v = 0.0
        for c in range(4):
            v += w[WS_H + 4 * r + c] * w[WS_PM + c]
        out[ot + r] = 0.25 * v
    ores = ot + 3
    for j in range(kw):
        comp = ip[I_COMP + j] & IX
        v = 0.0
        for c in range(4):
            v += w[WS_H + 4 * comp + c] * out[3 + c]
        out[ores + j] = v - w[WS_BW + j]
    for j in range(kp):
        i = ip[iidx + j] & IX
        out[ores + kw + j] = out[7 + i] - out[7 + i]  # q̈_i - b_i, b_i stored as q̈_i


def make_solve_gauss(deps: int):
    """The C callback body of stages 7-9 under Gauss weighting (:data:`analytic.runtime.abi.
    SOLVE_SIG`), closing over the kernel's source fingerprint; :mod:`analytic.kernel.halves`
    compiles it once (a warm-up: in one process while another compiles stages 1-6,
    :mod:`validation.runs.warmup`)."""

    def solve_gauss(q, fp, ip, out, len_out, w, full):
        """Stages 7-9 (Gauss): the Schur complement, the bordered solve and the control outputs,
        from what stages 1-6 wrote into ``w`` and ``out``, indexing the C pointers themselves (see
        :func:`analytic.kernel.system.make_build_system`).

        Returns:
            ``STATUS_NOT_PD`` when a Schur complement or the bordered Gram matrix is not
            numerically positive definite, else ``STATUS_OK``.
        """
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return STATUS_UNSUPPORTED
        n = ip[I_N] & IX
        kw = ip[I_KW] & IX
        kp = ip[I_KP] & IX
        status = schur_complement(q, fp, w)
        if status != STATUS_OK:
            return status
        status = bordered_solve(q, ip, kw, out, w)
        if status != STATUS_OK:
            return status
        control_outputs(q, fp, ip, n, kw, kp, out, full != 0, w)
        return STATUS_OK

    return solve_gauss


evaluate = make_evaluate(W_GAUSS)
"""One evaluation under Gauss weighting, or without control: ``evaluate(t, q, qd, fp, ip, out)
-> status`` (:func:`analytic.kernel.weighting.make_evaluate`); an ``out`` of length nq gets ``q̈``
alone."""
