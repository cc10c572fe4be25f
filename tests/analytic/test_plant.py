"""The plant protocol's effects: a plant claims exactly the effects it lists (none by default), so
an effect no code of a plant implements is never claimed by it."""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.plant import AnalyticPlant, AnalyticSettings, Plant
from analytic.scene import modified_scene
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


# --- the batched entry and the pointwise entry ------------------------------------------------


def _batch(count=3, n=2, t_end=0.05, **options):
    """Scenes of one structure (n masses, the same effects), each its own parameters and state."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scenes = [
            random_scene(np.random.default_rng(10 + i), n, track_all=True, **options)
            for i in range(count)
        ]
    return [modified_scene(s, {"output": {"t_end": t_end, "rate": 100.0}}) for s in scenes]


def test_the_default_batch_is_the_loop_of_per_scene_runs():
    scenes = _batch()
    assert len({s.effects for s in scenes}) == 1 and len({s.n for s in scenes}) == 1
    assert len({float(s.body.inertia[0]) for s in scenes}) == 3  # different parameters
    plant = AnalyticPlant()
    assert plant.batched is False and Plant.batched is False
    reached = []
    batch = plant.simulate_batch(scenes, progress=reached.append)
    assert len(batch) == len(scenes)
    for scene, tr in zip(scenes, batch, strict=True):
        one = plant.simulate(scene)
        assert tr.scene == scene.name and tr.engine == plant.engine
        np.testing.assert_array_equal(tr.t, one.t)
        # the loop is the per-scene run itself: the same arithmetic in the same process
        np.testing.assert_array_equal(tr.q, one.q)
        np.testing.assert_array_equal(tr.qdot, one.qdot)
    assert reached == sorted(reached) and reached[-1] == pytest.approx(0.05)
    assert plant.simulate_batch([]) == []


def test_a_batch_honours_the_horizon_and_the_settings_given():
    scenes = _batch(count=2)
    settings = AnalyticSettings(rtol=1e-9, atol=1e-10)
    batch = AnalyticPlant().simulate_batch(scenes, settings, t_end=0.02)
    assert all(tr.t[-1] == pytest.approx(0.02) for tr in batch)
    assert all(tr.info["rtol"] == 1e-9 for tr in batch)


def test_a_batch_of_mixed_structures_is_refused_naming_the_scene():
    plant = AnalyticPlant()
    same = _batch(count=2)
    other_n = _batch(count=1, n=3)[0]
    with pytest.raises(ValueError, match=r"^scenes\[2\]: .*one structure: n = 3 masses, "
                       r"scenes\[0\] has 2$"):  # fmt: skip
        plant.simulate_batch([*same, other_n])
    torque = _batch(count=1, external_torque=True)[0]
    with pytest.raises(ValueError, match=r"^scenes\[1\]: .*effects differ.*has external_torque"):
        plant.simulate_batch([same[0], torque])


def test_a_batch_is_refused_before_it_runs():
    scenes = _batch(count=2)
    with pytest.raises(ValueError, match=r"^settings: the analytic plant takes AnalyticSettings "
                       r"\(got EchoLike\)$"):  # fmt: skip
        AnalyticPlant().simulate_batch(scenes, type("EchoLike", (), {})())
    with pytest.raises(ValueError, match=r"^t_end: "):
        AnalyticPlant().simulate_batch(scenes, t_end=-1.0)
    with pytest.raises(ValueError, match=r"^scenes\[0\]: scene\.effects: the bare plant"):
        Bare().simulate_batch(scenes)


def test_an_unavailable_plant_refuses_a_batch():
    class Missing(Bare):
        @classmethod
        def unavailable(cls):
            return "the missing plant needs the package 'nothing'"

    with pytest.raises(ImportError, match="needs the package"):
        Missing().simulate_batch(_batch(count=1))


def test_pointwise_is_not_offered_by_default():
    scene = _batch(count=1)[0]
    q, qdot = scene.initial.q0()[None], scene.initial.qdot0()[None]
    assert AnalyticPlant().pointwise(scene, AnalyticSettings(), np.zeros(1), q, qdot) is None
