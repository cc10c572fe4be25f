"""The Drake plant behind the plant protocol, as the plant plugin ``drake``: the class the project's
own entry point names (``pyproject.toml``, group ``tumbling_testbed.plants``).

Light on purpose: the registry imports this module whenever the plants are listed (to read
``default``, ``effects`` and ``unavailable``), so it imports neither Drake nor the integration
(:mod:`mj_bridge.drake_plant`, numba and the kernels: ``docs/performance.md``);
:meth:`DrakePlant._simulate` imports that when it runs. Not a default plant
(``default = False``): ``--plants analytic,mujoco,drake`` or ``--plants all`` runs it.
"""

from __future__ import annotations

from mj_bridge.drake_effects import EFFECTS as DRAKE_EFFECTS
from mj_bridge.drake_settings import DrakeSettings, drake_unavailable
from mj_bridge.scipy_loop_plant import ScipyLoopPlant


class DrakePlant(ScipyLoopPlant):
    """The same body in Drake (:mod:`mj_bridge.drake_plant`; optional engine, a plugin, not among
    the default plants). Its effects: gravity and the masses' inertia are Drake's model
    (:mod:`mj_bridge.drake_effects`), the springs and the given torque generalized forces
    (:mod:`mj_bridge.scipy_forces`), the control (ω and/or any subset of the masses, any
    weighting) the controller's."""

    engine = "drake"
    label = "Drake"
    default = False
    model_effects = frozenset(DRAKE_EFFECTS)
    settings_type = DrakeSettings
    integration = "mj_bridge.drake_plant"

    @classmethod
    def unavailable(cls) -> str:
        return drake_unavailable()


__all__ = ["DrakePlant", "DrakeSettings"]
