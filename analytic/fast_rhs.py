"""The integrator's whole right-hand side in one compiled call: ``ẏ`` for ``y = [q, q̇, W, I_L, I_P]``.

:func:`analytic.simulate._rhs` builds ``ẏ`` in Python from :meth:`FastModel.acceleration`
(q̈ and the control outputs) and :func:`analytic.aux_rates.aux_rates` (work and impulse rates), where
the Python around the kernel costs many times the kernel (``docs/performance.md``). This module
does the same lines in one numba function (same kernel, same arithmetic, same order of operations,
so the same numbers), so a right-hand side costs about one kernel call plus numba's dispatch.

``rhs_into(t, y, fp, ip, work, out)`` returns a status: ``layout.STATUS_OK``; the kernel's nonzero
status (the caller answers that evaluation with the numpy model); or :data:`STATUS_NONFINITE` when
``ẏ`` has a NaN or an infinity.

One compiled function per solve (:class:`analytic.kernel.entry.Solver`): :func:`rhs_for` gives the
one a scene needs, so a Gauss scene never compiles the M⁻² solve; :data:`rhs_into` serves any scene
(both solves compiled in).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from analytic import aux_rates as _aux
from analytic.aux_rates import rates
from analytic.kernel.calls import tail
from analytic.kernel.entry import Solver, evaluate_as, solver_of
from analytic.kernel.forces import dissipated_power
from analytic.kernel.layout import (
    F_MBR,
    F_MU0,
    F_TA,
    F_TC,
    F_TFREQ,
    I_KP,
    I_N,
    I_TORQ,
    STATUS_OK,
    STATUS_UNSUPPORTED,
)
from analytic.runtime.jit import HAVE_NUMBA, KERNEL_SOURCES, inline_always, jit, source_fingerprint

STATUS_NONFINITE = 3


@inline_always
def rhs_body(solver, t, y, fp, ip, work, out):  # pragma: no cover - compiled
    """:func:`rhs_into`'s work, called by it and by the stepping loop's C callback
    (:mod:`analytic.compiled_rhs`); ``solver`` (a :class:`Solver` value) is a constant of each
    caller, so numba keeps only that solve."""
    n = ip[I_N]
    kp = ip[I_KP]
    nq = n + 7
    q = y[:nq]
    qd = y[nq : 2 * nq]
    status = evaluate_as(solver, t, q, qd, fp, ip, work)  # only this solve is compiled in
    if status != STATUS_OK:
        return status
    for i in range(nq):
        out[i] = qd[i]
        out[nq + i] = work[i]
    tau = work[2 * nq : 2 * nq + 3]  # control torque, then + the given torque (Remark 2)
    if ip[I_TORQ]:
        ct = math.cos(fp[F_TFREQ] * t)
        for r in range(3):
            tau[r] = tau[r] + (fp[F_TC + r] + fp[F_TA + r] * ct)
    o = tail(n, kp)
    rates(
        q,
        qd,
        tau,
        work[nq + 7 : 2 * nq],  # rod forces Q^C_p
        work[nq : nq + 3],  # force at C Q^C_R
        fp[o.a : o.a + 3],
        fp[o.d : o.d + 3],
        fp[o.m : o.m + n],
        fp[F_MU0],
        fp[F_MBR] + fp[F_MU0],  # m_T = m_BR + μ0, as TumblingModel.m_T
        out[2 * nq :],
    )
    if out.shape[0] > 2 * nq + 7:  # D, with a dissipative effect on (analytic.assemble)
        out[2 * nq + 7] = dissipated_power(q, qd, fp, ip)
    for i in range(out.shape[0]):
        if not math.isfinite(out[i]):
            return STATUS_NONFINITE
    return STATUS_OK


def _make(deps: int, solver: int):
    """``rhs_into`` closing over ``deps`` (the source fingerprint of the kernel and of
    :mod:`analytic.aux_rates`, which it embeds; see :func:`analytic.runtime.jit.jit_entry`) and the
    solve it embeds (``solver``, a :class:`Solver`: numba drops the other branches)."""

    def rhs_into(t, y, fp, ip, work, out):  # pragma: no cover - compiled
        """Fill ``out`` (2 nq + 7, or 2 nq + 8 with ``D``) with ``ẏ``; ``work`` (2 nq + 3 + k)
        receives the kernel's output.

        Args:
            t: time, s. y: ``[q (nq), q̇ (nq), W, I_L (3), I_P (3)(, D)]``
                (:func:`analytic.assemble.aux_count`).
            fp, ip: packed parameters (:func:`analytic.fast.pack`).
        """
        if deps < 0:  # never true: ties numba's cache key to the sources this embeds
            return STATUS_UNSUPPORTED
        return rhs_body(solver, t, y, fp, ip, work, out)

    return rhs_into


DEPS = source_fingerprint(*KERNEL_SOURCES, _aux)


@functools.cache
def rhs_as(solver: Solver):
    """The compiled right-hand side embedding the solve ``solver`` (a :class:`Solver`; compiled,
    or loaded from numba's cache, on its first call); None without numba."""
    return jit(_make(DEPS, int(solver))) if HAVE_NUMBA else None


def rhs_for(ip: np.ndarray):
    """The compiled right-hand side for the packed scene ``ip``: the one embedding only the solve
    it needs (same call and numbers as :data:`rhs_into`)."""
    return rhs_as(solver_of(ip))


rhs_into = rhs_as(Solver.ANY)
"""The compiled right-hand side for any scene (embeds both solves; compiled on first call)."""

rhs_gauss = rhs_as(Solver.GAUSS)
rhs_minv2 = rhs_as(Solver.MINV2)
"""The variants :func:`rhs_for` gives, bound at module level like every compiled function."""

__all__ = ["DEPS", "STATUS_NONFINITE", "rhs_as", "rhs_for", "rhs_gauss", "rhs_into", "rhs_minv2"]
