"""Everything a validation run needs from its input, checked before any plant runs.

:func:`check_validation_inputs` refuses, with a ``ValueError`` naming the field, what would
otherwise be found only after the analytic plant has run (or after both have): a bad or unknown
``[thresholds]`` entry, a horizon or MuJoCo time step that does not fit the output grid, an
integrator MuJoCo does not have, a run too long to hold. :func:`plant_choice` refuses a
choice of plants that leaves nothing to compare (one plant, or one plant named twice), and leaves
out of a default set or of ``--plants all`` the plants that refuse the scene, each with one
warning (:func:`accepting_plants`; the report's referee note names them), and so does
:func:`without_refusals` with the plants whose pointwise check refuses the scene. All are
steps of :func:`validation.validate.validation_request`, the one function that checks a
validation's whole input, once per boundary.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from analytic.scene import Scene
from analytic.trajectory import Engine
from mj_bridge.plan import plan_steps
from mj_bridge.plants import ALL, installed_plants, parse_plants, plant, plants_for_scene


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


@dataclass(frozen=True)
class LeftOut:
    """A plant a run would have used (the default set, or ``--plants all``) that refused the
    scene: its ``engine`` name and the one-line ``reason`` its ``check_scene`` gave."""

    engine: str
    reason: str

    def __str__(self) -> str:
        return f"{self.engine} plant left out: {self.reason}"


@dataclass(frozen=True)
class PlantChoice:
    """The plants a validation runs (report order) and those of its set left out (:class:`LeftOut`,
    empty when the plants were named: a named plant that refuses the scene is an error)."""

    plants: tuple[str, ...]
    left_out: tuple[LeftOut, ...] = ()
    named: bool = False
    """The plants were named (not a default set nor ``--plants all``): one that refuses the scene
    refuses the run."""


def accepting_plants(scene: Scene, candidates: Sequence[str]) -> PlantChoice:
    """Those of ``candidates`` whose ``check_scene`` accepts ``scene``, in the same order; each
    other one is left out with one warning (``<plant> plant left out: <reason>``) and listed in
    :attr:`PlantChoice.left_out`. How a default plant set or ``--plants all`` meets a scene some
    of its plants cannot run."""
    candidates = tuple(str(e) for e in candidates)
    chosen = plants_for_scene(scene, candidates)
    left: list[LeftOut] = []
    for e in candidates:
        if e not in chosen:
            try:
                plant(e).check_scene(scene)
            except ValueError as exc:
                left.append(LeftOut(str(e), " ".join(str(exc).split())))
                warnings.warn(str(left[-1]), stacklevel=2)
    return PlantChoice(chosen, tuple(left))


def plant_choice(
    plants: Sequence[Engine | str] | str | None, scene: Scene | None = None
) -> PlantChoice:
    """The plants a validation runs, in report order, and the plants of its set left out.

    ``plants`` None (every installed default plant) or ``"all"`` (every runnable plant,
    :func:`mj_bridge.plants.runnable_plants`): the plants that can run ``scene``; one whose
    ``check_scene`` refuses it (Pinocchio beyond its mass limit, a plugin that cannot run the
    scene) is left out with one warning naming why (``<plant> plant left out: <reason>``) and
    listed in :attr:`PlantChoice.left_out`. Otherwise the plants named (engine names, or
    ``"analytic,mujoco"``), which must each accept the scene (checked by the caller).

    Raises:
        ValueError: naming ``plants`` and the value: an unknown or missing plant, a plant named
            twice, or fewer than two (a validation compares plants with each other).
    """
    if plants is None:
        installed = installed_plants()
        if scene is None:
            return PlantChoice(installed)
        choice = accepting_plants(scene, installed)
        if len(choice.plants) < 2:
            raise ValueError(
                f"plants: fewer than two of the installed plants can run {scene.name!r} "
                f"({', '.join(choice.plants) or 'none'}); nothing to compare"
            )
        return choice
    text = (
        plants if isinstance(plants, str) else ",".join(str(getattr(p, "value", p)) for p in plants)
    )
    named = [plant(n.strip()).engine for n in text.split(",") if n.strip() not in ("", ALL)]
    twice = sorted({e for e in named if named.count(e) > 1})
    if twice:
        raise ValueError(f"plants: {', '.join(twice)} named twice (got {text!r})")
    chosen = parse_plants(text)
    if scene is not None and [n.strip() for n in text.split(",") if n.strip()] == [ALL]:
        choice = accepting_plants(scene, chosen)
        if len(choice.plants) < 2:
            raise ValueError(
                f"plants: fewer than two of the runnable plants can run {scene.name!r} "
                f"({', '.join(choice.plants) or 'none'}; got {text!r}); nothing to compare"
            )
        return choice
    if len(chosen) < 2:
        raise ValueError(
            f"plants: a validation compares at least two plants (got {text!r}; "
            "e.g. analytic,mujoco)"
        )
    return PlantChoice(chosen, named=True)


def without_refusals(
    choice: PlantChoice, refused: Sequence[tuple[str, str]], scene: Scene
) -> PlantChoice:
    """``choice`` less the plants that refused ``scene`` after ``check_scene`` accepted it (their
    ``pointwise`` raised the ``ValueError`` of a refusal: ``(engine, one-line reason)`` each). Of a
    default set or ``--plants all`` each is left out with one warning, as :func:`accepting_plants`
    does; a named plant's refusal refuses the run.

    Raises:
        ValueError: the first named plant's refusal (``<plant>: <reason>``), or fewer than two
            plants left.
    """
    if not refused:
        return choice
    if choice.named:
        engine, why = refused[0]
        raise ValueError(f"{engine}: {why}")
    gone = [LeftOut(str(e), why) for e, why in refused]
    for x in gone:
        warnings.warn(str(x), stacklevel=2)
    names = {x.engine for x in gone}
    plants = tuple(e for e in choice.plants if e not in names)
    if len(plants) < 2:
        raise ValueError(
            f"plants: fewer than two of the plants can run {scene.name!r} "
            f"({', '.join(plants) or 'none'}); nothing to compare"
        )
    return PlantChoice(plants, (*choice.left_out, *gone))


def validation_plants(
    plants: Sequence[Engine | str] | str | None, scene: Scene | None = None
) -> tuple[str, ...]:
    """:attr:`PlantChoice.plants` of :func:`plant_choice` (same arguments, warnings, errors)."""
    return plant_choice(plants, scene).plants


__all__ = [
    "LeftOut",
    "PlantChoice",
    "accepting_plants",
    "check_validation_inputs",
    "plant_choice",
    "validation_plants",
    "without_refusals",
]
