"""Random scenes for the tests, all from the one generator :mod:`analytic.scene.random_scenes`.

* hypothesis strategies (:func:`scene_and_state`): hypothesis draws the discrete choices (n, the
  mass exponents, control on or off) and a seed; the generator draws the rest from a numpy
  ``Generator`` seeded by it (the examples stay small and shrink well);
* the model tests' draws (:func:`random_scene_dict`, :func:`random_scene`): the generator's
  unit-sized scenes (:func:`analytic.scene.random_scenes.unit_scene_dict`) with every force table present
  (so a test can switch any effect on), no control, and each mass's inertia a random body-axis
  matrix or a ring; :func:`random_state` gives states off the unit sphere (which no engine plant
  accepts, and the model must handle).
"""

from __future__ import annotations

import numpy as np

from analytic.scene import Scene, random_scenes, scene_from_dict
from analytic.scene.random_scenes import unit as _unit

FORCE_EFFECTS = ("gravity", "springs.linear", "springs.cubic", "mass_inertia", "external_torque")


def unit(rng: np.random.Generator, k: int = 3) -> np.ndarray:
    """A random unit vector of length k."""
    return _unit(rng.normal(size=k))


def random_scene_dict(
    rng: np.random.Generator,
    n: int,
    effects=FORCE_EFFECTS,
    *,
    inertia_kind: str = "body",
    a=None,
    d=None,
) -> dict:
    """The generator's unit-sized model scene (:func:`analytic.scene.random_scenes.unit_scene_dict`)
    listing ``effects``, every force table present; ``inertia_kind``: ``"body"`` (a random SPD
    inertia per mass, body axes) or ``"ring"``; ``a``, ``d``: the rod's axis and offset."""
    return random_scenes.unit_scene_dict(
        rng, n, effects, mass_inertia=inertia_kind, axis=a, offset=d
    )


def random_scene(rng: np.random.Generator, n: int, effects=FORCE_EFFECTS, **kw) -> Scene:
    return scene_from_dict(random_scene_dict(rng, n, effects, **kw))


def random_state(
    rng: np.random.Generator, n: int, *, unit_u: bool = False, tangent: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """q = [R, u, p], q̇; u off the unit sphere unless ``unit_u``; u̇ ⊥ u when ``tangent``."""
    u = rng.normal(size=4)
    u = u / np.linalg.norm(u) if unit_u else u / np.linalg.norm(u) * rng.uniform(0.7, 1.3)
    ud = rng.normal(size=4)
    if tangent:
        ud = ud - u * (u @ ud) / (u @ u)
    q = np.concatenate([rng.normal(size=3), u, rng.normal(size=n)])
    qd = np.concatenate([rng.normal(size=3), ud, rng.normal(size=n)])
    return q, qd


def rel_err(x, ref) -> float:
    """``|x - ref| / |ref|`` (Frobenius / Euclidean norms)."""
    return float(np.linalg.norm(np.asarray(x) - np.asarray(ref)) / np.linalg.norm(ref))


try:
    from hypothesis import strategies as st
except ImportError:  # the property tests skip themselves without hypothesis
    st = None

if st is not None:

    @st.composite
    def scene_and_state(draw, max_masses: int = 8, mass_decades: float = 6.0):
        """A random valid scene (n ≤ ``max_masses``, masses over ``mass_decades`` decades, with or
        without control) and a random time and on-manifold state of it: ``(scene, t, q, q̇)``."""
        n = draw(st.integers(0, max_masses))
        half = mass_decades / 2
        expo = draw(st.lists(st.floats(-half, half), min_size=n, max_size=n))
        controlled = draw(st.booleans())
        rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
        scene = random_scenes.random_scene(
            rng, n, controlled=controlled, mass_exponents=np.array(expo)
        )
        t, q, qd = random_scenes.random_state(rng, scene)
        return scene, t, q, qd
