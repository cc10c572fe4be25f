"""The compiled analytic controller as a *native* ``mjcb_control``: MuJoCo calls machine code at each
integrator stage, with no Python in the loop.

Why: a Python ``mjcb_control`` costs about 0.6 µs per call before it does anything, and handing
sixteen arguments to a numba function another ~1.5 µs; RK4 makes four calls per step, so the
interpreter alone cost about as much as MuJoCo's whole step (the speed goal is that the controller
adds no more than the step it sits in). MuJoCo 4's ``set_mjcb_control`` also accepts a C function
pointer; this module provides one, a numba ``cfunc`` of C type ``void(const mjModel*, mjData*)``.

Where its numbers come from, each from a documented source (nothing is read at a guessed offset):

* **MuJoCo's arrays.** ``qpos``, ``qvel``, ``ctrl`` and ``xfrc_applied`` are buffers of the twin's
  ``MjData`` that keep their addresses for its life; the bindings give them
  (``d.qpos.ctypes.data``, :func:`data_arrays`) and :class:`Context` binds them with their sizes.
* **The time of the stage.** ``mjData.time`` is a scalar, with no array address. The callback asks
  MuJoCo for it with the public C function ``mj_getState(m, d, state, mjSTATE_TIME)`` (MuJoCo's
  ``mujoco.h``), resolved in the ``libmujoco`` that the bindings loaded; the value lands in a slot
  of the context (``F_TIME``).
* **The ``mjData`` it serves.** The first call after binding records the ``mjData*`` MuJoCo passes
  (the verification probe makes that call on the twin's own data, see
  :class:`mj_bridge.stepper.Stepper`); a call with any other ``mjData*`` touches nothing and counts
  as a failure.
* **The twin's data.** One process-wide context block ``CTX`` (int64 slots, layout ``C_*`` below;
  float slots read through a float64 view) holds the addresses and sizes of the bound arrays
  (numpy's ``.ctypes.data``), the accumulator's state (active flag, step ``h``, stage weights, call
  counter) and a failure counter. The cfunc reaches ``CTX`` and ``mj_getState`` through external
  symbols registered with LLVM (``llvmlite.binding.add_symbol``) when this module is imported, so
  the compiled code, cached on disk by numba, finds both wherever they lie in this process.
  MuJoCo's callbacks are process-global anyway, so one context suffices; :class:`Context` refuses a
  second binding.

Before a twin trusts this path, :class:`mj_bridge.stepper.Stepper` runs one stage through it and
through the Python callback and compares every output bit for bit; on any difference it uses the
Python callback and says so in one warning.

When the kernel declines a stage (``status != 0``: a Schur complement not numerically positive
definite, or, under the identity weighting, control rows numerically dependent), the callback cannot call the numpy model (no interpreter in the loop). It counts the
failure and leaves ``ctrl`` as it was; :class:`mj_bridge.stepper.Stepper` checks the count after
every ``mj_step``/``mj_forward`` and reruns that batch of steps from its saved start with the Python
callback, which answers such stages with the numpy model.
"""

from __future__ import annotations

import ctypes
import functools
import threading
from pathlib import Path

import mujoco
import numpy as np

from analytic.kernel.entry import Solver, solver_of
from analytic.kernel.layout import F_TA, F_TC, F_TFREQ, STATUS_OK
from analytic.runtime.jit import HAVE_NUMBA, KERNEL_SOURCES, inner, source_fingerprint
from analytic.runtime.jit import cfunc as cached_cfunc
from mj_bridge import fast_stage

if HAVE_NUMBA:
    from llvmlite import ir
    from numba import carray, types
    from numba.extending import intrinsic

    @intrinsic
    def _as_ptr(typingctx, addr):  # pragma: no cover - compiled
        """``int64`` address -> ``float64*`` (for ``numba.carray``)."""
        sig = types.CPointer(types.float64)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], ir.PointerType(ir.DoubleType()))

        return sig, codegen

    @intrinsic
    def _as_iptr(typingctx, addr):  # pragma: no cover - compiled
        """``int64`` address -> ``int64*``."""
        sig = types.CPointer(types.int64)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], ir.PointerType(ir.IntType(64)))

        return sig, codegen

    @intrinsic
    def _addr(typingctx, ptr):  # pragma: no cover - compiled
        """``void*`` -> ``int64`` address."""
        sig = types.int64(types.voidptr)

        def codegen(context, builder, signature, args):
            return builder.ptrtoint(args[0], ir.IntType(64))

        return sig, codegen


# ----------------------------------------------------------------------------------------------
# Context layout (int64 slots; F_* slots hold float64 bit patterns)
# ----------------------------------------------------------------------------------------------
C_ARMED, C_ACTIVE, C_CALLS, C_FAILS, C_NSTAGE = 0, 1, 2, 3, 4
C_DATA = 5  # the mjData* served; 0: recorded at the next call
C_QPOS, C_QVEL, C_CTRL, C_XFRC = 6, 7, 8, 9  # addresses of the MjData's buffers
F_TIME = 10  # the stage's time, written by mj_getState(m, d, &CTX[F_TIME], mjSTATE_TIME)
C_NQ, C_NV, C_NU, C_NQP = 11, 12, 13, 14  # MuJoCo nq, nv, nu; paper nq = n + 7
C_FP, C_FP_LEN, C_IP, C_IP_LEN = 15, 16, 17, 18
C_OUT, C_OUT_LEN, C_Q, C_QD = 19, 20, 21, 22
C_TQ, C_NTQ, C_F, C_NF = 23, 24, 25, 26
C_TAUG, C_GEO, C_GEO_LEN, C_ACC = 27, 28, 29, 30
C_HAS_TORQUE = 31
F_H, F_INV_GEAR = 32, 33
F_WEIGHTS = 34  # 4 slots
C_FORCE_BODY = 38  # -1: no force at C (Gauss); else the body whose xfrc_applied[:3] receives it
C_NBODY = 39
CTX_LEN = 40

MJSTATE_TIME = int(mujoco.mjtState.mjSTATE_TIME)

_CTX_SYMBOL = "tumble_mj_bridge_native_ctx"
_GETSTATE_SYMBOL = "mj_getState"


def _libmujoco_get_state() -> int | None:
    """Address of ``mj_getState`` in the ``libmujoco`` beside the bindings (the one they loaded),
    or None when it is not found."""
    pkg = Path(mujoco.__file__).parent
    for pattern in ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll"):
        for path in sorted(pkg.glob(pattern)):
            try:
                lib = ctypes.CDLL(str(path))
                return ctypes.cast(lib.mj_getState, ctypes.c_void_p).value
            except (OSError, AttributeError):
                continue
    return None


_GET_STATE = _libmujoco_get_state() if HAVE_NUMBA else None


if HAVE_NUMBA:
    import llvmlite.binding as _llvm

    @intrinsic
    def _get_time(typingctx, m_addr, d_addr, dst_addr):  # pragma: no cover - compiled
        """``mj_getState(m, d, dst, mjSTATE_TIME)``: MuJoCo writes ``d->time`` to ``*dst``."""
        sig = types.void(types.int64, types.int64, types.int64)

        def codegen(context, builder, signature, args):
            i8p = ir.IntType(8).as_pointer()
            fnty = ir.FunctionType(
                ir.VoidType(), [i8p, i8p, ir.PointerType(ir.DoubleType()), ir.IntType(32)]
            )
            mod = builder.module
            try:
                fn = mod.get_global(_GETSTATE_SYMBOL)
            except KeyError:
                fn = ir.Function(mod, fnty, name=_GETSTATE_SYMBOL)
            m, d, dst = args
            builder.call(
                fn,
                [
                    builder.inttoptr(m, i8p),
                    builder.inttoptr(d, i8p),
                    builder.inttoptr(dst, ir.PointerType(ir.DoubleType())),
                    ir.Constant(ir.IntType(32), MJSTATE_TIME),
                ],
            )
            return context.get_dummy_value()

        return sig, codegen


_GAUSS, _MINV2, _IDENTITY = int(Solver.GAUSS), int(Solver.MINV2), int(Solver.IDENTITY)


def _make_native_stage(deps: int, solver: int):
    """:func:`_native_stage` closing over ``deps`` (see :data:`DEPS`) and the solve it embeds
    (``solver``, a :class:`Solver`: ``fast_stage.stage_gauss``, ``stage_minv2``,
    ``stage_identity`` or ``stage``)."""

    def _native_stage(m_addr, d_addr, ctx_addr):  # pragma: no cover - compiled
        """One ``mjcb_control`` call: what ``Stages.stage_callback`` does, from the bound arrays."""
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return
        ctx = carray(_as_iptr(ctx_addr), (CTX_LEN,))
        ctxf = carray(_as_ptr(ctx_addr), (CTX_LEN,))
        if ctx[C_ARMED] == 0:
            ctx[C_FAILS] += 1
            return
        if ctx[C_DATA] == 0:
            ctx[C_DATA] = d_addr
        elif ctx[C_DATA] != d_addr:  # not the MjData whose arrays are bound
            ctx[C_FAILS] += 1
            return
        _get_time(m_addr, d_addr, ctx_addr + 8 * F_TIME)
        t = ctxf[F_TIME]
        qpos = carray(_as_ptr(ctx[C_QPOS]), (ctx[C_NQ],))
        qvel = carray(_as_ptr(ctx[C_QVEL]), (ctx[C_NV],))
        ctrl = carray(_as_ptr(ctx[C_CTRL]), (ctx[C_NU],))
        fp = carray(_as_ptr(ctx[C_FP]), (ctx[C_FP_LEN],))
        ip = carray(_as_iptr(ctx[C_IP]), (ctx[C_IP_LEN],))
        out = carray(_as_ptr(ctx[C_OUT]), (ctx[C_OUT_LEN],))
        q = carray(_as_ptr(ctx[C_Q]), (ctx[C_NQP],))
        qd = carray(_as_ptr(ctx[C_QD]), (ctx[C_NQP],))
        tq = carray(_as_iptr(ctx[C_TQ]), (ctx[C_NTQ],))
        fi = carray(_as_iptr(ctx[C_F]), (ctx[C_NF],))
        tau_g = carray(_as_ptr(ctx[C_TAUG]), (3,))
        geo = carray(_as_ptr(ctx[C_GEO]), (ctx[C_GEO_LEN],))
        acc = carray(_as_ptr(ctx[C_ACC]), (7,))
        if ctx[C_HAS_TORQUE]:  # the given torque of Remark 2: constant + amplitude cos(freq t)
            ct = np.cos(fp[F_TFREQ] * t)
            for r in range(3):
                tau_g[r] = fp[F_TC + r] + fp[F_TA + r] * ct
        w = 0.0
        if ctx[C_ACTIVE]:
            w = ctxf[F_H] * ctxf[F_WEIGHTS + ctx[C_CALLS] % ctx[C_NSTAGE]]
        inv_gear = ctxf[F_INV_GEAR]
        if solver == _GAUSS:
            status = fast_stage.stage_gauss(
                t, qpos, qvel, ctrl, tq, fi, fp, ip, out, q, qd, tau_g, geo, inv_gear, w, acc
            )
        elif solver == _MINV2:
            status = fast_stage.stage_minv2(
                t, qpos, qvel, ctrl, tq, fi, fp, ip, out, q, qd, tau_g, geo, inv_gear, w, acc
            )
        elif solver == _IDENTITY:
            status = fast_stage.stage_identity(
                t, qpos, qvel, ctrl, tq, fi, fp, ip, out, q, qd, tau_g, geo, inv_gear, w, acc
            )
        else:
            status = fast_stage.stage(
                t, qpos, qvel, ctrl, tq, fi, fp, ip, out, q, qd, tau_g, geo, inv_gear, w, acc
            )
        if status != STATUS_OK:
            ctx[C_FAILS] += 1
            return
        b = ctx[C_FORCE_BODY]
        if b >= 0:  # the force at C of a non-Gauss weighting: a world force at BR's CoM (= C)
            xfrc = carray(_as_ptr(ctx[C_XFRC]), (6 * ctx[C_NBODY],))
            nqp = ctx[C_NQP]
            for r in range(3):
                xfrc[6 * b + r] = out[nqp + r]
        if ctx[C_ACTIVE]:
            ctx[C_CALLS] += 1

    return _native_stage


# numba's disk cache checks only this file; the compiled callback also embeds the kernel and the stage
# (other files): their fingerprint is a closure variable, which numba hashes into the cache key.
DEPS = source_fingerprint(*KERNEL_SOURCES, fast_stage)


def _inlined_stage(solver: Solver):
    return inner(_make_native_stage(DEPS, int(solver))) if HAVE_NUMBA else None


# one per solve (module globals: the callback refers to them by name), compiled into the callback
# (not cached on their own)
native_stage_gauss = _inlined_stage(Solver.GAUSS)
native_stage_minv2 = _inlined_stage(Solver.MINV2)
native_stage_identity = _inlined_stage(Solver.IDENTITY)
native_stage = _inlined_stage(Solver.ANY)


def available() -> bool:
    """True when numba is present and MuJoCo's ``mj_getState`` was found: the native callback can
    run (whether it agrees with the Python callback is checked per twin before it is used)."""
    return HAVE_NUMBA and _GET_STATE is not None


def data_arrays(d: mujoco.MjData) -> dict[str, np.ndarray]:
    """The ``MjData`` buffers the callback reads and writes, by their context names."""
    return {"qpos": d.qpos, "qvel": d.qvel, "ctrl": d.ctrl, "xfrc_applied": d.xfrc_applied}


# ----------------------------------------------------------------------------------------------
# The process-wide context and the compiled callback
# ----------------------------------------------------------------------------------------------

CTX = np.zeros(CTX_LEN, dtype=np.int64)  # fixed address for the life of the process
CTX_F = CTX.view(np.float64)
_bind_lock = threading.Lock()
_bound_solver = Solver.GAUSS  # the solve of the scene bound in CTX (callback() compiles that one)


if HAVE_NUMBA:
    # The compiled callback refers to the context and to mj_getState through these external
    # symbols, resolved when the (disk-cached) code is loaded; so the cfunc itself can be cached
    # although both move between processes.
    _llvm.add_symbol(_CTX_SYMBOL, int(CTX.ctypes.data))
    if _GET_STATE is not None:
        _llvm.add_symbol(_GETSTATE_SYMBOL, int(_GET_STATE))

    @intrinsic
    def _ctx_addr(typingctx):  # pragma: no cover - compiled
        """Address of :data:`CTX` (the external symbol registered above)."""
        sig = types.int64()

        def codegen(context, builder, signature, args):
            mod = builder.module
            try:
                gv = mod.get_global(_CTX_SYMBOL)
            except KeyError:
                gv = ir.GlobalVariable(mod, ir.IntType(64), name=_CTX_SYMBOL)
                gv.linkage = "external"
            return builder.ptrtoint(gv, ir.IntType(64))

        return sig, codegen

    def _make_cb(deps: int, solver: int):
        def _cb(m, d):  # pragma: no cover - compiled
            if deps < 0:  # never true: ties the cache key to the kernel's sources (see DEPS)
                return
            if solver == _GAUSS:
                native_stage_gauss(_addr(m), _addr(d), _ctx_addr())
            elif solver == _MINV2:
                native_stage_minv2(_addr(m), _addr(d), _ctx_addr())
            elif solver == _IDENTITY:
                native_stage_identity(_addr(m), _addr(d), _ctx_addr())
            else:
                native_stage(_addr(m), _addr(d), _ctx_addr())

        return _cb


@functools.cache
def compiled(solver: Solver = Solver.GAUSS):
    """The numba ``cfunc`` of the callback embedding ``solver``; compiled on first use, then
    loaded from numba's disk cache."""
    if not available():
        raise RuntimeError("the native controller callback is not available here")
    return cached_cfunc(types.void(types.voidptr, types.voidptr), _make_cb(DEPS, int(solver)))


def callback():
    """The native ``mjcb_control``: a ctypes function object for ``mujoco.set_mjcb_control``,
    embedding the solve of the scene bound by the current :class:`Context` (Gauss when none is)."""
    return compiled(_bound_solver).ctypes


class Context:
    """Binds one twin's arrays into :data:`CTX` for the duration of a ``with`` block.

    Args:
        m: the twin's ``MjModel``; d: its ``MjData`` (its buffers are bound, :func:`data_arrays`).
        arrays: ``fp, ip, out, q, qd, tq_ids, f_ids, tau_g, geo, acc`` (contiguous; kept alive by
            this object while bound).
        weights: the integrator's stage weights; ``inv_gear``: 1 / the control actuators' gear;
        has_torque: whether the given torque of Remark 2 is on;
        force_body: the body (BR) whose ``xfrc_applied[:3]`` receives the control's force at C,
            or None when the weighting puts none there (Gauss).

    Attributes:
        data_ptr: the ``mjData*`` the callback serves (0: the next call records the one MuJoCo
            passes; :class:`mj_bridge.stepper.Stepper` keeps the one its verified probe saw).
    """

    def __init__(
        self,
        m,
        d,
        arrays: dict[str, np.ndarray],
        weights,
        inv_gear: float,
        has_torque,
        force_body: int | None = None,
    ):
        self.force_body = -1 if force_body is None else int(force_body)
        self.arrays = arrays
        self.m, self.d = m, d
        self.weights = tuple(float(w) for w in weights)
        self.inv_gear = float(inv_gear)
        self.has_torque = bool(has_torque)
        self.data_ptr = 0
        if len(self.weights) > 4:
            raise ValueError(f"weights: at most 4 stages (got {len(self.weights)})")
        if self.force_body >= m.nbody:
            raise ValueError(f"force_body: {self.force_body} is not a body of the model")
        for k, a in arrays.items():
            if not a.flags.c_contiguous:
                raise ValueError(f"{k}: must be C-contiguous for the native callback")

    def _data_arrays(self) -> dict[str, np.ndarray]:
        """The MjData's buffers, checked: float64, contiguous, of the model's sizes."""
        m = self.m
        want = {"qpos": m.nq, "qvel": m.nv, "ctrl": m.nu, "xfrc_applied": 6 * m.nbody}
        arrays = data_arrays(self.d)
        for k, size in want.items():
            a = arrays[k]
            if a.dtype != np.float64 or not a.flags.c_contiguous or a.size != size:
                raise ValueError(f"mjData.{k}: not a contiguous float64 buffer of {size} values")
        return arrays

    def __enter__(self) -> Context:
        global _bound_solver
        if not available():
            raise RuntimeError("the native controller callback is not available here")
        data = self._data_arrays()
        if not _bind_lock.acquire(blocking=False):
            raise RuntimeError("the native callback context is already bound")
        a = self.arrays
        CTX[:] = 0
        CTX[C_DATA] = self.data_ptr
        CTX[C_QPOS], CTX[C_QVEL] = data["qpos"].ctypes.data, data["qvel"].ctypes.data
        CTX[C_CTRL], CTX[C_XFRC] = data["ctrl"].ctypes.data, data["xfrc_applied"].ctypes.data
        CTX[C_FORCE_BODY], CTX[C_NBODY] = self.force_body, self.m.nbody
        CTX[C_NQ], CTX[C_NV], CTX[C_NU] = self.m.nq, self.m.nv, self.m.nu
        CTX[C_NQP] = a["q"].shape[0]
        for slot, key, len_slot in (
            (C_FP, "fp", C_FP_LEN), (C_IP, "ip", C_IP_LEN), (C_OUT, "out", C_OUT_LEN),
            (C_Q, "q", None), (C_QD, "qd", None), (C_TQ, "tq_ids", C_NTQ), (C_F, "f_ids", C_NF),
            (C_TAUG, "tau_g", None), (C_GEO, "geo", C_GEO_LEN), (C_ACC, "acc", None),
        ):  # fmt: skip
            CTX[slot] = a[key].ctypes.data
            if len_slot is not None:
                CTX[len_slot] = a[key].shape[0]
        CTX[C_NSTAGE] = len(self.weights)
        CTX[C_HAS_TORQUE] = self.has_torque
        CTX_F[F_INV_GEAR] = self.inv_gear
        CTX_F[F_WEIGHTS : F_WEIGHTS + len(self.weights)] = self.weights
        CTX[C_ARMED] = 1
        _bound_solver = solver_of(a["ip"])
        return self

    def __exit__(self, *exc) -> None:
        global _bound_solver
        CTX[:] = 0
        _bound_solver = Solver.GAUSS
        _bind_lock.release()

    # accumulator state, mirrored for mj_bridge.accumulator.Accumulator
    def start(self, h: float) -> None:
        """Accumulate the next steps' work and impulses with step ``h``; resets the call count."""
        CTX_F[F_H] = h
        CTX[C_CALLS] = 0
        CTX[C_ACTIVE] = 1

    def stop(self) -> int:
        """Stop accumulating; returns the number of stages the controller ran since :meth:`start`."""
        CTX[C_ACTIVE] = 0
        return int(CTX[C_CALLS])

    @property
    def failures(self) -> int:
        """Stages the kernel declined (or calls refused) since binding or the last
        :meth:`clear_failures`."""
        return int(CTX[C_FAILS])

    def clear_failures(self) -> None:
        CTX[C_FAILS] = 0

    @property
    def data_seen(self) -> int:
        """The ``mjData*`` the callback serves (recorded at its first call after binding)."""
        return int(CTX[C_DATA])

    @property
    def time_seen(self) -> float:
        """The time the callback read from MuJoCo at its last call."""
        return float(CTX_F[F_TIME])


__all__ = ["Context", "available", "callback", "compiled", "data_arrays"]
