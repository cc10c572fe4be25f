"""Everything a validation run needs from its input, checked before any plant runs.

:func:`check_validation_inputs` refuses, with a ``ValueError`` naming the field, what would
otherwise be found only after the analytic plant has run (or after both have): a bad or unknown
``[thresholds]`` entry, a horizon or MuJoCo time step that does not fit the output grid, an
integrator MuJoCo does not have, a run too long to hold. :func:`validation_plants` refuses a
choice of plants that leaves nothing to compare (one plant, or one plant named twice). Both are
steps of :func:`validation.validate.validation_request`, the one function that checks a
validation's whole input, once per boundary.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

from analytic.scene import Scene
from analytic.trajectory import Engine
from mj_bridge.plan import plan_steps
from mj_bridge.plants import installed_plants, parse_plants, plant, plants_for_scene


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
        scene: a loaded scene (its fields checked by the loader; its ``[thresholds]`` are checked
            by :func:`validation_request`).
        integrator, dt, t_end: the overrides of :func:`validation.validate.run_validation`.
        mujoco: whether the MuJoCo plant runs (its integrator, step and grid are checked then).
    """
    scene.output.with_t_end(t_end, "t_end")  # the output grid every plant samples
    if not mujoco:
        return

    plan_steps(scene, integrator, dt, t_end)  # MuJoCo's steps on that grid


def validation_plants(
    plants: Sequence[Engine | str] | str | None, scene: Scene | None = None
) -> tuple[str, ...]:
    """The plants a validation runs, in report order: when ``plants`` is None, every installed one
    that can run ``scene`` (a plant whose ``check_scene`` refuses it, such as Pinocchio beyond its
    mass limit, is left out with one warning naming why); else those named (engine names, or
    ``"analytic,mujoco"``), which must each accept the scene (checked by the caller).

    Raises:
        ValueError: naming ``plants`` and the value: an unknown or missing plant, a plant named
            twice, or fewer than two (a validation compares plants with each other).
    """
    if plants is None:
        installed = installed_plants()
        if scene is None:
            return installed

        chosen = plants_for_scene(scene, installed)
        for e in installed:
            if e not in chosen:
                try:
                    plant(e).check_scene(scene)
                except ValueError as exc:
                    warnings.warn(f"{e} plant left out: {exc}", stacklevel=2)
        if len(chosen) < 2:
            raise ValueError(
                f"plants: fewer than two of the installed plants can run {scene.name!r} "
                f"({', '.join(chosen) or 'none'}); nothing to compare"
            )
        return chosen
    text = plants if isinstance(plants, str) else ",".join(str(getattr(p, "value", p)) for p in plants)
    named = [plant(n.strip()).engine for n in text.split(",") if n.strip() not in ("", "all")]
    twice = sorted({e for e in named if named.count(e) > 1})
    if twice:
        raise ValueError(f"plants: {', '.join(twice)} named twice (got {text!r})")
    chosen = parse_plants(text)
    if len(chosen) < 2:
        raise ValueError(
            f"plants: a validation compares at least two plants (got {text!r}; "
            "e.g. analytic,mujoco)"
        )
    return chosen


__all__ = ["check_validation_inputs", "validation_plants"]
