"""The body of a scene as a Drake ``MultibodyPlant`` in continuous time, and the maps between Drake's
state and the paper's coordinates.

Drake (PyPI ``drake`` >= 1.51, ``import pydrake``) is an optional dependency: this module imports it
only inside :func:`build_model`. The plant is built from the scene's numbers alone (not from the
MJCF twin, whose ``<tendon>`` springs Drake's MJCF parser ignores, and not from the analytic model):

* ``BR``: a rigid body with ``SpatialInertia.MakeFromCentralInertia(m_BR, 0, diag J_BR)``: its
  origin at C, its axes BR's principal axes (the paper's body frame); Drake gives it a quaternion
  floating joint itself when the plant is finalised.
* ``rod``: a frame fixed on BR at ``d`` (O′), not rotated.
* ``mass1 … massN``: rigid bodies of mass ``m_i`` and rotational inertia ``J_i`` about their centre
  (body axes; the scene's with the ``mass_inertia`` effect, else zero), each
  joined to ``rod`` by ``PrismaticJoint("p<i>", rod, mass_i, a)`` without limits or damping: its
  centre is at ``O′ + a p_i`` and it keeps BR's orientation. Every ``p_i`` is measured from O′.
* gravity: the scene's vector with the ``gravity`` effect, else zero.

Those two are the effects Drake implements itself: each has its function in
:data:`mj_bridge.drake_effects.EFFECTS`, which sets its part of the plant
(:class:`~mj_bridge.drake_effects.Parts`) before the plant is built.

The springs, the given torque and the control are generalized forces fed to the plant's applied
generalized-force input port by whoever drives it (:mod:`mj_bridge.drake_plant`); the plant has no
damping, armature, limits or contact.

**Drake's state** (the plant's continuous state, measured for Drake 1.51): positions
``q_d = [qw, qx, qy, qz, x, y, z, p…]`` (n + 7: the paper's u, w first, body -> inertial, then R = C)
and velocities ``v_d = [ω_W, v_W, ṗ…]`` (n + 6) with ``ω_W = S(u) ω`` the angular velocity of BR in
**inertial** axes (not body axes) and ``v_W = Ṙ``; ``v̇_d = [α_W, R̈, p̈]`` with ``α_W = S(u) ω̇``
(``Ṡᵀ ω_W = −ω × ω = 0``). The offsets are read from the plant
(``floating_positions_start``, ``floating_velocities_start_in_v``, ``position_start``,
``velocity_start``) and checked against this layout by :func:`build_model`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from analytic.kinematics import S_batch
from analytic.scene import Scene
from mj_bridge.drake_effects import EFFECTS, Parts
from model_xml.builder import BODY, joint_name, mass_name
from model_xml.coordinates import (
    IPOS_AT_C,
    IQUAT_AT_C,
    mujoco_to_paper_batch,
    paper_to_mujoco_state,
)

ROD_FRAME = "rod"
"""The name of the frame at O′ fixed on BR."""


def import_drake():
    """``import pydrake.all``, or ImportError saying how to install it."""
    try:
        import pydrake.all as drake
    except ImportError as exc:  # pragma: no cover - exercised only without drake
        raise ImportError(
            "the Drake plant needs the 'drake' package (>= 1.51): pip install '.[drake]'"
        ) from exc
    return drake


@dataclass(frozen=True)
class DrakeModel:
    """A finalised continuous-time ``MultibodyPlant`` of one scene and its context.

    Attributes:
        plant: the ``MultibodyPlant`` (``time_step = 0``), finalised.
        context: its context; the applied generalized-force port is fixed on it (:attr:`force`).
        force: the ``FixedInputPortValue`` of the applied generalized force (n + 6, Drake's velocity
            order); update it with ``force.GetMutableVectorData().SetFromVector(tau)``.
        n: masses; nq = n + 7 positions, nv = n + 6 velocities (Drake's, the layout above).
    """

    plant: Any
    context: Any
    force: Any
    n: int

    @property
    def nq(self) -> int:
        return self.n + 7

    @property
    def nv(self) -> int:
        return self.n + 6


def build_model(scene: Scene) -> DrakeModel:
    """The Drake plant of ``scene`` (see the module docstring for its layout).

    Args:
        scene: a validated scene.

    Returns:
        the :class:`DrakeModel`; bodies ``BR``, ``mass1 … massN``, joints ``p1 … pN``.

    Raises:
        RuntimeError: Drake laid its state out otherwise than the module docstring says.
    """
    d = import_drake()
    plant = d.MultibodyPlant(time_step=0.0)
    J = np.asarray(scene.body.inertia, dtype=float)
    br = plant.AddRigidBody(
        BODY,
        d.SpatialInertia.MakeFromCentralInertia(
            float(scene.body.mass), np.zeros(3), d.RotationalInertia(J[0], J[1], J[2])
        ),
    )
    rod = plant.AddFrame(
        d.FixedOffsetFrame(
            ROD_FRAME, br.body_frame(), d.RigidTransform(np.asarray(scene.rod.offset, dtype=float))
        )
    )
    axis = np.asarray(scene.rod.axis, dtype=float)
    point = d.RotationalInertia(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    parts = Parts(mass_inertias=[None] * scene.n)
    for effect, switch_on in EFFECTS.items():
        if scene.has(effect):
            switch_on(scene, parts)
    joints = []
    for i, inertia in enumerate(parts.mass_inertias):
        body = plant.AddRigidBody(
            mass_name(i),
            d.SpatialInertia.MakeFromCentralInertia(
                float(scene.masses.mass[i]), np.zeros(3), point if inertia is None else inertia
            ),
        )
        joints.append(
            plant.AddJoint(
                d.PrismaticJoint(joint_name(i), rod, body.body_frame(), axis, -np.inf, np.inf, 0.0)
            )
        )
    plant.mutable_gravity_field().set_gravity_vector(parts.gravity)
    plant.Finalize()
    n = scene.n
    layout = (
        plant.num_positions() == n + 7
        and plant.num_velocities() == n + 6
        and br.floating_positions_start() == 0
        and br.floating_velocities_start_in_v() == 0
        and all(j.position_start() == 7 + i for i, j in enumerate(joints))
        and all(j.velocity_start() == 6 + i for i, j in enumerate(joints))
    )
    if not layout:  # pragma: no cover - a Drake that orders its state otherwise
        raise RuntimeError(
            f"Drake {d.__name__}: unexpected state layout of the plant (nq "
            f"{plant.num_positions()}, nv {plant.num_velocities()}); mj_bridge.drake_model "
            "expects [quaternion, C, p] and [ω_W, v_W, ṗ]"
        )
    context = plant.CreateDefaultContext()
    force = plant.get_applied_generalized_force_input_port().FixValue(context, np.zeros(n + 6))
    return DrakeModel(plant, context, force, n)


# ----------------------------------------------------------------------------------------------
# Maps between Drake's state and the paper's coordinates (numpy, one sample or N rows)
# ----------------------------------------------------------------------------------------------


def _rot_t(quat: np.ndarray) -> np.ndarray:
    """``S(û)ᵀ`` of (N, 4) w-first quaternions, normalised first, (N, 3, 3)."""
    u = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    return np.swapaxes(S_batch(u), 1, 2)


def drake_to_mujoco_layout(
    q_d: np.ndarray, v_d: np.ndarray, vdot_d: np.ndarray | None = None
) -> tuple[np.ndarray, ...]:
    """Drake's state (and ``v̇``) in MuJoCo's layout for a body frame at C.

    Args:
        q_d (N, n+7), v_d (N, n+6), vdot_d (N, n+6) or None: Drake's positions, velocities and
            their derivative (the layout of the module docstring).

    Returns:
        ``qpos = [R, u, p]`` (u as given), ``qvel = [Ṙ, ω, ṗ]`` and, when ``vdot_d`` is given,
        ``qacc = [R̈, ω̇, p̈]`` (ω, ω̇ body axes: ``S(û)ᵀ`` times Drake's inertial ones).
    """
    single = np.ndim(q_d) == 1
    q_d, v_d = np.atleast_2d(q_d).astype(float), np.atleast_2d(v_d).astype(float)
    St = _rot_t(q_d[:, :4])
    qpos = np.concatenate([q_d[:, 4:7], q_d[:, :4], q_d[:, 7:]], axis=1)
    omega = np.einsum("nij,nj->ni", St, v_d[:, :3])
    qvel = np.concatenate([v_d[:, 3:6], omega, v_d[:, 6:]], axis=1)
    out = [qpos, qvel]
    if vdot_d is not None:
        a = np.atleast_2d(vdot_d).astype(float)
        out.append(np.concatenate([a[:, 3:6], np.einsum("nij,nj->ni", St, a[:, :3]), a[:, 6:]], 1))
    return tuple(x[0] for x in out) if single else tuple(out)


def drake_to_paper_batch(
    q_d: np.ndarray, v_d: np.ndarray, vdot_d: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Drake ``(q_d, v_d, v̇_d)`` ((N, ·)) -> the paper's ``(q, q̇, q̈)`` ((N, n+7) each) and ω
    ((N, 3), body axes, rad/s). u is Drake's quaternion as given; ``u̇ = H(u)ᵀ ω / (4|u|²)``,
    ``ü = ¼ (H(u̇)ᵀ ω + H(u)ᵀ ω̇)`` (:func:`model_xml.coordinates.mujoco_to_paper_batch`)."""
    qpos, qvel, qacc = drake_to_mujoco_layout(
        np.atleast_2d(q_d), np.atleast_2d(v_d), np.atleast_2d(vdot_d)
    )
    return mujoco_to_paper_batch(qpos, qvel, qacc, IPOS_AT_C, IQUAT_AT_C)


def paper_to_drake(q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper ``(q, q̇)`` ((n+7,) each or (N, n+7)) -> Drake ``(q_d, v_d)``: u normalised,
    ``ω = H(u) u̇`` at the given u, ``ω_W = S(û) ω``, ``v_W = Ṙ``."""
    single = np.ndim(q) == 1
    qpos, qvel = paper_to_mujoco_state(np.atleast_2d(q), np.atleast_2d(qdot))
    u = qpos[:, 3:7] / np.linalg.norm(qpos[:, 3:7], axis=1, keepdims=True)
    omega_w = np.einsum("nij,nj->ni", S_batch(u), qvel[:, 3:6])
    q_d = np.concatenate([u, qpos[:, :3], qpos[:, 7:]], axis=1)
    v_d = np.concatenate([omega_w, qvel[:, :3], qvel[:, 6:]], axis=1)
    return (q_d[0], v_d[0]) if single else (q_d, v_d)


__all__ = [
    "ROD_FRAME",
    "DrakeModel",
    "build_model",
    "drake_to_mujoco_layout",
    "drake_to_paper_batch",
    "import_drake",
    "paper_to_drake",
]
