"""The plant protocol's effects: a plant claims exactly the effects it lists (none by default), so
an effect no code of a plant implements is never claimed by it."""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.plant import AnalyticPlant, AnalyticSettings, Plant
from analytic.scene.random_scenes import random_scene


class Bare(Plant):
    """A plant that lists no effects."""

    engine = "bare"
    label = "Bare"
    settings_type = AnalyticSettings

    def default_settings(self, scene):
        return AnalyticSettings()

    def describe(self, settings):
        return "bare"

    def _simulate(self, scene, settings, t_end, progress):  # pragma: no cover - never reached
        raise AssertionError("a refused scene must not run")


def _scene(**options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # data given for effects that are off
        return random_scene(np.random.default_rng(3), 2, **options)


def test_a_plant_that_lists_no_effects_claims_none():
    assert Bare.effects == frozenset()
    with pytest.raises(ValueError, match=r"^scene\.effects: the bare plant cannot simulate .*gravity"
                       r".*\(it declares no effects: Plant\.effects\)$"):  # fmt: skip
        Bare().check_scene(_scene(controlled=False))
    Bare().check_scene(_scene(controlled=False, effects=()))  # free motion: nothing to claim


def test_a_plant_refuses_the_one_effect_it_does_not_list():
    class NoTorque(Bare):
        effects = frozenset(Effect) - {Effect.EXTERNAL_TORQUE}

    with pytest.raises(ValueError, match=r"cannot simulate external_torque$"):
        NoTorque().check_scene(_scene(external_torque=True))
    NoTorque().check_scene(_scene())


def test_the_analytic_plant_lists_each_effect_of_its_model():
    """Named one by one, not "every member of Effect": a new member is not claimed until listed."""
    assert AnalyticPlant.effects == frozenset(Effect)  # today's Effect: the model has every one
    assert "frozenset(Effect)" not in inspect.getsource(AnalyticPlant)
