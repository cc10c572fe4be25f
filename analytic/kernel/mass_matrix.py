"""The mass matrix ``M(q)`` of Eq. (51) in the kernel's structured form (stage 3, :func:`body_block`).

Coordinates ``q = [R (3), u (4), p (n)]``, body block ``b = [R, u]`` of size 7. Eq. (51) is never
formed as an (n+7)² matrix:

* ``M_pp = s diag(m)`` with ``s = (Sa)ᵀSa``;
* column i of ``M_bp`` is ``m_i (c1 + p_i c2)`` with ``c1 = [Sa; L_dᵀSa]``, ``c2 = [0; L_aᵀSa]``
  (7-vectors);
* ``M_bb = [[m_T I, B], [Bᵀ, HᵀJH + L_aᵀ(μ2 L_a + μ1 L_d) + L_dᵀ B]]`` with ``B = μ1 L_a + μ0 L_d``
  (``A_d`` of Eq. 51 folded in).

So only the 7x7 body block and the two 7-vectors are stored.
"""

from __future__ import annotations

from analytic.kernel.layout import (
    F_J,
    F_MBR,
    F_MU0,
    WS_C1,
    WS_C2,
    WS_H,
    WS_JH,
    WS_LA,
    WS_LD,
    WS_MB,
    WS_MU1,
    WS_MU2,
    WS_PM,
    WS_SA,
)
from analytic.runtime.jit import inner


@inner
def body_block(fp, w):
    """Stage 3: ``M_bb`` (Eq. 51, 7x7 row-major, both triangles) into ``w[WS_MB:]`` and the
    ``M_bp`` column vectors ``c1``, ``c2`` into ``w[WS_C1:]``, ``w[WS_C2:]`` (module docstring).
    Reads ``H``, ``L_a``, ``L_d``, ``Sa``, ``μ1``, ``μ2`` from ``w`` (stages 1, 2)."""
    mu0 = fp[F_MU0]
    m_T = fp[F_MBR] + mu0
    mu1 = w[WS_MU1]
    mu2 = w[WS_MU2]
    for r in range(3):
        for c in range(3):
            w[WS_MB + 7 * r + c] = m_T if r == c else 0.0
        for c in range(4):
            la = w[WS_LA + 4 * r + c]
            ld = w[WS_LD + 4 * r + c]
            b = mu1 * la + mu0 * ld
            w[WS_MB + 7 * r + 3 + c] = b
            w[WS_MB + 7 * (3 + c) + r] = b
            w[WS_PM + 4 * r + c] = mu2 * la + mu1 * ld
            w[WS_JH + 4 * r + c] = (
                fp[F_J + 3 * r] * w[WS_H + c]
                + fp[F_J + 3 * r + 1] * w[WS_H + 4 + c]
                + fp[F_J + 3 * r + 2] * w[WS_H + 8 + c]
            )
    for i in range(4):
        for j in range(i, 4):
            v = 0.0
            for r in range(3):
                v += (
                    w[WS_H + 4 * r + i] * w[WS_JH + 4 * r + j]
                    + w[WS_LA + 4 * r + i] * w[WS_PM + 4 * r + j]
                    + w[WS_LD + 4 * r + i] * w[WS_MB + 7 * r + 3 + j]
                )
            w[WS_MB + 7 * (3 + i) + 3 + j] = v
            w[WS_MB + 7 * (3 + j) + 3 + i] = v
    Sa0, Sa1, Sa2 = w[WS_SA], w[WS_SA + 1], w[WS_SA + 2]
    w[WS_C1] = Sa0
    w[WS_C1 + 1] = Sa1
    w[WS_C1 + 2] = Sa2
    w[WS_C2] = 0.0
    w[WS_C2 + 1] = 0.0
    w[WS_C2 + 2] = 0.0
    for c in range(4):
        w[WS_C1 + 3 + c] = w[WS_LD + c] * Sa0 + w[WS_LD + 4 + c] * Sa1 + w[WS_LD + 8 + c] * Sa2
        w[WS_C2 + 3 + c] = w[WS_LA + c] * Sa0 + w[WS_LA + 4 + c] * Sa1 + w[WS_LA + 8 + c] * Sa2
