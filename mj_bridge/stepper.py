"""MuJoCo steps under one twin's callbacks, in batches: the native controller callback where it
applies, and a batch it could not finish redone with the Python callback.

The native callback (:mod:`mj_bridge.native`) runs the compiled stage with no interpreter in the
loop, so it cannot ask the numpy model when the kernel declines a stage; it counts the failure and
leaves ``ctrl`` as it was. :meth:`Stepper.step` saves MuJoCo's integration state, the accumulator and
the warning counts before each batch of ``mj_step`` calls and, when the batch had a declined stage,
restores them and reruns the batch with the Python callback (:class:`mj_bridge.stages.Stages`),
which answers such stages with the numpy model. The result is the run the Python callback gives.

Before the native callback drives a twin, :meth:`Stepper.callbacks` verifies it once (per twin, so
per model and ``MjData``): one stage, with accumulation on, through MuJoCo into the native callback
and the same stage through the Python one, at the current state and a time away from it; the
controls, ``xfrc_applied``, the stage's outputs, the accumulated work and impulses, the stage count
and the time read must agree bit for bit. If anything differs, the twin uses the Python callback
from then on, and one warning says why.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator

import mujoco
import numpy as np

from mj_bridge import native
from mj_bridge.accumulator import Accumulator
from mj_bridge.callbacks import (
    bad_warning_counts,
    collapsed_warnings,
    installed,
    set_bad_warning_counts,
    spring_user_bias,
)
from mj_bridge.stages import INV_GEAR, Stages
from mj_bridge.twin_model import TwinModel

_SAVE = mujoco.mjtState.mjSTATE_INTEGRATION
_PROBE_DT = 0.3183098861837907  # s; the verification stage's time is d.time + this (1/π: no
# special value, so a time read from the wrong place shows)


class Stepper:
    """Steps and forward evaluations of one twin with its callbacks installed.

    Args:
        tm: the compiled twin; d: its data; stages: its controller stages; acc: their accumulator.
        needs_control: whether a control callback is needed at all (control or a given torque).
        native_callback: use the native callback where the compiled stage applies.

    Attributes:
        context: the native callback's :class:`mj_bridge.native.Context`, or None (also after
            a failed verification).
        verified: whether the native callback was checked against the Python one (once).
        redos: batches rerun with the Python callback after a declined stage.
    """

    def __init__(
        self,
        tm: TwinModel,
        d: mujoco.MjData,
        stages: Stages,
        acc: Accumulator,
        needs_control: bool,
        native_callback: bool,
    ):
        self.tm, self.m, self.d = tm, tm.m, d
        self.stages = stages
        self.acc = acc
        self.needs_control = needs_control
        self.bound = False
        self.redos = 0
        self.verified = False
        self.context: native.Context | None = None
        if stages.compiled and native_callback and native.available():
            self.context = native.Context(
                tm.m,
                d,
                stages.native_arrays(),
                acc.weights,
                INV_GEAR,
                stages.has_torque,
                force_body=None if stages.gauss else tm.body_id,
            )

    @contextlib.contextmanager
    def callbacks(self) -> Iterator[None]:
        """Install the callbacks (control, user bias) as needed for a ``with`` block: the native
        controller when available, else the Python one. MuJoCo's warnings in the block are
        reported once each when it ends, with their count
        (:class:`mj_bridge.callbacks.collapsed_warnings`), not once per step."""
        act_bias = spring_user_bias if self.tm.needs_act_bias else None
        if self.context is not None and self.needs_control and not self.verified:
            differs = self._verify(act_bias)
            self.verified = True
            if differs:
                self.context = None
                warnings.warn(
                    "native controller callback disagrees with the Python one on this model "
                    f"({', '.join(differs)}); using the Python callback",
                    RuntimeWarning,
                    stacklevel=3,
                )
        if self.context is None or not self.needs_control:
            control = self.stages.callback if self.needs_control else None
            with collapsed_warnings(), installed(control=control, act_bias=act_bias):
                yield
            return
        with (
            collapsed_warnings(),
            self.context,
            installed(control=native.callback(), act_bias=act_bias),
        ):
            self.bound = True
            try:
                yield
            finally:
                self.bound = False

    def step(self, nstep: int) -> None:
        """``nstep`` MuJoCo steps, accumulating the controller's work and impulses (``acc``;
        ``acc.calls`` = controller stages run). Call inside :meth:`callbacks`."""
        self.acc.h = self.tm.dt
        if not self.bound:
            self._python_steps(nstep)
            return
        ctx = self.context
        saved = self._save()
        ctx.clear_failures()
        ctx.start(self.tm.dt)
        try:
            mujoco.mj_step(self.m, self.d, nstep=nstep)
        finally:
            self.acc.calls = ctx.stop()
        if ctx.failures:
            self._restore(saved)
            self.redos += 1
            with self._python_control():
                self._python_steps(nstep)

    def forward(self) -> None:
        """``mj_forward`` at the current state, keeping the controller's output in
        ``stages.last_control``. Call inside :meth:`callbacks`."""
        if not self.bound:
            self._python_forward()
            return
        self.context.clear_failures()
        warn = bad_warning_counts(self.d)
        mujoco.mj_forward(self.m, self.d)
        if self.context.failures:  # the kernel declined: undo any warnings, ask Python
            set_bad_warning_counts(self.d, warn)
            with self._python_control():
                self._python_forward()
            return
        self.stages.last_control = self.stages.stage_output()

    def _verify(self, act_bias) -> list[str]:
        """One stage through the native callback (inside ``mj_forward``) and the same stage through
        the Python one, with accumulation on; the names of what differs (empty: bit-identical).
        Leaves the integration state, the accumulator and the warning counts as they were."""
        ctx, d, acc, stages = self.context, self.d, self.acc, self.stages
        arrays = stages.native_arrays()
        saved = self._save()
        kept = acc.calls, acc.active, acc.h, stages.fast.fallbacks
        t = d.time + _PROBE_DT

        def outputs() -> dict[str, np.ndarray]:
            return {
                "ctrl": d.ctrl.copy(), "xfrc_applied": d.xfrc_applied.copy(),
                "stage output": arrays["out"].copy(), "given torque": arrays["tau_g"].copy(),
                "work and impulses": acc.v.copy(),
            }  # fmt: skip

        def at_probe_time() -> None:
            d.time = t
            d.ctrl[:] = 0.0
            d.xfrc_applied[:] = 0.0

        try:
            with (
                collapsed_warnings(),
                ctx,
                installed(control=native.callback(), act_bias=act_bias),
            ):
                at_probe_time()
                ctx.clear_failures()
                ctx.start(self.tm.dt)
                mujoco.mj_forward(self.m, d)
                got = outputs()
                got["stages"] = np.array([ctx.stop(), ctx.failures])
                got["time"] = np.array([ctx.time_seen])
                data_ptr = ctx.data_seen
            self._restore(saved)
            at_probe_time()
            acc.calls, acc.active, acc.h = 0, True, self.tm.dt
            stages.stage_callback(self.m, d)
            want = outputs()
            want["stages"] = np.array([acc.calls, 0])
            want["time"] = np.array([t])
        finally:
            acc.calls, acc.active, acc.h, stages.fast.fallbacks = kept
            self._restore(saved)
        differs = [
            k
            for k in want
            if got[k].dtype != want[k].dtype or got[k].tobytes() != want[k].tobytes()
        ]
        if not differs:
            ctx.data_ptr = data_ptr
        return differs

    def _python_steps(self, nstep: int) -> None:
        acc = self.acc
        acc.calls = 0
        acc.active = True
        try:
            mujoco.mj_step(self.m, self.d, nstep=nstep)
        finally:
            acc.active = False

    def _python_forward(self) -> None:
        self.stages.record = True
        try:
            mujoco.mj_forward(self.m, self.d)
        finally:
            self.stages.record = False

    @contextlib.contextmanager
    def _python_control(self) -> Iterator[None]:
        """Swap the native control callback for the Python one inside an active :meth:`callbacks`."""
        mujoco.set_mjcb_control(self.stages.callback)
        try:
            yield
        finally:
            mujoco.set_mjcb_control(native.callback())

    def _save(self) -> tuple[np.ndarray, np.ndarray, list[int]]:
        st = np.empty(mujoco.mj_stateSize(self.m, _SAVE))
        mujoco.mj_getState(self.m, self.d, st, _SAVE)
        return st, self.acc.v.copy(), bad_warning_counts(self.d)

    def _restore(self, saved: tuple[np.ndarray, np.ndarray, list[int]]) -> None:
        st, v, warn = saved
        mujoco.mj_setState(self.m, self.d, st, _SAVE)
        self.acc.v[:] = v
        set_bad_warning_counts(self.d, warn)


__all__ = ["Stepper"]
