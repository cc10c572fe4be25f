"""Everything a validation run needs from its input, checked before any plant runs.

:func:`check_validation_inputs` refuses, with a ``ValueError`` naming the field, what would
otherwise be found only after the analytic plant has run (or after both have): a bad or unknown
``[thresholds]`` entry, a horizon or MuJoCo time step that does not fit the output grid, an
integrator MuJoCo does not have, a run too long to hold.
"""

from __future__ import annotations

from typing import Any

from analytic.scene import Scene
from validation.thresholds import thresholds_for


def check_validation_inputs(
    scene: Scene,
    *,
    integrator: Any = None,
    dt: float | None = None,
    t_end: float | None = None,
    mujoco: bool = True,
) -> None:
    """Raise ``ValueError`` naming the field if ``scene`` with these overrides cannot be
    validated; build nothing and run nothing.

    Args:
        scene: a loaded scene (its fields are checked by the loader already).
        integrator, dt, t_end: the overrides of :func:`validation.validate.run_validation`.
        mujoco: whether the MuJoCo plant runs (its integrator, step and grid are checked then).
    """
    thresholds_for(scene)  # names and values of the scene's [thresholds]
    scene.output.with_t_end(t_end, "t_end")  # the output grid every plant samples
    if not mujoco:
        return
    from mj_bridge.plan import plan_steps  # light: numpy and the scene, not MuJoCo

    plan_steps(scene, integrator, dt, t_end)  # MuJoCo's steps on that grid


__all__ = ["check_validation_inputs"]
