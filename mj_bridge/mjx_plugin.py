"""The MJX plant behind the plant protocol, as the plant plugin ``mjx``: MuJoCo's MJX (JAX) on the
C plant's own twin, under the project's controller in every RK4 stage.

Light on purpose, like :mod:`mj_bridge.drake_plugin`: the registry imports this module whenever
the plants are listed, so it imports neither JAX nor MJX nor the integration
(:mod:`mj_bridge.mjx_plant`); every run, batch and pointwise evaluation is done by that module in
a fresh spawned process (:func:`mj_bridge.accelerated.run_isolated`: JAX does not survive a
fork, and its x64 mode is process-wide, so float32 and float64 never share a process). Not a
default plant: ``--plants analytic,mujoco,mjx`` or ``--plants all`` runs it.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata

import numpy as np

from analytic.effects import Effect, MjIntegrator, SpringModel
from analytic.plant import TIGHTER_STEP, Plant
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from mj_bridge.mjx_settings import MjxController, MjxSettings, mjx_unavailable
from mj_bridge.plan import plan_steps
from model_xml.tendon_terms import TWIN_EFFECTS


def mjx_version() -> str:
    """The installed ``mujoco-mjx`` version (from its metadata: nothing imported), or "?"."""
    try:
        return importlib.metadata.version("mujoco-mjx")
    except importlib.metadata.PackageNotFoundError:
        return "?"


class MjxPlant(Plant):
    """MJX on the C plant's twin (:mod:`mj_bridge.mjx_plant`), float32 or float64, batched
    natively (``jax.vmap`` over scenes of one structure)."""

    engine = "mjx"
    label = "MJX"
    default = False
    batched = True
    effects = TWIN_EFFECTS  # the C plant's twin and control channels
    """What the C plant's twin holds and the stages apply (the same list as the MuJoCo plant's):
    a law MJX then leaves out (its cubic tendon stiffness) is a difference of the engine, found
    by the comparison and named in the run's ``info["dropped_fields"]``, never hidden."""
    settings_type = MjxSettings

    @classmethod
    def unavailable(cls) -> str:
        return mjx_unavailable()

    def default_settings(self, scene: Scene) -> MjxSettings:
        return MjxSettings.from_table(scene.extra.get("mjx"), scene.mujoco.timestep)

    def describe(self, settings: MjxSettings) -> str:
        device = settings.device or "JAX's default device"
        dt = "the scene's step" if settings.timestep is None else f"dt {settings.timestep:g} s"
        host = ", host controller" if settings.controller is MjxController.HOST else ""
        return f"MJX {mjx_version()} {settings.precision.value} on {device} RK4 {dt}{host}"

    def tightened(self, scene: Scene, settings: MjxSettings) -> MjxSettings:
        dt = scene.mujoco.timestep if settings.timestep is None else settings.timestep
        return dataclasses.replace(settings, timestep=dt / TIGHTER_STEP)

    def check_scene(self, scene: Scene) -> None:
        """The effects (as every plant), then what this plant's stages cannot run: an integrator
        other than RK4 (the plant runs MuJoCo's RK4 around MJX's forward dynamics) and the spring
        actuators' cubic term (MuJoCo's ``mjcb_act_bias`` callback, which MJX has no place for)."""
        super().check_scene(scene)
        integ = MjIntegrator(scene.mujoco.integrator)
        if integ is not MjIntegrator.RK4:
            raise ValueError(
                f"mujoco.integrator: the mjx plant integrates with MuJoCo's RK4 only, its stages "
                f"around MJX's forward dynamics (got {integ.value!r})"
            )
        if SpringModel(scene.mujoco.spring_model) is SpringModel.ACTUATOR and (
            scene.has(Effect.SPRINGS_CUBIC) and np.any(np.asarray(scene.springs.k_cubic) != 0)
        ):
            raise ValueError(
                "mujoco.spring_model: 'actuator' with cubic springs needs MuJoCo's user-bias "
                "callback (mjcb_act_bias), which MJX has no place for; use 'tendon'"
            )

    def _plan(self, scene: Scene, settings: MjxSettings, t_end: float | None) -> None:
        """The step against the output grid, checked here before a process starts."""
        plan_steps(scene, MjIntegrator.RK4, settings.timestep, t_end)

    def _simulate(self, scene, settings, t_end, progress) -> Trajectory:
        self._plan(scene, settings, t_end)
        return self._simulate_batch([scene], settings, t_end, progress)[0]

    def _simulate_batch(self, scenes, settings, t_end, progress) -> list[Trajectory]:
        for i, scene in enumerate(scenes):
            try:
                self._plan(scene, settings, t_end)
            except ValueError as exc:
                raise ValueError(f"scenes[{i}]: {exc}" if len(scenes) > 1 else str(exc)) from None
        from mj_bridge import mjx_plant
        from mj_bridge.accelerated import run_isolated

        return run_isolated(
            mjx_plant.simulate_runs, list(scenes), settings, t_end, progress=progress
        )

    def pointwise(self, scene, settings, t, q, qdot) -> np.ndarray:
        self.check_scene(scene)
        from mj_bridge import mjx_plant
        from mj_bridge.accelerated import run_isolated

        return run_isolated(
            mjx_plant.pointwise,
            scene,
            settings,
            np.asarray(t, float),
            np.asarray(q, float),
            np.asarray(qdot, float),
        )


__all__ = ["MjxController", "MjxPlant", "MjxSettings", "mjx_version"]
