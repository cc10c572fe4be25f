"""The MuJoCo Warp plant behind the plant protocol, as the plant plugin ``mjwarp``: the class the
project's own entry point names (``pyproject.toml``, group ``tumbling_testbed.plants``).

MuJoCo Warp (``mujoco_warp``, on NVIDIA Warp) runs the twin the C plant runs (the MJCF of
:mod:`model_xml`, only the energy flag off: :func:`mj_bridge.accelerated.accelerated_twin`), in
float32, many worlds at once, on Warp's device (CUDA where Warp sees one, else the CPU). The
engine work is :mod:`mj_bridge.warp_plant`; every call of it (:meth:`WarpPlant._simulate`,
:meth:`WarpPlant._simulate_batch`, :meth:`WarpPlant.pointwise`) runs in a fresh spawned process
(:func:`mj_bridge.accelerated.run_isolated`): Warp and a CUDA context do not survive a fork, so
this module imports neither (the registry imports it whenever the plants are listed).

Not a default plant (``default = False``): ``--plants analytic,mujoco,mjwarp`` or ``--plants
all`` runs it. ``batched = True``: a batch of scenes of one structure is one ``nworld`` run.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from analytic.effects import Precision
from analytic.plant import TIGHTER_STEP, Plant
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from mj_bridge.warp_settings import (
    DEVICE_AUTO,
    ENGINE,
    WarpSettings,
    warp_unavailable,
    warp_version,
)
from model_xml.tendon_terms import TWIN_EFFECTS


class WarpPlant(Plant):
    """MuJoCo Warp on the C plant's twin, float32, under the project's controller in every stage
    (:mod:`mj_bridge.warp_plant`); optional engine, a plugin, not among the default plants."""

    engine = ENGINE
    label = "MuJoCo Warp"
    default = False
    batched = True
    effects = TWIN_EFFECTS  # the C plant's twin and control channels
    """The C plant's effects: the same twin (its spring laws :data:`TENDON_TERMS`, as tendons or
    as spring actuators, whose cubic term Warp's ``act_bias`` callback computes as the C plant's
    ``mjcb_act_bias`` does) and the same control channels, applied by Warp's control callback."""
    settings_type = WarpSettings
    precision = Precision.FLOAT32

    @classmethod
    def unavailable(cls) -> str:
        return warp_unavailable()

    def default_settings(self, scene: Scene) -> WarpSettings:
        return WarpSettings(timestep=float(scene.mujoco.timestep))

    def describe(self, settings: WarpSettings) -> str:
        dt = "the scene's dt" if settings.timestep is None else f"dt {settings.timestep:g} s"
        device = settings.device or "auto device (CUDA if Warp sees one, else cpu)"
        return f"MuJoCo Warp {warp_version()} float32 {dt} on {device}"

    def tightened(self, scene: Scene, settings: WarpSettings) -> WarpSettings:
        dt = scene.mujoco.timestep if settings.timestep is None else settings.timestep
        return dataclasses.replace(settings, timestep=float(dt) / TIGHTER_STEP)

    def _simulate(self, scene, settings, t_end, progress) -> Trajectory:
        return self._simulate_batch([scene], settings, t_end, progress)[0]

    def _simulate_batch(self, scenes, settings, t_end, progress) -> list[Trajectory]:
        from mj_bridge.accelerated import run_isolated
        from mj_bridge.warp_plant import run_batch

        return run_isolated(
            run_batch, list(scenes), settings.timestep, settings.device, t_end,
            progress=progress,
        )  # fmt: skip

    def pointwise(self, scene, settings, t, q, qdot) -> np.ndarray:
        from mj_bridge.accelerated import run_isolated
        from mj_bridge.warp_plant import pointwise_qddot

        self.check_scene(scene)  # the effects
        settings = self.default_settings(scene) if settings is None else settings
        t = np.atleast_1d(np.asarray(t, dtype=float))
        q, qdot = np.atleast_2d(np.asarray(q, float)), np.atleast_2d(np.asarray(qdot, float))
        if not (len(t) == len(q) == len(qdot) and math.prod(q.shape) and q.shape == qdot.shape):
            raise ValueError(
                f"q: pointwise takes t (N,), q and qdot (N, n+7) of one N "
                f"(got {t.shape}, {q.shape}, {qdot.shape})"
            )
        return run_isolated(pointwise_qddot, scene, settings.timestep, settings.device, t, q, qdot)


__all__ = ["DEVICE_AUTO", "ENGINE", "WarpPlant", "WarpSettings", "warp_unavailable"]
