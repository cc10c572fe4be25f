"""The controller inside MuJoCo's integrator: the ``mjcb_control`` functions of one twin.

MuJoCo calls ``mjcb_control`` at every integrator stage (four per RK4 step) with that stage's time
and state. The callback evaluates the control law there, writes the actuators' ``ctrl`` (physical
torque and rod forces divided by the gear, :data:`model_xml.builder.CONTROL_GEAR`) and a force at C
into ``xfrc_applied``, and, while a step is being taken, adds the stage's work and impulses to the
:class:`~mj_bridge.accumulator.Accumulator`. Which implementation of the (same) law runs is the
twin's :class:`ControllerSource`:

* the compiled stage (:mod:`mj_bridge.fast_stage`: map, analytic kernel, ctrl and accumulation in
  one numba call) for the compiled controller with BR's body frame at C; the numpy model answers a
  stage the kernel declines;
* otherwise Python: the state mapped to the paper's (:mod:`model_xml.coordinates`), the analytic
  controller (numpy or compiled) or the law from MuJoCo's matrices (:mod:`mj_bridge.mujoco_law`).

:mod:`mj_bridge.native` runs the compiled stage as a native callback, with the arrays of
:meth:`Stages.native_arrays`.
"""

from __future__ import annotations

import mujoco
import numpy as np

from analytic.effects import Effect, Weighting
from analytic.model import ControlOutput, TumblingModel
from analytic.scene import Scene
from mj_bridge import fast_stage
from mj_bridge.accumulator import Accumulator
from mj_bridge.mujoco_law import check_weighting, mujoco_law
from mj_bridge.mujoco_settings import ControllerSource
from mj_bridge.twin_model import TwinModel
from model_xml.builder import CONTROL_GEAR
from model_xml.rotations import cross3, quat_to_mat

INV_GEAR = 1.0 / CONTROL_GEAR  # exact: a power of two


class Stages:
    """The control at every integrator stage of one twin.

    Args:
        scene: the scene; model: its analytic model; tm: the compiled twin.
        controller: which implementation of the law runs.
        acc: the accumulator the stages add their work and impulses to.

    Attributes:
        controller_fn: ``(t, q, q̇) -> (q̈, ControlOutput)`` of the Python path: the numpy model or
            the compiled kernel's wrapper (``analytic.fast.FastModel.acceleration``).
        fast: the ``FastModel`` (None for the numpy controller).
        compiled: whether the compiled stage is the callback.
        last_control: the control at the last stage recorded (:attr:`record`), or None.
        record: keep the compiled stage's output as :attr:`last_control` (set while sampling).
    """

    def __init__(
        self,
        scene: Scene,
        model: TumblingModel,
        tm: TwinModel,
        controller: ControllerSource,
        acc: Accumulator,
    ):
        self.model = model
        self.tm = tm
        self.controller = controller
        self.acc = acc
        self.n = scene.n
        self.controlled = scene.controlled
        self.has_torque = scene.has(Effect.EXTERNAL_TORQUE)
        self.body_id = tm.body_id
        self.controller_fn = model.acceleration
        self.fast = None
        if controller is ControllerSource.ANALYTIC_FAST:
            from analytic.fast import FastModel

            self.fast = FastModel(scene, model)
            self.controller_fn = self.fast.acceleration
        if controller is ControllerSource.MUJOCO and self.controlled:
            check_weighting(model)
        self.last_control: ControlOutput | None = None
        self.record = False
        self._M = np.zeros((tm.m.nv, tm.m.nv))
        self.compiled = bool(
            self.fast is not None
            and self.fast.compiled
            and tm.frame_at_C
            and self.controlled
            and fast_stage.HAVE_NUMBA
        )
        if self.compiled:
            nq = self.n + 7
            self._out = np.empty(2 * nq + 3 + model.k)
            self._q = np.empty(nq)
            self._qd = np.empty(nq)
            self._tau_g = np.zeros(3)
            self._geo = fast_stage.geometry(model)
            self._tq = np.asarray(tm.torque_ids, dtype=np.int64)
            self._f = np.asarray(tm.force_ids, dtype=np.int64)
            self.gauss = scene.control.weighting is Weighting.M_INV
            self._stage = fast_stage.stage_for(self.fast.ip)  # embeds only this scene's solve
            self._args = (
                self._tq, self._f, self.fast.fp, self.fast.ip, self._out,
                self._q, self._qd, self._tau_g, self._geo,
            )  # fmt: skip

    def native_arrays(self) -> dict[str, np.ndarray]:
        """The compiled stage's arrays, by the names :class:`mj_bridge.native.Context` binds."""
        return dict(
            fp=self.fast.fp, ip=self.fast.ip, out=self._out, q=self._q, qd=self._qd,
            tq_ids=self._tq, f_ids=self._f, tau_g=self._tau_g, geo=self._geo, acc=self.acc.v,
        )  # fmt: skip

    @property
    def callback(self):
        """The Python ``mjcb_control`` (compiled stage or Python law)."""
        return self.stage_callback if self.compiled else self.control_callback

    def paper_state(self, d: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """The paper's ``(q, q̇)`` of the state in ``d``."""
        return self.tm.to_paper(d.qpos, d.qvel)

    def write_controls(
        self, d: mujoco.MjData, torque: np.ndarray, rod: np.ndarray, force_C: np.ndarray
    ) -> None:
        """Physical torque (body axes, N·m), rod forces (N) and force at C (inertial, N) -> ctrl
        (divided by the actuators' gear) and ``xfrc_applied`` of BR."""
        tm = self.tm
        if tm.torque_ids is not None:
            d.ctrl[tm.torque_ids] = torque * INV_GEAR
        if tm.force_ids is not None:
            d.ctrl[tm.force_ids] = rod * INV_GEAR
            d.xfrc_applied[self.body_id, :3] = force_C  # world force at C (zero for Gauss)

    def stage_output(self) -> ControlOutput:
        """The compiled stage's last result as a :class:`ControlOutput` (copies)."""
        nq = self.n + 7
        out = self._out
        QC = out[nq : 2 * nq].copy()
        return ControlOutput(
            QC=QC, torque=out[2 * nq : 2 * nq + 3].copy(), rod_forces=QC[7:],
            force_at_C=QC[:3], residual=out[2 * nq + 3 :].copy(), rank=self.model.k,
        )  # fmt: skip

    def stage_callback(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """``mjcb_control`` through the compiled stage (:mod:`mj_bridge.fast_stage`)."""
        t = d.time
        acc = self.acc
        if self.has_torque:
            self._tau_g[:] = self.model.given_torque(t)
        w = acc.h * acc.weights[acc.calls % len(acc.weights)] if acc.active else 0.0
        status = self._stage(t, d.qpos, d.qvel, d.ctrl, *self._args, INV_GEAR, w, acc.v)
        if status != 0:  # the kernel declined: the numpy model answers this stage
            self.fast.fallbacks += 1
            q, qd = self.paper_state(d)
            _, c = self.model.acceleration(t, q, qd)
            self.finish(d, q, qd, c.torque, c.rod_forces, c.force_at_C, c)
            return
        if acc.active:
            acc.calls += 1
        nq = self.n + 7
        out = self._out
        if not self.gauss:
            d.xfrc_applied[self.body_id, :3] = out[nq : nq + 3]
        if self.record:
            self.last_control = self.stage_output()

    def control_callback(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """``mjcb_control`` in Python: the controller at this stage's time and state."""
        t = d.time
        q, qd = self.paper_state(d)
        c = None
        if not self.controlled:
            tau, rod, fC = np.zeros(3), np.zeros(self.n), np.zeros(3)
        elif self.controller is not ControllerSource.MUJOCO:
            _, c = self.controller_fn(t, q, qd)
            tau, rod, fC = c.torque, c.rod_forces, c.force_at_C
        else:
            mc = mujoco_law(self.tm, self.model, d, t, in_callback=True, M=self._M)
            tau, rod, fC = mc.torque, mc.rod_forces, np.zeros(3)
            c = ControlOutput(
                QC=np.full(self.n + 7, np.nan), torque=tau, rod_forces=rod, force_at_C=fC,
                residual=mc.residual, rank=len(mc.residual),
            )  # fmt: skip
        self.finish(d, q, qd, tau, rod, fC, c)

    def finish(self, d: mujoco.MjData, q, qd, tau, rod, fC, c: ControlOutput | None) -> None:
        """Apply a stage's control (plus the given torque) at the state in ``d`` (paper ``q, q̇``)
        and accumulate its work and impulses: power ``(τ + τ_g)·ω + F·ṗ + F_C·Ṙ`` and moment
        ``S(u)(τ + τ_g) + (R - c)×F_C``."""
        self.last_control = c
        t = d.time
        tau_tot = tau + self.model.given_torque(t)
        self.write_controls(d, tau_tot, rod, fC)
        if self.acc.active:
            omega = self.tm.R_I.T @ d.qvel[3:6]
            power = float(tau_tot @ omega) + float(rod @ qd[7:]) + float(fC @ qd[:3])
            Sm = quat_to_mat(q[3:7])
            moment = Sm @ tau_tot
            if np.any(fC):
                # a force at C has a moment about the system CoM c: R - c = -(μ1 Sa + μ0 Sd)/m_T
                mdl = self.model
                R_minus_c = (
                    -(float(mdl.m @ q[7:]) * (Sm @ mdl.a) + mdl.mu0 * (Sm @ mdl.d)) / mdl.m_T
                )
                moment = moment + cross3(R_minus_c, fC)
            self.acc.add(power, moment, fC)


__all__ = ["INV_GEAR", "ControllerSource", "Stages"]
