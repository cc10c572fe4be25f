"""Random scenes and states for the model tests (built through the public scene schema)."""

from __future__ import annotations

import numpy as np

from analytic.scene import Scene, scene_from_dict

FORCE_EFFECTS = ("gravity", "springs.linear", "springs.cubic", "mass_inertia", "external_torque")


def unit(rng: np.random.Generator, k: int = 3) -> np.ndarray:
    v = rng.normal(size=k)
    return v / np.linalg.norm(v)


def random_spd(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    """A random rigid-body inertia: symmetric positive definite with principal moments that
    satisfy A + B >= C (as every mass distribution's do, and as the scene loader and MuJoCo
    require), in a random orientation; a matrix that satisfies it is the plain ``B Bᵀ + 0.1 I``."""
    B = rng.normal(size=(3, 3))
    J = B @ B.T + 0.1 * np.eye(3)
    e, V = np.linalg.eigh(J)
    if e[2] > e[0] + e[1]:  # the largest moment brought down to the sum of the others
        e[2] = e[0] + e[1]
        J = V @ np.diag(e) @ V.T
        J = (J + J.T) / 2
    return scale * J


def random_scene_dict(
    rng: np.random.Generator,
    n: int,
    effects=FORCE_EFFECTS,
    *,
    inertia_kind: str = "body",
    a=None,
    d=None,
) -> dict:
    """A scene dict with random physical data (same schema as the TOML files).

    ``inertia_kind``: ``"body"`` (a random SPD inertia per mass, body axes) or ``"ring"``.
    """
    a = unit(rng) if a is None else np.asarray(a, float)
    d = rng.normal(size=3) if d is None else np.asarray(d, float)
    data: dict = {
        "scene": {"name": "random", "effects": list(effects)},
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
        masses: dict = {
            "mass": rng.uniform(0.5, 3.0, n).tolist(),
            "p_e": rng.normal(size=n).tolist(),
        }
        if inertia_kind == "ring":
            masses["ring_radius"] = rng.uniform(0.1, 1.0, n).tolist()
        else:
            masses["inertia_body"] = [random_spd(rng, 0.2).tolist() for _ in range(n)]
        data["masses"] = masses
        data["initial"]["p"] = rng.normal(size=n).tolist()
        data["springs"] = {
            "k_linear": rng.uniform(1.0, 10.0, n + 1).tolist(),
            "k_cubic": rng.uniform(0.5, 5.0, n + 1).tolist(),
        }
    return data


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
