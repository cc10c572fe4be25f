"""The one random-scene generator (``analytic/scene/random_scenes.py``): what kinds of scene it draws.
(What the scenes are for is tested where they are used: the engine, property and model tests.)"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.scene.random_scenes import MassInertia, chain_scene, random_scene, random_scene_dict
from validation.bench.timing import chain_scene as bench_chain_scene


@pytest.mark.parametrize("n", [1, 2, 5, 50])
def test_chain_scene_is_the_benchmarks_kind_of_scene(n):
    """Controlled, n masses with their own inertia on a rod not through C, every ω axis and every
    mass tracked; the same scene for the same seed, another for another seed."""
    sc = chain_scene(n)
    assert sc.name == f"bench_chain_{n}" and sc.n == n
    assert sc.effects >= CONTROL_EFFECTS | {Effect.GRAVITY, Effect.MASS_INERTIA}
    assert tuple(sc.control.omega.components) == (0, 1, 2)
    assert tuple(sc.control.masses.indices) == tuple(range(n))
    assert np.linalg.norm(sc.rod.offset) > 0
    assert np.array_equal(bench_chain_scene(n).masses.mass, sc.masses.mass)
    assert not np.array_equal(chain_scene(n, seed=1).masses.mass, sc.masses.mass)


def test_same_seed_same_scene():
    a = random_scene_dict(np.random.default_rng(5), 3, external_torque=True)
    b = random_scene_dict(np.random.default_rng(5), 3, external_torque=True)
    assert a == b


def test_options():
    rng = np.random.default_rng(2)
    rigid = random_scene(rng, 0, controlled=True)
    assert rigid.n == 0 and Effect.SPRINGS_LINEAR not in rigid.effects
    assert Effect.CONTROL_MASSES not in rigid.effects
    free = random_scene(rng, 3, controlled=False, mass_inertia=MassInertia.BODY, axis=[0, 0, 2])
    assert not free.controlled and np.allclose(free.rod.axis, [0, 0, 1])
    wide = random_scene(rng, 4, mass_exponents=[-3, -1, 1, 3])
    m = np.asarray(wide.masses.mass)
    assert np.allclose(m / m[0], [1, 1e2, 1e4, 1e6])


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"n": -1}, r"^n: must be a non-negative integer"),
        ({"n": 2, "mass_exponents": [1.0]}, r"^mass_exponents: must have length n = 2"),
    ],
)
def test_bad_arguments_name_the_field(kw, message):
    with pytest.raises(ValueError, match=message):
        random_scene_dict(np.random.default_rng(0), **kw)
