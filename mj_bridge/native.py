"""The compiled analytic controller as a *native* ``mjcb_control``: MuJoCo calls machine code at each
integrator stage, with no Python in the loop.

Why: a Python ``mjcb_control`` costs about 0.6 µs per call before it does anything, and handing
sixteen arguments to a numba function another ~1.5 µs; RK4 makes four calls per step, so the
interpreter alone cost about as much as MuJoCo's whole step (the speed goal is that the controller
adds no more than the step it sits in). MuJoCo 4's ``set_mjcb_control`` also accepts a C function
pointer; this module provides one, a numba ``cfunc`` of C type ``void(const mjModel*, mjData*)``.

How it finds its data (nothing here is evaluated from user input):

* **MuJoCo's fields.** The callback receives the ``mjData*``. The byte offsets of ``time``, ``qpos``,
  ``qvel`` and ``ctrl`` inside ``struct mjData_`` are found once per process by reading a probe
  ``MjData`` (:func:`layout`): a pointer field is located by its value (``d.qpos.ctypes.data``,
  taking the last match, since zero-sized arrays just before it share its address), ``time`` by two
  distinctive values written in turn. The offsets are then checked on a second, differently sized
  ``MjData``. If anything is ambiguous, :func:`available` is False and the Python callback is used.
* **The twin's data.** One process-wide context block ``CTX`` (int64 slots, layout ``C_*`` below;
  float slots read through a float64 view) holds the addresses and sizes of the twin's packed
  parameters and work arrays, the accumulator's state (active flag, step ``h``, stage weights, call
  counter) and a failure counter. The cfunc reaches ``CTX`` through an external
  symbol registered with LLVM (``llvmlite.binding.add_symbol``) when this module is imported, so the
  compiled code, cached on disk by numba, finds the context wherever it lies in this process.
  MuJoCo's callbacks are process-global anyway, so one context suffices; :class:`Context` refuses a
  second binding.

When the kernel declines a stage (``status != 0``: a Schur complement not numerically positive
definite), the callback cannot call the numpy model (no interpreter in the loop). It counts the
failure and leaves ``ctrl`` as it was; :class:`mj_bridge.stepper.Stepper` checks the count after
every ``mj_step``/``mj_forward`` and reruns that batch of steps from its saved start with the Python
callback, which answers such stages with the numpy model.
"""

from __future__ import annotations

import ctypes
import functools
import threading
from dataclasses import dataclass

import mujoco
import numpy as np

from analytic import fast_kernel as fk
from mj_bridge import fast_stage

HAVE_NUMBA = fk.HAVE_NUMBA

if HAVE_NUMBA:
    from llvmlite import ir
    from numba import carray, cfunc, types
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
C_OFF_TIME, C_OFF_QPOS, C_OFF_QVEL, C_OFF_CTRL = 5, 6, 7, 8
C_NQ, C_NV, C_NU, C_NQP = 9, 10, 11, 12  # MuJoCo nq, nv, nu; paper nq = n + 7
C_FP, C_FP_LEN, C_IP, C_IP_LEN = 13, 14, 15, 16
C_OUT, C_OUT_LEN, C_Q, C_QD = 17, 18, 19, 20
C_TQ, C_NTQ, C_F, C_NF = 21, 22, 23, 24
C_TAUG, C_GEO, C_GEO_LEN, C_ACC = 25, 26, 27, 28
C_HAS_TORQUE = 29
F_H, F_INV_GEAR = 30, 31
F_WEIGHTS = 32  # 4 slots
C_TOTAL = 36  # stage calls since binding
C_DECLINE_AT = 37  # fault injection for tests: treat call number C_DECLINE_AT (1-based) as declined
C_OFF_XFRC = 38  # mjData.xfrc_applied
C_FORCE_BODY = 39  # -1: no force at C (Gauss); else the body whose xfrc_applied[:3] receives it
C_NBODY = 40
CTX_LEN = 41


def _data_array(d_addr, ctx, slot, n):  # pragma: no cover - compiled
    """The ``mjtNum*`` field of ``mjData`` whose byte offset is in ``ctx[slot]``, as n float64."""
    return carray(_as_ptr(carray(_as_iptr(d_addr + ctx[slot]), (1,))[0]), (n,))


data_array = fk._jit(_data_array) if HAVE_NUMBA else None


def _make_native_stage(deps: int):
    """:func:`_native_stage` closing over ``deps`` (see :data:`DEPS`)."""

    def _native_stage(d_addr, ctx_addr):  # pragma: no cover - compiled
        """One ``mjcb_control`` call: what ``Stages.stage_callback`` does, from raw addresses."""
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return
        ctx = carray(_as_iptr(ctx_addr), (CTX_LEN,))
        ctxf = carray(_as_ptr(ctx_addr), (CTX_LEN,))
        if ctx[C_ARMED] == 0:
            ctx[C_FAILS] += 1
            return
        t = carray(_as_ptr(d_addr + ctx[C_OFF_TIME]), (1,))[0]
        qpos = data_array(d_addr, ctx, C_OFF_QPOS, ctx[C_NQ])
        qvel = data_array(d_addr, ctx, C_OFF_QVEL, ctx[C_NV])
        ctrl = data_array(d_addr, ctx, C_OFF_CTRL, ctx[C_NU])
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
        if ctx[
            C_HAS_TORQUE
        ]:  # the given torque of Remark 2: constant + amplitude cos(freq t), body
            ct = np.cos(fp[fk.F_TFREQ] * t)
            for r in range(3):
                tau_g[r] = fp[fk.F_TC + r] + fp[fk.F_TA + r] * ct
        w = 0.0
        if ctx[C_ACTIVE]:
            w = ctxf[F_H] * ctxf[F_WEIGHTS + ctx[C_CALLS] % ctx[C_NSTAGE]]
        ctx[C_TOTAL] += 1
        if ctx[C_TOTAL] == ctx[C_DECLINE_AT]:
            status = fk.STATUS_NOT_PD
        else:
            status = fast_stage.stage(
                t,
                qpos,
                qvel,
                ctrl,
                tq,
                fi,
                fp,
                ip,
                out,
                q,
                qd,
                tau_g,
                geo,
                ctxf[F_INV_GEAR],
                w,
                acc,
            )
        if status != fk.STATUS_OK:
            ctx[C_FAILS] += 1
            return
        b = ctx[C_FORCE_BODY]
        if b >= 0:  # the force at C of a non-Gauss weighting: a world force at BR's CoM (= C)
            xfrc = data_array(d_addr, ctx, C_OFF_XFRC, 6 * ctx[C_NBODY])
            nqp = ctx[C_NQP]
            for r in range(3):
                xfrc[6 * b + r] = out[nqp + r]
        if ctx[C_ACTIVE]:
            ctx[C_CALLS] += 1

    return _native_stage


# numba's disk cache checks only this file; the compiled callback also embeds the kernel and the stage
# (other files): their fingerprint is a closure variable, which numba hashes into the cache key.
DEPS = fk.source_fingerprint(fk, fast_stage)
native_stage = fk._jit(_make_native_stage(DEPS)) if HAVE_NUMBA else None


# ----------------------------------------------------------------------------------------------
# mjData layout
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DataLayout:
    """Byte offsets of fields inside ``struct mjData_`` (this MuJoCo build)."""

    time: int
    qpos: int
    qvel: int
    ctrl: int
    xfrc_applied: int


_PROBE_XML = """<mujoco><worldbody><body><freejoint/><geom size="0.1"/>
<body><joint name="s{i}" type="slide"/><geom size="0.1"/></body></body></worldbody>
<actuator><motor joint="s{i}"/></actuator></mujoco>"""
_SCAN_LIMIT = 1 << 22  # bytes; the fields sought sit after MuJoCo's fixed-size statistics arrays


def _scan(d: mujoco.MjData, targets: dict[str, int], times: tuple[float, float]) -> DataLayout:
    base = d._address
    found: dict[str, list[int]] = {k: [] for k in targets}
    time_hits: list[int] = []
    d.time = times[0]
    off = 0
    pending = set(targets)
    while off < _SCAN_LIMIT:
        word = ctypes.c_int64.from_address(base + off).value
        for k, v in targets.items():
            if word == v:
                found[k].append(off)
        if ctypes.c_double.from_address(base + off).value == times[0]:
            time_hits.append(off)
        pending -= {k for k in targets if found[k] and found[k][-1] < off - 64}
        if not pending and time_hits:
            break
        off += 8
    d.time = times[1]
    time_hits = [o for o in time_hits if ctypes.c_double.from_address(base + o).value == times[1]]
    if len(time_hits) != 1 or any(not found[k] for k in targets):
        raise LookupError("mjData layout: time or a pointer field not found uniquely")
    # last match: a zero-sized array allocated just before a field shares its address
    return DataLayout(
        time_hits[0],
        found["qpos"][-1],
        found["qvel"][-1],
        found["ctrl"][-1],
        found["xfrc_applied"][-1],
    )


def _probe(i: int) -> DataLayout:
    m = mujoco.MjModel.from_xml_string(_PROBE_XML.format(i=i))
    d = mujoco.MjData(m)
    targets = {k: getattr(d, k).ctypes.data for k in ("qpos", "qvel", "ctrl", "xfrc_applied")}
    return _scan(d, targets, (1.2345678901234567e-3 + i, -7.654321098765432e-5 - i))


@functools.cache
def layout() -> DataLayout | None:
    """The offsets, found on one probe and confirmed on a second; None when not found."""
    try:
        a, b = _probe(0), _probe(1)
    except LookupError:
        return None
    return a if a == b else None


def read_fields(d: mujoco.MjData, lay: DataLayout) -> tuple[float, int, int, int, int]:
    """``(time, qpos, qvel, ctrl, xfrc_applied addresses)`` read through the offsets (for tests)."""
    base = d._address
    return (
        ctypes.c_double.from_address(base + lay.time).value,
        ctypes.c_int64.from_address(base + lay.qpos).value,
        ctypes.c_int64.from_address(base + lay.qvel).value,
        ctypes.c_int64.from_address(base + lay.ctrl).value,
        ctypes.c_int64.from_address(base + lay.xfrc_applied).value,
    )


def available() -> bool:
    """True when numba is present and the mjData layout was found: the native callback can run."""
    return HAVE_NUMBA and layout() is not None


# ----------------------------------------------------------------------------------------------
# The process-wide context and the compiled callback
# ----------------------------------------------------------------------------------------------

CTX = np.zeros(CTX_LEN, dtype=np.int64)  # fixed address for the life of the process
CTX_F = CTX.view(np.float64)
_bind_lock = threading.Lock()


_CTX_SYMBOL = "tumble_mj_bridge_native_ctx"


if HAVE_NUMBA:
    import llvmlite.binding as _llvm

    # The compiled callback refers to the context through this external symbol, resolved when the
    # (disk-cached) code is loaded; so the cfunc itself can be cached although CTX moves between runs.
    _llvm.add_symbol(_CTX_SYMBOL, int(CTX.ctypes.data))

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

    def _make_cb(deps: int):
        def _cb(m, d):  # pragma: no cover - compiled
            if deps >= 0:  # always: ties the cache key to the kernel's sources (see DEPS)
                native_stage(_addr(d), _ctx_addr())

        return _cb


@functools.cache
def compiled():
    """The numba ``CFunc`` of the callback; compiled on first use, then loaded from numba's disk
    cache (its ``cache_hits`` say which)."""
    if not available():
        raise RuntimeError("the native controller callback is not available here")
    sig = types.void(types.voidptr, types.voidptr)
    try:
        return cfunc(sig, nopython=True, cache=True)(_make_cb(DEPS))
    except RuntimeError:  # no usable cache directory (see analytic.fast_kernel._jit)
        return cfunc(sig, nopython=True)(_make_cb(DEPS))


def callback():
    """The native ``mjcb_control``: a ctypes function object for ``mujoco.set_mjcb_control``."""
    return compiled().ctypes


class Context:
    """Binds one twin's arrays into :data:`CTX` for the duration of a ``with`` block.

    Args:
        m: the twin's ``MjModel``.
        arrays: ``fp, ip, out, q, qd, tq_ids, f_ids, tau_g, geo, acc`` (contiguous; kept alive by
            this object while bound).
        weights: the integrator's stage weights; ``inv_gear``: 1 / the control actuators' gear;
        has_torque: whether the given torque of Remark 2 is on;
        force_body: the body (BR) whose ``xfrc_applied[:3]`` receives the control's force at C,
            or None when the weighting puts none there (Gauss).
    """

    def __init__(
        self,
        m,
        arrays: dict[str, np.ndarray],
        weights,
        inv_gear: float,
        has_torque,
        force_body: int | None = None,
    ):
        self.force_body = -1 if force_body is None else int(force_body)
        self.arrays = arrays
        self.m = m
        self.weights = tuple(float(w) for w in weights)
        self.inv_gear = float(inv_gear)
        self.has_torque = bool(has_torque)
        if len(self.weights) > 4:
            raise ValueError(f"weights: at most 4 stages (got {len(self.weights)})")
        for k, a in arrays.items():
            if not a.flags.c_contiguous:
                raise ValueError(f"{k}: must be C-contiguous for the native callback")

    def __enter__(self) -> Context:
        lay = layout()
        if lay is None:
            raise RuntimeError("the native controller callback is not available here")
        if not _bind_lock.acquire(blocking=False):
            raise RuntimeError("the native callback context is already bound")
        a = self.arrays
        CTX[:] = 0
        CTX[C_OFF_TIME], CTX[C_OFF_QPOS] = lay.time, lay.qpos
        CTX[C_OFF_QVEL], CTX[C_OFF_CTRL] = lay.qvel, lay.ctrl
        CTX[C_OFF_XFRC], CTX[C_FORCE_BODY], CTX[C_NBODY] = (
            lay.xfrc_applied,
            self.force_body,
            self.m.nbody,
        )
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
        return self

    def __exit__(self, *exc) -> None:
        CTX[:] = 0
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
        """Stages the kernel declined since binding or the last :meth:`clear_failures`."""
        return int(CTX[C_FAILS])

    def clear_failures(self) -> None:
        CTX[C_FAILS] = 0

    def decline_at(self, call: int) -> None:
        """Fault injection (tests): the ``call``-th stage call from binding on (1-based) behaves as
        if the kernel had declined it. 0 switches this off."""
        CTX[C_DECLINE_AT] = int(call)


__all__ = ["Context", "DataLayout", "available", "callback", "compiled", "layout", "read_fields"]
