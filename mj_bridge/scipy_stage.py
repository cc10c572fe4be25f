"""The compiled stage of the plants on scipy's loop: everything of a right-hand side but the
engine's own dynamics, in one numba call.

The stage works in one state layout, the *stage state* (the Pinocchio plant's integrated state;
another engine maps its own into it, as the Drake plant does)::

    y = [x (3), qx, qy, qz, qw, p (n) | Ṙ (3), ω (3), ṗ (n) | W, I_L (3), I_P (3)]

and fills the work array (:func:`work_layout`) and ``ẏ`` but the accelerations:

1. the map of ``y`` to the paper state ``(q, q̇)`` the controller gets (``u`` the normalised
   quaternion, ``u̇ = ¼ Hᵀ ω``) and to Pinocchio's ``(q_pin, v_pin = [Sᵀ Ṙ, ω, ṗ])``;
2. the control at that state (``MODE_KERNEL``: the compiled kernel; ``MODE_GIVEN``: the control
   the caller wrote into the work array);
3. the force effects of :data:`mj_bridge.scipy_forces.FORCES`, each function compiled in, in the
   table's order, gated by its flag: the body torque ``tt = τ_c + τ_g`` and the spring tensions,
   applied to the rods as ``F^S = −∂U_s/∂p`` (Eq. 38);
4. the generalized force ``τ = [Sᵀ F_C, tt, F + F^S]`` (body axes, Pinocchio's order), the position
   and quaternion rates, and the work and impulse rates of :mod:`analytic.aux_rates`;
5. the check that what it wrote is finite.

The maps written out for numba are those of :mod:`model_xml.coordinates`
(:func:`~model_xml.coordinates.pinocchio_plant_to_pinocchio`,
:func:`~model_xml.coordinates.pinocchio_plant_to_paper`), and tested against them.
"""

from __future__ import annotations

import math

import numpy as np

from analytic import aux_rates as _aux
from analytic.aux_rates import rates
from analytic.kernel.calls import tail
from analytic.kernel.entry import Solver, evaluate_as, solver_of
from analytic.kernel.kinematics import rotation
from analytic.kernel.layout import (
    F_MBR,
    F_MU0,
    I_KP,
    I_KW,
    I_N,
    STATUS_OK,
    STATUS_UNSUPPORTED,
)
from analytic.runtime.jit import KERNEL_SOURCES, inner, jit, source_fingerprint
from mj_bridge import scipy_forces
from mj_bridge.scipy_forces import FORCES

# Modes of the compiled stage
MODE_GIVEN = 0  # use the control already in the work array
MODE_KERNEL = 1  # evaluate the control with the compiled kernel
MODE_MAP = 2  # only map y to the paper's (q, q̇) in the work array, then return
STATUS_NONFINITE = 3  # as analytic.fast_rhs.STATUS_NONFINITE


def _no_force(t, q, qd, fp, ip, off, tt, ten):  # pragma: no cover - compiled
    return


def _then(flag: int, first, rest):
    """``first`` (when ``ip[flag]`` is set), then ``rest``: one link of :func:`chain`."""

    def apply(t, q, qd, fp, ip, off, tt, ten):  # pragma: no cover - compiled
        if ip[flag] != 0:
            first(t, q, qd, fp, ip, off, tt, ten)
        rest(t, q, qd, fp, ip, off, tt, ten)

    return inner(apply)


def chain(forces):
    """One compiled function applying every ``(flag, force)`` of ``forces`` in order (the force
    functions' signature, :mod:`mj_bridge.scipy_forces`)."""
    apply = inner(_no_force)
    for flag, fn in reversed(list(forces)):
        apply = _then(flag, inner(fn), apply)
    return apply


apply_forces = chain(FORCES.values())
"""Every force of :data:`mj_bridge.scipy_forces.FORCES`, in its order."""

DEPS = source_fingerprint(*KERNEL_SOURCES, _aux, scipy_forces)
"""The sources the stage embeds besides its own: the kernel, the quadratures' rates, the forces."""


def work_layout(n: int, k: int) -> dict[str, tuple[int, int]]:
    """Slices ``name -> (start, stop)`` of the work array (float64) shared with the compiled stage.

    ``qpin`` (n+7), ``vpin`` (n+6), ``tau`` (n+6): the arguments of ``aba``; ``q``, ``qd`` (n+7):
    the mapped paper state; ``ctl`` = ``[τ_c (3), F_C (3), F (n)]`` the control; ``tt`` (3) the total
    body torque ``τ_c + τ_g``; ``kout`` (2(n+7) + 3 + k) the kernel's output; ``ten`` (n + 1) the
    spring tensions (:mod:`mj_bridge.scipy_forces`); ``rot`` (9, last) the rotation ``S`` (body ->
    inertial, row-major) of the normalised quaternion.
    """
    nq, nv = n + 7, n + 6
    sizes = [
        ("qpin", nq),
        ("vpin", nv),
        ("tau", nv),
        ("q", nq),
        ("qd", nq),
        ("ctl", n + 6),
        ("tt", 3),
        ("kout", 2 * nq + 3 + k),
        ("ten", n + 1),
        ("rot", 9),
    ]
    out, o = {}, 0
    for name, size in sizes:
        out[name] = (o, o + size)
        o += size
    return out


def _make_stage(deps: int, solver: int):
    """The stage closing over ``deps`` (:data:`DEPS`: the sources it embeds, see
    :func:`analytic.runtime.jit.jit_entry`) and the solve it embeds (``solver``, a
    :class:`Solver`; numba drops the other branches)."""

    def stage(t, y, fp, ip, work, ydot, mode):  # pragma: no cover - compiled
        """Everything of ``ẏ`` but ``v̇``, and ``aba``'s arguments (the module docstring).

        Args:
            t: time, s. y (2n + 20): the integrated state. fp, ip: :func:`analytic.fast.pack`.
            work: the work array (:func:`work_layout`). ydot (2n + 20): receives ``ẏ`` except
                ``ydot[n+7 : 2n+13]`` (``v̇``, from ``aba``). mode: ``MODE_*``.

        Returns:
            status: 0; the kernel's nonzero status (the caller supplies the control and calls again
            with ``MODE_GIVEN``); :data:`STATUS_NONFINITE` for a non-finite ``ẏ`` or ``τ``.
        """
        if deps < 0:  # never true: ties numba's cache key to the sources this embeds
            return STATUS_UNSUPPORTED
        n = ip[I_N]
        kp = ip[I_KP]
        k = ip[I_KW] + kp
        nq = n + 7
        nv = n + 6
        o_v = nq
        o_tau = o_v + nv
        o_q = o_tau + nv
        o_qd = o_q + nq
        o_ctl = o_qd + nq
        o_tt = o_ctl + n + 6
        o_k = o_tt + 3
        o_ten = o_k + 2 * nq + 3 + k
        o_rot = o_ten + n + 1
        # quaternion (x, y, z, w in y), normalised
        qx, qy, qz, qw = y[3], y[4], y[5], y[6]
        s = 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        u0, u1, u2, u3 = qw * s, qx * s, qy * s, qz * s
        s00, s01, s02, s10, s11, s12, s20, s21, s22 = rotation(u0, u1, u2, u3)  # S(u), Eq. 11
        work[o_rot], work[o_rot + 1], work[o_rot + 2] = s00, s01, s02
        work[o_rot + 3], work[o_rot + 4], work[o_rot + 5] = s10, s11, s12
        work[o_rot + 6], work[o_rot + 7], work[o_rot + 8] = s20, s21, s22
        Rd0, Rd1, Rd2 = y[nq], y[nq + 1], y[nq + 2]
        w0, w1, w2 = y[nq + 3], y[nq + 4], y[nq + 5]
        # aba's q and v; the paper's q, q̇ (u̇ = ¼ Hᵀ ω, Eq. 12 inverted)
        for i in range(3):
            work[i] = y[i]
            work[o_q + i] = y[i]
        work[3], work[4], work[5], work[6] = u1, u2, u3, u0
        work[o_q + 3], work[o_q + 4], work[o_q + 5], work[o_q + 6] = u0, u1, u2, u3
        for i in range(n):
            work[7 + i] = y[7 + i]
            work[o_q + 7 + i] = y[7 + i]
        # Pinocchio's local linear velocity v = Sᵀ Ṙ
        work[o_v] = s00 * Rd0 + s10 * Rd1 + s20 * Rd2
        work[o_v + 1] = s01 * Rd0 + s11 * Rd1 + s21 * Rd2
        work[o_v + 2] = s02 * Rd0 + s12 * Rd1 + s22 * Rd2
        for i in range(3, nv):
            work[o_v + i] = y[nq + i]
        work[o_qd], work[o_qd + 1], work[o_qd + 2] = Rd0, Rd1, Rd2
        work[o_qd + 3] = 0.5 * (-u1 * w0 - u2 * w1 - u3 * w2)
        work[o_qd + 4] = 0.5 * (u0 * w0 - u3 * w1 + u2 * w2)
        work[o_qd + 5] = 0.5 * (u3 * w0 + u0 * w1 - u1 * w2)
        work[o_qd + 6] = 0.5 * (-u2 * w0 + u1 * w1 + u0 * w2)
        for i in range(n):
            work[o_qd + 7 + i] = y[nq + 6 + i]
        if mode == MODE_MAP:
            return STATUS_OK
        # the control at this state
        if mode == MODE_KERNEL and k > 0:
            kout = work[o_k : o_k + 2 * nq + 3 + k]
            qk, qdk = work[o_q : o_q + nq], work[o_qd : o_qd + nq]
            status = evaluate_as(solver, t, qk, qdk, fp, ip, kout)  # only this solve compiled in
            if status != STATUS_OK:
                return status
            for r in range(3):
                work[o_ctl + r] = kout[2 * nq + r]  # τ_c, body axes
                work[o_ctl + 3 + r] = kout[nq + r]  # F_C = Q^C_R, inertial
            for i in range(n):
                work[o_ctl + 6 + i] = kout[nq + 7 + i]  # F_i = Q^C_p,i
        # the body torque τ_c (+ the force effects' torques) and the spring tensions
        for r in range(3):
            work[o_tt + r] = work[o_ctl + r]
        for j in range(n + 1):
            work[o_ten + j] = 0.0
        apply_forces(
            t,
            work[o_q : o_q + nq],
            work[o_qd : o_qd + nq],
            fp,
            ip,
            tail(n, kp),
            work[o_tt : o_tt + 3],
            work[o_ten : o_ten + n + 1],
        )
        tt0, tt1, tt2 = work[o_tt], work[o_tt + 1], work[o_tt + 2]
        f0, f1, f2 = work[o_ctl + 3], work[o_ctl + 4], work[o_ctl + 5]
        # τ: force at C in body axes (Sᵀ F_C), torque, rod forces + springs
        work[o_tau] = s00 * f0 + s10 * f1 + s20 * f2
        work[o_tau + 1] = s01 * f0 + s11 * f1 + s21 * f2
        work[o_tau + 2] = s02 * f0 + s12 * f1 + s22 * f2
        work[o_tau + 3], work[o_tau + 4], work[o_tau + 5] = tt0, tt1, tt2
        for i in range(n):
            work[o_tau + 6 + i] = work[o_ctl + 6 + i]
        # F^S = -∂U_s/∂p, Eq. (38): mass i gets f_{i+1} - f_i of the spring tensions
        for j in range(n + 1):
            f = work[o_ten + j]
            if j < n:
                work[o_tau + 6 + j] -= f
            if j > 0:
                work[o_tau + 5 + j] += f
        # ẏ except the accelerations: Ṙ, quaternion rate ½ q ⊗ (0, ω) of the integrated (raw) quaternion, ṗ
        ydot[0], ydot[1], ydot[2] = Rd0, Rd1, Rd2
        ydot[3] = 0.5 * (qw * w0 + qy * w2 - qz * w1)
        ydot[4] = 0.5 * (qw * w1 + qz * w0 - qx * w2)
        ydot[5] = 0.5 * (qw * w2 + qx * w1 - qy * w0)
        ydot[6] = -0.5 * (qx * w0 + qy * w1 + qz * w2)
        for i in range(n):
            ydot[7 + i] = y[nq + 6 + i]
        # work and impulses (analytic.aux_rates; a, d follow the mass-track arrays in fp)
        o = tail(n, kp)
        rates(
            work[o_q : o_q + nq],
            work[o_qd : o_qd + nq],
            work[o_tt : o_tt + 3],
            work[o_ctl + 6 : o_ctl + 6 + n],
            work[o_ctl + 3 : o_ctl + 6],
            fp[o.a : o.a + 3],
            fp[o.d : o.d + 3],
            fp[o.m : o.m + n],
            fp[F_MU0],
            fp[F_MBR] + fp[F_MU0],
            ydot[nq + nv :],
        )
        for i in range(nq):
            if not math.isfinite(ydot[i]):
                return STATUS_NONFINITE
        for i in range(nq + nv, ydot.shape[0]):
            if not math.isfinite(ydot[i]):
                return STATUS_NONFINITE
        for i in range(nv):
            if not math.isfinite(work[o_tau + i]):
                return STATUS_NONFINITE
        return STATUS_OK

    return stage


stage_gauss = jit(_make_stage(DEPS, int(Solver.GAUSS)))
stage_minv2 = jit(_make_stage(DEPS, int(Solver.MINV2)))
stage_identity = jit(_make_stage(DEPS, int(Solver.IDENTITY)))
stage = jit(_make_stage(DEPS, int(Solver.ANY)))  # any scene: every solve compiled in


def stage_for(ip: np.ndarray):
    """The compiled stage embedding only the solve the packed scene ``ip`` needs."""
    solver = solver_of(ip)
    return {Solver.MINV2: stage_minv2, Solver.IDENTITY: stage_identity}.get(solver, stage_gauss)


__all__ = [
    "MODE_GIVEN",
    "MODE_KERNEL",
    "MODE_MAP",
    "STATUS_NONFINITE",
    "apply_forces",
    "chain",
    "stage",
    "stage_for",
    "work_layout",
]
