"""The Drake plant: a fourth engine (Drake's ``MultibodyPlant`` in continuous time, built from the
scene) against the analytic model, and its agreement goals.

References: the analytic model of the paper (``TumblingModel.acceleration``: q̈ and the controller at
a state), the analytic plant's trajectories, the spring energy of Eq. (38) (finite differences) and
the scene's numbers for the mass properties. Thresholds: ``tests/support/tolerances.py``
(``DRAKE_*``), each with its reason and what was measured.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pydrake")

from analytic import simulate as analytic_simulate
from analytic.effects import Effect
from analytic.kinematics import S as S_of
from analytic.kinematics import omega_of
from analytic.model import TumblingModel, spring_energy
from analytic.scene import Scene, scene_from_dict
from analytic.trajectory import RunStatus
from mj_bridge.drake_model import (
    build_model,
    drake_to_mujoco_layout,
    drake_to_paper_batch,
    paper_to_drake,
)
from mj_bridge.drake_plant import DrakeDynamics, DrakeSettings
from mj_bridge.drake_plugin import DrakePlant
from mj_bridge.drake_settings import DRAKE_MISSING, drake_unavailable
from mj_bridge.plants import installed_plants, plant
from mj_bridge.stages import ControllerSource
from model_xml.coordinates import mujoco_to_paper_state
from tests.support import tolerances as tol
from tests.support.mj_scenes import paper_scene, random_state
from tests.support.scene_strategies import random_scene_dict

ALL_FORCES = [
    Effect.GRAVITY,
    Effect.SPRINGS_LINEAR,
    Effect.SPRINGS_CUBIC,
    Effect.MASS_INERTIA,
    Effect.EXTERNAL_TORQUE,
]
WEIGHTINGS = ("M^-1", "M^-2", "identity")


def _rel(x, ref) -> float:
    return float(np.linalg.norm(np.asarray(x) - np.asarray(ref)) / np.linalg.norm(ref))


def _scene(seed: int, n: int, *, controlled: bool, weighting: str = "M^-1", kind="body") -> Scene:
    """A random scene with every force effect (random a, d, masses with inertia, springs, gravity,
    a given torque) and, when ``controlled``, tracking of a random subset of ω's axes and of the
    masses (Remark 4) under ``weighting``."""
    rng = np.random.default_rng(seed)
    data = random_scene_dict(rng, n, [e.value for e in ALL_FORCES], inertia_kind=kind)
    if controlled:
        comps = sorted(rng.choice(3, size=int(rng.integers(1, 4)), replace=False) + 1)
        data["scene"]["effects"] = [*data["scene"]["effects"], Effect.CONTROL_OMEGA.value]
        data["control"] = {
            "weighting": weighting,
            "omega": {
                "components": [int(c) for c in comps],
                "b": rng.normal(size=3).tolist(),
                "sigma": rng.uniform(0, 3, 3).tolist(),
                "gamma": float(rng.uniform(0.1, 2)),
            },
        }
        if n:
            idx = sorted(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False) + 1)
            k = len(idx)
            data["scene"]["effects"].append(Effect.CONTROL_MASSES.value)
            data["control"]["masses"] = {
                "indices": [int(i) for i in idx],
                "l": rng.normal(scale=0.5, size=k).tolist(),
                "lambda": rng.uniform(0, 3, k).tolist(),
                "alpha": rng.uniform(0.5, 3, k).tolist(),
                "beta": rng.uniform(1, 10, k).tolist(),
            }
    return scene_from_dict(data)


# ----------------------------------------------------------------------------------------------
# The model and the coordinate maps
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["body", "ring"])
def test_model_has_the_scenes_masses_inertias_gravity_and_layout(kind):
    scene = _scene(3, 3, controlled=False, kind=kind)
    m = build_model(scene)
    p = m.plant
    assert (p.num_positions(), p.num_velocities()) == (scene.n + 7, scene.n + 6)
    assert p.time_step() == 0.0  # continuous time
    ctx = p.CreateDefaultContext()
    br = p.GetBodyByName("BR")
    assert br.default_mass() == scene.body.mass
    J_br = br.CalcSpatialInertiaInBodyFrame(ctx).CalcRotationalInertia().CopyToFullMatrix3()
    J_ref = np.diag(scene.body.inertia)  # Drake keeps m and J/m: J comes back to a few ulps
    assert np.max(np.abs(J_br - J_ref)) <= tol.ULP_REL.value * np.max(J_ref)
    for i in range(scene.n):
        body = p.GetBodyByName(f"mass{i + 1}")
        assert body.default_mass() == scene.masses.mass[i]
        M = body.CalcSpatialInertiaInBodyFrame(ctx)
        np.testing.assert_array_equal(M.get_com(), np.zeros(3))
        J = M.CalcRotationalInertia().CopyToFullMatrix3()
        ref = np.asarray(scene.masses.inertia[i])
        assert np.max(np.abs(J - ref)) <= tol.ULP_REL.value * np.max(np.abs(ref))
        joint = p.GetJointByName(f"p{i + 1}")
        np.testing.assert_allclose(joint.translation_axis(), scene.rod.axis, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(p.gravity_field().gravity_vector(), scene.gravity)


def test_state_maps_round_trip_and_agree_with_drakes_kinematics():
    """Paper -> Drake -> paper is the identity on on-manifold states, and Drake's own kinematics at
    the mapped state give the paper's: BR's pose (C, S(u)), its spatial velocity (Ṙ, S ω) and mass
    i's centre at ``R + S (d + a p_i)``."""
    scene = _scene(5, 2, controlled=False)
    m = build_model(scene)
    p, ctx = m.plant, m.context
    rng = np.random.default_rng(5)
    for _ in range(5):
        _, q, qd = random_state(rng, scene)
        q_d, v_d = paper_to_drake(q, qd)
        qpos, qvel = drake_to_mujoco_layout(q_d, v_d)
        q2, qd2 = mujoco_to_paper_state(qpos, qvel)
        np.testing.assert_allclose(q2, q, rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value)
        np.testing.assert_allclose(qd2, qd, rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value)
        p.SetPositionsAndVelocities(ctx, np.concatenate([q_d, v_d]))
        br = p.GetBodyByName("BR")
        X = p.EvalBodyPoseInWorld(ctx, br)
        S = S_of(q[3:7])
        np.testing.assert_allclose(X.translation(), q[:3], rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value)
        np.testing.assert_allclose(X.rotation().matrix(), S, rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value)
        V = p.EvalBodySpatialVelocityInWorld(ctx, br)
        omega = omega_of(q[3:7], qd[3:7])  # H(u) u̇, Eq. (12)
        np.testing.assert_allclose(V.rotational(), S @ omega, rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value)
        np.testing.assert_allclose(V.translational(), qd[:3], rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value)
        d, a = np.asarray(scene.rod.offset), np.asarray(scene.rod.axis)
        for i in range(scene.n):
            Xi = p.EvalBodyPoseInWorld(ctx, p.GetBodyByName(f"mass{i + 1}"))
            ref = q[:3] + S @ (d + a * q[7 + i])
            np.testing.assert_allclose(Xi.translation(), ref, rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value * 10)


# ----------------------------------------------------------------------------------------------
# Goal 1: q̈ at random states of random scenes (n = 0 … 6, every effect, every weighting)
# ----------------------------------------------------------------------------------------------


def _pointwise_cases():
    cases = [(f"n{n}_uncontrolled", _scene(700 + n, n, controlled=False)) for n in range(7)]
    cases += [
        (f"n{n}_{w}", _scene(800 + 10 * n + i, n, controlled=True, weighting=w))
        for n in range(7)
        for i, w in enumerate(WEIGHTINGS)
    ]
    cases += [(name, paper_scene(name)) for name in ("paper_example1", "paper_example1_controlled")]
    return cases


@pytest.mark.parametrize(
    ("label", "scene"), _pointwise_cases(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_qddot_equals_the_analytic_model_at_random_states(label, scene):
    """Drake's q̈ under the controller (the compiled kernel, the numpy model where it declines)
    against the analytic model's controlled q̈ (Eq. 89) at 8 random on-manifold states; the control
    torque too (the same controller at the same state)."""
    plant_ = DrakeDynamics(scene)
    model = TumblingModel(scene)
    rng = np.random.default_rng(len(label))
    worst = 0.0
    for _ in range(8):
        t, q, qd = random_state(rng, scene)
        a_d, ctl = plant_.acceleration(t, q, qd)
        a_ref, c_ref = model.acceleration(t, q, qd)
        worst = max(worst, _rel(a_d, a_ref))
        if scene.controlled:
            assert _rel(ctl.torque, c_ref.torque) <= tol.DRAKE_QDDOT_REL.value
        else:
            assert ctl is None
    assert worst <= tol.DRAKE_QDDOT_REL.value, (label, worst)
    if scene.controlled and scene.control.weighting == "M^-2" and scene.n:
        assert np.any(c_ref.force_at_C != 0.0)  # the force-at-C path is exercised


def test_numpy_controller_gives_the_same_qddot():
    scene = _scene(811, 4, controlled=True)
    fast = DrakeDynamics(scene)
    slow = DrakeDynamics(scene, ControllerSource.ANALYTIC)
    rng = np.random.default_rng(1)
    for _ in range(4):
        t, q, qd = random_state(rng, scene)
        a_ref, _ = TumblingModel(scene).acceleration(t, q, qd)
        assert _rel(slow.acceleration(t, q, qd)[0], a_ref) <= tol.DRAKE_QDDOT_REL.value
        assert _rel(fast.acceleration(t, q, qd)[0], a_ref) <= tol.DRAKE_QDDOT_REL.value
    assert slow.fallbacks == slow.nfev > 0


def test_generalized_force_is_springs_of_eq38_and_the_given_torque_of_remark2():
    """Uncontrolled: Drake's applied generalized force on the prismatic joints is ``−∂U_s/∂p``
    (central differences of the analytic spring energy), on BR's rotation ``S(u) τ_g`` (the given
    body-axis torque, inertial), nothing at C."""
    scene = _scene(9, 4, controlled=False)
    dyn = DrakeDynamics(scene)
    model = TumblingModel(scene)
    rng = np.random.default_rng(9)
    t, q, qd = random_state(rng, scene)
    f = dyn.generalized_force(t, dyn.state_from_paper(q, qd))
    h = 1e-6
    grad = [
        (spring_energy(model, (q[7:] + h * e)[None])[0] - spring_energy(model, (q[7:] - h * e)[None])[0])
        / (2 * h)
        for e in np.eye(scene.n)
    ]
    np.testing.assert_allclose(f[6:], -np.array(grad), rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(
        f[:3], S_of(q[3:7]) @ scene.external_torque.at(t), rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value
    )
    assert np.all(f[3:6] == 0.0)


# ----------------------------------------------------------------------------------------------
# Goals 2 and 3: trajectories against the analytic plant
# ----------------------------------------------------------------------------------------------


def _distances(a, b) -> dict[str, float]:
    """Largest distance over the run: C (m), the rod positions (m), the attitude angle (rad)."""
    u1, u2 = a.u, b.u  # the angle of the relative rotation u1* ⊗ u2: 2 atan2(|vec|, |w|)
    w = np.sum(u1 * u2, axis=1)
    vec = u1[:, :1] * u2[:, 1:] - u2[:, :1] * u1[:, 1:] - np.cross(u1[:, 1:], u2[:, 1:])
    return {
        "C": float(np.max(np.linalg.norm(a.R - b.R, axis=1))),
        "p": float(np.max(np.abs(a.p - b.p))) if a.n else 0.0,
        "attitude": float(np.max(2.0 * np.arctan2(np.linalg.norm(vec, axis=1), np.abs(w)))),
    }


@pytest.mark.parametrize("name", ["paper_example1", "paper_example2"])
def test_twenty_seconds_uncontrolled_agree_with_the_analytic_plant(name):
    """Both plants at the scene's DOP853 tolerances (rtol 1e-12) over its 20 s: C and the rod
    positions within DRAKE_UNCONTROLLED_M; ~1.5 s each."""
    scene = paper_scene(name)
    ana = analytic_simulate(scene)
    dr = DrakePlant().simulate(scene)
    assert dr.status is RunStatus.OK and dr.t[-1] == scene.output.t_end, dr.message
    dist = _distances(dr, ana)
    assert max(dist["C"], dist["p"]) <= tol.DRAKE_UNCONTROLLED_M.value, dist


def test_controlled_example1_agrees_with_the_analytic_plant_at_rtol_1e12():
    """The controlled Example 1 over 20 s, both plants at rtol 1e-12 (atol 1e-13), the analytic
    controller at Drake's state in every evaluation: C within DRAKE_CONTROLLED_EX1_M, and the
    record is the analytic plant's (times, shapes, engine, tracking)."""
    scene = paper_scene("paper_example1_controlled")
    assert (scene.solver.rtol, scene.solver.atol) == (1e-12, 1e-13)
    ana = analytic_simulate(scene)
    dr = DrakePlant().simulate(scene)
    assert dr.engine == "drake" and dr.status is RunStatus.OK, dr.message
    np.testing.assert_array_equal(dr.t, ana.t)
    for f in ("q", "qdot", "qddot", "QC", "torque", "rod_forces", "force_at_C", "residual_norm"):
        assert getattr(dr, f).shape == getattr(ana, f).shape, f
    dist = _distances(dr, ana)
    assert dist["C"] <= tol.DRAKE_CONTROLLED_EX1_M.value, dist
    assert max(dist["p"], dist["attitude"]) <= tol.DRAKE_CONTROLLED_EX1_M.value, dist
    assert np.max(np.abs(dr.tracking.e_p - ana.tracking.e_p)) <= tol.DRAKE_CONTROLLED_EX1_M.value
    assert dr.info["controller_fallbacks"] == 0 and dr.info["nfev"] > 0
    assert np.all(dr.force_at_C == 0.0)  # the paper's cost has no force at C


TIGHT_RTOL = 2.5e-14
"""Just above scipy's floor (100 eps): where integration error is far below the model's agreement."""


@pytest.mark.slow
@pytest.mark.parametrize("seed_n", [(31, 3), (32, 6)])
def test_twenty_seconds_random_scenes_and_spacecraft_agree(seed_n):
    """Random n = 3 and n = 6 scenes with every force effect (and the spacecraft scene with the n = 3
    one), 20 s uncontrolled, both plants at rtol 2.5e-14: C and the rod positions within
    DRAKE_UNCONTROLLED_M. (At rtol 1e-12 the random scenes' C travels ~1 km and each plant's own
    integration error is ~1.5e-9 m, so the comparison is made where that error is gone.)"""
    seed, n = seed_n
    scenes = [_scene(seed, n, controlled=False)]
    if n == 3:
        scenes.append(paper_scene("spacecraft_slosh"))
    settings = DrakeSettings(rtol=TIGHT_RTOL, atol=TIGHT_RTOL / 10)
    for scene in scenes:
        t_end = min(scene.output.t_end, 20.0)
        ana = analytic_simulate(scene, t_end=t_end, rtol=TIGHT_RTOL, atol=TIGHT_RTOL / 10)
        dr = DrakePlant().simulate(scene, settings, t_end=t_end)
        assert dr.status is RunStatus.OK, dr.message
        dist = _distances(dr, ana)
        assert max(dist["C"], dist["p"]) <= tol.DRAKE_UNCONTROLLED_M.value, (scene.name, dist)


# ----------------------------------------------------------------------------------------------
# The plant protocol, settings, registration
# ----------------------------------------------------------------------------------------------


def test_short_runs_under_other_weightings_agree():
    """2 s of random controlled scenes under M^-2 (a force at C) and identity (compiled too) at
    rtol 1e-12: C within DRAKE_CONTROLLED_EX1_M of the analytic plant."""
    for w in ("M^-2", "identity"):
        scene = _scene(850, 3, controlled=True, weighting=w)
        ana = analytic_simulate(scene, t_end=2.0)
        dr = DrakePlant().simulate(scene, t_end=2.0)
        assert dr.status is RunStatus.OK, dr.message
        dist = _distances(dr, ana)
        assert dist["C"] <= tol.DRAKE_CONTROLLED_EX1_M.value, (w, dist)
        assert dr.info["controller_fallbacks"] == 0  # every weighting is compiled


def test_plant_protocol_settings_and_effects():
    pl = DrakePlant()
    assert pl.engine == "drake" and pl.effects == frozenset(Effect)
    assert pl.unavailable() == drake_unavailable() == ""
    scene = paper_scene("paper_example1_controlled")
    pl.check_scene(scene)  # every effect is supported
    s = pl.default_settings(scene)
    assert (s.rtol, s.atol) == (scene.solver.rtol, scene.solver.atol)
    assert pl.describe(s).startswith("Drake DOP853")
    for bad in ({"rtol": -1.0}, {"atol": 0}, {"max_step": float("nan")}, {"method": "Euler"}):
        field = next(iter(bad))
        with pytest.raises(ValueError, match=field):
            DrakeSettings(**bad)
    with pytest.raises(ValueError, match="controller"):
        DrakeSettings(controller="mujoco")
    with pytest.raises(ValueError, match="settings"):
        pl.simulate(scene, object())
    with pytest.raises(ValueError, match="t_end"):
        pl.simulate(scene, t_end=-1.0)


def test_registered_as_a_plugin_but_not_a_default_plant():
    """The project's own entry point registers Drake (group ``tumbling_testbed.plants``): ``plant``
    and ``--plants`` know it, it sorts after the built-ins, but it is not among the default plants
    (``default = False``), so a run that names no plants is the three built-ins' as before."""
    from mj_bridge.plants import parse_plants, plugin_errors, registered

    assert registered()["drake"] is DrakePlant
    assert not [e for e in plugin_errors() if e.name == "drake"]
    assert "drake" not in installed_plants()
    assert isinstance(plant("drake"), DrakePlant)
    assert parse_plants("drake, analytic") == ("analytic", "drake")
    assert "drake" in parse_plants("all")


def test_unavailable_says_how_to_install(monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "pydrake" else real(name, *a)
    )
    assert DrakePlant.unavailable() == DRAKE_MISSING
    assert "[drake]" in DRAKE_MISSING
    with pytest.raises(ImportError, match="drake"):
        DrakePlant().simulate(paper_scene("paper_example1"))


def test_sample_accelerations_are_drakes_mapped_to_paper_coordinates():
    """The record's q̈ at each sample is the paper's q̈ of Drake's v̇ at that sample (the batch map
    against the one-state path)."""
    scene = paper_scene("paper_example2")
    dr = DrakePlant().simulate(scene, t_end=0.5)
    dyn = DrakeDynamics(scene)
    for i in (0, len(dr.t) // 2, len(dr.t) - 1):
        a, _ = dyn.acceleration(dr.t[i], dr.q[i], dr.qdot[i])
        assert _rel(dr.qddot[i], a) <= tol.DRAKE_QDDOT_REL.value
    q_d, v_d = paper_to_drake(dr.q, dr.qdot)
    q2, _, _, _ = drake_to_paper_batch(q_d, v_d, np.zeros_like(v_d))
    np.testing.assert_allclose(q2, dr.q, rtol=0, atol=tol.STATE_MAP_ROUNDTRIP.value * 10)
