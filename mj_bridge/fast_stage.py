"""The analytic controller at one MuJoCo integrator stage, compiled (numba).

One call does what :meth:`mj_bridge.stages.Stages.control_callback` does in Python, for BR's body
frame at C (the default model): map MuJoCo's ``(qpos, qvel)`` to the paper's ``(q, q̇)``
(``u = q_b``, ``u̇ = ¼ Hᵀ ω / |u|²``: :func:`model_xml.coordinates.mujoco_to_paper_state`, written
out for numba and tested against it), evaluate the analytic side's compiled kernel
(:mod:`analytic.kernel`, the paper's Eq. 89), write the actuators' ``ctrl``
(torque + given torque on ``torque_x..z``, rod forces on ``force1..N``, divided by the gear) and, with weight ``w > 0``,
add ``w·[P, S(u)(τ+τ_g) + (R-c)×F_C, F_C]`` to the work/impulse accumulator.

Its status is the kernel's: anything but ``STATUS_OK`` makes the caller fall back to the numpy model
for that stage.

One compiled stage per solve (:class:`analytic.kernel.entry.Solver`): :func:`stage_for` gives the
one a scene needs (``stage_gauss``, ``stage_minv2``, ``stage_identity``), so a Gauss scene never
compiles the other weightings' solves; :data:`stage` serves any scene (every solve compiled in).
"""

from __future__ import annotations

import numpy as np

from analytic.kernel.entry import Solver, evaluate_as, solver_of
from analytic.kernel.kinematics import rotation
from analytic.kernel.layout import STATUS_OK, STATUS_UNSUPPORTED
from analytic.runtime.jit import HAVE_NUMBA, KERNEL_SOURCES, jit, source_fingerprint


def make_stage(deps: int, solver: int):
    """The stage function closing over ``deps`` (:data:`DEPS`, the fingerprint of the kernel's
    sources), so numba's disk cache recompiles it when the kernel changes, and over the solve it
    embeds (``solver``, a :class:`Solver`; numba drops the other branches)."""

    def _stage(
        t, qpos, qvel, ctrl, tq_ids, f_ids, fp, ip, out, q, qd, tau_g, geo, inv_gear, w, acc
    ):  # pragma: no cover - compiled
        if deps < 0:  # never true: ties numba's cache key to the kernel's source (see above)
            return STATUS_UNSUPPORTED
        n = q.shape[0] - 7
        nq = n + 7
        for i in range(nq):
            q[i] = qpos[i]
        u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
        w0, w1, w2 = qvel[3], qvel[4], qvel[5]
        s = 0.5 / (u0 * u0 + u1 * u1 + u2 * u2 + u3 * u3)
        qd[0], qd[1], qd[2] = qvel[0], qvel[1], qvel[2]
        qd[3] = s * (-u1 * w0 - u2 * w1 - u3 * w2)
        qd[4] = s * (u0 * w0 - u3 * w1 + u2 * w2)
        qd[5] = s * (u3 * w0 + u0 * w1 - u1 * w2)
        qd[6] = s * (-u2 * w0 + u1 * w1 + u0 * w2)
        for i in range(n):
            qd[7 + i] = qvel[6 + i]
        status = evaluate_as(solver, t, q, qd, fp, ip, out)  # only this solve is compiled in
        if status != STATUS_OK:
            return status
        tau0 = out[2 * nq] + tau_g[0]
        tau1 = out[2 * nq + 1] + tau_g[1]
        tau2 = out[2 * nq + 2] + tau_g[2]
        if tq_ids.shape[0] == 3:
            ctrl[tq_ids[0]] = tau0 * inv_gear
            ctrl[tq_ids[1]] = tau1 * inv_gear
            ctrl[tq_ids[2]] = tau2 * inv_gear
        power = tau0 * w0 + tau1 * w1 + tau2 * w2
        for i in range(f_ids.shape[0]):
            F = out[nq + 7 + i]
            ctrl[f_ids[i]] = F * inv_gear
            power += F * qvel[6 + i]
        if w > 0.0:
            f0, f1, f2 = out[nq], out[nq + 1], out[nq + 2]
            power += f0 * qvel[0] + f1 * qvel[1] + f2 * qvel[2]
            # S(u), Eq. (11) (MuJoCo keeps qpos quaternions unit)
            S00, S01, S02, S10, S11, S12, S20, S21, S22 = rotation(u0, u1, u2, u3)
            L0 = S00 * tau0 + S01 * tau1 + S02 * tau2
            L1 = S10 * tau0 + S11 * tau1 + S12 * tau2
            L2 = S20 * tau0 + S21 * tau1 + S22 * tau2
            if f0 != 0.0 or f1 != 0.0 or f2 != 0.0:
                # R - c = -(μ1 Sa + μ0 Sd)/m_T; geo = [m_T, μ0, a (3), d (3), m (n)]
                mu1 = 0.0
                for i in range(n):
                    mu1 += geo[8 + i] * q[7 + i]
                b0 = mu1 * geo[2] + geo[1] * geo[5]
                b1 = mu1 * geo[3] + geo[1] * geo[6]
                b2 = mu1 * geo[4] + geo[1] * geo[7]
                r0 = -(S00 * b0 + S01 * b1 + S02 * b2) / geo[0]
                r1 = -(S10 * b0 + S11 * b1 + S12 * b2) / geo[0]
                r2 = -(S20 * b0 + S21 * b1 + S22 * b2) / geo[0]
                L0 += r1 * f2 - r2 * f1
                L1 += r2 * f0 - r0 * f2
                L2 += r0 * f1 - r1 * f0
            acc[0] += w * power
            acc[1] += w * L0
            acc[2] += w * L1
            acc[3] += w * L2
            acc[4] += w * f0
            acc[5] += w * f1
            acc[6] += w * f2
        return status

    return _stage


DEPS = source_fingerprint(*KERNEL_SOURCES)


def _compiled(solver: Solver):
    return jit(make_stage(DEPS, int(solver))) if HAVE_NUMBA else None


stage_gauss = _compiled(Solver.GAUSS)
stage_minv2 = _compiled(Solver.MINV2)
stage_identity = _compiled(Solver.IDENTITY)
stage = _compiled(Solver.ANY)
"""The compiled stage for any scene (embeds every solve; compiled on first call)."""


def argument_types() -> tuple:
    """numba's types of the stage's arguments as both of its callers pass them: the native
    callback (:mod:`mj_bridge.native`, contiguous ``carray`` views of MuJoCo's and the kernel's
    buffers) and the Python callback (:class:`mj_bridge.stages.Stages`, contiguous numpy arrays):
    ``t`` float64, thirteen 1-d C-contiguous arrays (``tq_ids``, ``f_ids`` and ``ip`` int64, the
    rest float64) with ``inv_gear`` and ``w`` float64 in their places."""
    from numba import types

    f, F = types.float64, types.Array(types.float64, 1, "C")
    ints = types.Array(types.int64, 1, "C")
    # t, qpos, qvel, ctrl, tq_ids, f_ids, fp, ip, out, q, qd, tau_g, geo, inv_gear, w, acc
    return (f, F, F, F, ints, ints, F, ints, F, F, F, F, F, f, f, F)


def compile_for(solver: Solver) -> None:
    """Compile (or load from numba's disk cache) the stage embedding ``solver`` for
    :func:`argument_types`, without running it: what the native callback then links, and the
    Python callback calls (a first run compiles it in a second process meanwhile)."""
    if HAVE_NUMBA:
        _by_solver(Solver(solver)).compile(argument_types())


def stage_for(ip: np.ndarray):
    """The compiled stage for the packed scene ``ip``, embedding only the solve it needs (same
    call and numbers as :data:`stage`)."""
    return _by_solver(solver_of(ip))


def _by_solver(solver: Solver):
    """The compiled stage embedding ``solver`` (:data:`stage` for ``Solver.ANY``)."""
    return {
        Solver.GAUSS: stage_gauss,
        Solver.MINV2: stage_minv2,
        Solver.IDENTITY: stage_identity,
    }.get(solver, stage)


def geometry(model) -> np.ndarray:
    """``[m_T, μ0, a (3), d (3), m (n)]`` of a :class:`~analytic.model.TumblingModel`."""
    return np.ascontiguousarray(
        np.concatenate([[model.m_T, model.mu0], model.a, model.d, model.m]), dtype=float
    )
