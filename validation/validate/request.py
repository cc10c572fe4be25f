"""A validation's first step: its whole input checked, once, into a frozen request, and the
request's plants made ready to run.

:func:`validation_request` checks everything (scene, thresholds, plants, overrides, figure
formats, time limit) into a :class:`ValidationRequest`, which the job trusts; it runs no plant,
only the pointwise check of the plants that offer one (:mod:`validation.validate.pointwise`: their
``q̈`` at a few states against MuJoCo C's and the analytic model's, in seconds, before any run).
:func:`prepared_plants` gives each plant of a request its settings and its one-line
description; a plant whose ``check_scene`` (with anything but the ``ValueError`` of a refusal),
``default_settings`` or ``describe`` raises fails alone, in one line naming it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.scene import Scene
from analytic.threshold import Threshold
from analytic.trajectory import Engine
from mj_bridge.plants import MujocoRunSettings, plant
from validation.compare.pointwise import PointwiseCheck
from validation.compare.thresholds import thresholds_for
from validation.preflight import LeftOut, check_validation_inputs, plant_choice, without_refusals
from validation.report.figures import DEFAULT_FORMATS, FigureFormat, parse_formats
from validation.runs.contract import plant_scene
from validation.runs.plant_runs import PlantRun, check_time_limit, plant_time_limit
from validation.scenes import resolve_scene, with_threshold_overrides
from validation.validate.pointwise import check_pointwise


@dataclass(frozen=True)
class ValidationRequest:
    """A validation's input, checked whole by :func:`validation_request` before any plant runs.

    Attributes:
        scene: the scene (checked: fields, ``[thresholds]``; every plant accepts it).
        thresholds: name -> threshold in force (the comparison's).
        plants: the plants, in report order, at least two, each once.
        integrator: MuJoCo integrator override (None: the scene's).
        dt: MuJoCo time step override, s (None: the scene's).
        t_end: horizon override, s (None: the scene's).
        horizon: the horizon in force, s.
        figure_formats: the figures' file formats, each once.
        left_out: the plants of the default set or of ``--plants all`` that refused the scene,
            each with its reason (the report's referee note names them).
        time_limit: the wall-time limit of each plant's run, s (None: :func:`plant_time_limit`'s
            defaults).
        unusable: plant -> why it cannot be run (its ``check_scene`` raised something other than
            the ``ValueError`` of a refusal): that plant fails alone, the others run.
        pointwise: the pointwise check of the plants that offer one
            (:func:`validation.validate.pointwise.check_pointwise`), made before any run.
    """

    scene: Scene
    thresholds: Mapping[str, Threshold]
    plants: tuple[str, ...]
    integrator: Any
    dt: float | None
    t_end: float | None
    horizon: float
    figure_formats: tuple[FigureFormat, ...]
    left_out: tuple[LeftOut, ...] = ()
    time_limit: float | None = None
    unusable: Mapping[str, str] = field(default_factory=dict)
    pointwise: PointwiseCheck = field(default_factory=PointwiseCheck)

    def limit_of(self, engine: str) -> float | None:
        """Plant ``engine``'s wall-time limit, s (:func:`plant_time_limit`)."""
        return plant_time_limit(engine, self.time_limit)


def checked_formats(formats: Sequence[FigureFormat | str] | str) -> tuple[FigureFormat, ...]:
    """The formats as enums, once each; ValueError naming ``figure_format`` (before any work)."""
    if isinstance(formats, str):
        return parse_formats(formats)
    out = parse_formats(",".join(str(getattr(f, "value", f)) for f in formats)) if formats else ()
    if not out:
        raise ValueError("figure_format: at least one format is needed (got none)")
    return out


def validation_request(
    scene: Scene | str | Path | None,
    *,
    plants: Sequence[Engine | str] | str | None = None,
    integrator: Any = None,
    dt: float | None = None,
    t_end: float | None = None,
    figure_formats: Sequence[FigureFormat | str] | str = DEFAULT_FORMATS,
    thresholds: Mapping[str, Any] | None = None,
    time_limit: float | None = None,
) -> ValidationRequest:
    """Check a validation's whole input, once: the scene (a :class:`Scene` as given, else
    :func:`validation.scenes.resolve_scene`) with ``thresholds`` (overrides, name -> number or
    ``{value, reason}``) laid over its ``[thresholds]``, and those thresholds
    (:func:`validation.compare.thresholds.thresholds_for`); the plants
    (:func:`~validation.preflight.validation_plants`); the overrides (:func:`check_validation_inputs`); the figure
    formats; the time limit (:func:`check_time_limit`); and that every plant accepts the scene
    (its ``check_scene``; one that raises anything but ``ValueError`` is noted ``unusable``, to
    fail alone). Runs no plant; then the plants that offer ``pointwise`` (the accelerated
    engines) are compared with MuJoCo C and the analytic model at a few states
    (:func:`validation.validate.pointwise.check_pointwise`, seconds; each finding one warning),
    and one whose ``pointwise`` refuses the scene is treated as a ``check_scene`` refusal
    (:func:`validation.preflight.without_refusals`).

    Raises:
        ValueError: naming the field and the value (scene, thresholds, plants, integrator, dt,
            t_end, figure_format, time_limit).
    """
    if not isinstance(scene, Scene):
        scene = resolve_scene(scene, check_thresholds=False)  # checked below, once
    sc = with_threshold_overrides(scene, thresholds)
    checked_thresholds = thresholds_for(sc)
    choice = plant_choice(plants, sc)
    chosen = choice.plants
    check_validation_inputs(
        sc, integrator=integrator, dt=dt, t_end=t_end, mujoco=Engine.MUJOCO in chosen
    )
    formats = checked_formats(figure_formats)
    if t_end is not None and not (t_end > 0):
        raise ValueError(f"t_end: must be a positive time in s (got {t_end!r})")
    limit = check_time_limit(time_limit)
    unusable: dict[str, str] = {}
    for e in chosen:
        try:
            plant(e).check_scene(plant_scene(sc))
        except ValueError:
            raise  # the plant refuses the scene: bad input
        except Exception as exc:  # a plant's own bug: that plant fails alone
            unusable[e] = f"check_scene raised {one_line(exc)}"
    horizon = float(t_end) if t_end is not None else sc.output.t_end
    pointwise = check_pointwise(
        plant_scene(sc),
        [e for e in chosen if e not in unusable],
        lambda e: _plant_settings(e, plant_scene(sc), integrator, dt),
        horizon,
    )
    choice = without_refusals(choice, pointwise.refused, sc)
    chosen = choice.plants
    return ValidationRequest(
        scene=sc,
        thresholds=checked_thresholds,
        plants=tuple(chosen),
        integrator=integrator,
        dt=dt,
        t_end=t_end,
        horizon=horizon,
        figure_formats=formats,
        left_out=choice.left_out,
        time_limit=limit,
        unusable=unusable,
        pointwise=pointwise.check,
    )


def one_line(exc: BaseException) -> str:
    """``TypeName: first line of the message``."""
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


@dataclass(frozen=True)
class PreparedPlants:
    """A request's plants ready to run (:func:`prepared_plants`).

    Attributes:
        runs: each plant that can run, with its settings and its time limit, in report order.
        names: plant -> its one-line description (how the report names its settings).
        refused: one line for each plant that cannot run, naming it and why.
    """

    runs: tuple[PlantRun, ...]
    names: Mapping[str, str]
    refused: tuple[str, ...]


def prepared_plants(request: ValidationRequest) -> PreparedPlants:
    """Each plant of ``request`` with its settings, its time limit and its one-line description,
    in order, and the failures of those that cannot run: ``unusable`` ones, and those whose
    ``default_settings`` or ``describe`` raises (or describes itself with no text)."""
    runs: list[PlantRun] = []
    names: dict[str, str] = {}
    refused: list[str] = []
    for e in request.plants:
        pl = plant(e)
        if e in request.unusable:
            refused.append(f"{pl.label} plant: not run: {request.unusable[e]}")
            continue
        call = "default_settings"
        try:  # a plant's own bug in either: that plant fails alone
            settings = _plant_settings(
                e, plant_scene(request.scene), request.integrator, request.dt
            )
            call = "describe"
            name = pl.describe(settings)
        except Exception as exc:
            refused.append(f"{pl.label} plant: not run: {call} raised {one_line(exc)}")
            continue
        if not (isinstance(name, str) and name.strip()):
            refused.append(
                f"{pl.label} plant: not run: describe returned {name!r}, not a line of text"
            )
            continue
        runs.append(PlantRun(pl, settings, request.limit_of(pl.engine)))
        names[pl.engine] = name.splitlines()[0]
    return PreparedPlants(tuple(runs), names, tuple(refused))


def _plant_settings(engine: str, sc: Scene, integrator: Any, dt: float | None) -> Any:
    """Each plant's settings: the scene's, with the MuJoCo overrides of the command line."""
    if engine == Engine.MUJOCO:
        return MujocoRunSettings(
            sc.mujoco.integrator if integrator is None else integrator,
            sc.mujoco.timestep if dt is None else dt,
        )
    return plant(engine).default_settings(sc)


__all__ = [
    "PreparedPlants",
    "ValidationRequest",
    "checked_formats",
    "one_line",
    "prepared_plants",
    "validation_request",
]
