"""Plants that offer ``pointwise`` (as the accelerated engines do), for the pointwise check's tests.

Each is a plugin_example-style plant (``tests/support/plugin_example``): a frozen settings
dataclass, the class attributes the registry checks, ``default_settings``, ``describe``,
``_simulate`` (the analytic plant's run), and a ``pointwise`` that is the analytic model's ``q̈``:

* :class:`DroppedTermPlant` (``dropterm``): the analytic model with :data:`DROPPED` switched off,
  as an engine that ignores one field of the model would be;
* :class:`HalfTermPlant` (``halfterm``): the analytic model with :data:`DROPPED` at half its
  strength (the mean of the two models' ``q̈``: uncontrolled, ``q̈`` is linear in the forces);
* :class:`ExactPlant` (``exact``): the analytic model as it is, no finding;
* :class:`RefusingPlant` (``refusing``): ``pointwise`` refuses every scene with a ``ValueError``
  naming a field, as an engine that rejects a field of the model does.

Their ``precision`` setting is the precision the check assumes they compute in (the arithmetic
itself is float64).
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np

from analytic.effects import Effect
from analytic.model import TumblingModel
from analytic.plant import AnalyticPlant, AnalyticSettings, Plant
from analytic.scene.dump import modified_scene

DROPPED = Effect.SPRINGS_CUBIC
"""The term :class:`DroppedTermPlant` leaves out of its model."""

REFUSAL = "scene.springs.k_cubic: this engine has no cubic stiffness"
"""What :class:`RefusingPlant`'s ``pointwise`` raises."""


@dataclass(frozen=True)
class PointwiseSettings:
    """The precision the plant states it computes in."""

    precision: str = "float64"


def without_dropped(scene):
    """``scene`` without :data:`DROPPED` (itself when it does not simulate it)."""
    if DROPPED not in scene.effects:
        return scene
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        keep = [e.value for e in scene.effects if e is not DROPPED]
        return modified_scene(scene, {"scene": {"effects": keep}})


def analytic_qddot(scene, t, q, qdot) -> np.ndarray:
    """The analytic model's ``q̈`` at N states, shape (N, nq)."""
    model = TumblingModel(scene)
    return np.array([model.acceleration(*s)[0] for s in zip(t, q, qdot, strict=True)])


class _AnalyticRun(Plant):
    """The analytic plant's run under this plant's name (of the scene :meth:`modelled`)."""

    settings_type = PointwiseSettings
    effects = AnalyticPlant.effects
    default = False

    def modelled(self, scene):
        return scene

    def default_settings(self, scene):
        return PointwiseSettings()

    def describe(self, settings: PointwiseSettings) -> str:
        return f"{self.label} ({settings.precision})"

    def _simulate(self, scene, settings, t_end, progress):
        inner = AnalyticSettings(stepper="scipy")
        tr = AnalyticPlant().simulate(self.modelled(scene), inner, t_end=t_end, progress=progress)
        return dataclasses.replace(tr, engine=self.engine)

    def pointwise(self, scene, settings, t, q, qdot):
        return analytic_qddot(self.modelled(scene), t, q, qdot)


class DroppedTermPlant(_AnalyticRun):
    """The analytic model without :data:`DROPPED`."""

    engine = "dropterm"
    label = "Dropped term"

    def modelled(self, scene):
        return without_dropped(scene)


class HalfTermPlant(_AnalyticRun):
    """The analytic model with :data:`DROPPED` at half strength (its ``pointwise`` only)."""

    engine = "halfterm"
    label = "Half term"

    def pointwise(self, scene, settings, t, q, qdot):
        full = analytic_qddot(scene, t, q, qdot)
        return 0.5 * (full + analytic_qddot(without_dropped(scene), t, q, qdot))


class ExactPlant(_AnalyticRun):
    """The analytic model as it is."""

    engine = "exact"
    label = "Exact"


class RefusingPlant(_AnalyticRun):
    """A plant whose ``pointwise`` refuses every scene."""

    engine = "refusing"
    label = "Refusing"

    def pointwise(self, scene, settings, t, q, qdot):
        raise ValueError(REFUSAL)


POINTWISE_PLANTS = {
    p.engine: p for p in (DroppedTermPlant, HalfTermPlant, ExactPlant, RefusingPlant)
}
"""The plants of this module by name, as the registry holds plugins."""
