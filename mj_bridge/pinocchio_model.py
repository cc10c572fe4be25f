"""The body of a scene as a Pinocchio model.

Pinocchio (PyPI ``pin``, 4.1, ``import pinocchio``) is an optional dependency: this module imports
it only inside :func:`build_model`. The maps between Pinocchio's state and the paper's are in
:mod:`model_xml.coordinates` (pure numpy; re-exported here under the names they had).

Model (joint names as in the MJCF twin, :mod:`model_xml.builder`; mass indices 1-based):

* joint 1, ``root``: ``JointModelFreeFlyer`` under the universe; its frame is at C along BR's
  principal axes (the paper's body frame); inertia ``(m_BR, 0, diag J_BR)``.
* joints 2 … n+1, ``p1 … pN``: ``JointModelPrismaticUnaligned(a)``, each a child of ``root`` (not a
  chain: every ``p_i`` is measured from O'), placed at ``SE3(I, d)``; inertia ``(m_i, 0, J_i)`` with
  ``J_i`` the scene's ``masses.inertia[i]`` in body axes (Remark 1: ring, axial + transverse, or a
  full matrix) when the ``mass_inertia`` effect is on, else a point mass (``J_i = 0``).
* ``gravity`` = the scene's vector when the ``gravity`` effect is on, else zero.

The model is built with both effects off, then each effect of the scene that
:data:`mj_bridge.pinocchio_effects.EFFECTS` implements is switched on by its function. Springs, the
given torque and the control are generalized forces applied by whoever drives the model
(:mod:`mj_bridge.pinocchio_plant`); the model has no armature, damping or friction.

``pin.buildModelFromMJCF`` of the exported twin (:func:`model_xml.to_mjcf`) gives the same tree and
mass properties (``tests/mj_bridge/test_pinocchio_plant.py``), except that Pinocchio 4.1's reader ignores
``<option gravity>`` (it keeps 0, 0, -9.81), picks ``JointModelPX/PY/PZ`` when ``a`` is a coordinate
axis, and carries the MJCF's tiny isotropic padding of point masses (taken off BR); tendons and
actuators are not read. This module builds the model from the scene directly.

Coordinates: ``q_pin = [R, qx, qy, qz, qw, p]`` (the quaternion **scalar last**), ``v_pin = [Sᵀ Ṙ,
ω, ṗ]`` (the free flyer's twist in its **local** frame); see :mod:`model_xml.coordinates`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from analytic.effects import Effect
from analytic.scene import Scene
from mj_bridge.pinocchio_effects import EFFECTS
from model_xml.builder import BODY, ROOT, joint_name, mass_name
from model_xml.coordinates import (
    paper_to_pinocchio,
    pinocchio_to_mujoco_layout,
    pinocchio_to_paper,
    pinocchio_to_paper_acc,
    pinocchio_to_paper_batch,
)

if TYPE_CHECKING:  # pragma: no cover
    import pinocchio


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
    for i in range(scene.n):  # point masses: the mass_inertia effect gives them their inertia
        jid = model.addJoint(root, pin.JointModelPrismaticUnaligned(a), at_d, joint_name(i))
        point = pin.Inertia(float(scene.masses.mass[i]), np.zeros(3), np.zeros((3, 3)))
        model.appendBodyToJoint(jid, point, pin.SE3.Identity())
        model.addBodyFrame(mass_name(i), jid, pin.SE3.Identity(), frame)
    model.gravity = pin.Motion(np.zeros(3), np.zeros(3))  # the gravity effect sets it
    for effect, switch_on in EFFECTS.items():
        if scene.has(effect):
            switch_on(scene, model)
    return model


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
