"""The right-hand side of the compiled loop (:mod:`analytic.compiled_stepping`): a numba ``cfunc``
with the C signature CyRK's solver calls, ``void(double* dy, double t, double* y, double* args)``,
doing what :func:`analytic.fast_rhs.rhs_into` does (it calls its body,
:func:`analytic.fast_rhs.rhs_body`).

It needs numba (imported here at module level); :mod:`analytic.compiled_stepping` imports this module
only when numba is installed.

``args`` (float64, :data:`N_ARGS`): ``[ny, len fp, len ip, len work, &fp, &ip, &work, &ctx]``: the
sizes and addresses of the packed constants (:func:`analytic.fast.pack`), the kernel's work array and
``ctx``, an array shared with Python (addresses below 2**53 are exact in a float64). ``ctx``
(:data:`N_CTX`, the ``C_*`` slots): evaluations made; the first nonzero status of
:func:`~analytic.fast_rhs.rhs_into` and its time (from then on ``dy`` is NaN, which stops CyRK's
loop); and the watch of the steps' ends (:mod:`analytic.compiled_stepping`, "Steps"): the time of
the previous evaluation, the pending trial step's end (time, ``| |u|² - 1 |``), the largest
``| |u|² - 1 |`` of the accepted steps, the time of the last one (the call's start before any) and
its size.

The ``cfunc`` is cached on disk by numba. Its cache key has only plain values in it (module globals
resolve at compile time; the one closure variable is the fingerprint of the sources it embeds), so a
new process loads it instead of compiling it again.
"""

from __future__ import annotations

import numpy as np
from numba import carray, types
from numba.extending import intrinsic

from analytic.fast_rhs import rhs_body
from analytic.kernel.entry import Solver
from analytic.runtime.jit import cfunc

A_NY, A_NFP, A_NIP, A_NWORK, A_FP, A_IP, A_WORK, A_CTX = range(8)
N_ARGS = 8
C_NFEV, C_STATUS, C_T, C_PREV_T, C_CAND_T, C_CAND_E, C_MAX_E, C_LAST_T, C_LAST_H = range(9)
N_CTX = 9

SIGNATURE = types.void(
    types.CPointer(types.float64),
    types.float64,
    types.CPointer(types.float64),
    types.CPointer(types.float64),
)
"""``void(double* dy, double t, double* y, double* args)``: CyRK's ``DiffeqFuncType`` (it passes a
fifth argument, its pre-evaluation function, which the C calling convention lets us ignore)."""


@intrinsic
def _f64_at(typingctx, address):
    """``double*`` at ``address`` (int64)."""
    sig = types.CPointer(types.float64)(types.int64)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

    return sig, codegen


@intrinsic
def _i64_at(typingctx, address):
    """``int64*`` at ``address`` (int64)."""
    sig = types.CPointer(types.int64)(types.int64)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

    return sig, codegen


def _make(deps: int, solver: int):
    """The ``cfunc`` body, closing over ``deps`` and ``solver`` (see :func:`make`)."""

    def diffeq(dy_ptr, t, y_ptr, args_ptr):  # pragma: no cover - compiled
        """``dy = ẏ(t, y)``, or NaN once a nonzero status was seen; and the watch of the steps."""
        if deps < 0:  # never true: ties numba's cache key to the sources this embeds
            return
        a = carray(args_ptr, (N_ARGS,))
        ny = np.int64(a[A_NY])
        ctx = carray(_f64_at(np.int64(a[A_CTX])), (N_CTX,))
        dy = carray(dy_ptr, (ny,))
        y = carray(y_ptr, (ny,))
        ctx[C_NFEV] += 1.0
        # steps: a later evaluation accepts the pending trial step; a repeated time marks one
        if t > ctx[C_CAND_T]:  # False while there is none (NaN)
            ctx[C_MAX_E] = max(ctx[C_MAX_E], ctx[C_CAND_E])
            ctx[C_LAST_H] = ctx[C_CAND_T] - ctx[C_LAST_T]
            ctx[C_LAST_T] = ctx[C_CAND_T]
            ctx[C_CAND_T] = np.nan
        if t == ctx[C_PREV_T]:
            ctx[C_CAND_T] = t
            ctx[C_CAND_E] = abs(y[3] * y[3] + y[4] * y[4] + y[5] * y[5] + y[6] * y[6] - 1.0)
        ctx[C_PREV_T] = t
        if ctx[C_STATUS] == 0.0:
            fp = carray(_f64_at(np.int64(a[A_FP])), (np.int64(a[A_NFP]),))
            ip = carray(_i64_at(np.int64(a[A_IP])), (np.int64(a[A_NIP]),))
            work = carray(_f64_at(np.int64(a[A_WORK])), (np.int64(a[A_NWORK]),))
            # `solver` is a constant of the closure: the solve this callback embeds
            status = rhs_body(solver, t, y, fp, ip, work, dy)
            if status == 0:  # the kernel's STATUS_OK
                return
            ctx[C_STATUS] = status
            ctx[C_T] = t
        for i in range(ny):
            dy[i] = np.nan

    return diffeq


def make(deps: int, solver: Solver = Solver.ANY):
    """The compiled ``cfunc`` (its ``address`` is what CyRK calls).

    Args:
        deps: the fingerprint of the sources it embeds (:func:`analytic.runtime.jit.
            source_fingerprint`): numba's cache checks only this file, and hashes closure variables
            into its key, so editing the kernel recompiles this instead of loading a stale copy.
        solver: the solve it embeds (:func:`analytic.kernel.entry.solver_of` of the scene), so a
            Gauss scene compiles no M⁻² code.
    """
    return cfunc(SIGNATURE, _make(deps, int(solver)))


__all__ = ["N_ARGS", "N_CTX", "SIGNATURE", "make"]
