"""The compiled MJCF twin of a scene: MuJoCo's model with the run's integrator and step, where BR's
inertial frame sits in its body frame, the ids of the actuators the controller writes, and the
paper <-> MuJoCo maps for this model (:mod:`model_xml.coordinates`, given that inertial frame).

Frames: the paper's body axes are BR's principal axes at C; MuJoCo's ``qvel[3:6]`` is in BR's MuJoCo
body frame, rotated from those by ``iquat`` (``R_I = Rot(iquat)``; the identity unless a
:class:`model_xml.BodyFrame` was given).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from analytic.effects import Effect, MjIntegrator, SpringModel
from analytic.scene import Scene, as_enum
from model_xml import (
    BODY,
    TORQUE_ACTUATORS,
    BodyFrame,
    build_spec,
    force_actuator_name,
    spring_actuator_name,
    spring_tendons,
)
from model_xml.builder import _INTEGRATORS
from model_xml.coordinates import (
    mujoco_to_paper_acc,
    mujoco_to_paper_batch,
    mujoco_to_paper_state,
    paper_to_mujoco_state,
)
from model_xml.rotations import quat_to_mat


@dataclass(frozen=True)
class TwinModel:
    """A scene's MJCF twin, compiled for one run.

    Attributes:
        m: the ``MjModel`` (``opt.integrator`` and ``opt.timestep`` set).
        integrator: MuJoCo's integrator; dt: its step, s.
        body_id: body ``BR``.
        ipos: C in BR's body frame, m, shape (3,); iquat: BR's principal axes in its body frame
            (w first), shape (4,); R_I: ``Rot(iquat)``, paper body axes -> MuJoCo body frame, (3, 3).
        torque_ids: actuators ``torque_x..z`` (body-axis torque), or None without control and
            given torque; force_ids: actuators ``force1..N`` (rod forces), or None uncontrolled.
        spring_act_ids: the spring actuators (``spring_model = "actuator"``), else empty.
        needs_act_bias: the spring actuators have a cubic term (MuJoCo's user-bias callback).
    """

    m: mujoco.MjModel
    integrator: MjIntegrator
    dt: float
    body_id: int
    ipos: np.ndarray
    iquat: np.ndarray
    R_I: np.ndarray
    torque_ids: np.ndarray | None
    force_ids: np.ndarray | None
    spring_act_ids: np.ndarray
    needs_act_bias: bool

    @classmethod
    def build(
        cls,
        scene: Scene,
        integrator: MjIntegrator | str | None = None,
        dt: float | None = None,
        body_frame: BodyFrame | None = None,
    ) -> TwinModel:
        """Compile ``scene``'s twin; ``integrator`` and ``dt`` (s) override the scene's
        ``[mujoco]`` table, ``body_frame`` places BR's body frame (default at C)."""
        integ = as_enum(
            MjIntegrator,
            scene.mujoco.integrator if integrator is None else integrator,
            "integrator",
        )
        h = float(scene.mujoco.timestep if dt is None else dt)
        if not (math.isfinite(h) and h > 0):
            raise ValueError(f"dt: must be a positive finite time step in s (got {dt!r})")
        m = build_spec(scene, body_frame).compile()
        m.opt.integrator = int(_INTEGRATORS[integ])
        m.opt.timestep = h
        b = m.body(BODY).id
        iquat = m.body_iquat[b].copy()
        controlled = scene.controlled
        tendons = spring_tendons(scene)
        spring_ids = (
            np.array([m.actuator(spring_actuator_name(j)).id for j in range(len(tendons))], int)
            if SpringModel(scene.mujoco.spring_model) is SpringModel.ACTUATOR
            else np.zeros(0, dtype=int)
        )
        return cls(
            m=m,
            integrator=integ,
            dt=h,
            body_id=b,
            ipos=m.body_ipos[b].copy(),
            iquat=iquat,
            R_I=quat_to_mat(iquat),
            torque_ids=(
                np.array([m.actuator(nm).id for nm in TORQUE_ACTUATORS])
                if (controlled or scene.has(Effect.EXTERNAL_TORQUE))
                else None
            ),
            force_ids=(
                np.array([m.actuator(force_actuator_name(i)).id for i in range(scene.n)], int)
                if controlled
                else None
            ),
            spring_act_ids=spring_ids,
            needs_act_bias=bool(any(sp.k_cubic != 0.0 for sp in tendons) and len(spring_ids)),
        )

    @property
    def frame_at_C(self) -> bool:
        """BR's body frame is its inertial frame (the default model)."""
        return bool(np.all(self.ipos == 0) and np.all(self.iquat == [1, 0, 0, 0]))

    def to_mujoco(self, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Paper ``(q, q̇)`` -> ``(qpos, qvel)`` of this model."""
        return paper_to_mujoco_state(q, qdot, self.ipos, self.iquat)

    def to_paper(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(qpos, qvel)`` -> paper ``(q, q̇)``."""
        return mujoco_to_paper_state(qpos, qvel, self.ipos, self.iquat)

    def paper_q_of(self):
        """``q_of(qpos)``: the paper's ``q`` of one ``qpos`` (a new array), as
        :meth:`to_paper_batch` makes it: a copy of ``qpos`` for a body frame at C."""
        if self.frame_at_C:
            return lambda qpos: np.array(qpos, dtype=float)

        def q_of(qpos: np.ndarray) -> np.ndarray:
            qvel = np.zeros(len(qpos) - 1)  # nv = nq - 1 (a free joint, then slides); q ignores it
            return mujoco_to_paper_state(qpos, qvel, self.ipos, self.iquat)[0]

        return q_of

    def to_paper_acc(self, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray) -> np.ndarray:
        """``qacc`` at ``(qpos, qvel)`` -> paper ``q̈``."""
        return mujoco_to_paper_acc(qpos, qvel, qacc, self.ipos, self.iquat)

    def to_paper_batch(
        self, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """N samples -> paper ``(q, q̇, q̈)`` and body-axis ω (:func:`mujoco_to_paper_batch`)."""
        return mujoco_to_paper_batch(qpos, qvel, qacc, self.ipos, self.iquat)


# The same maps for any compiled twin, reading BR's inertial frame from the model.


def inertial_frame(m: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """``(ipos (3,), iquat (4,))`` of body ``BR`` of the compiled twin m."""
    b = m.body(BODY).id
    return m.body_ipos[b], m.body_iquat[b]


def to_mujoco(m: mujoco.MjModel, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper ``(q (n+7), q̇ (n+7))`` -> ``(qpos (n+7), qvel (n+6))`` of model m."""
    return paper_to_mujoco_state(q, qdot, *inertial_frame(m))


def to_paper(
    m: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(qpos, qvel)`` of model m -> paper ``(q, q̇)`` (``u̇ = ¼ Hᵀ ω``)."""
    return mujoco_to_paper_state(qpos, qvel, *inertial_frame(m))


def to_paper_acc(
    m: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray
) -> np.ndarray:
    """MuJoCo ``qacc (n+6)`` at ``(qpos, qvel)`` -> paper ``q̈ (n+7)``."""
    return mujoco_to_paper_acc(qpos, qvel, qacc, *inertial_frame(m))


__all__ = ["TwinModel", "as_enum", "inertial_frame", "to_mujoco", "to_paper", "to_paper_acc"]
