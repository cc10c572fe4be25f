"""``springs.damping`` against closed forms: one mass between two damped springs on a body a
million times heavier, not rotating, no gravity, is the damped oscillator of the reduced mass
``μ = m M / (m + M)``, with stiffness ``2k`` and damping ``2c`` (the two elements in parallel);
and the energy the damping dissipates, ``D``, is the energy the motion lost.

The line of the mass passes through C (rod offset 0, ``p_e = 0``) and the total momentum is zero,
so the body only recoils along the rod: ``μ p̈ = -2k p - 2c ṗ`` holds exactly for the engines'
``p``, whatever the recoil.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.effects.registry import SPRING_LAWS, spring_law
from analytic.scene import scene_from_dict
from analytic.simulate import simulate
from tests.support import tolerances as tol

M_MASS = 0.5  # kg
M_BODY = 1e6 * M_MASS
K = 2.0  # N/m, each element
X0, V0 = 0.1, -0.2  # m, m/s
T_END = 3.0  # s


def _scene(zeta: float) -> tuple[dict, float]:
    """The scene dict for damping ratio ``zeta``, and the reduced mass."""
    mu = M_MASS * M_BODY / (M_MASS + M_BODY)
    c = zeta * 2.0 * math.sqrt(2.0 * K * mu) / 2.0  # each element: c_eff = 2c = ζ 2 √(k_eff μ)
    # zero total momentum: m (Ṙ + ṗ) + M Ṙ = 0
    rdot = -M_MASS * V0 / (M_MASS + M_BODY)
    data = {
        "scene": {
            "name": f"damped_{zeta:g}",
            "effects": [Effect.SPRINGS_LINEAR.value, Effect.SPRINGS_DAMPING.value],
        },
        "body": {"mass": M_BODY, "inertia": [1e6, 1e6, 1e6]},
        "rod": {"axis": [1.0, 0.0, 0.0], "offset": [0.0, 0.0, 0.0]},
        "masses": {"mass": [M_MASS], "p_e": [0.0]},
        "springs": {"k_linear": [K, K], "c_damping": [c, c]},
        "initial": {
            "R": [0.0, 0.0, 0.0],
            "Rdot": [rdot, 0.0, 0.0],
            "omega": [0.0, 0.0, 0.0],
            "p": [X0],
            "pdot": [V0],
        },
        "solver": {"method": "DOP853", "rtol": 1e-12, "atol": 1e-14},
        "output": {"t_end": T_END, "rate": 100},
    }
    return data, mu


def damped_oscillator(t: np.ndarray, zeta: float, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """``x(t), ẋ(t)`` of ``μ ẍ + 2c ẋ + 2k x = 0`` from ``(X0, V0)``, by its three closed forms."""
    w0 = math.sqrt(2.0 * K / mu)
    if zeta < 1.0:
        wd = w0 * math.sqrt(1.0 - zeta**2)
        a, b = X0, (V0 + zeta * w0 * X0) / wd
        env = np.exp(-zeta * w0 * t)
        x = env * (a * np.cos(wd * t) + b * np.sin(wd * t))
        v = -zeta * w0 * x + env * (-a * wd * np.sin(wd * t) + b * wd * np.cos(wd * t))
    elif zeta == 1.0:
        b = V0 + w0 * X0
        env = np.exp(-w0 * t)
        x = env * (X0 + b * t)
        v = env * (b - w0 * (X0 + b * t))
    else:
        s = w0 * math.sqrt(zeta**2 - 1.0)
        r1, r2 = -zeta * w0 + s, -zeta * w0 - s
        b = (V0 - r1 * X0) / (r2 - r1)
        a = X0 - b
        x = a * np.exp(r1 * t) + b * np.exp(r2 * t)
        v = a * r1 * np.exp(r1 * t) + b * r2 * np.exp(r2 * t)
    return x, v


CASES = pytest.mark.parametrize("zeta", [0.1, 1.0, 3.0], ids=["under", "critical", "over"])


@CASES
@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_one_damped_mass_is_the_damped_oscillator(zeta, backend):
    data, mu = _scene(zeta)
    run = simulate(scene_from_dict(data), backend=backend)
    assert run.status == "ok", run.message
    x, v = damped_oscillator(run.t, zeta, mu)
    assert np.max(np.abs(run.q[:, 7] - x)) < tol.DAMPED_OSCILLATOR_ABS.value
    assert np.max(np.abs(run.qdot[:, 7] - v)) < tol.DAMPED_OSCILLATOR_ABS.value * 10
    # the body recoils along the rod only and does not turn
    assert np.max(np.abs(run.q[:, 3:7] - [1.0, 0.0, 0.0, 0.0])) < 1e-12


@CASES
def test_the_dissipated_work_is_the_energy_lost(zeta):
    data, mu = _scene(zeta)
    run = simulate(scene_from_dict(data))
    x, v = damped_oscillator(run.t, zeta, mu)
    lost = (0.5 * mu * V0**2 + K * X0**2) - (0.5 * mu * v**2 + K * x**2)
    inv = run.invariants
    assert np.all(np.diff(inv.dissipated) >= 0.0)  # D only grows
    assert np.max(np.abs(inv.dissipated - lost)) < tol.DISSIPATED_ENERGY_ABS.value
    assert np.max(np.abs(inv.energy_balance())) < tol.DISSIPATED_ENERGY_ABS.value


def test_d_over_the_samples_agrees_with_d_along_the_motion():
    """A plant that gives only ``W, I_L, I_P`` gets ``D`` by the Hermite rule over its samples."""
    from analytic.assemble import N_AUX, assemble
    from analytic.model import TumblingModel

    data, _ = _scene(0.1)
    scene = scene_from_dict(data)
    run = simulate(scene)
    model = TumblingModel(scene)
    quads = np.column_stack(
        [run.invariants.work, run.invariants.angular_impulse, np.zeros((len(run.t), 3))]
    )
    assert quads.shape[1] == N_AUX
    again = assemble(
        model,
        "analytic",
        run.t,
        run.q,
        run.qdot,
        run.qddot,
        [None] * len(run.t),
        quads,
        run.status,
        "",
        {},
    )
    gap = np.max(np.abs(again.invariants.dissipated - run.invariants.dissipated))
    assert gap < tol.DISSIPATED_ENERGY_ABS.value


def test_the_damping_law_is_the_viscous_force_and_its_power():
    law = spring_law(Effect.SPRINGS_DAMPING)
    e, ed = np.array([0.3, -1.0]), np.array([2.0, -0.5])
    assert np.array_equal(law.force(e, ed), ed)  # f = c ė: against the stretching
    assert np.array_equal(law.dissipation(e, ed), ed * ed)  # P = f ė = c ė² ≥ 0
    assert law.potential is None and law in SPRING_LAWS


def test_without_the_effect_nothing_of_it_is_computed():
    """The same scene without ``springs.damping``: no D column, the undamped oscillator."""
    data, mu = _scene(0.1)
    data["scene"]["effects"] = [Effect.SPRINGS_LINEAR.value]
    del data["springs"]["c_damping"]
    run = simulate(scene_from_dict(data))
    assert not run.invariants.dissipated.any()
    x, _ = damped_oscillator(run.t, 0.0, mu)
    assert np.max(np.abs(run.q[:, 7] - x)) < tol.DAMPED_OSCILLATOR_ABS.value
