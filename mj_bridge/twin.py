"""A compiled MuJoCo twin of one scene: the state in the paper's coordinates, forward dynamics there,
the analytic controller inside MuJoCo's integrator, and the same law computed from MuJoCo's matrices.

:class:`Twin` puts together parts with one job each:

* :class:`~mj_bridge.twin_model.TwinModel`: the compiled model, BR's inertial frame, the actuator
  ids and the paper <-> MuJoCo maps for them;
* :class:`~mj_bridge.stages.Stages`: the ``mjcb_control`` functions (the controller at every
  integrator stage) and :class:`~mj_bridge.accumulator.Accumulator` (the work and impulses there);
* :class:`~mj_bridge.stepper.Stepper`: the callbacks installed for a block, steps in batches, the
  native callback's declined batches redone in Python;
* :func:`~mj_bridge.mujoco_law.mujoco_law`: Udwadia–Kalaba from MuJoCo's own ``M`` and forces.

Notation as in the paper (Koganti & Udwadia 2017) for paper quantities; MuJoCo names for MuJoCo's.
Frames: ``τ`` (torque) and ``ω`` in the paper's body axes (BR's principal axes at C); MuJoCo's
``qvel[3:6]`` is in BR's *MuJoCo body frame*, rotated from those by ``iquat`` (identity unless a
:class:`model_xml.BodyFrame` was given).
"""

from __future__ import annotations

import contextlib

import mujoco
import numpy as np

from analytic.effects import Effect, MjIntegrator
from analytic.model import ControlOutput, TumblingModel
from analytic.scene import Scene
from mj_bridge.accumulator import STAGE_WEIGHTS, Accumulator
from mj_bridge.callbacks import BAD_WARNINGS, bad_warnings, installed, spring_user_bias
from mj_bridge.mujoco_law import MjControl, check_weighting, mujoco_law
from mj_bridge.stages import ControllerSource, Stages
from mj_bridge.stepper import Stepper
from mj_bridge.twin_model import TwinModel, as_enum
from model_xml import BodyFrame


class Twin:
    """The scene's MuJoCo model and data, plus the analytic model of the same scene.

    Args:
        scene: a validated scene.
        integrator: overrides ``scene.mujoco.integrator``.
        dt: overrides ``scene.mujoco.timestep``, s.
        body_frame: BR's MuJoCo body frame relative to C (default: at C).
        controller: which implementation of the control law runs in the callback.
        native_callback: run the compiled stage as a native ``mjcb_control`` where it applies.

    Attributes:
        scene, model (its :class:`TumblingModel`), n; tm (:class:`TwinModel`) and its ``m``,
        ``body_id``, ``ipos``, ``iquat``, ``R_I``; d: the ``MjData``; integrator, dt, controller;
        stages (:class:`Stages`), acc (:class:`Accumulator`), stepper (:class:`Stepper`).
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
        integ = scene.mujoco.integrator if integrator is None else integrator
        as_enum(MjIntegrator, integ, "integrator")  # the integrator is checked first
        self.controller = as_enum(ControllerSource, controller, "controller")
        self.tm = tm = TwinModel.build(scene, integrator, dt, body_frame)
        self.integrator, self.dt = tm.integrator, tm.dt
        self.m, self.body_id = tm.m, tm.body_id
        self.ipos, self.iquat, self.R_I = tm.ipos, tm.iquat, tm.R_I
        self.d = mujoco.MjData(self.m)
        self.model = TumblingModel(scene)
        self.n = scene.n
        self.controlled = scene.controlled
        self.needs_control_cb = self.controlled or scene.has(Effect.EXTERNAL_TORQUE)
        self.acc = Accumulator(STAGE_WEIGHTS[self.integrator])
        self.stages = Stages(scene, self.model, tm, self.controller, self.acc)
        self.stepper = Stepper(
            tm, self.d, self.stages, self.acc, self.needs_control_cb, native_callback
        )

    # -- state --------------------------------------------------------------------------------

    def to_mujoco(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Paper ``(q, q̇)`` -> ``(qpos, qvel)`` of this model."""
        return self.tm.to_mujoco(q, qdot)

    def to_paper(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(qpos, qvel)`` -> paper ``(q, q̇)``."""
        return self.tm.to_paper(qpos, qvel)

    def set_state(self, t: float, q: np.ndarray, qdot: np.ndarray) -> None:
        """Set ``d`` to a paper-coordinates state at time t, s."""
        qpos, qvel = self.to_mujoco(q, qdot)
        self.d.qpos[:] = qpos
        self.d.qvel[:] = qvel
        self.d.time = float(t)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """The paper's ``(q, q̇)`` of ``d``."""
        return self.to_paper(self.d.qpos, self.d.qvel)

    # -- the controller inside MuJoCo's integrator ----------------------------------------------

    @property
    def native(self) -> bool:
        """Whether :meth:`callbacks` installs the native (machine-code) controller callback."""
        return self.stepper.context is not None

    @property
    def native_redos(self) -> int:
        """Batches rerun with the Python callback after a declined stage."""
        return self.stepper.redos

    @property
    def control_callback(self):
        """The Python ``mjcb_control`` this twin installs (compiled stage or Python law)."""
        return self.stages.callback

    @property
    def last_control(self) -> ControlOutput | None:
        """The controller's output at the last state sampled (:meth:`forward_here`)."""
        return self.stages.last_control

    def callbacks(self) -> contextlib.AbstractContextManager[None]:
        """Install this twin's callbacks for a ``with`` block (:meth:`Stepper.callbacks`)."""
        return self.stepper.callbacks()

    def step(self, nstep: int) -> None:
        """``nstep`` MuJoCo steps with the installed callbacks, accumulating the controller's work
        and impulses (``acc``; ``acc.calls`` = controller stages run). Call inside
        :meth:`callbacks`; a batch the native callback could not finish is redone in Python."""
        self.stepper.step(nstep)

    def forward_here(self) -> None:
        """``mj_forward`` at the current state with the installed callbacks, keeping the
        controller's output in :attr:`last_control`. Call inside :meth:`callbacks`."""
        self.stepper.forward()

    # -- pointwise evaluations ----------------------------------------------------------------

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
        return self.tm.to_paper_acc(self.d.qpos, self.d.qvel, self.d.qacc)

    def mujoco_control(self, t: float, q: np.ndarray, qdot: np.ndarray) -> MjControl:
        """Udwadia–Kalaba control from MuJoCo's ``mj_fullM`` and ``qfrc_passive − qfrc_bias`` in
        MuJoCo's coordinates (no quaternion constraint there), at a paper-coordinates state."""
        if not self.controlled:
            raise ValueError(f"scene.effects: {self.scene.name!r} has no control effect")
        check_weighting(self.model)
        self.set_state(t, q, qdot)
        d = self.d
        d.ctrl[:] = 0.0
        d.xfrc_applied[:] = 0.0
        with installed(act_bias=spring_user_bias if self.tm.needs_act_bias else None):
            mujoco.mj_forward(self.m, d)
            return mujoco_law(self.tm, self.model, d, t, in_callback=False, M=self.stages._M)


def acceleration(scene: Scene, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """MuJoCo's forward dynamics of ``scene`` at a paper-coordinates state, as paper ``q̈``."""
    return Twin(scene).acceleration(t, q, qdot)


def mujoco_control(scene: Scene, t: float, q: np.ndarray, qdot: np.ndarray) -> MjControl:
    """The Udwadia–Kalaba control of ``scene`` from MuJoCo's own matrices (see
    :meth:`Twin.mujoco_control`)."""
    return Twin(scene).mujoco_control(t, q, qdot)


__all__ = ["ControllerSource", "MjControl", "Twin", "acceleration", "mujoco_control"]
