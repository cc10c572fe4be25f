"""A compiled MuJoCo twin of one scene: state maps, forward dynamics in paper coordinates, the
analytic controller inside MuJoCo's integrator, and the same law computed from MuJoCo's matrices.

Notation as in the paper (Koganti & Udwadia 2017) for paper quantities; MuJoCo names for MuJoCo's.
Frames: ``τ`` (torque) and ``ω`` in the paper's body axes (BR's principal axes at C); MuJoCo's
``qvel[3:6]`` is in BR's *MuJoCo body frame*, rotated from those by ``iquat`` (identity unless a
:class:`model_xml.BodyFrame` was given).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from enum import StrEnum

import mujoco
import numpy as np
from scipy.linalg import cho_factor, cho_solve

from analytic.effects import Effect, MjIntegrator, SpringModel, Weighting
from analytic.model import ControlOutput, TumblingModel
from analytic.scene import Scene
from mj_bridge import fast_stage, native
from mj_bridge.callbacks import collapsed_warnings, installed, spring_user_bias
from model_xml import (
    BODY,
    TORQUE_ACTUATORS,
    BodyFrame,
    build_spec,
    force_actuator_name,
    spring_actuator_name,
    spring_tendons,
)
from model_xml.builder import _INTEGRATORS, CONTROL_GEAR
from model_xml.rotations import cross3, quat_to_mat
from model_xml.state import mujoco_to_paper_acc, mujoco_to_paper_state, paper_to_mujoco_state

INV_GEAR = 1.0 / CONTROL_GEAR  # exact: a power of two

# MuJoCo warnings after which the step is not the model's dynamics (MuJoCo resets or zeroes silently).
BAD_WARNINGS = {
    mujoco.mjtWarning.mjWARN_BADQPOS: "bad qpos (MuJoCo reset the state)",
    mujoco.mjtWarning.mjWARN_BADQVEL: "bad qvel (MuJoCo reset the state)",
    mujoco.mjtWarning.mjWARN_BADQACC: "bad qacc (MuJoCo reset the state)",
    mujoco.mjtWarning.mjWARN_BADCTRL: "bad ctrl (MuJoCo zeroed every control)",
}


def bad_warnings(d: mujoco.MjData) -> list[str]:
    """Descriptions of the MuJoCo warnings raised so far that invalidate the dynamics."""
    return [
        f"{w.name} x{d.warning[int(w)].number}: {text}"
        for w, text in BAD_WARNINGS.items()
        if d.warning[int(w)].number > 0
    ]


class ControllerSource(StrEnum):
    """Which implementation of the (same) control law drives the MuJoCo plant."""

    ANALYTIC = "analytic"
    """``analytic.TumblingModel.acceleration`` at MuJoCo's state (the paper's Eq. 89)."""
    ANALYTIC_FAST = "analytic_fast"
    """The same controller from the analytic side's compiled kernel (``analytic.fast.FastModel``,
    tested against the numpy model to 1e-12 there); the numpy model answers when numba is absent."""
    MUJOCO = "mujoco"
    """Udwadia–Kalaba from MuJoCo's own ``M`` and forces (Gauss weighting only)."""


@dataclass(frozen=True)
class MjControl:
    """The control law evaluated from MuJoCo's matrices at one state.

    Attributes:
        torque: body-axis control torque, N·m, shape (3,).
        rod_forces: force along the rod on each mass, N, shape (n,).
        qacc: MuJoCo's controlled acceleration (MuJoCo coordinates), shape (n+6,).
        residual: ``A qacc - b``, the unattainable part of the requirements, shape (k,).
    """

    torque: np.ndarray
    rod_forces: np.ndarray
    qacc: np.ndarray
    residual: np.ndarray


class _Accumulator:
    """Work and impulse integrals accumulated per integrator stage with the scheme's weights.

    ``v = [W (J), angular impulse about the system CoM (3, N·m·s), linear impulse (3, N·s)]``.
    """

    def __init__(self, weights: tuple[float, ...]):
        self.weights = weights
        self.h = 0.0
        self.active = False
        self.calls = 0
        self.v = np.zeros(7)

    def weight(self) -> float:
        """``h`` times the weight of the next stage (0 when not accumulating)."""
        if not self.active:
            return 0.0
        return self.h * self.weights[self.calls % len(self.weights)]

    def add(self, power: float, torque_world: np.ndarray, force: np.ndarray) -> None:
        w = self.h * self.weights[self.calls % len(self.weights)]
        self.calls += 1
        self.v[0] += w * power
        self.v[1:4] += w * torque_world
        self.v[4:7] += w * force

    @property
    def work(self) -> float:
        return float(self.v[0])

    @property
    def angular_impulse(self) -> np.ndarray:
        return self.v[1:4].copy()

    @property
    def linear_impulse(self) -> np.ndarray:
        return self.v[4:7].copy()


_STAGE_WEIGHTS = {
    MjIntegrator.RK4: (1 / 6, 1 / 3, 1 / 3, 1 / 6),
    MjIntegrator.EULER: (1.0,),
    MjIntegrator.IMPLICIT: (1.0,),
    MjIntegrator.IMPLICITFAST: (1.0,),
}


class Twin:
    """The scene's MuJoCo model and data, plus the analytic model of the same scene.

    Args:
        scene: a validated scene.
        integrator: overrides ``scene.mujoco.integrator``.
        dt: overrides ``scene.mujoco.timestep``, s.
        body_frame: BR's MuJoCo body frame relative to C (default: at C).
        controller: which implementation of the control law runs in the callback.
    """

    def __init__(
        self,
        scene: Scene,
        integrator: MjIntegrator | str | None = None,
        dt: float | None = None,
        body_frame: BodyFrame | None = None,
        controller: ControllerSource | str = ControllerSource.ANALYTIC_FAST,
        native_callback: bool = True,
    ):
        self.scene = scene
        self.integrator = _as_enum(
            MjIntegrator,
            scene.mujoco.integrator if integrator is None else integrator,
            "integrator",
        )
        self.controller = _as_enum(ControllerSource, controller, "controller")
        self.dt = float(scene.mujoco.timestep if dt is None else dt)
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"dt: must be a positive finite time step in s (got {dt!r})")
        self.model = TumblingModel(scene)
        self._controller_fn = self.model.acceleration
        self._fast = None
        if self.controller is ControllerSource.ANALYTIC_FAST:
            from analytic.fast import FastModel

            self._fast = FastModel(scene, self.model)
            self._controller_fn = self._fast.acceleration_output
        self.n = scene.n
        self.m = build_spec(scene, body_frame).compile()
        self.m.opt.integrator = int(_INTEGRATORS[self.integrator])
        self.m.opt.timestep = self.dt
        self.d = mujoco.MjData(self.m)
        self.body_id = self.m.body(BODY).id
        self.ipos = self.m.body_ipos[self.body_id].copy()
        self.iquat = self.m.body_iquat[self.body_id].copy()
        self.R_I = quat_to_mat(self.iquat)  # paper body axes -> MuJoCo body frame
        self._frame_at_C = bool(np.all(self.ipos == 0) and np.all(self.iquat == [1, 0, 0, 0]))
        self.controlled = scene.controlled
        self.has_torque = scene.has(Effect.EXTERNAL_TORQUE)
        if self.controller is ControllerSource.MUJOCO and self.controlled:
            if scene.control.weighting is not Weighting.M_INV:
                raise ValueError(
                    "control.weighting: the MuJoCo-coordinate Udwadia–Kalaba law is implemented for "
                    f"Gauss's weighting M^-1 only (coordinate-invariant); got {scene.control.weighting.value!r}"
                )
        self.torque_ids = (
            np.array([self.m.actuator(nm).id for nm in TORQUE_ACTUATORS])
            if (self.controlled or self.has_torque)
            else None
        )
        self.force_ids = (
            np.array([self.m.actuator(force_actuator_name(i)).id for i in range(self.n)], dtype=int)
            if self.controlled
            else None
        )
        tendons = spring_tendons(scene)
        self.spring_act_ids = (
            np.array(
                [self.m.actuator(spring_actuator_name(j)).id for j in range(len(tendons))],
                dtype=int,
            )
            if SpringModel(scene.mujoco.spring_model) is SpringModel.ACTUATOR
            else np.zeros(0, dtype=int)
        )
        self.needs_act_bias = any(sp.k_cubic != 0.0 for sp in tendons) and len(self.spring_act_ids)
        self.needs_control_cb = self.controlled or self.has_torque
        self.acc = _Accumulator(_STAGE_WEIGHTS[self.integrator])
        self.last_control: ControlOutput | None = None
        self._record = False  # the compiled stage keeps a ControlOutput only when asked (samples)
        self._M = np.zeros((self.m.nv, self.m.nv))
        self._use_stage = bool(
            self._fast is not None
            and self._fast.compiled
            and self._frame_at_C
            and self.controlled
            and fast_stage.HAVE_NUMBA
        )
        if self._use_stage:
            nq = self.n + 7
            self._st_out = np.empty(2 * nq + 3 + self.model.k)
            self._st_q = np.empty(nq)
            self._st_qd = np.empty(nq)
            self._st_tau_g = np.zeros(3)
            self._st_geo = fast_stage.geometry(self.model)
            self._st_tq = np.asarray(self.torque_ids, dtype=np.int64)
            self._st_f = np.asarray(self.force_ids, dtype=np.int64)
            self._st_gauss = scene.control.weighting is Weighting.M_INV
            self._st_args = (
                self._st_tq, self._st_f, self._fast.fp, self._fast.ip, self._st_out,
                self._st_q, self._st_qd, self._st_tau_g, self._st_geo,
            )  # fmt: skip
        # The compiled stage as a native mjcb_control (mj_bridge.native): no Python per stage.
        self._ctx: native.Context | None = None
        self._native_bound = False
        self.native_redos = 0  # batches rerun with the Python callback after a declined stage
        if self._use_stage and native_callback and native.available():
            arrays = dict(
                fp=self._fast.fp, ip=self._fast.ip, out=self._st_out, q=self._st_q,
                qd=self._st_qd, tq_ids=self._st_tq, f_ids=self._st_f, tau_g=self._st_tau_g,
                geo=self._st_geo, acc=self.acc.v,
            )  # fmt: skip
            self._ctx = native.Context(
                self.m,
                arrays,
                self.acc.weights,
                INV_GEAR,
                self.has_torque,
                force_body=None if self._st_gauss else self.body_id,
            )

    # ------------------------------------------------------------------------------------------
    # State
    # ------------------------------------------------------------------------------------------

    def to_mujoco(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Paper ``(q, q̇)`` -> ``(qpos, qvel)`` of this model."""
        return paper_to_mujoco_state(q, qdot, self.ipos, self.iquat)

    def to_paper(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(qpos, qvel)`` -> paper ``(q, q̇)``."""
        return mujoco_to_paper_state(qpos, qvel, self.ipos, self.iquat)

    def set_state(self, t: float, q: np.ndarray, qdot: np.ndarray) -> None:
        qpos, qvel = self.to_mujoco(q, qdot)
        self.d.qpos[:] = qpos
        self.d.qvel[:] = qvel
        self.d.time = float(t)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        return self.to_paper(self.d.qpos, self.d.qvel)

    @property
    def native(self) -> bool:
        """Whether :meth:`callbacks` installs the native (machine-code) controller callback."""
        return self._ctx is not None

    @contextlib.contextmanager
    def callbacks(self) -> Iterator[None]:
        """Install this twin's callbacks (control, user bias) as needed for a ``with`` block: the
        native controller when available (:mod:`mj_bridge.native`), else :attr:`control_callback`.
        MuJoCo's warnings in the block are reported once each when it ends, with their count
        (:class:`mj_bridge.callbacks.collapsed_warnings`), not once per step."""
        act_bias = spring_user_bias if self.needs_act_bias else None
        if self._ctx is None or not self.needs_control_cb:
            control = self.control_callback if self.needs_control_cb else None
            with collapsed_warnings(), installed(control=control, act_bias=act_bias):
                yield
            return
        with (
            collapsed_warnings(),
            self._ctx,
            installed(control=native.callback(), act_bias=act_bias),
        ):
            self._native_bound = True
            try:
                yield
            finally:
                self._native_bound = False

    def step(self, nstep: int) -> None:
        """``nstep`` MuJoCo steps with the installed callbacks, accumulating the controller's work
        and impulses (``acc``; ``acc.calls`` = controller stages run). Call inside :meth:`callbacks`.

        With the native callback, a batch in which the kernel declined a stage is rerun from its
        saved start with the Python callback (which answers that stage with the numpy model).
        """
        self.acc.h = self.dt
        if not self._native_bound:
            self._python_steps(nstep)
            return
        ctx = self._ctx
        saved = self._save()
        ctx.clear_failures()
        ctx.start(self.dt)
        try:
            mujoco.mj_step(self.m, self.d, nstep=nstep)
        finally:
            self.acc.calls = ctx.stop()
        if ctx.failures:
            self._restore(saved)
            self.native_redos += 1
            with self._python_control():
                self._python_steps(nstep)

    def forward_here(self) -> None:
        """``mj_forward`` at the current state with the installed callbacks, keeping the
        controller's output in :attr:`last_control`. Call inside :meth:`callbacks`."""
        if not self._native_bound:
            self._python_forward()
            return
        self._ctx.clear_failures()
        warn = [self.d.warning[int(w)].number for w in BAD_WARNINGS]
        mujoco.mj_forward(self.m, self.d)
        if self._ctx.failures:  # the kernel declined: undo any warnings, ask Python
            for w, k in zip(BAD_WARNINGS, warn, strict=True):
                self.d.warning[int(w)].number = k
            with self._python_control():
                self._python_forward()
            return
        self.last_control = self._stage_output()

    def _python_steps(self, nstep: int) -> None:
        acc = self.acc
        acc.calls = 0
        acc.active = True
        try:
            mujoco.mj_step(self.m, self.d, nstep=nstep)
        finally:
            acc.active = False

    def _python_forward(self) -> None:
        self._record = True
        try:
            mujoco.mj_forward(self.m, self.d)
        finally:
            self._record = False

    def _stage_output(self) -> ControlOutput:
        """The compiled stage's last result as a :class:`ControlOutput` (copies)."""
        nq = self.n + 7
        out = self._st_out
        QC = out[nq : 2 * nq].copy()
        return ControlOutput(
            QC=QC, torque=out[2 * nq : 2 * nq + 3].copy(), rod_forces=QC[7:],
            force_at_C=QC[:3], residual=out[2 * nq + 3 :].copy(), rank=self.model.k,
        )  # fmt: skip

    @contextlib.contextmanager
    def _python_control(self) -> Iterator[None]:
        """Swap the native control callback for the Python one inside an active :meth:`callbacks`."""
        mujoco.set_mjcb_control(self.control_callback)
        try:
            yield
        finally:
            mujoco.set_mjcb_control(native.callback())

    _SAVE = mujoco.mjtState.mjSTATE_INTEGRATION

    def _save(self) -> tuple[np.ndarray, np.ndarray, list[int]]:
        st = np.empty(mujoco.mj_stateSize(self.m, self._SAVE))
        mujoco.mj_getState(self.m, self.d, st, self._SAVE)
        return st, self.acc.v.copy(), [self.d.warning[int(w)].number for w in BAD_WARNINGS]

    def _restore(self, saved: tuple[np.ndarray, np.ndarray, list[int]]) -> None:
        st, v, warn = saved
        mujoco.mj_setState(self.m, self.d, st, self._SAVE)
        self.acc.v[:] = v
        for w, k in zip(BAD_WARNINGS, warn, strict=True):
            self.d.warning[int(w)].number = k

    # ------------------------------------------------------------------------------------------
    # The controller inside MuJoCo's integrator
    # ------------------------------------------------------------------------------------------

    def _write_controls(self, torque: np.ndarray, rod: np.ndarray, force_C: np.ndarray) -> None:
        """Physical torque (body axes, N·m), rod forces (N) and force at C (inertial, N) -> ctrl
        (divided by the actuators' gear, :data:`model_xml.builder.CONTROL_GEAR`) and xfrc_applied."""
        d = self.d
        if self.torque_ids is not None:
            d.ctrl[self.torque_ids] = torque * INV_GEAR
        if self.force_ids is not None:
            d.ctrl[self.force_ids] = rod * INV_GEAR
            d.xfrc_applied[self.body_id, :3] = force_C  # world force at C (zero for Gauss)

    def _paper_state(self, d: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Paper state of ``d``; a short path when BR's body frame is at C (the default)."""
        if not self._frame_at_C:
            return mujoco_to_paper_state(d.qpos, d.qvel, self.ipos, self.iquat)
        q = d.qpos.copy()
        v = d.qvel
        u = q[3:7]
        w0, w1, w2 = v[3], v[4], v[5]
        u0, u1, u2, u3 = u
        s = 0.5 / float(u @ u)  # u̇ = ¼ Hᵀ ω / |u|², H of Eq. (13) carries the factor 2
        qd = np.empty(self.n + 7)
        qd[:3] = v[:3]
        qd[3] = s * (-u1 * w0 - u2 * w1 - u3 * w2)
        qd[4] = s * (u0 * w0 - u3 * w1 + u2 * w2)
        qd[5] = s * (u3 * w0 + u0 * w1 - u1 * w2)
        qd[6] = s * (-u2 * w0 + u1 * w1 + u0 * w2)
        qd[7:] = v[6:]
        return q, qd

    @property
    def control_callback(self):
        """The ``mjcb_control`` function this twin installs (compiled stage or Python)."""
        return self._stage_callback if self._use_stage else self._control_callback

    def _stage_callback(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """``mjcb_control`` through the compiled stage (:mod:`mj_bridge.fast_stage`)."""
        t = d.time
        acc = self.acc
        if self.has_torque:
            self._st_tau_g[:] = self.model.given_torque(t)
        w = acc.h * acc.weights[acc.calls % len(acc.weights)] if acc.active else 0.0
        status = fast_stage.stage(t, d.qpos, d.qvel, d.ctrl, *self._st_args, INV_GEAR, w, acc.v)
        if status != 0:  # the kernel declined: the numpy model answers this stage
            self._fast.fallbacks += 1
            _, c = self.model.acceleration(t, *self._paper_state(d))
            self._finish_stage(d, c.torque, c.rod_forces, c.force_at_C, c)
            return
        if acc.active:
            acc.calls += 1
        nq = self.n + 7
        out = self._st_out
        if not self._st_gauss:
            d.xfrc_applied[self.body_id, :3] = out[nq : nq + 3]
        if self._record:
            self.last_control = self._stage_output()

    def _finish_stage(self, d, tau, rod, fC, c) -> None:
        self.last_control = c
        t = d.time
        q, qd = self._paper_state(d)
        tau_tot = tau + self.model.given_torque(t)
        self._write_controls(tau_tot, rod, fC)
        if self.acc.active:
            omega = self.R_I.T @ d.qvel[3:6]
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

    def _control_callback(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """``mjcb_control`` in Python: the controller at this stage's time and state."""
        t = d.time
        c = None
        if not self.controlled:
            tau, rod, fC = np.zeros(3), np.zeros(self.n), np.zeros(3)
        elif self.controller is not ControllerSource.MUJOCO:
            _, c = self._controller_fn(t, *self._paper_state(d))
            tau, rod, fC = c.torque, c.rod_forces, c.force_at_C
        else:
            mc = self._uk_from_data(t, in_callback=True)
            tau, rod, fC = mc.torque, mc.rod_forces, np.zeros(3)
            c = ControlOutput(
                QC=np.full(self.n + 7, np.nan), torque=tau, rod_forces=rod, force_at_C=fC,
                residual=mc.residual, rank=len(mc.residual),
            )  # fmt: skip
        self._finish_stage(d, tau, rod, fC, c)

    # ------------------------------------------------------------------------------------------
    # Pointwise evaluations
    # ------------------------------------------------------------------------------------------

    def forward(self, t: float, q: np.ndarray, qdot: np.ndarray) -> None:
        """``mj_forward`` at a paper-coordinates state with the controller applied."""
        self.set_state(t, q, qdot)
        self.d.ctrl[:] = 0.0
        self.d.xfrc_applied[:] = 0.0
        for w in BAD_WARNINGS:
            self.d.warning[int(w)].number = 0
        with self.callbacks():
            self.forward_here()
        bad = bad_warnings(self.d)
        if bad:
            raise RuntimeError(f"MuJoCo warning at t = {t!r} s: {'; '.join(bad)}")

    def acceleration(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """MuJoCo's forward dynamics at a paper-coordinates state, as ``q̈`` (n+7) in paper
        coordinates (controlled scenes: the analytic controller evaluated at that state)."""
        self.forward(t, q, qdot)
        return mujoco_to_paper_acc(self.d.qpos, self.d.qvel, self.d.qacc, self.ipos, self.iquat)

    def mujoco_control(self, t: float, q: np.ndarray, qdot: np.ndarray) -> MjControl:
        """Udwadia–Kalaba control from MuJoCo's ``mj_fullM`` and ``qfrc_passive − qfrc_bias`` in
        MuJoCo's coordinates (no quaternion constraint there), at a paper-coordinates state."""
        if not self.controlled:
            raise ValueError(f"scene.effects: {self.scene.name!r} has no control effect")
        if self.scene.control.weighting is not Weighting.M_INV:
            raise ValueError(
                "control.weighting: the MuJoCo-coordinate law is implemented for M^-1 only "
                f"(got {self.scene.control.weighting.value!r})"
            )
        self.set_state(t, q, qdot)
        d = self.d
        d.ctrl[:] = 0.0
        d.xfrc_applied[:] = 0.0
        with installed(act_bias=spring_user_bias if self.needs_act_bias else None):
            mujoco.mj_forward(self.m, d)
            return self._uk_from_data(t, in_callback=False)

    def _uk_from_data(self, t: float, in_callback: bool) -> MjControl:
        """Gauss's principle in MuJoCo's coordinates: ``M qacc = F + Aᵀμ`` with ``A qacc = b``,
        ``F = qfrc_passive − qfrc_bias`` (+ spring actuators, + the given torque), A the tracked
        rows (ω̇ components on the free joint's rotational dofs, q̈ of tracked slide joints) and b
        the paper's stabilised requirements (Eqs. 81, 84) at MuJoCo's state."""
        m, d = self.m, self.d
        nv = m.nv
        mujoco.mj_fullM(m, d, self._M)
        F = d.qfrc_passive - d.qfrc_bias
        if len(self.spring_act_ids):
            if in_callback:  # qfrc_actuator is computed after mjcb_control: springs only here
                d.ctrl[:] = 0.0
                mujoco.mj_fwdActuation(m, d)
            F = F + d.qfrc_actuator
        tau_g = self.model.given_torque(t)
        F = F.copy()
        F[3:6] += self.R_I @ tau_g
        model = self.model
        req = model.requirements(t)
        rows, rhs = [], []
        omega = self.R_I.T @ d.qvel[3:6]
        if model.omega_track:
            c = model._w_comps
            gain = model.omega_track.gain
            e = omega[c] - req["omega_bar"]
            b_w = req["omega_bar_dot"] - gain @ e  # Eq. (84) / (B8)
            for j, comp in enumerate(c):
                row = np.zeros(nv)
                row[3:6] = self.R_I.T[comp]  # ω̇_comp = (R_Iᵀ qacc[3:6])_comp
                rows.append(row)
                rhs.append(b_w[j])
        if model.mass_track:
            mt = model.mass_track
            idx = model._p_idx
            p, pd = d.qpos[7 + idx], d.qvel[6 + idx]
            b_p = (
                req["p_bar_ddot"]
                - mt.alpha * (pd - req["p_bar_dot"])
                - mt.beta * (p - req["p_bar"])
            )  # Eq. (81)
            for j, i in enumerate(idx):
                row = np.zeros(nv)
                row[6 + i] = 1.0
                rows.append(row)
                rhs.append(b_p[j])
        A = np.array(rows).reshape(len(rows), nv)
        b = np.array(rhs)
        # M⁻¹ [F, Aᵀ] from MuJoCo's dense mass matrix (mj_fullM), symmetric positive definite
        Y = cho_solve(cho_factor(self._M), np.column_stack([F, A.T]))
        a0, MinvAt = Y[:, 0], Y[:, 1:]
        G = A @ MinvAt
        mu = np.linalg.lstsq(0.5 * (G + G.T), b - A @ a0, rcond=None)[0]
        Qc = A.T @ mu
        qacc = a0 + MinvAt @ mu
        return MjControl(
            torque=self.R_I.T @ Qc[3:6],
            rod_forces=Qc[6:].copy(),
            qacc=qacc,
            residual=A @ qacc - b,
        )


def _as_enum(kind, value, name: str):
    if isinstance(value, kind):
        return value
    try:
        return kind(value)
    except ValueError:
        allowed = ", ".join(repr(e.value) for e in kind)
        raise ValueError(f"{name}: unknown value {value!r} (allowed: {allowed})") from None


def acceleration(scene: Scene, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """MuJoCo's forward dynamics of ``scene`` at a paper-coordinates state, as paper ``q̈``."""
    return Twin(scene).acceleration(t, q, qdot)


def mujoco_control(scene: Scene, t: float, q: np.ndarray, qdot: np.ndarray) -> MjControl:
    """The Udwadia–Kalaba control of ``scene`` from MuJoCo's own matrices (see
    :meth:`Twin.mujoco_control`)."""
    return Twin(scene).mujoco_control(t, q, qdot)
