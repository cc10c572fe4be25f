"""The plant class of an engine on scipy's loop (Pinocchio, Drake, the next one): the protocol's
bookkeeping they share, and the effects each claims, derived from the code that implements them.

A plant on scipy's loop simulates exactly these effects (:func:`scipy_loop_effects`):

* the ones its engine builds into its model, one function each: the keys of the engine's own
  table (``mj_bridge.pinocchio_effects.EFFECTS``, ``mj_bridge.drake_effects.EFFECTS``), which the
  subclass names as :attr:`ScipyLoopPlant.model_effects`;
* the generalized forces the shared stage applies, one function each
  (:data:`mj_bridge.scipy_forces.FORCES`);
* the control effects (:data:`analytic.effects.CONTROL_EFFECTS`): the controller's, applied by the
  shared stage.

So a new effect is claimed when its function exists, never before; a subclass that sets
``effects`` to claim more is refused when the class is made (``TypeError``).

Light on purpose (no engine, no numba): the registry imports the plants' classes whenever the
plants are listed; :meth:`ScipyLoopPlant._simulate` imports the integration module
(:attr:`ScipyLoopPlant.integration`) when it runs.
"""

from __future__ import annotations

import importlib
from collections.abc import Collection
from typing import Any, ClassVar

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.plant import Plant, Progress
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from mj_bridge.scipy_forces import FORCE_EFFECTS
from mj_bridge.scipy_loop_settings import ScipyLoopSettings, tightened_scipy_loop


def scipy_loop_effects(model_effects: Collection[Effect]) -> frozenset[Effect]:
    """The effects a plant on scipy's loop simulates whose engine builds ``model_effects`` into its
    model (the module docstring)."""
    return frozenset(model_effects) | FORCE_EFFECTS | CONTROL_EFFECTS


class ScipyLoopPlant(Plant):
    """A plant whose engine's dynamics :mod:`mj_bridge.scipy_plant` steps on scipy's loop.

    Class attributes a subclass sets (besides ``engine``, ``label``, ``settings_type``, a
    :class:`~mj_bridge.scipy_loop_settings.ScipyLoopSettings` subclass):
        model_effects: the effects its engine builds into its model (its table's keys);
            ``effects`` is derived from them (:func:`scipy_loop_effects`).
        integration: the module whose ``simulate(scene, settings, t_end=, progress=)`` runs it.
    """

    model_effects: ClassVar[Collection[Effect]] = ()
    integration: ClassVar[str]
    settings_type: ClassVar[type[ScipyLoopSettings]]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        implemented = scipy_loop_effects(cls.model_effects)
        if "effects" in cls.__dict__:
            extra = sorted(e.value for e in frozenset(cls.effects) - implemented)
            if extra:
                raise TypeError(
                    f"{cls.__name__}.effects claims {', '.join(extra)}, which no function of its "
                    "engine's table nor of mj_bridge.scipy_forces implements"
                )
        else:
            cls.effects = implemented

    def default_settings(self, scene: Scene) -> ScipyLoopSettings:
        return self.settings_type(scene.solver.method, scene.solver.rtol, scene.solver.atol)

    def describe(self, settings: ScipyLoopSettings) -> str:
        rtol = "the scene's" if settings.rtol is None else f"{settings.rtol:g}"
        return f"{self.label} {settings.method.value} rtol {rtol}"

    def tightened(self, scene: Scene, settings: ScipyLoopSettings) -> ScipyLoopSettings | None:
        return tightened_scipy_loop(scene, settings)

    def _simulate(
        self,
        scene: Scene,
        settings: ScipyLoopSettings,
        t_end: float | None,
        progress: Progress | None,
    ) -> Trajectory:
        run = importlib.import_module(self.integration).simulate
        return run(scene, settings, t_end=t_end, progress=progress)


__all__ = ["ScipyLoopPlant", "scipy_loop_effects"]
