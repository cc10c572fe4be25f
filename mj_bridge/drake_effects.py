"""The effects the Drake engine implements in its model, one function per effect, found by the
effect's name (:data:`EFFECTS`).

:func:`mj_bridge.drake_model.build_model` starts from the parts of a plant with every such effect off
(:class:`Parts`: no gravity, point masses), calls ``EFFECTS[e](scene, parts)`` for each effect ``e``
of the scene in the table, and builds the ``MultibodyPlant`` from the parts (Drake takes a body's
inertia when the body is added, its gravity before the plant is finalised). The springs and
the given torque are generalized forces the stage applies (:mod:`mj_bridge.scipy_forces`), the
control effects the controller's; the Drake plant claims exactly these effects
(:class:`mj_bridge.scipy_loop_plant.ScipyLoopPlant`). Adding an effect Drake builds into its model
is one function here.

Light on purpose: the plugin's class reads the table's keys when the plants are listed; Drake is
imported by the functions only, when a model is built.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analytic.effects import Effect
from analytic.scene import Scene


@dataclass
class Parts:
    """What the plant is built from where an effect has a say; each field is the effect's off value
    until its function sets it.

    Attributes:
        gravity: the uniform gravity field, inertial, m/s² (3,).
        mass_inertias: each mass's ``pydrake`` ``RotationalInertia`` about its centre, body axes
            (None: a point mass).
    """

    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    mass_inertias: list[Any] = field(default_factory=list)


ModelEffect = Callable[[Scene, Parts], None]
"""``fn(scene, parts)``: the effect's parts of the plant."""


def _gravity(scene: Scene, parts: Parts) -> None:
    """The scene's gravity (inertial, m/s²) as the plant's uniform gravity field."""
    parts.gravity = np.array(scene.gravity, dtype=float)


def _mass_inertia(scene: Scene, parts: Parts) -> None:
    """Each mass's own inertia about its centre (body axes, Remark 1, symmetrised) as its body's."""
    import pydrake.all as d

    J = np.array(scene.masses.inertia, dtype=float).reshape(scene.n, 3, 3)
    parts.mass_inertias = []
    for Ji in J:
        Ji = 0.5 * (Ji + Ji.T)
        parts.mass_inertias.append(
            d.RotationalInertia(Ji[0, 0], Ji[1, 1], Ji[2, 2], Ji[0, 1], Ji[0, 2], Ji[1, 2])
        )


EFFECTS: dict[Effect, ModelEffect] = {
    Effect.GRAVITY: _gravity,
    Effect.MASS_INERTIA: _mass_inertia,
}
"""Each effect the Drake model implements, and the function that switches it on."""


__all__ = ["EFFECTS", "ModelEffect", "Parts"]
