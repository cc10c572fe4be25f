"""The body of a scene as a Pinocchio model, and the maps between Pinocchio's state and the paper's.

Pinocchio (PyPI ``pin``, 4.1, ``import pinocchio``) is an optional dependency: this module imports
it only inside :func:`build_model`; the coordinate maps are pure numpy.

Model (joint names as in the MJCF twin, :mod:`model_xml.builder`; mass indices 1-based):

* joint 1, ``root``: ``JointModelFreeFlyer`` under the universe; its frame is at C along BR's
  principal axes (the paper's body frame); inertia ``(m_BR, 0, diag J_BR)``.
* joints 2 … n+1, ``p1 … pN``: ``JointModelPrismaticUnaligned(a)``, each a child of ``root`` (not a
  chain: every ``p_i`` is measured from O'), placed at ``SE3(I, d)``; inertia ``(m_i, 0, J_i)`` with
  ``J_i`` the scene's ``masses.inertia[i]`` in body axes (Remark 1: ring, axial + transverse, or a
  full matrix) when the ``mass_inertia`` effect is on, else a point mass (``J_i = 0``).
* ``gravity`` = the scene's vector when the ``gravity`` effect is on, else zero. Springs, the given
  torque and the control are generalized forces applied by whoever drives the model
  (:mod:`mj_bridge.pinocchio_plant`); the model has no armature, damping or friction.

``pin.buildModelFromMJCF`` of the exported twin (:func:`model_xml.to_mjcf`) gives the same tree and
mass properties (``tests/test_pinocchio.py``), except that Pinocchio 4.1's reader ignores
``<option gravity>`` (it keeps 0, 0, -9.81), picks ``JointModelPX/PY/PZ`` when ``a`` is a coordinate
axis, and carries the MJCF's tiny isotropic padding of point masses (taken off BR); tendons and
actuators are not read. This module builds the model from the scene directly.

Coordinates (``n`` masses; paper ``q = [R, u, p]`` of Eq. 44, ``u`` w first; ``S = S(u)`` of
Eq. 11, ``ω = H(u) u̇`` of Eq. 12):

* Pinocchio ``q_pin = [x, y, z, qx, qy, qz, qw, p]`` (n + 7): C and the quaternion **scalar last**;
* Pinocchio ``v_pin = [v, ω, ṗ]`` (n + 6), twist of the free flyer in its **local** frame:
  ``v = Sᵀ Ṙ`` (body axes, m/s), ``ω`` the body-axis angular velocity (rad/s);
* ``a_pin = v̇_pin`` (what ``pin.aba`` returns): ``R̈ = S (v̇ + ω × v)``, ``ω̇ = a_pin[3:6]``,
  ``ü = ¼ (H(u̇)ᵀ ω + H(u)ᵀ ω̇)``, ``p̈ = a_pin[6:]``.

The Pinocchio → paper direction is done by converting to MuJoCo's free-joint layout
(``[x, qw, qx, qy, qz, p]``, ``[Ṙ, ω, ṗ]``, ``[R̈, ω̇, p̈]`` for a body frame at C) and reusing
:func:`model_xml.state.mujoco_to_paper_batch`, so that map exists once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from analytic.effects import Effect
from analytic.kinematics import S as S_of
from analytic.kinematics import S_batch, omega_of
from analytic.scene import Scene
from model_xml.builder import BODY, ROOT, joint_name, mass_name
from model_xml.state import mujoco_to_paper_batch

if TYPE_CHECKING:  # pragma: no cover
    import pinocchio

_IPOS0 = np.zeros(3)
_IQUAT0 = np.array([1.0, 0.0, 0.0, 0.0])


def import_pinocchio():
    """``import pinocchio``, or ImportError saying how to install it."""
    try:
        import pinocchio
    except ImportError as exc:  # pragma: no cover - exercised only without pin
        raise ImportError(
            "the Pinocchio plant needs the 'pin' package (>= 4.1): pip install '.[pinocchio]'"
        ) from exc
    return pinocchio


def mass_inertias(scene: Scene) -> np.ndarray:
    """Rotational inertia of each mass about its own centre, body axes, kg·m², shape (n, 3, 3):
    the scene's (Remark 1) with the ``mass_inertia`` effect, zeros (point masses) without."""
    if scene.has(Effect.MASS_INERTIA):
        return np.array(scene.masses.inertia, dtype=float).reshape(scene.n, 3, 3)
    return np.zeros((scene.n, 3, 3))


def gravity_vector(scene: Scene) -> np.ndarray:
    """Inertial gravity, m/s², shape (3,): the scene's with the ``gravity`` effect, else zeros."""
    return np.array(scene.gravity, dtype=float) if scene.has(Effect.GRAVITY) else np.zeros(3)


def build_model(scene: Scene) -> pinocchio.Model:
    """The Pinocchio model of ``scene`` (see the module docstring for its layout).

    Args:
        scene: a validated scene.

    Returns:
        a ``pinocchio.Model`` with ``nq = n + 7``, ``nv = n + 6``; joint ``root`` (id 1) and
        ``p1 … pN`` (ids 2 … n+1), bodies named ``BR``, ``mass1 … massN``.
    """
    pin = import_pinocchio()
    a = np.array(scene.rod.axis, dtype=float)
    d = np.array(scene.rod.offset, dtype=float)
    model = pin.Model()
    model.name = scene.name
    root = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), ROOT)
    model.appendBodyToJoint(
        root,
        pin.Inertia(float(scene.body.mass), np.zeros(3), np.diag(np.asarray(scene.body.inertia))),
        pin.SE3.Identity(),
    )
    frame = model.addBodyFrame(BODY, root, pin.SE3.Identity(), 0)
    at_d = pin.SE3(np.eye(3), d)
    for i, J in enumerate(mass_inertias(scene)):
        jid = model.addJoint(root, pin.JointModelPrismaticUnaligned(a), at_d, joint_name(i))
        model.appendBodyToJoint(
            jid, pin.Inertia(float(scene.masses.mass[i]), np.zeros(3), J), pin.SE3.Identity()
        )
        model.addBodyFrame(mass_name(i), jid, pin.SE3.Identity(), frame)
    model.gravity = pin.Motion(gravity_vector(scene), np.zeros(3))
    return model


# ----------------------------------------------------------------------------------------------
# Coordinate maps
# ----------------------------------------------------------------------------------------------


def paper_to_pinocchio(q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper ``(q, q̇)`` (n+7 each) -> Pinocchio ``(q_pin (n+7), v_pin (n+6))``.

    u is normalised (Pinocchio's quaternion is a rotation); ``ω = H(u) u̇`` is evaluated at the given,
    possibly non-unit, u (as :func:`model_xml.state.paper_to_mujoco_state` does), ``v = S(û)ᵀ Ṙ``.
    """
    q = np.asarray(q, dtype=float)
    qdot = np.asarray(qdot, dtype=float)
    u = q[3:7] / np.linalg.norm(q[3:7])
    omega = omega_of(q[3:7], qdot[3:7])
    q_pin = np.concatenate([q[:3], u[1:4], u[:1], q[7:]])
    v_pin = np.concatenate([S_of(u).T @ qdot[:3], omega, qdot[7:]])
    return q_pin, v_pin


def pinocchio_to_mujoco_layout(
    q_pin: np.ndarray, v_pin: np.ndarray, a_pin: np.ndarray | None = None
) -> tuple[np.ndarray, ...]:
    """Pinocchio's state (and acceleration) in MuJoCo's free-joint layout, batched.

    Args:
        q_pin (N, n+7), v_pin (N, n+6), a_pin (N, n+6) or None.

    Returns:
        ``qpos = [x, qw, qx, qy, qz, p]``, ``qvel = [S v, ω, ṗ]`` and, when ``a_pin`` is given,
        ``qacc = [S (v̇ + ω × v), ω̇, p̈]`` (a body frame at C along the principal axes).
    """
    q_pin = np.atleast_2d(np.asarray(q_pin, dtype=float))
    v_pin = np.atleast_2d(np.asarray(v_pin, dtype=float))
    quat = np.concatenate([q_pin[:, 6:7], q_pin[:, 3:6]], axis=1)  # w first
    qpos = np.concatenate([q_pin[:, :3], quat, q_pin[:, 7:]], axis=1)
    Sm = _rot_rows(quat)
    v, w = v_pin[:, :3], v_pin[:, 3:6]
    qvel = np.concatenate([np.einsum("nij,nj->ni", Sm, v), v_pin[:, 3:]], axis=1)
    if a_pin is None:
        return qpos, qvel
    a_pin = np.atleast_2d(np.asarray(a_pin, dtype=float))
    Rdd = np.einsum("nij,nj->ni", Sm, a_pin[:, :3] + np.cross(w, v))
    qacc = np.concatenate([Rdd, a_pin[:, 3:]], axis=1)
    return qpos, qvel, qacc


def pinocchio_to_paper_batch(
    q_pin: np.ndarray, v_pin: np.ndarray, a_pin: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pinocchio ``(q_pin, v_pin, a_pin)`` for N samples -> paper ``(q, q̇, q̈)`` (N, n+7 each) and
    ``ω`` (N, 3), body axes, rad/s. ``u`` is the quaternion as given (not renormalised);
    ``u̇ = H(u)ᵀ ω / (4|u|²)``."""
    qpos, qvel, qacc = pinocchio_to_mujoco_layout(q_pin, v_pin, a_pin)
    return mujoco_to_paper_batch(qpos, qvel, qacc, _IPOS0, _IQUAT0)


def pinocchio_to_paper(q_pin: np.ndarray, v_pin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One Pinocchio state ``(q_pin (n+7), v_pin (n+6))`` -> paper ``(q, q̇)`` (n+7 each)."""
    q_pin = np.asarray(q_pin, dtype=float)
    v_pin = np.asarray(v_pin, dtype=float)
    q, qd, _, _ = pinocchio_to_paper_batch(q_pin[None], v_pin[None], np.zeros((1, v_pin.size)))
    return q[0], qd[0]


def pinocchio_to_paper_acc(q_pin: np.ndarray, v_pin: np.ndarray, a_pin: np.ndarray) -> np.ndarray:
    """Pinocchio's ``v̇`` (n+6) at ``(q_pin, v_pin)`` -> the paper's ``q̈`` (n+7)."""
    return pinocchio_to_paper_batch(
        np.asarray(q_pin, float)[None],
        np.asarray(v_pin, float)[None],
        np.asarray(a_pin, float)[None],
    )[2][0]


def _rot_rows(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices of (N, 4) w-first quaternions, normalised first, shape (N, 3, 3)."""
    return S_batch(quat / np.linalg.norm(quat, axis=1, keepdims=True))


__all__ = [
    "build_model",
    "gravity_vector",
    "import_pinocchio",
    "mass_inertias",
    "paper_to_pinocchio",
    "pinocchio_to_mujoco_layout",
    "pinocchio_to_paper",
    "pinocchio_to_paper_acc",
    "pinocchio_to_paper_batch",
]
