"""Gauss weighting (N = M⁻¹, Eq. 89), part 2: the 4x4 system on u bordered by the constraint rows
(stage 8, :func:`bordered_solve`), and the body accelerations.

After :mod:`analytic.kernel.schur`, the KKT system of Gauss's principle restricted to u is

``[[S_4, Cᵀ], [C, 0]] [q̈_u; -ν] = [r_4; b]``, ``C = [uᵀ; H_ω]`` (``a_m`` on u, Eq. 56, and the
tracked rows of ``H``, Eq. 85), ``b = [b_m; b_ω]``,

with ``1 + k_ω ≤ 4`` border rows. With ``S_4 = L D Lᵀ`` (L unit lower, unrolled), ``Z = L⁻¹ Cᵀ``,
``z = L⁻¹ r_4``: ``G = C S_4⁻¹ Cᵀ = Zᵀ D⁻¹ Z``, ``ν = G⁻¹ (b - Zᵀ D⁻¹ z)`` (``ν = [λ, μ_ω]``) and
``q̈_u = L⁻ᵀ D⁻¹ (z + Z ν)``. Then ``q̈_R = A⁻¹ (r_R - B_F q̈_u)``. No square roots (LDLᵀ).
"""

from __future__ import annotations

from analytic.kernel.layout import (
    I_COMP,
    IX,
    STATUS_NOT_PD,
    STATUS_OK,
    WS_BF,
    WS_BM,
    WS_BW,
    WS_GAM,
    WS_GC,
    WS_GI,
    WS_H,
    WS_HT,
    WS_KT,
    WS_NU,
    WS_R4,
    WS_S4,
    WS_SA,
    WS_XR,
    WS_Z,
)
from analytic.runtime.jit import inner


@inner
def ldl_in_place(w, o, ld, oi, k):
    """In-place ``A = L D Lᵀ`` (L unit lower, stored below the diagonal) of the k x k matrix at
    ``w[o + ld i + j]`` (lower triangle read); ``w[oi + j] = 1 / D_j``. Returns False if a pivot is
    not positive (A not numerically positive definite)."""
    for j in range(k):
        rj = o + ld * j
        for c in range(j):  # row j <- L_jc D_c
            rc = o + ld * c
            v = w[rj + c]
            for e in range(c):
                v -= w[rj + e] * w[rc + e]
            w[rj + c] = v
        d = w[rj + j]
        for c in range(j):  # row j <- L_jc
            lc = w[rj + c] * w[oi + c]
            d -= lc * w[rj + c]
            w[rj + c] = lc
        if not d > 0.0:
            return False
        w[oi + j] = 1.0 / d
    return True


@inner
def ldl_solve(w, o, ld, oi, k, ox):
    """``x <- (L D Lᵀ)⁻¹ x`` for ``x = w[ox:ox+k]``, with the factors of :func:`ldl_in_place`."""
    for i in range(k):
        v = w[ox + i]
        for c in range(i):
            v -= w[o + ld * i + c] * w[ox + c]
        w[ox + i] = v
    for i in range(k):
        w[ox + i] *= w[oi + i]
    for i in range(k - 1, -1, -1):
        v = w[ox + i]
        for c in range(i + 1, k):
            v -= w[o + ld * c + i] * w[ox + c]
        w[ox + i] = v


@inner
def bordered_solve(q, ip, kw, out, w):
    """Stage 8: ``q̈_u`` and ``ν = [λ, μ_ω]`` (to ``w[WS_NU:]``) from the bordered 4x4 system, then
    ``q̈_R`` (module docstring); writes ``out[0:7]``.

    Returns:
        ``STATUS_NOT_PD`` when ``S_4`` or ``G`` has a non-positive pivot, else ``STATUS_OK``.
    """
    u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
    b_m = w[WS_BM]
    # S_4 = L D Lᵀ, L unit lower (unrolled: S_4 is 4x4)
    a00 = w[WS_S4]
    if not a00 > 0.0:
        return STATUS_NOT_PD
    iv0 = 1.0 / a00
    a10 = w[WS_S4 + 4]
    a20 = w[WS_S4 + 8]
    a30 = w[WS_S4 + 12]
    l10 = a10 * iv0
    l20 = a20 * iv0
    l30 = a30 * iv0
    d1 = w[WS_S4 + 5] - l10 * a10
    if not d1 > 0.0:
        return STATUS_NOT_PD
    iv1 = 1.0 / d1
    t21 = w[WS_S4 + 9] - l20 * a10  # L_21 d_1
    t31 = w[WS_S4 + 13] - l30 * a10
    l21 = t21 * iv1
    l31 = t31 * iv1
    d2 = w[WS_S4 + 10] - l20 * a20 - l21 * t21
    if not d2 > 0.0:
        return STATUS_NOT_PD
    iv2 = 1.0 / d2
    t32 = w[WS_S4 + 14] - l30 * a20 - l31 * t21
    l32 = t32 * iv2
    d3 = w[WS_S4 + 15] - l30 * a30 - l31 * t31 - l32 * t32
    if not d3 > 0.0:
        return STATUS_NOT_PD
    iv3 = 1.0 / d3
    # Z = L⁻¹ Cᵀ, z = L⁻¹ r_4: G = C S_4⁻¹ Cᵀ = Zᵀ D⁻¹ Z, ν = G⁻¹ (b - Zᵀ D⁻¹ z)
    z0 = w[WS_R4]
    z1 = w[WS_R4 + 1] - l10 * z0
    z2 = w[WS_R4 + 2] - l20 * z0 - l21 * z1
    z3 = w[WS_R4 + 3] - l30 * z0 - l31 * z1 - l32 * z2
    z0 *= iv0  # D⁻¹ z
    z1 *= iv1
    z2 *= iv2
    z3 *= iv3
    nc = 1 + kw
    for j in range(nc):
        if j == 0:
            x0, x1, x2, x3 = u0, u1, u2, u3
            bj = b_m
        else:
            oh = WS_H + 4 * (ip[I_COMP + j - 1] & IX)
            x0, x1, x2, x3 = w[oh], w[oh + 1], w[oh + 2], w[oh + 3]
            bj = w[WS_BW + j - 1]
        y0 = x0
        y1 = x1 - l10 * y0
        y2 = x2 - l20 * y0 - l21 * y1
        y3 = x3 - l30 * y0 - l31 * y1 - l32 * y2
        oz = WS_Z + 4 * j
        w[oz] = y0
        w[oz + 1] = y1
        w[oz + 2] = y2
        w[oz + 3] = y3
        w[WS_NU + j] = bj - (y0 * z0 + y1 * z1 + y2 * z2 + y3 * z3)
        y0 *= iv0
        y1 *= iv1
        y2 *= iv2
        y3 *= iv3
        for c in range(j + 1):
            oc = WS_Z + 4 * c
            w[WS_GC + 4 * j + c] = y0 * w[oc] + y1 * w[oc + 1] + y2 * w[oc + 2] + y3 * w[oc + 3]
    if not ldl_in_place(w, WS_GC, 4, WS_GI, nc):
        return STATUS_NOT_PD
    ldl_solve(w, WS_GC, 4, WS_GI, nc, WS_NU)  # ν = [λ, μ_ω]
    for j in range(nc):  # D⁻¹ (z + Z ν)
        oz = WS_Z + 4 * j
        nu = w[WS_NU + j]
        z0 += w[oz] * nu * iv0
        z1 += w[oz + 1] * nu * iv1
        z2 += w[oz + 2] * nu * iv2
        z3 += w[oz + 3] * nu * iv3
    x3 = z3  # q̈_u = L⁻ᵀ D⁻¹ (z + Z ν)
    x2 = z2 - l32 * x3
    x1 = z1 - l21 * x2 - l31 * x3
    x0 = z0 - l10 * x1 - l20 * x2 - l30 * x3
    out[3] = x0
    out[4] = x1
    out[5] = x2
    out[6] = x3
    # q̈_R = A⁻¹ (r_R - B_F q̈_u) = A⁻¹ r_R - (B_F q̈_u + γ Sa (h·q̈_u)) / m_T
    kT = w[WS_KT]
    Sa0, Sa1, Sa2 = w[WS_SA], w[WS_SA + 1], w[WS_SA + 2]
    sh = w[WS_GAM] * (w[WS_HT] * x0 + w[WS_HT + 1] * x1 + w[WS_HT + 2] * x2 + w[WS_HT + 3] * x3)
    bf = WS_BF
    out[0] = (
        w[WS_XR] - (w[bf] * x0 + w[bf + 1] * x1 + w[bf + 2] * x2 + w[bf + 3] * x3 + sh * Sa0) * kT
    )
    out[1] = (
        w[WS_XR + 1]
        - (w[bf + 4] * x0 + w[bf + 5] * x1 + w[bf + 6] * x2 + w[bf + 7] * x3 + sh * Sa1) * kT
    )
    out[2] = (
        w[WS_XR + 2]
        - (w[bf + 8] * x0 + w[bf + 9] * x1 + w[bf + 10] * x2 + w[bf + 11] * x3 + sh * Sa2) * kT
    )
    return STATUS_OK
