"""Quaternion kinematics of the paper (Eqs. 11-13, 23-29, 34) in scalar form for compiled code, and
the kernel's first stage, :func:`kinematic_terms`.

The scalar helpers take and return plain floats (tuples), so numba keeps them in registers; they
are the compiled counterparts of :mod:`analytic.kinematics` (numpy), with the same formulas written
in the same order. :func:`rotation` is the one compiled ``S(u)`` of the project.
"""

from __future__ import annotations

from analytic.kernel.layout import (
    F_J,
    F_TAT,
    F_TDT,
    WS_H,
    WS_JW,
    WS_LA,
    WS_LAD,
    WS_LAU,
    WS_LD,
    WS_LDD,
    WS_OM,
    WS_S,
    WS_SA,
    WS_SLAD,
    WS_SLAU,
    WS_SLDD,
)
from analytic.runtime.jit import inner


@inner
def rotation(u0, u1, u2, u3):
    """``S(u)``, the active rotation body -> inertial of Eq. (11), written in the paper's form
    ``2u0² - 1 + 2ui²`` (a rotation only for unit u; docs/errata.md C2). Returns its nine entries,
    row-major ``(s00, s01, s02, s10, s11, s12, s20, s21, s22)``."""
    return (
        2 * u0 * u0 - 1 + 2 * u1 * u1,
        2 * u1 * u2 - 2 * u0 * u3,
        2 * u1 * u3 + 2 * u0 * u2,
        2 * u1 * u2 + 2 * u0 * u3,
        2 * u0 * u0 - 1 + 2 * u2 * u2,
        2 * u2 * u3 - 2 * u0 * u1,
        2 * u1 * u3 - 2 * u0 * u2,
        2 * u2 * u3 + 2 * u0 * u1,
        2 * u0 * u0 - 1 + 2 * u3 * u3,
    )


@inner
def omega(u0, u1, u2, u3, v0, v1, v2, v3):
    """Body-axis angular velocity ``ω = H(u) u̇`` (Eqs. 12-13; docs/errata.md item 1), rad/s."""
    return (
        2.0 * (-u1 * v0 + u0 * v1 + u3 * v2 - u2 * v3),
        2.0 * (-u2 * v0 - u3 * v1 + u0 * v2 + u1 * v3),
        2.0 * (-u3 * v0 + u2 * v1 - u1 * v2 + u0 * v3),
    )


@inner
def H_into(u0, u1, u2, u3, w, o):
    """``H(u)`` of Eq. (13), row-major (3, 4) at ``w[o:o+12]``."""
    w[o] = -2 * u1
    w[o + 1] = 2 * u0
    w[o + 2] = 2 * u3
    w[o + 3] = -2 * u2
    w[o + 4] = -2 * u2
    w[o + 5] = -2 * u3
    w[o + 6] = 2 * u0
    w[o + 7] = 2 * u1
    w[o + 8] = -2 * u3
    w[o + 9] = 2 * u2
    w[o + 10] = -2 * u1
    w[o + 11] = 2 * u0


@inner
def Ht_times(u0, u1, u2, u3, x0, x1, x2):
    """``H(u)ᵀ x`` (Eq. 13) for a 3-vector x, as a 4-tuple (e.g. ``Q_τ = Hᵀτ``, Eq. 61)."""
    return (
        -2.0 * (u1 * x0 + u2 * x1 + u3 * x2),
        2.0 * (u0 * x0 - u3 * x1 + u2 * x2),
        2.0 * (u3 * x0 + u0 * x1 - u1 * x2),
        2.0 * (-u2 * x0 + u1 * x1 + u0 * x2),
    )


@inner
def kinematic_terms(q, qd, fp, o_a, w):
    """Stage 1: everything kinematic the other stages read (Eqs. 11-13, 23-29, 34), into ``w``.

    ``L_a(u) = T_a u`` and ``L_d(u) = T_d u`` (Eqs. 29, 34; ``T`` packed in ``fp``), ``L_a u̇``,
    ``L̇_a u̇ = L_a(u̇) u̇`` and ``L̇_d u̇`` (L is linear in u); ``Sa = S(u) a = ½ L_a(u) u - a``
    (``S(u) a + a`` is quadratic in u with Jacobian ``L_a``, Eqs. 23-29) and
    ``s = (Sa)ᵀSa`` (``M_pp = s diag(m)``, Eq. 51); the projections on Sa; ``H(u)``;
    ``ω = H u̇`` (Eq. 12) and ``J ω``. ``o_a``: offset of ``a`` in fp.

    Written as loops over the packed tensors rather than unrolled: numba's compile time grows
    with the number of statements, not of iterations (LLVM unrolls these fixed-count loops).
    """
    s = 0.0
    slau = 0.0
    slad = 0.0
    sldd = 0.0
    for r in range(3):
        lad = 0.0
        ldd = 0.0
        lau = 0.0
        sa = 0.0
        for c in range(4):
            ta = F_TAT + 16 * r + 4 * c
            td = F_TDT + 16 * r + 4 * c
            va = 0.0  # L_a(u)[r, c]
            vd = 0.0
            xa = 0.0  # L_a(u̇)[r, c]
            xd = 0.0
            for k in range(4):
                va += fp[ta + k] * q[3 + k]
                vd += fp[td + k] * q[3 + k]
                xa += fp[ta + k] * qd[3 + k]
                xd += fp[td + k] * qd[3 + k]
            w[WS_LA + 4 * r + c] = va
            w[WS_LD + 4 * r + c] = vd
            sa += va * q[3 + c]
            lau += va * qd[3 + c]
            lad += xa * qd[3 + c]
            ldd += xd * qd[3 + c]
        sa = 0.5 * sa - fp[o_a + r]
        w[WS_SA + r] = sa
        w[WS_LAU + r] = lau
        w[WS_LAD + r] = lad
        w[WS_LDD + r] = ldd
        s += sa * sa
        slau += sa * lau
        slad += sa * lad
        sldd += sa * ldd
    w[WS_S] = s
    w[WS_SLAU] = slau
    w[WS_SLAD] = slad
    w[WS_SLDD] = sldd
    H_into(q[3], q[4], q[5], q[6], w, WS_H)
    for r in range(3):
        om = 0.0
        for c in range(4):
            om += w[WS_H + 4 * r + c] * qd[3 + c]
        w[WS_OM + r] = om
    for r in range(3):
        jw = 0.0
        for c in range(3):
            jw += fp[F_J + 3 * r + c] * w[WS_OM + c]
        w[WS_JW + r] = jw
