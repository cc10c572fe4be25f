"""Gauss weighting (N = M⁻¹, Eq. 89), part 1: eliminate the rods and R (stage 7,
:func:`schur_complement`).

The control is the KKT system of Gauss's principle ``M_α q̈ = Q_α + a_m λ + A_cᵀ μ``,
``a_mᵀ q̈ = b_m``, ``A_c q̈ = b_c``. The tracked-mass rows of ``A_c`` are unit rows, so
``q̈_p,i = b_c,i`` for a tracked mass (T), and the free rod rows (F) are eliminated by the Schur
complement of ``M_pp = s diag(m)`` (Eq. 51):

``S_F = (M_α)_bb - (1/s) Σ_F m_i (c1 + p_i c2)(c1 + p_i c2)ᵀ``, i.e. three moments ``Σ_F m_i p_iʲ``,
``r_b = (Q_α)_b - (1/s) Σ_F Q_i (c1 + p_i c2) - Σ_T m_i b_i (c1 + p_i c2)``.

Since ``c2`` and ``a_m`` vanish on the R rows, ``S_F = [[A, B_F], [B_Fᵀ, D]]`` with
``A = m_T I - (n0/s) Sa Saᵀ``, ``B_F = B - Sa g_uᵀ`` (``g = (n0 c1 + n1 c2)/s``) and, by
Sherman-Morrison, ``A⁻¹ = (I + γ Sa Saᵀ)/m_T``, ``γ = n0 / (s (m_T - n0))`` (``m_T - n0 =
m_BR + Σ_T m_i ≥ m_BR``). R is eliminated in closed form:
``S_4 = D - B_Fᵀ A⁻¹ B_F = D - (B_FᵀB_F + γ h hᵀ)/m_T`` with ``h = B_Fᵀ Sa = Σ_T m_i (c1 + p_i c2)_u``,
and ``r_4 = r_u - B_Fᵀ A⁻¹ r_R``. What is left, a 4x4 system on u bordered by ``1 + k_ω`` rows, is
:mod:`analytic.kernel.bordered`'s. (A Cholesky of the 7x7 ``S_F`` took 7 dependent sqrt + division
steps.)
"""

from __future__ import annotations

from analytic.kernel.layout import (
    F_MBR,
    F_MU0,
    STATUS_NOT_PD,
    STATUS_OK,
    WS_ALPHA,
    WS_BF,
    WS_C1,
    WS_C2,
    WS_GAM,
    WS_HT,
    WS_KT,
    WS_MB,
    WS_N0,
    WS_N1,
    WS_N2,
    WS_NT0,
    WS_NT1,
    WS_QB,
    WS_R4,
    WS_RB,
    WS_S,
    WS_S4,
    WS_SA,
    WS_SPQ,
    WS_SQ,
    WS_T0,
    WS_T1,
    WS_XR,
)
from analytic.runtime.jit import inner


@inner
def schur_complement(q, fp, w):
    """Stage 7: ``r_b``, ``A⁻¹ r_R`` (to ``WS_XR``), ``B_F``, ``h``, ``r_4`` and the lower
    triangle of ``S_4`` (module docstring) into ``w``; ``γ`` and ``1/m_T`` to ``WS_GAM``, ``WS_KT``.

    Returns:
        ``STATUS_NOT_PD`` when ``m_T`` or ``m_T - n0`` is not positive, else ``STATUS_OK``.
    """
    s = w[WS_S]
    m_BR = fp[F_MBR]
    m_T = m_BR + fp[F_MU0]
    n0, n1, n2 = w[WS_N0], w[WS_N1], w[WS_N2]
    nt0, nt1 = w[WS_NT0], w[WS_NT1]
    sq, spq = w[WS_SQ], w[WS_SPQ]
    t0, t1 = w[WS_T0], w[WS_T1]
    alpha = w[WS_ALPHA]
    Sa0, Sa1, Sa2 = w[WS_SA], w[WS_SA + 1], w[WS_SA + 2]
    inv_s = 1.0 / s
    m_Tt = m_BR + nt0
    rs = 0.0  # 1/s in S_F: no rod term when s = 0 (as in the dense S_F)
    gam = 0.0
    if s > 0.0:
        if not m_Tt > 0.0:
            return STATUS_NOT_PD
        rs = inv_s
        gam = n0 * inv_s / m_Tt
    if not m_T > 0.0:
        return STATUS_NOT_PD
    kT = 1.0 / m_T
    for i in range(7):  # r_b
        c1i = w[WS_C1 + i]
        c2i = w[WS_C2 + i]
        w[WS_RB + i] = w[WS_QB + i] - (c1i * sq + c2i * spq) * inv_s - c1i * t0 - c2i * t1
    rR0 = w[WS_RB]
    rR1 = w[WS_RB + 1]
    rR2 = w[WS_RB + 2]
    sr = gam * (Sa0 * rR0 + Sa1 * rR1 + Sa2 * rR2)
    xr0 = (rR0 + sr * Sa0) * kT  # A⁻¹ r_R
    xr1 = (rR1 + sr * Sa1) * kT
    xr2 = (rR2 + sr * Sa2) * kT
    for c in range(4):
        c1c = w[WS_C1 + 3 + c]
        c2c = w[WS_C2 + 3 + c]
        gc = (n0 * c1c + n1 * c2c) * rs
        b0 = w[WS_MB + 3 + c] - Sa0 * gc  # B_F column c
        b1 = w[WS_MB + 10 + c] - Sa1 * gc
        b2 = w[WS_MB + 17 + c] - Sa2 * gc
        w[WS_BF + c] = b0
        w[WS_BF + 4 + c] = b1
        w[WS_BF + 8 + c] = b2
        w[WS_HT + c] = nt0 * c1c + nt1 * c2c  # h
        w[WS_R4 + c] = w[WS_RB + 3 + c] - (b0 * xr0 + b1 * xr1 + b2 * xr2)
    for i in range(4):
        c1i = w[WS_C1 + 3 + i]
        c2i = w[WS_C2 + 3 + i]
        g1 = (n0 * c1i + n1 * c2i) * rs
        g2 = (n1 * c1i + n2 * c2i) * rs
        ai = alpha * q[3 + i]  # α a_m a_mᵀ, a_m = u on these rows
        gh = gam * w[WS_HT + i]
        for j in range(i + 1):
            v = w[WS_MB + 7 * (3 + i) + 3 + j] + ai * q[3 + j]
            v -= g1 * w[WS_C1 + 3 + j] + g2 * w[WS_C2 + 3 + j]
            bb = (
                w[WS_BF + i] * w[WS_BF + j]
                + w[WS_BF + 4 + i] * w[WS_BF + 4 + j]
                + w[WS_BF + 8 + i] * w[WS_BF + 8 + j]
            )
            w[WS_S4 + 4 * i + j] = v - (bb + gh * w[WS_HT + j]) * kT
    w[WS_XR] = xr0
    w[WS_XR + 1] = xr1
    w[WS_XR + 2] = xr2
    w[WS_GAM] = gam
    w[WS_KT] = kT
    return STATUS_OK
