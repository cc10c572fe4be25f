"""Quaternion kinematics of the paper (Eqs. 11-13, 23-29, 34) in scalar form for compiled code, and
the kernel's first stage, :func:`kinematic_terms`.

The scalar helpers take and return plain floats (tuples), so numba keeps them in registers; they
are the compiled counterparts of :mod:`analytic.kinematics` (numpy), with the same formulas written
in the same order. :func:`rotation` is the one compiled ``S(u)`` of the project.
"""

from __future__ import annotations

from analytic.kernel.jit import inline
from analytic.kernel.layout import (
    F_J,
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


@inline
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


@inline
def omega(u0, u1, u2, u3, v0, v1, v2, v3):
    """Body-axis angular velocity ``ω = H(u) u̇`` (Eqs. 12-13; docs/errata.md item 1), rad/s."""
    return (
        2.0 * (-u1 * v0 + u0 * v1 + u3 * v2 - u2 * v3),
        2.0 * (-u2 * v0 - u3 * v1 + u0 * v2 + u1 * v3),
        2.0 * (-u3 * v0 + u2 * v1 - u1 * v2 + u0 * v3),
    )


@inline
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


@inline
def Ht_times(u0, u1, u2, u3, x0, x1, x2):
    """``H(u)ᵀ x`` (Eq. 13) for a 3-vector x, as a 4-tuple (e.g. ``Q_τ = Hᵀτ``, Eq. 61)."""
    return (
        -2.0 * (u1 * x0 + u2 * x1 + u3 * x2),
        2.0 * (u0 * x0 - u3 * x1 + u2 * x2),
        2.0 * (u3 * x0 + u0 * x1 - u1 * x2),
        2.0 * (-u2 * x0 + u1 * x1 + u0 * x2),
    )


@inline
def L_into(x0, x1, x2, u0, u1, u2, u3, w, o):
    """``L_x(u) = Σ x_i L_i(u)`` (Eqs. 23-29, 34), row-major (3, 4) at ``w[o:o+12]``: the closed
    form of ``T_x @ u`` (each entry has at most three of the 48 terms)."""
    w[o] = 4.0 * x0 * u0 - 2.0 * x1 * u3 + 2.0 * x2 * u2
    w[o + 1] = 4.0 * x0 * u1 + 2.0 * x1 * u2 + 2.0 * x2 * u3
    w[o + 2] = 2.0 * x1 * u1 + 2.0 * x2 * u0
    w[o + 3] = -2.0 * x1 * u0 + 2.0 * x2 * u1
    w[o + 4] = 2.0 * x0 * u3 + 4.0 * x1 * u0 - 2.0 * x2 * u1
    w[o + 5] = 2.0 * x0 * u2 - 2.0 * x2 * u0
    w[o + 6] = 2.0 * x0 * u1 + 4.0 * x1 * u2 + 2.0 * x2 * u3
    w[o + 7] = 2.0 * x0 * u0 + 2.0 * x2 * u2
    w[o + 8] = -2.0 * x0 * u2 + 2.0 * x1 * u1 + 4.0 * x2 * u0
    w[o + 9] = 2.0 * x0 * u3 + 2.0 * x1 * u0
    w[o + 10] = -2.0 * x0 * u0 + 2.0 * x1 * u3
    w[o + 11] = 2.0 * x0 * u1 + 2.0 * x1 * u2 + 4.0 * x2 * u3


@inline
def kinematic_terms(q, qd, fp, o_a, w):
    """Stage 1: everything kinematic the other stages read (Eqs. 11-13, 23-29, 34), into ``w``.

    ``Sa = S(u) a`` and ``s = (Sa)ᵀSa`` (the rod direction and ``M_pp = s diag(m)``, Eq. 51);
    ``H(u)``, ``L_a(u)``, ``L_d(u)``; ``L_a u̇``; ``L̇_a u̇ = L_a(u̇) u̇`` and ``L̇_d u̇``; their
    projections on Sa; ``ω = H u̇`` (Eq. 12) and ``J ω``. ``o_a``: offset of ``a`` (then ``d``) in fp.
    """
    u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
    v0, v1, v2, v3 = qd[3], qd[4], qd[5], qd[6]  # u̇
    s00, s01, s02, s10, s11, s12, s20, s21, s22 = rotation(u0, u1, u2, u3)
    a0, a1, a2 = fp[o_a], fp[o_a + 1], fp[o_a + 2]
    d0, d1, d2 = fp[o_a + 3], fp[o_a + 4], fp[o_a + 5]
    Sa0 = s00 * a0 + s01 * a1 + s02 * a2
    Sa1 = s10 * a0 + s11 * a1 + s12 * a2
    Sa2 = s20 * a0 + s21 * a1 + s22 * a2
    w[WS_SA] = Sa0
    w[WS_SA + 1] = Sa1
    w[WS_SA + 2] = Sa2
    w[WS_S] = Sa0 * Sa0 + Sa1 * Sa1 + Sa2 * Sa2
    H_into(u0, u1, u2, u3, w, WS_H)
    L_into(a0, a1, a2, u0, u1, u2, u3, w, WS_LA)
    L_into(d0, d1, d2, u0, u1, u2, u3, w, WS_LD)
    # L̇_a u̇ = L_a(u̇) u̇ = 2 (S(u̇) + I) a: L_a(u) is the Jacobian of the quadratic form S(u) a
    # (Eqs. 23-29), so L_a(v) v is twice that form at v; same for d
    r00 = 2 * v0 * v0 + 2 * v1 * v1
    r01 = 2 * v1 * v2 - 2 * v0 * v3
    r02 = 2 * v1 * v3 + 2 * v0 * v2
    r10 = 2 * v1 * v2 + 2 * v0 * v3
    r11 = 2 * v0 * v0 + 2 * v2 * v2
    r12 = 2 * v2 * v3 - 2 * v0 * v1
    r20 = 2 * v1 * v3 - 2 * v0 * v2
    r21 = 2 * v2 * v3 + 2 * v0 * v1
    r22 = 2 * v0 * v0 + 2 * v3 * v3
    Lad0 = 2.0 * (r00 * a0 + r01 * a1 + r02 * a2)
    Lad1 = 2.0 * (r10 * a0 + r11 * a1 + r12 * a2)
    Lad2 = 2.0 * (r20 * a0 + r21 * a1 + r22 * a2)
    Ldd0 = 2.0 * (r00 * d0 + r01 * d1 + r02 * d2)
    Ldd1 = 2.0 * (r10 * d0 + r11 * d1 + r12 * d2)
    Ldd2 = 2.0 * (r20 * d0 + r21 * d1 + r22 * d2)
    la = WS_LA
    Lau0 = w[la] * v0 + w[la + 1] * v1 + w[la + 2] * v2 + w[la + 3] * v3
    Lau1 = w[la + 4] * v0 + w[la + 5] * v1 + w[la + 6] * v2 + w[la + 7] * v3
    Lau2 = w[la + 8] * v0 + w[la + 9] * v1 + w[la + 10] * v2 + w[la + 11] * v3
    w[WS_LAD], w[WS_LAD + 1], w[WS_LAD + 2] = Lad0, Lad1, Lad2
    w[WS_LDD], w[WS_LDD + 1], w[WS_LDD + 2] = Ldd0, Ldd1, Ldd2
    w[WS_LAU], w[WS_LAU + 1], w[WS_LAU + 2] = Lau0, Lau1, Lau2
    w[WS_SLAU] = Sa0 * Lau0 + Sa1 * Lau1 + Sa2 * Lau2
    w[WS_SLAD] = Sa0 * Lad0 + Sa1 * Lad1 + Sa2 * Lad2
    w[WS_SLDD] = Sa0 * Ldd0 + Sa1 * Ldd1 + Sa2 * Ldd2
    om0, om1, om2 = omega(u0, u1, u2, u3, v0, v1, v2, v3)
    w[WS_OM] = om0
    w[WS_OM + 1] = om1
    w[WS_OM + 2] = om2
    w[WS_JW] = fp[F_J] * om0 + fp[F_J + 1] * om1 + fp[F_J + 2] * om2
    w[WS_JW + 1] = fp[F_J + 3] * om0 + fp[F_J + 4] * om1 + fp[F_J + 5] * om2
    w[WS_JW + 2] = fp[F_J + 6] * om0 + fp[F_J + 7] * om1 + fp[F_J + 8] * om2
