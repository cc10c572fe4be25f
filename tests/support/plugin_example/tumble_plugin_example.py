"""An example plant plugin: the analytic plant's integration, run under the name ``echo``.

The smallest complete plant: a frozen settings dataclass, the class attributes the registry checks
(``engine`` equal to the entry point's name, ``label``, ``settings_type``), the ``effects`` it
simulates (a plant claims none it does not list), ``default_settings``,
``describe`` and ``_simulate``, which returns a :class:`analytic.trajectory.Trajectory` in the
paper's coordinates on the scene's output grid. A real plugin would integrate its own engine here
and map its state to ``q = [R, u (w first), p]`` (``docs/plugins.md``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from analytic.effects import SolverMethod
from analytic.plant import AnalyticPlant, AnalyticSettings, Plant, check_positive, coerce_enum


@dataclass(frozen=True)
class EchoSettings:
    """How the echo plant integrates: a scipy method and its tolerances."""

    method: SolverMethod = SolverMethod.DOP853
    rtol: float = 1e-12
    atol: float = 1e-13

    def __post_init__(self) -> None:  # bad settings: a ValueError naming the field
        coerce_enum(self, "method", SolverMethod)
        check_positive(self, "rtol")
        check_positive(self, "atol")


class EchoPlant(Plant):
    """The analytic plant's motion, reported as the plant ``echo``."""

    engine = "echo"
    label = "Echo"
    settings_type = EchoSettings
    effects = AnalyticPlant.effects  # what it runs: the analytic plant's

    def default_settings(self, scene):
        return EchoSettings(scene.solver.method, scene.solver.rtol, scene.solver.atol)

    def describe(self, settings: EchoSettings) -> str:
        return f"Echo {settings.method.value} rtol {settings.rtol:g}"

    def _simulate(self, scene, settings, t_end, progress):
        inner = AnalyticSettings(settings.method, settings.rtol, settings.atol, stepper="scipy")
        tr = AnalyticPlant().simulate(scene, inner, t_end=t_end, progress=progress)
        return dataclasses.replace(tr, engine=self.engine, info={**tr.info, "echo": True})
