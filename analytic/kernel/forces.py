"""The generalized force ``Q(q, q̇)`` of Eq. (52), in two kernel stages: :func:`rod_pass` (the rod
rows, one pass over the masses that also sums the mass moments) and :func:`body_forces` (the R and
u rows, including the given torque of Remark 2, Eq. 61).

Every mass term derives from ``r̈_i = J_i q̈ + κ_i`` with
``κ_i = 2 ṗ_i L_a u̇ + p_i L̇_a u̇ + L̇_d u̇`` (Eq. 40), so the sums over masses reduce to the moments
``μ0 = Σm``, ``μ1 = Σ m p``, ``μ2 = Σ m p²``, ``Σ m ṗ``, ``Σ m p ṗ`` (see :mod:`analytic.model`).
"""

from __future__ import annotations

import math

from analytic.effects import Effect
from analytic.effects.damping import damping_dissipation, damping_force
from analytic.effects.springs import cubic_force, linear_force
from analytic.kernel.calls import tail
from analytic.kernel.kinematics import Ht_times
from analytic.kernel.layout import (
    F_G,
    F_MBR,
    F_MU0,
    F_TA,
    F_TC,
    F_TFREQ,
    I_GRAV,
    I_KP,
    I_LAWS,
    I_N,
    I_TORQ,
    I_TRACK,
    IX,
    LAW_INDEX,
    WS_JW,
    WS_LA,
    WS_LAD,
    WS_LAU,
    WS_LD,
    WS_LDD,
    WS_MPD,
    WS_MPPD,
    WS_MU1,
    WS_MU2,
    WS_N0,
    WS_N1,
    WS_N2,
    WS_NT0,
    WS_NT1,
    WS_QB,
    WS_SA,
    WS_SLAD,
    WS_SLAU,
    WS_SLDD,
    WS_SPQ,
    WS_SQ,
)
from analytic.runtime.jit import inner

LINEAR = LAW_INDEX[Effect.SPRINGS_LINEAR]
CUBIC = LAW_INDEX[Effect.SPRINGS_CUBIC]
DAMPING = LAW_INDEX[Effect.SPRINGS_DAMPING]
phi_linear = inner(linear_force)  # the laws' shapes, as declared (analytic.effects)
phi_cubic = inner(cubic_force)
phi_damping = inner(damping_force)
delta_damping = inner(damping_dissipation)


@inner
def rod_pass(q, qd, fp, ip, n, o, out, full, w):
    """Stage 2: the rod rows of Q (Eq. 52, third block row; springs ``F^S = -∂U_s/∂p`` of Eq. 38,
    docs/errata.md item 2) and, in the same pass, the moments the other stages need.

    ``Q_i`` goes straight into ``out``: the q̈_i slot of a free mass (the Gauss solve turns it into
    q̈_i in place), the ``Q^C_i`` slot of a tracked one (full output only; it becomes μ_i).
    Writes to ``w``: ``μ1, μ2, Σmṗ, Σmpṗ`` (all masses), ``Σ_F m p⁰ ¹ ²`` (free), ``Σ_T m, Σ_T m p``
    (tracked), ``Σ_F Q_i, Σ_F p_i Q_i``. ``o``: the offsets of ``fp``'s tail
    (:class:`analytic.kernel.layout.FpTail`).
    """
    o_m, o_pe = o.m, o.p_e
    nq = n + 7
    itr = I_TRACK
    Sa0, Sa1, Sa2 = w[WS_SA], w[WS_SA + 1], w[WS_SA + 2]
    grav = ip[I_GRAV] != 0
    sg = Sa0 * fp[F_G] + Sa1 * fp[F_G + 1] + Sa2 * fp[F_G + 2]
    lin = ip[I_LAWS + LINEAR] != 0
    cub = ip[I_LAWS + CUBIC] != 0
    damp = ip[I_LAWS + DAMPING] != 0
    springs = n > 0 and (lin or cub or damp)
    o_kl = o.laws + LINEAR * (n + 1)
    o_kn = o.laws + CUBIC * (n + 1)
    o_c = o.laws + DAMPING * (n + 1)
    sLad = w[WS_SLAD]
    sLdd = w[WS_SLDD]
    mu1 = 0.0
    mu2 = 0.0
    mpd = 0.0
    mppd = 0.0
    n0 = 0.0
    n1 = 0.0
    n2 = 0.0
    nt0 = 0.0  # Σ_T m_i, Σ_T m_i p_i (tracked)
    nt1 = 0.0
    sq = 0.0
    spq = 0.0
    sl2 = 2.0 * w[WS_SLAU]
    # spring j joins x_{j-1} and x_j (x = p - p_e, x_{-1} = x_n = 0) with force f_j;
    # Q_p,i += f_{i+1} - f_i
    x = 0.0
    xd = 0.0  # ẋ = ṗ
    f_prev = 0.0
    if springs:
        x = q[7] - fp[o_pe]
        xd = qd[7]
        if lin:
            f_prev += fp[o_kl] * phi_linear(x, xd)
        if cub:
            f_prev += fp[o_kn] * phi_cubic(x, xd)
        if damp:
            f_prev += fp[o_c] * phi_damping(x, xd)
    for i in range(n):
        mi = fp[o_m + i]
        pi = q[7 + i]
        pdi = qd[7 + i]
        mp = mi * pi
        mu1 += mp
        mu2 += mp * pi
        mpd += mi * pdi
        mppd += mp * pdi
        Qi = -mi * (sl2 * pdi + sLad * pi + sLdd)
        if grav:
            Qi += sg * mi
        if springs:
            xn = q[8 + i] - fp[o_pe + i + 1] if i + 1 < n else 0.0
            xdn = qd[8 + i] if i + 1 < n else 0.0
            e = xn - x
            ed = xdn - xd
            f = 0.0
            if lin:
                f += fp[o_kl + i + 1] * phi_linear(e, ed)
            if cub:
                f += fp[o_kn + i + 1] * phi_cubic(e, ed)
            if damp:
                f += fp[o_c + i + 1] * phi_damping(e, ed)
            Qi += f - f_prev
            f_prev = f
            x = xn
            xd = xdn
        if ip[itr + i] == 0:
            out[7 + i] = Qi  # q̈_i is computed from it in place
            n0 += mi
            n1 += mp
            n2 += mp * pi
            sq += Qi
            spq += pi * Qi
        else:
            if full:
                out[nq + 7 + i] = Qi  # μ_i (Q^C_i) is computed from it in place
            nt0 += mi
            nt1 += mp
    w[WS_MU1] = mu1
    w[WS_MU2] = mu2
    w[WS_MPD] = mpd
    w[WS_MPPD] = mppd
    w[WS_N0] = n0
    w[WS_N1] = n1
    w[WS_N2] = n2
    w[WS_NT0] = nt0
    w[WS_NT1] = nt1
    w[WS_SQ] = sq
    w[WS_SPQ] = spq


@inner
def body_forces(t, q, qd, fp, ip, w):
    """Stage 4: the R and u rows of Q (Eq. 52, first two block rows, with ``B_d``) into
    ``w[WS_QB:WS_QB+7]``, and the given torque's ``Q_τ = Hᵀτ`` (Remark 2, Eq. 61):

    ``Q_R = -Σ m κ (+ m_T g)``,
    ``Q_u = -2 H(u̇)ᵀ J ω - L_aᵀ Σ m p κ - L_dᵀ Σ m κ (+ L_aᵀ μ1 g + L_dᵀ μ0 g) (+ Hᵀ τ_e)``.
    """
    u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
    v0, v1, v2, v3 = qd[3], qd[4], qd[5], qd[6]
    oq = WS_QB
    mu0 = fp[F_MU0]
    m_T = fp[F_MBR] + mu0
    mu1 = w[WS_MU1]
    mu2 = w[WS_MU2]
    mpd = w[WS_MPD]
    mppd = w[WS_MPPD]
    Lau0, Lau1, Lau2 = w[WS_LAU], w[WS_LAU + 1], w[WS_LAU + 2]
    Lad0, Lad1, Lad2 = w[WS_LAD], w[WS_LAD + 1], w[WS_LAD + 2]
    Ldd0, Ldd1, Ldd2 = w[WS_LDD], w[WS_LDD + 1], w[WS_LDD + 2]
    smk0 = 2.0 * mpd * Lau0 + mu1 * Lad0 + mu0 * Ldd0
    smk1 = 2.0 * mpd * Lau1 + mu1 * Lad1 + mu0 * Ldd1
    smk2 = 2.0 * mpd * Lau2 + mu1 * Lad2 + mu0 * Ldd2
    xa0 = -(2.0 * mppd * Lau0 + mu2 * Lad0 + mu1 * Ldd0)
    xa1 = -(2.0 * mppd * Lau1 + mu2 * Lad1 + mu1 * Ldd1)
    xa2 = -(2.0 * mppd * Lau2 + mu2 * Lad2 + mu1 * Ldd2)
    xd0 = -smk0
    xd1 = -smk1
    xd2 = -smk2
    w[oq] = -smk0
    w[oq + 1] = -smk1
    w[oq + 2] = -smk2
    if ip[I_GRAV] != 0:
        g0, g1, g2 = fp[F_G], fp[F_G + 1], fp[F_G + 2]
        w[oq] += m_T * g0
        w[oq + 1] += m_T * g1
        w[oq + 2] += m_T * g2
        xa0 += mu1 * g0
        xa1 += mu1 * g1
        xa2 += mu1 * g2
        xd0 += mu0 * g0
        xd1 += mu0 * g1
        xd2 += mu0 * g2
    h0, h1, h2, h3 = Ht_times(
        v0, v1, v2, v3, -2.0 * w[WS_JW], -2.0 * w[WS_JW + 1], -2.0 * w[WS_JW + 2]
    )
    if ip[I_TORQ]:
        ct = math.cos(fp[F_TFREQ] * t)
        e0, e1, e2, e3 = Ht_times(
            u0,
            u1,
            u2,
            u3,
            fp[F_TC] + fp[F_TA] * ct,
            fp[F_TC + 1] + fp[F_TA + 1] * ct,
            fp[F_TC + 2] + fp[F_TA + 2] * ct,
        )
        h0 += e0
        h1 += e1
        h2 += e2
        h3 += e3
    w[oq + 3] = h0
    w[oq + 4] = h1
    w[oq + 5] = h2
    w[oq + 6] = h3
    for c in range(4):
        w[oq + 3 + c] += (
            w[WS_LA + c] * xa0
            + w[WS_LA + 4 + c] * xa1
            + w[WS_LA + 8 + c] * xa2
            + w[WS_LD + c] * xd0
            + w[WS_LD + 4 + c] * xd1
            + w[WS_LD + 8 + c] * xd2
        )


@inner
def dissipated_power(q, qd, fp, ip):
    """``Ḋ = Σ_j c_j δ(e_j, ė_j)``, W: the power the dissipative spring laws that are on take out
    of the motion (:func:`analytic.model.dissipated_power`, the same sum)."""
    n = ip[I_N] & IX
    if n == 0 or ip[I_LAWS + DAMPING] == 0:
        return 0.0
    o = tail(n, ip[I_KP] & IX)
    o_c = o.laws + DAMPING * (n + 1)
    power = 0.0
    x = 0.0
    xd = 0.0
    for j in range(n + 1):
        xn = q[7 + j] - fp[o.p_e + j] if j < n else 0.0
        xdn = qd[7 + j] if j < n else 0.0
        power += fp[o_c + j] * delta_damping(xn - x, xdn - xd)
        x = xn
        xd = xdn
    return power
