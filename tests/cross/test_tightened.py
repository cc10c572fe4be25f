"""Each plant's own error estimate: its run at the given settings against its run at
``Plant.tightened``'s settings, checked against the true error on a closed-form motion."""

from __future__ import annotations

import numpy as np
import pytest

from analytic.plant import RTOL_FLOOR, TIGHTER_RTOL, TIGHTER_STEP, AnalyticPlant, AnalyticSettings
from analytic.scene import scene_from_dict
from mj_bridge.mujoco_settings import MujocoRunSettings
from mj_bridge.pinocchio_settings import PinocchioSettings
from mj_bridge.plants import plant
from tests.support import tolerances as tol

J1, J3 = 2.0, 3.5
"""An axisymmetric body (J1 = J2), kg·m²."""
W0 = np.array([0.7, -0.4, 20.0])
"""Its initial body angular velocity, rad/s: a fast spin about the symmetry axis."""
T_END = 2.0


def _top_scene():
    """The body alone (no masses, no gravity, no control), so its motion is Euler's torque-free
    axisymmetric precession."""
    return scene_from_dict(
        {
            "scene": {"name": "top", "effects": []},
            "body": {"mass": 1.5, "inertia": [J1, J1, J3]},
            "rod": {"axis": [0.0, 0.0, 1.0], "offset": [0.2, -1.3, 0.7]},
            "initial": {"omega": list(W0)},
            "output": {"t_end": T_END, "rate": 100.0},
        }
    )


def _omega_closed_form(t: np.ndarray) -> np.ndarray:
    """ω̇1 = -Ω ω2, ω̇2 = Ω ω1 with Ω = (J3 - J1)/J1 ω3, ω3 constant; shape (len(t), 3)."""
    om = (J3 - J1) / J1 * W0[2]
    c, s = np.cos(om * t), np.sin(om * t)
    return np.stack([W0[0] * c - W0[1] * s, W0[0] * s + W0[1] * c, np.full_like(t, W0[2])], 1)


@pytest.mark.parametrize(
    "name, settings",
    [
        # settings loose enough for an error far above round-off, so the estimate is measurable
        ("analytic", AnalyticSettings(rtol=1e-8, atol=1e-10)),
        ("mujoco", MujocoRunSettings(dt=1e-3)),
        ("pinocchio", PinocchioSettings(rtol=1e-8, atol=1e-10)),
    ],
)
def test_own_error_estimate_matches_the_true_error(name, settings):
    pl = plant(name)
    if pl.unavailable():
        pytest.skip(pl.unavailable())
    scene = _top_scene()
    tight = pl.tightened(scene, settings)
    assert tight is not None and type(tight) is type(settings)
    given = pl.simulate(scene, settings, t_end=T_END)
    tighter = pl.simulate(scene, tight, t_end=T_END)
    exact = _omega_closed_form(given.t)
    estimate = np.max(np.linalg.norm(given.omega - tighter.omega, axis=1))
    true = np.max(np.linalg.norm(given.omega - exact, axis=1))
    assert abs(estimate / true - 1.0) < tol.OWN_ERROR_ESTIMATE_REL.value


def test_tightened_settings_follow_the_stated_factors():
    scene = _top_scene()
    a = AnalyticPlant().tightened(scene, AnalyticSettings(rtol=1e-9, atol=1e-11))
    assert a.rtol == pytest.approx(1e-9 / TIGHTER_RTOL) and a.atol == pytest.approx(1e-11 / TIGHTER_RTOL)
    # never below scipy's floor, and nothing to tighten once there
    assert AnalyticPlant().tightened(scene, AnalyticSettings(rtol=1e-12)).rtol == RTOL_FLOOR
    assert AnalyticPlant().tightened(scene, AnalyticSettings(rtol=RTOL_FLOOR)) is None
    m = plant("mujoco").tightened(scene, MujocoRunSettings(dt=2.5e-4))
    assert m.dt == pytest.approx(2.5e-4 / TIGHTER_STEP)
    # the scipy-loop plants take the scene's tolerances where theirs are None
    p = plant("pinocchio").tightened(scene, PinocchioSettings())
    assert p.rtol == pytest.approx(max(scene.solver.rtol / TIGHTER_RTOL, RTOL_FLOOR))
