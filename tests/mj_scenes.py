"""The tests' random scenes and on-manifold states (helpers, not tests): the MuJoCo-twin,
Pinocchio, coordinate and MJCF tests and the hypothesis property tests (``test_properties.py``)
all draw from :func:`random_scene`. (``tests/random_scenes.py`` keeps the model tests' draws: body
inertias in any orientation and states off the unit sphere, which no engine plant accepts.)"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from analytic.kinematics import udot_of
from analytic.scene import Scene, load_scene, scene_from_dict

SCENE_DIR = Path(__file__).resolve().parents[1] / "analytic" / "scenes"
PAPER = (
    "paper_example1",
    "paper_example1_controlled",
    "paper_example2",
    "paper_example2_controlled",
)


def paper_scene(name: str) -> Scene:
    return load_scene(SCENE_DIR / f"{name}.toml")


def random_scene(
    rng: np.random.Generator,
    n: int | None = None,
    *,
    controlled: bool = True,
    spring_model: str = "tendon",
    external_torque: bool = False,
    effects: list[str] | None = None,
    mass_exponents: np.ndarray | None = None,
) -> Scene:
    """A random valid scene: random a, d, masses, stiffnesses, ring inertias, initial state.

    ``n``: the number of masses (0 allowed; default a random 1…6). ``mass_exponents`` (length n):
    the masses are ``J̄/10 · 10^e`` (spread over as many decades as the exponents span; the
    hypothesis tests draw them) instead of ``J̄/10`` times a factor in [0.2, 3]. The scene is built
    through the public schema (``scene_from_dict``), so the loader validates it."""
    n = int(rng.integers(1, 7)) if n is None else n
    J = rng.uniform(1.0, 1.9, 3) * 10.0 ** rng.uniform(0, 3)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    if mass_exponents is None:
        m = rng.uniform(0.2, 3.0, n) * J.mean() / 10
    else:
        m = J.mean() / 10 * 10.0 ** np.asarray(mass_exponents, float)
    p_e = np.sort(rng.uniform(-3, 3, n))
    eff = effects or ["gravity", "springs.linear", "springs.cubic", "mass_inertia"]
    eff = list(eff)
    m_scale = float(m.mean()) if n else J.mean() / 10
    data = {
        "scene": {"name": f"random_n{n}", "effects": eff},
        "body": {
            "mass": float(rng.uniform(1, 10) * (m.sum() if n else m_scale)),
            "inertia": J.tolist(),
        },
        "rod": {"axis": a.tolist(), "offset": rng.normal(size=3).tolist()},
        "masses": {
            "mass": m.tolist(),
            "p_e": p_e.tolist(),
            "ring_radius": rng.uniform(0.0, 0.5, n).tolist(),
        },
        "springs": {
            "k_linear": (rng.uniform(1, 10, n + 1) * m_scale).tolist(),
            "k_cubic": (rng.uniform(0, 1, n + 1) * m_scale).tolist(),
        },
        "gravity": {"vector": rng.normal(size=3).tolist()},
        "initial": {
            "R": rng.normal(size=3).tolist(),
            "Rdot": rng.normal(size=3).tolist(),
            "omega": rng.normal(size=3).tolist(),
            "p": (p_e + rng.normal(scale=0.3, size=n)).tolist(),
            "pdot": rng.normal(size=n).tolist(),
            "attitude": {"quaternion": _unit(rng.normal(size=4)).tolist()},
        },
        "mujoco": {"spring_model": spring_model},
    }
    if not n:  # a rigid body alone: no per-mass tables (the loader refuses empty ones)
        for key in ("masses", "springs"):
            del data[key]
        for key in ("p", "pdot"):
            del data["initial"][key]
        data["scene"]["effects"] = eff = [e for e in eff if not e.startswith("springs")]
    if controlled:  # (draws in this order for every n: the seeded scenes of the tests)
        comps = sorted(rng.choice(3, size=int(rng.integers(1, 4)), replace=False) + 1)
        idx = (
            sorted(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False) + 1) if n else []
        )
        data["scene"]["effects"] = [*eff, "control.omega"]
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
            data["scene"]["effects"].append("control.masses")
            data["control"]["masses"] = {
                "indices": [int(i) for i in idx],
                "l": rng.normal(scale=0.5, size=k).tolist(),
                "lambda": rng.uniform(0, 3, k).tolist(),
                "alpha": rng.uniform(0.5, 3, k).tolist(),
                "beta": rng.uniform(1, 10, k).tolist(),
            }
    if external_torque:
        data["scene"]["effects"] = [*data["scene"]["effects"], "external_torque"]
        data["external_torque"] = {
            "constant": (rng.normal(size=3) * J).tolist(),
            "amplitude": (rng.normal(size=3) * J).tolist(),
            "frequency": float(rng.uniform(0, 3)),
        }
    return scene_from_dict(data)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def random_state(
    rng: np.random.Generator, scene: Scene, scale: float = 1.0
) -> tuple[float, np.ndarray, np.ndarray]:
    """A random time and an on-manifold paper state (unit u, u̇ = ¼Hᵀω)."""
    n = scene.n
    u = _unit(rng.normal(size=4))
    omega = rng.normal(size=3) * scale
    q = np.concatenate([rng.normal(size=3), u, np.asarray(scene.masses.p_e) + rng.normal(size=n)])
    qdot = np.concatenate([rng.normal(size=3) * scale, udot_of(u, omega), rng.normal(size=n)])
    return float(rng.uniform(0, 20)), q, qdot
