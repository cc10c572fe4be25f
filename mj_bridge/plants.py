"""The engine plants behind :class:`analytic.plant.Plant`, and the registry of every plant.

* :class:`MujocoPlant`: the MJCF twin (:mod:`model_xml`) stepped by MuJoCo, the analytic controller
  inside every integrator stage (:func:`mj_bridge.simulate.simulate`);
* :class:`PinocchioPlant`: the same body in Pinocchio, ``aba`` integrated by scipy in Pinocchio's
  coordinates, the same controller (:func:`mj_bridge.pinocchio_plant.simulate`); optional
  (``pip install ".[pinocchio]"``), the referee when the other two disagree.

:func:`plant` gives a plant by name, :func:`installed_plants` the ones this installation can run.
"""

from __future__ import annotations

import importlib.util

from analytic.plant import AnalyticPlant, AnalyticSettings, Plant
from analytic.scene import Scene
from analytic.trajectory import Engine, Trajectory
from mj_bridge.mujoco_settings import MujocoRunSettings
from mj_bridge.pinocchio_settings import (
    PINOCCHIO_MAX_MASSES,
    PinocchioSettings,
    check_pinocchio_size,
)


class MujocoPlant(Plant):
    """The MuJoCo twin under the analytic controller."""

    engine = Engine.MUJOCO
    label = "MuJoCo"
    settings_type = MujocoRunSettings

    def default_settings(self, scene: Scene) -> MujocoRunSettings:
        return MujocoRunSettings(scene.mujoco.integrator, scene.mujoco.timestep)

    def describe(self, settings: MujocoRunSettings) -> str:
        return f"MuJoCo {settings.integrator.value} dt {settings.dt:g} s"

    def _simulate(self, scene, settings, t_end, progress) -> Trajectory:
        from mj_bridge.simulate import simulate

        return simulate(
            scene,
            integrator=settings.integrator,
            dt=settings.dt,
            t_end=t_end,
            controller=settings.controller,
            progress=progress,
            native_callback=settings.native_callback,
        )


class PinocchioPlant(Plant):
    """The same body in Pinocchio (optional engine: the referee)."""

    engine = Engine.PINOCCHIO
    label = "Pinocchio"
    settings_type = PinocchioSettings

    @classmethod
    def unavailable(cls) -> str:
        if importlib.util.find_spec("pinocchio") is None:
            return (
                "the Pinocchio plant needs the 'pin' package (>= 4.1): "
                "pip install 'pin>=4.1' (the [pinocchio] extra)"
            )
        return ""

    def check_scene(self, scene: Scene) -> None:
        """The effects (as every plant), and at most :data:`PINOCCHIO_MAX_MASSES` masses."""
        super().check_scene(scene)
        check_pinocchio_size(scene)

    def default_settings(self, scene: Scene) -> PinocchioSettings:
        return PinocchioSettings(scene.solver.method, scene.solver.rtol, scene.solver.atol)

    def describe(self, settings: PinocchioSettings) -> str:
        rtol = "the scene's" if settings.rtol is None else f"{settings.rtol:g}"
        return f"Pinocchio {settings.method.value} rtol {rtol}"

    def _simulate(self, scene, settings, t_end, progress) -> Trajectory:
        from mj_bridge.pinocchio_plant import simulate

        return simulate(scene, settings, t_end=t_end, progress=progress)


PLANTS: dict[Engine, type[Plant]] = {
    Engine.ANALYTIC: AnalyticPlant,
    Engine.MUJOCO: MujocoPlant,
    Engine.PINOCCHIO: PinocchioPlant,
}
"""Every plant, in report order (the analytic plant first: relative checks use its scales)."""


def plant(name: Engine | str) -> Plant:
    """The plant called ``name`` (``analytic``, ``mujoco``, ``pinocchio``)."""
    try:
        return PLANTS[Engine(name)]()
    except (ValueError, KeyError):  # KeyError: an engine not registered here (drake, for now)
        raise ValueError(
            f"plants: unknown plant {name!r} (known: {', '.join(e.value for e in PLANTS)})"
        ) from None


def plants_for_scene(scene: Scene, engines: tuple[Engine, ...]) -> tuple[Engine, ...]:
    """Those of ``engines`` whose :meth:`~analytic.plant.Plant.check_scene` accepts ``scene`` (a
    default plant set without the ones that cannot run this scene, e.g. Pinocchio beyond
    :data:`PINOCCHIO_MAX_MASSES` masses), in the same order."""
    out = []
    for e in engines:
        try:
            plant(e).check_scene(scene)
        except ValueError:
            continue
        out.append(e)
    return tuple(out)


def installed_plants() -> tuple[Engine, ...]:
    """The plants this installation can run, in report order."""
    return tuple(e for e, cls in PLANTS.items() if not cls.unavailable())


def parse_plants(text: str) -> tuple[Engine, ...]:
    """``"analytic,mujoco"`` -> plants in report order; ``ValueError`` naming ``plants``."""
    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names:
        raise ValueError(f"plants: give at least one plant (got {text!r})")
    chosen = {plant(n).engine for n in names}
    for e in chosen:
        why = PLANTS[e].unavailable()
        if why:
            raise ValueError(f"plants: {e.value} is not installed ({why})")
    return tuple(e for e in PLANTS if e in chosen)


__all__ = [
    "PINOCCHIO_MAX_MASSES",
    "PLANTS",
    "AnalyticPlant",
    "AnalyticSettings",
    "MujocoPlant",
    "MujocoRunSettings",
    "PinocchioPlant",
    "PinocchioSettings",
    "check_pinocchio_size",
    "installed_plants",
    "parse_plants",
    "plant",
    "plants_for_scene",
]
