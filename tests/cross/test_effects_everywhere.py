"""Every declared effect is carried everywhere it must be: the test that tells whoever adds an
effect what is still missing (``docs/architecture.md``, *Adding an effect*).

* it is declared once, with its meaning and the keys only it reads;
* the paper's model assembles it, and the compiled kernel computes the same ``q̈`` with it as the
  numpy model (a kernel that ignored it would agree only with the effect off);
* every built-in plant claims it and its motion changes when it is switched off
  (``tests/mj_bridge/test_plants.py`` checks each claim on every plant);
* a spring law has its place in the MJCF twin and in the scipy plants' forces.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.effects.registry import BY_EFFECT, DECLARATIONS, SPRING_LAWS
from analytic.model import MODEL_EFFECTS, TumblingModel
from analytic.scene.random_scenes import random_scene, random_state
from analytic.scene.schema import KEYS
from tests.support import tolerances as tol

FORCE_EFFECTS = [d.effect for d in DECLARATIONS if d.effect not in CONTROL_EFFECTS]


def test_every_effect_is_declared_once_with_its_meaning():
    assert set(BY_EFFECT) == set(Effect) and len(DECLARATIONS) == len(Effect)
    for d in DECLARATIONS:
        assert d.meaning.strip(), d.effect
        for key in d.keys:
            assert key.effect is d.effect, key.dotted
    for law in SPRING_LAWS:
        assert law.key in KEYS and law.key.effect is law.effect


def test_the_model_assembles_every_effect():
    assert MODEL_EFFECTS == set(Effect)


@pytest.mark.parametrize("effect", FORCE_EFFECTS, ids=str)
def test_the_kernel_computes_each_effect_as_the_numpy_model(effect):
    """One scene with only ``effect`` on (and the same scene with nothing on): the kernel's ``q̈``
    is the numpy model's in both, and differs between them."""
    from analytic import fast

    if not fast.available():
        pytest.skip("numba not installed")
    rng = np.random.default_rng(5)
    on = random_scene(
        rng,
        3,
        controlled=False,
        external_torque=effect is Effect.EXTERNAL_TORQUE,
        effects=[e.value for e in FORCE_EFFECTS if e is not Effect.EXTERNAL_TORQUE],
    ).with_effects({effect})
    off = on.with_effects(set())
    t, q, qd = random_state(np.random.default_rng(6), on)
    got = {}
    for name, sc in (("on", on), ("off", off)):
        model = TumblingModel(sc)
        ref, _ = model.acceleration(t, q, qd)
        fm = fast.FastModel(sc, model)
        qdd, _ = fm.acceleration(t, q, qd)
        assert fm.fallbacks == 0, f"{effect}: the kernel declined"
        scale = max(float(np.max(np.abs(ref))), 1.0)
        assert np.max(np.abs(qdd - ref)) <= tol.FAST_VS_NUMPY_REL.value * scale, (effect, name)
        got[name] = qdd
    assert not np.array_equal(got["on"], got["off"]), f"{effect}: changes nothing in q̈"


@pytest.mark.parametrize("name", ["analytic", "mujoco", "pinocchio", "drake"])
def test_every_built_in_plant_claims_every_effect(name):
    from mj_bridge.plants import registered

    cls = registered().get(name)
    if cls is None:
        pytest.skip(f"{name}: not registered")
    missing = set(Effect) - set(cls.effects)
    assert not missing, f"{name} does not implement {sorted(e.value for e in missing)}"


def test_every_spring_law_has_its_place_in_the_twin_and_the_scipy_forces():
    from mj_bridge.scipy_forces import FORCE_EFFECTS as SCIPY
    from model_xml.tendon_terms import TENDON_TERMS

    for law in SPRING_LAWS:
        assert law.effect in TENDON_TERMS, f"{law.effect}: no place in the MJCF twin"
        assert law.effect in SCIPY, f"{law.effect}: no force in mj_bridge.scipy_forces"
