"""How the kernel's callers reach its two compiled halves: the arrays behind a half's pointer
arguments, the offsets of ``fp``'s tail in compiled code, the stack workspace, and the call of both
halves by the addresses in ``ip``. The C signatures and the calls by address themselves are
:mod:`analytic.runtime.abi`'s; this module adds what the kernel's layout
(:mod:`analytic.kernel.layout`) says about them.
"""

from __future__ import annotations

import numpy as np

from analytic.kernel.layout import (
    I_FN_SOLVE,
    I_FN_SYSTEM,
    I_KP,
    I_N,
    I_TRACK,
    IX,
    STATUS_UNSUPPORTED,
    WS_LEN,
    tail_offsets,
)
from analytic.runtime.abi import call_solve, call_system
from analytic.runtime.jit import HAVE_NUMBA, JIT_ENABLED, inner

tail = inner(tail_offsets)
""":func:`analytic.kernel.layout.tail_offsets` for compiled code (the kernel, the compiled
right-hand sides and stages): the offsets of ``fp``'s tail, computed where they are read."""

if JIT_ENABLED:
    from llvmlite import ir
    from numba import types
    from numba.extending import intrinsic

    @intrinsic
    def stack_workspace(typingctx):
        """A ``double*`` to ``WS_LEN`` uninitialised float64 slots on the calling function's stack
        (slots: :mod:`analytic.kernel.layout` ``WS_*``); wrap it with ``numba.carray(p,
        (WS_LEN,))``.

        An intrinsic, so its code is emitted inside the caller (in its entry block): the memory
        lives as long as the caller's frame (never return it or a view of it). Unlike
        ``np.empty`` there is no heap allocation and no reference count.
        """
        sig = types.CPointer(types.float64)()

        def codegen(context, builder, signature, args):
            with builder.goto_entry_block():
                slots = builder.alloca(ir.ArrayType(ir.DoubleType(), WS_LEN))
            return builder.bitcast(slots, ir.DoubleType().as_pointer())

        return sig, codegen

else:  # pragma: no cover - plain Python (no numba, or NUMBA_DISABLE_JIT=1)

    def stack_workspace():
        return np.empty(WS_LEN)


if HAVE_NUMBA:
    from numba import carray

    @inner
    def arrays(q_p, fp_p, ip_p, out_p, len_out, w_p):
        """The arrays behind a half's pointer arguments, ``(q, fp, ip, out, w)``, with their
        lengths read from ``ip``: ``n + 7``; the end of ``fp``'s tail
        (:func:`~analytic.kernel.layout.tail_offsets`, ``.end``); the head, n flags and k_p
        indices; ``len_out``; ``WS_LEN``."""
        head = carray(ip_p, (I_TRACK,))
        n = head[I_N] & IX
        kp = head[I_KP] & IX
        return (
            carray(q_p, (n + 7,)),
            carray(fp_p, (tail(n, kp).end,)),
            carray(ip_p, (I_TRACK + n + kp,)),
            carray(out_p, (len_out,)),
            carray(w_p, (WS_LEN,)),
        )

    @inner
    def call_halves(t, q, qd, fp, ip, out, full):
        """Stages 1-6, then the solve, by the addresses in ``ip`` (one stack workspace between
        them): the body of every weighting's ``join`` (:mod:`analytic.kernel.weighting`).
        ``STATUS_UNSUPPORTED`` without a call when the addresses are not set (``ip`` straight from
        :func:`analytic.fast.pack`, or another process's); a strided ``q`` or ``qd`` (a caller's
        slice) is copied first."""
        if ip[I_FN_SYSTEM] == 0 or ip[I_FN_SOLVE] == 0:
            return STATUS_UNSUPPORTED
        w = carray(stack_workspace(), (WS_LEN,))
        qc = np.ascontiguousarray(q)  # a view (no copy) unless the caller's slice is strided
        qdc = np.ascontiguousarray(qd)
        call_system(ip[I_FN_SYSTEM], t, qc, qdc, fp, ip, out, full, w)
        return call_solve(ip[I_FN_SOLVE], qc, fp, ip, out, w, full)

else:  # pragma: no cover - without numba nothing calls the compiled halves

    def arrays(*args):
        raise RuntimeError("the compiled kernel needs numba")

    def call_halves(*args):
        raise RuntimeError("the compiled kernel needs numba")


__all__ = ["arrays", "call_halves", "stack_workspace", "tail"]
