"""The fuzzing campaign's scene space: seeded random scene files across the whole scene format.

:func:`draw_scene_dict` turns ``(seed, index)`` into the nested dict of a scene file (the schema
of ``validation/scenes/*.toml``), read by :func:`analytic.scene.scene_from_dict` like any file. Each
scene has its own numpy stream, ``default_rng([seed, index])``: scene ``index`` of a seed is the
same whichever worker draws it, in whatever order (the campaign's determinism on every executor).

What a draw covers (SI units; body axes are BR's principal axes at C):

* ``n`` masses, ``0 ... MAX_MASSES``, small counts most often (``floor(51^(U²)) - 1``: half the
  scenes have at most 2 masses, one in ten more than 20);
* ``J`` principal moments ``U(1, 1.9)`` (so every ordering, the intermediate axis included) times
  ``10^U(0, 4)`` kg·m²; ``m_BR = J̄ · 10^U(-1, 1)`` kg;
* the rod: a random unit axis (a coordinate axis one time in five) and offset ``N(0, 1)`` m (zero
  one time in five: the rod through C);
* masses ``J̄/10 · 10^U(-3, 3)`` kg each (mass ratios over six decades), ``p_e`` sorted in
  ``U(-3, 3)`` m, ring radii ``U(0, 0.5)`` m;
* linear springs ``m_min · 10^U(-1, 3)`` N/m always (n > 0), cubic ones ``m_min · 10^U(-2, 1)``
  N/m³ half the time (``m_min`` the lightest mass: spring periods stay above ~0.1 s, so a short
  run stays short on every plant);
* gravity ``N(0, 10²)`` m/s² per component half the time (off: no ``[gravity]`` effect);
* spin ``|ω(0)| = 10^U(-1, log10 MAX_SPIN)`` rad/s about a random body direction; attitude a
  uniformly random unit quaternion (w first, so w < 0 half the time);
* control of ω half the time (a random non-empty subset of axes), of a random non-empty subset
  of the masses half the time (n > 0), each weighting of :class:`analytic.effects.Weighting`
  equally often; a given torque ``τ_c + τ_a sin(f t)`` of the size of ``J`` three times in ten;
* each spring law declared after these (``springs.damping``) three times in ten (n > 0), its
  coefficients ``m_min · 10^U(lo, hi)`` with the law's declared ``fuzz`` range (damping
  ``10^U(-2, 1)`` N·s/m per kg: damping ratios from ~1e-3 to over 1), drawn after every other draw;
* the horizon ``t_end`` given, output at 100 Hz, every other setting the scene's default.

The parameters that drive a disagreement are read back by :func:`drivers`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from analytic.effects import Effect, Weighting
from analytic.effects.registry import SPRING_LAWS

MAX_MASSES = 50
"""Most masses of a drawn scene."""
MAX_SPIN = 300.0
"""Largest initial spin rate drawn, rad/s ("spins up to a few hundred rad/s")."""
OUTPUT_RATE = 100.0
"""Samples per second of every drawn scene's output grid, Hz."""
LATER_LAW_PROBABILITY = 0.3
"""How often a spring law declared after the seeded ones (the damping) is on, with masses."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _list(a: Any) -> list[float]:
    return [float(x) for x in np.asarray(a, float).ravel()]


def draw_scene_dict(seed: int, index: int, horizon: float) -> dict[str, Any]:
    """Scene ``index`` of the campaign ``seed`` as a scene file's nested dict (module docstring).

    The draws are made in a fixed order from ``default_rng([seed, index])``; a value not used by
    the scene (a cubic stiffness that is off) is drawn anyway, so every later draw stays put.
    """
    rng = np.random.default_rng([int(seed), int(index)])
    n = math.floor(51.0 ** (rng.uniform(0.0, 1.0) ** 2)) - 1
    n = min(max(n, 0), MAX_MASSES)
    J = rng.uniform(1.0, 1.9, 3) * 10.0 ** rng.uniform(0.0, 4.0)
    body_mass = float(J.mean() * 10.0 ** rng.uniform(-1.0, 1.0))
    axis_aligned = rng.uniform() < 0.2
    axis = np.eye(3)[int(rng.integers(0, 3))] if axis_aligned else _unit(rng.normal(size=3))
    through_c = rng.uniform() < 0.2
    offset = np.zeros(3) if through_c else rng.normal(size=3)
    m = J.mean() / 10.0 * 10.0 ** rng.uniform(-3.0, 3.0, n)
    p_e = np.sort(rng.uniform(-3.0, 3.0, n))
    ring = rng.uniform(0.0, 0.5, n)
    m_bar = float(m.mean()) if n else J.mean() / 10.0
    m_min = float(m.min()) if n else m_bar
    k_lin = m_min * 10.0 ** rng.uniform(-1.0, 3.0, n + 1)
    cubic = rng.uniform() < 0.5
    k_cub = m_min * 10.0 ** rng.uniform(-2.0, 1.0, n + 1)
    gravity_on = rng.uniform() < 0.5
    g = rng.normal(scale=10.0, size=3)
    spin = 10.0 ** rng.uniform(-1.0, math.log10(MAX_SPIN))
    omega = _unit(rng.normal(size=3)) * spin
    quat = _unit(rng.normal(size=4))
    R = rng.normal(size=3)
    Rdot = rng.normal(size=3)
    p = p_e + rng.normal(scale=0.3, size=n)
    pdot = rng.normal(size=n)
    ctrl_omega = rng.uniform() < 0.5
    comps = sorted(int(c) + 1 for c in rng.choice(3, size=int(rng.integers(1, 4)), replace=False))
    b, sigma, gamma = rng.normal(size=3), rng.uniform(0, 3, 3), float(rng.uniform(0.1, 2))
    ctrl_masses = n > 0 and rng.uniform() < 0.5
    idx = (
        sorted(int(i) + 1 for i in rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False))
        if n
        else []
    )
    k = len(idx)
    ell, lam = rng.normal(scale=0.5, size=k), rng.uniform(0, 3, k)
    alpha, beta = rng.uniform(0.5, 3, k), rng.uniform(1, 10, k)
    weighting = list(Weighting)[int(rng.integers(0, len(Weighting)))]
    torque_on = rng.uniform() < 0.3
    tau_c, tau_a, tau_f = rng.normal(size=3) * J, rng.normal(size=3) * J, float(rng.uniform(0, 3))

    effects: list[str] = []
    data: dict[str, Any] = {
        "scene": {"name": f"fuzz_{seed}_{index}", "effects": effects},
        "body": {"mass": body_mass, "inertia": _list(J)},
        "rod": {"axis": _list(axis), "offset": _list(offset)},
        "initial": {
            "R": _list(R),
            "Rdot": _list(Rdot),
            "omega": _list(omega),
            "attitude": {"quaternion": _list(quat)},
        },
        "output": {"t_end": float(horizon), "rate": OUTPUT_RATE},
    }
    if gravity_on:
        effects.append(Effect.GRAVITY.value)
        data["gravity"] = {"vector": _list(g)}
    if n:
        effects += [Effect.SPRINGS_LINEAR.value, Effect.MASS_INERTIA.value]
        data["masses"] = {"mass": _list(m), "p_e": _list(p_e), "ring_radius": _list(ring)}
        data["springs"] = {"k_linear": _list(k_lin)}
        if cubic:
            effects.append(Effect.SPRINGS_CUBIC.value)
            data["springs"]["k_cubic"] = _list(k_cub)
        data["initial"] |= {"p": _list(p), "pdot": _list(pdot)}
    control: dict[str, Any] = {}
    if ctrl_omega:
        effects.append(Effect.CONTROL_OMEGA.value)
        control["omega"] = {
            "components": comps,
            "b": _list(b),
            "sigma": _list(sigma),
            "gamma": gamma,
        }
    if ctrl_masses:
        effects.append(Effect.CONTROL_MASSES.value)
        control["masses"] = {
            "indices": idx,
            "l": _list(ell),
            "lambda": _list(lam),
            "alpha": _list(alpha),
            "beta": _list(beta),
        }
    if control:
        control["weighting"] = weighting.value
        data["control"] = control
    if torque_on:
        effects.append(Effect.EXTERNAL_TORQUE.value)
        data["external_torque"] = {
            "constant": _list(tau_c),
            "amplitude": _list(tau_a),
            "frequency": tau_f,
        }
    for law in SPRING_LAWS:  # a law declared later: drawn after every other draw, so the
        if law.seeded:  # scenes of a seed without it are what they were
            continue
        on = rng.uniform() < LATER_LAW_PROBABILITY
        c = m_min * 10.0 ** rng.uniform(*law.fuzz, size=max(n + 1, 1))
        if n and on:
            effects.append(law.effect.value)
            data["springs"][law.key.key] = _list(c)
    return data


@dataclass(frozen=True)
class Drivers:
    """The parameters of a scene that drive its disagreements (the campaign figure's axes).

    Attributes:
        n: masses.
        spin: ``|ω(0)|``, rad/s.
        mass_ratio: largest over smallest mass of the system (BR and the masses), 1.
        stiffness: largest ``k_l / m`` over the springs and the masses, 1/s² (0 without masses).
        offset: ``|d|``, m (0: the rod through C).
    """

    n: int
    spin: float
    mass_ratio: float
    stiffness: float
    offset: float

    def to_dict(self) -> dict[str, float]:
        return {
            "n": self.n,
            "spin": self.spin,
            "mass_ratio": self.mass_ratio,
            "stiffness": self.stiffness,
            "offset": self.offset,
        }


def drivers(data: dict[str, Any]) -> Drivers:
    """:class:`Drivers` of a scene file's dict (as :func:`draw_scene_dict` makes them)."""
    masses = [float(x) for x in data.get("masses", {}).get("mass", [])]
    all_m = [float(data["body"]["mass"]), *masses]
    k = [float(x) for x in data.get("springs", {}).get("k_linear", [])]
    stiff = max(k) / min(masses) if k and masses else 0.0
    return Drivers(
        n=len(masses),
        spin=float(np.linalg.norm(data.get("initial", {}).get("omega", [0.0, 0.0, 0.0]))),
        mass_ratio=max(all_m) / min(all_m),
        stiffness=stiff,
        offset=float(np.linalg.norm(data.get("rod", {}).get("offset", [0.0, 0.0, 0.0]))),
    )


__all__ = ["MAX_MASSES", "MAX_SPIN", "OUTPUT_RATE", "Drivers", "draw_scene_dict", "drivers"]
