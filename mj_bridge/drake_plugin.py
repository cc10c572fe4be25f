"""The Drake plant behind the plant protocol, as the plant plugin ``drake``: the class the project's
own entry point names (``pyproject.toml``, group ``tumbling_testbed.plants``).

Light on purpose: the registry imports this module whenever the plants are listed (to read
``default`` and ``unavailable``), so it imports neither Drake nor the integration
(:mod:`mj_bridge.drake_plant`: ~0.58 s of numba and kernels, measured after ``tumble validate``'s own
imports); :meth:`DrakePlant._simulate` imports that when it runs. Not a default plant
(``default = False``): ``--plants analytic,mujoco,drake`` or ``--plants all`` runs it.
"""

from __future__ import annotations

from analytic.effects import Effect
from analytic.plant import Plant
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from mj_bridge.drake_settings import DrakeSettings, drake_unavailable
from mj_bridge.scipy_loop_settings import tightened_scipy_loop

SUPPORTED_EFFECTS = frozenset(Effect)
"""Every effect of :class:`analytic.effects.Effect`: gravity is Drake's gravity field, the mass
inertias are the bodies' inertias, the springs, the given torque and the control (ω and/or any
subset of the masses, any weighting) are generalized forces."""


class DrakePlant(Plant):
    """The same body in Drake (:mod:`mj_bridge.drake_plant`; optional engine, a plugin, not among
    the default plants)."""

    engine = "drake"
    label = "Drake"
    default = False
    effects = SUPPORTED_EFFECTS
    settings_type = DrakeSettings

    @classmethod
    def unavailable(cls) -> str:
        return drake_unavailable()

    def default_settings(self, scene: Scene) -> DrakeSettings:
        return DrakeSettings(scene.solver.method, scene.solver.rtol, scene.solver.atol)

    def describe(self, settings: DrakeSettings) -> str:
        rtol = "the scene's" if settings.rtol is None else f"{settings.rtol:g}"
        return f"Drake {settings.method.value} rtol {rtol}"

    def tightened(self, scene: Scene, settings: DrakeSettings) -> DrakeSettings | None:
        return tightened_scipy_loop(scene, settings)

    def _simulate(self, scene, settings, t_end, progress) -> Trajectory:
        from mj_bridge.drake_plant import simulate

        return simulate(scene, settings, t_end=t_end, progress=progress)


__all__ = ["SUPPORTED_EFFECTS", "DrakePlant", "DrakeSettings"]
