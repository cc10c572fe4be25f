"""The effects the Pinocchio engine implements in its model, one function per effect, found by the
effect's name (:data:`EFFECTS`).

:func:`mj_bridge.pinocchio_model.build_model` builds the body with every such effect off (no gravity,
point masses), then calls ``EFFECTS[e](scene, model)`` for each effect ``e`` of the scene in the
table, before Pinocchio's ``Data`` is made. The springs and the given torque are generalized forces
the stage applies (:mod:`mj_bridge.scipy_forces`), the control effects the controller's; the
Pinocchio plant claims exactly these effects (:class:`mj_bridge.scipy_loop_plant.ScipyLoopPlant`).
Adding an effect Pinocchio builds into its model is one function here.

Light on purpose: the plant's class reads the table's keys when the plants are listed; Pinocchio is
imported by the functions only, when a model is built.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from analytic.effects import Effect
from analytic.scene import Scene

ModelEffect = Callable[[Scene, Any], None]
"""``fn(scene, model)``: switch the effect on in a ``pinocchio.Model`` built with it off."""


def _gravity(scene: Scene, model: Any) -> None:
    """The scene's gravity (inertial, m/s²) as the model's gravity."""
    import pinocchio as pin

    model.gravity = pin.Motion(np.array(scene.gravity, dtype=float), np.zeros(3))


def _mass_inertia(scene: Scene, model: Any) -> None:
    """Each mass's own inertia about its centre (body axes, Remark 1) as its body's inertia
    (joints ``p1 … pN`` are ids 2 … n+1)."""
    import pinocchio as pin

    J = np.array(scene.masses.inertia, dtype=float).reshape(scene.n, 3, 3)
    for i in range(scene.n):
        model.inertias[2 + i] = pin.Inertia(float(scene.masses.mass[i]), np.zeros(3), J[i])


EFFECTS: dict[Effect, ModelEffect] = {
    Effect.GRAVITY: _gravity,
    Effect.MASS_INERTIA: _mass_inertia,
}
"""Each effect the Pinocchio model implements, and the function that switches it on."""


__all__ = ["EFFECTS", "ModelEffect"]
