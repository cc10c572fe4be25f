"""The C calling convention of the kernel's two halves, and the calls by address that compiled
callers make (numba intrinsics). Knows nothing of the kernel's layout: what the pointers point at is
:mod:`analytic.kernel.layout`'s, and the kernel's own use of these calls is
:mod:`analytic.kernel.calls`.

The kernel is two compiled functions (:mod:`analytic.kernel.halves`): stages 1-6
(:func:`analytic.kernel.system.make_build_system`) and the weighting's solve. Each is compiled once, as
a C callback (numba ``cfunc``) with one of the signatures below, and cached on disk on its own.
A compiled caller (the integrator's right-hand side, the MuJoCo and Pinocchio stages, the entry
points) calls them through their addresses, which :class:`analytic.fast.FastModel` writes into
the packed integers ``ip`` (slots ``I_FN_SYSTEM``, ``I_FN_SOLVE``).

Why not an ordinary call between numba functions: numba links a callee's code into its caller's
and optimises and emits the linked whole again, so every caller of the kernel would redo the LLVM
work of the whole kernel and could be compiled only after both halves were. Through an address the
caller's own code is small, it compiles before the halves exist, and the halves are compiled exactly
once per process (compile times: ``docs/performance.md``). The cost is one indirect call per half
per evaluation.

The addresses belong to one process: a forked child may use them, a spawned process must build its
own :class:`~analytic.fast.FastModel` (as every plant and sweep worker does). A caller handed an
``ip`` whose slots are 0 gets ``STATUS_UNSUPPORTED``, never a call.

Signatures (all pointers to contiguous arrays; lengths follow from ``ip``, see the halves):

* :data:`SYSTEM_SIG` ``void(double t, double* q, double* qd, double* fp, int64* ip, double* out,
  int64 len_out, int64 full, double* w)``;
* :data:`SOLVE_SIG` ``int64(double* q, double* fp, int64* ip, double* out, int64 len_out,
  double* w, int64 full)``, returning the kernel's status.
"""

from __future__ import annotations

from analytic.runtime.jit import HAVE_NUMBA

if HAVE_NUMBA:
    from llvmlite import ir
    from numba import types
    from numba.extending import intrinsic

    _F64P = types.CPointer(types.float64)
    _I64P = types.CPointer(types.int64)

    SYSTEM_SIG = types.void(
        types.float64, _F64P, _F64P, _F64P, _I64P, _F64P, types.int64, types.int64, _F64P
    )
    SOLVE_SIG = types.int64(_F64P, _F64P, _I64P, _F64P, types.int64, _F64P, types.int64)

    def _arrays_fit(ints: tuple, floats: tuple) -> bool:
        """The pointer arguments are contiguous arrays of the dtypes the C signature says."""

        def fits(ty, dtype) -> bool:
            return isinstance(ty, types.Array) and ty.dtype == dtype and ty.layout == "C"

        return all(fits(a, types.int64) for a in ints) and all(
            fits(a, types.float64) for a in floats
        )

    def _data(context, builder, arrty, value):
        return context.make_array(arrty)(context, builder, value).data

    def _fn_type(context, sig) -> ir.FunctionType:
        return ir.FunctionType(
            context.get_value_type(sig.return_type),
            [context.get_value_type(a) for a in sig.args],
        )

    @intrinsic
    def call_system(typingctx, address, t, q, qd, fp, ip, out, full, w):
        """Stages 1-6 at ``address`` (a :data:`SYSTEM_SIG` function): ``q``, ``qd``, ``fp``,
        ``out``, ``w`` contiguous float64 arrays, ``ip`` int64, ``full`` a bool."""
        if not _arrays_fit((ip,), (q, qd, fp, out, w)):
            return None  # a typing error in the caller, never a call with the wrong layout
        sig = types.void(address, t, q, qd, fp, ip, out, full, w)

        def codegen(context, builder, signature, args):
            a_addr, a_t, a_q, a_qd, a_fp, a_ip, a_out, a_full, a_w = args
            ty = signature.args
            addr = context.cast(builder, a_addr, ty[0], types.int64)
            fn = builder.inttoptr(addr, _fn_type(context, SYSTEM_SIG).as_pointer())
            out_ary = context.make_array(ty[6])(context, builder, a_out)
            builder.call(
                fn,
                [
                    context.cast(builder, a_t, ty[1], types.float64),
                    _data(context, builder, ty[2], a_q),
                    _data(context, builder, ty[3], a_qd),
                    _data(context, builder, ty[4], a_fp),
                    _data(context, builder, ty[5], a_ip),
                    out_ary.data,
                    builder.extract_value(out_ary.shape, 0),
                    context.cast(builder, a_full, ty[7], types.int64),
                    _data(context, builder, ty[8], a_w),
                ],
            )
            return context.get_dummy_value()

        return sig, codegen

    @intrinsic
    def call_solve(typingctx, address, q, fp, ip, out, w, full):
        """The solve at ``address`` (a :data:`SOLVE_SIG` function); returns its status."""
        if not _arrays_fit((ip,), (q, fp, out, w)):
            return None
        sig = types.int64(address, q, fp, ip, out, w, full)

        def codegen(context, builder, signature, args):
            a_addr, a_q, a_fp, a_ip, a_out, a_w, a_full = args
            ty = signature.args
            addr = context.cast(builder, a_addr, ty[0], types.int64)
            fn = builder.inttoptr(addr, _fn_type(context, SOLVE_SIG).as_pointer())
            out_ary = context.make_array(ty[4])(context, builder, a_out)
            return builder.call(
                fn,
                [
                    _data(context, builder, ty[1], a_q),
                    _data(context, builder, ty[2], a_fp),
                    _data(context, builder, ty[3], a_ip),
                    out_ary.data,
                    builder.extract_value(out_ary.shape, 0),
                    _data(context, builder, ty[5], a_w),
                    context.cast(builder, a_full, ty[6], types.int64),
                ],
            )

        return sig, codegen

else:  # pragma: no cover - without numba nothing calls the compiled halves
    SYSTEM_SIG = SOLVE_SIG = None

    def call_system(*args):
        raise RuntimeError("the compiled kernel needs numba")

    def call_solve(*args):
        raise RuntimeError("the compiled kernel needs numba")
