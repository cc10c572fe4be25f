"""mj_bridge: the MuJoCo twin against the analytic model (state maps, pointwise q̈ and controller,
trajectories, convergence order).

References: the analytic model of the paper (q̈ and the controller at a state, and its trajectory),
MuJoCo's own kinematics and invariants, closed-form error dynamics of the control (docs/errata.md, item 3:
``e_ω(t) = e_ω(0) e^{-γt}``, ``ë_p + α ė_p + β e_p = 0``), and observed convergence orders.
"""

from __future__ import annotations

import zlib

import mujoco
import numpy as np
import pytest

from analytic.effects import Effect
from analytic.model import TumblingModel
from mj_bridge import (
    ControllerSource,
    Twin,
    acceleration,
    installed,
    mujoco_control,
    mujoco_to_paper_state,
    paper_to_mujoco_state,
    simulate,
)
from mj_bridge.callbacks import any_installed
from model_xml import BodyFrame, build_spec
from model_xml.rotations import attitude_angle, quat_to_mat
from tests.support import tolerances as th
from tests.support.mj_scenes import PAPER, paper_scene, random_scene, random_state


def _offset_frame() -> BodyFrame:
    q = np.array([0.8, 0.2, -0.4, 0.4])
    return BodyFrame(pos=np.array([0.7, -1.3, 2.1]), quat=q / np.linalg.norm(q))


def _rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _pointwise_cases():
    rng = np.random.default_rng(2017)
    cases = [(name, paper_scene(name)) for name in PAPER]
    cases.append(("rigid_n0", rigid_scene()))
    for k in range(8):
        cases.append(
            (
                f"random{k}",
                random_scene(rng, controlled=k % 4 != 0, external_torque=k % 3 == 1),
            )
        )
    return cases


def rigid_scene():
    """n = 0: a rigid body alone (M singular along u in the paper's coordinates), ω tracked."""
    from analytic.scene import scene_from_dict

    return scene_from_dict(
        {
            "scene": {"name": "rigid", "effects": ["gravity", "control.omega"]},
            "body": {"mass": 3.0, "inertia": [1.0, 1.5, 2.0]},
            "rod": {"axis": [0.0, 0.0, 1.0], "offset": [0.0, 0.0, 0.0]},
            "initial": {"omega": [1.0, 2.0, 0.5], "attitude": {"quaternion": [1.0, 0, 0, 0]}},
            "control": {"omega": {"b": [1.0, 1.0, 1.0], "sigma": [1.0, 2.0, 3.0], "gamma": 0.5}},
        }
    )


POINTWISE = _pointwise_cases()


# ------------------------------------------------------------------------------------------------
# State maps
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("frame", [None, "offset"])
def test_state_map_round_trip_and_mujoco_kinematics(frame):
    """paper -> MuJoCo -> paper is the identity, and MuJoCo's own kinematics of the mapped state
    put BR's centre of mass at R, its principal frame at S(u) and its CoM velocity at Ṙ."""
    scene = paper_scene("paper_example1")
    bf = _offset_frame() if frame else None
    tw = Twin(scene, body_frame=bf)
    rng = np.random.default_rng(4)
    for _ in range(5):
        _, q, qd = random_state(rng, scene, scale=3.0)
        qpos, qvel = tw.to_mujoco(q, qd)
        q2, qd2 = tw.to_paper(qpos, qvel)
        assert np.max(np.abs(q2 - q)) <= th.STATE_MAP_ROUNDTRIP.value * np.max(np.abs(q))
        assert np.max(np.abs(qd2 - qd)) <= th.STATE_MAP_ROUNDTRIP.value * np.max(np.abs(qd))
        d = tw.d
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(tw.m, d)
        b = tw.body_id
        tol = th.KINEMATICS_REL.value
        np.testing.assert_allclose(d.xipos[b], q[:3], rtol=0, atol=tol * np.abs(q).max())
        np.testing.assert_allclose(d.ximat[b].reshape(3, 3), quat_to_mat(q[3:7]), atol=tol)
        vel = np.zeros(6)  # [angular, linear] at the CoM, world frame
        mujoco.mj_objectVelocity(tw.m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)
        np.testing.assert_allclose(vel[3:], qd[:3], rtol=0, atol=tol * np.abs(qd).max())
        omega_world = quat_to_mat(q[3:7]) @ TumblingModel(scene)._kin(q, qd).omega
        np.testing.assert_allclose(vel[:3], omega_world, rtol=0, atol=tol * np.abs(qd).max())


@pytest.mark.parametrize("frame", [None, "offset"])
def test_batched_state_map_is_the_per_sample_map(frame):
    """mj_bridge.simulate maps all samples at once (model_xml.coordinates.mujoco_to_paper_batch): the
    same q, q̇, q̈ as the per-sample maps, and ω = R_Iᵀ ω_b."""
    from model_xml.coordinates import mujoco_to_paper_acc, mujoco_to_paper_batch

    scene = paper_scene("paper_example2")
    tw = Twin(scene, body_frame=_offset_frame() if frame else None)
    rng = np.random.default_rng(8)
    rows = []
    for _ in range(6):
        _, q, qd = random_state(rng, scene, scale=3.0)
        qpos, qvel = tw.to_mujoco(q, qd)
        rows.append((qpos, qvel, rng.normal(size=tw.m.nv) * 10))
    qpos, qvel, qacc = (np.array(x) for x in zip(*rows, strict=True))
    Q, QD, QDD, W = mujoco_to_paper_batch(qpos, qvel, qacc, tw.ipos, tw.iquat)
    tol = th.STATE_MAP_ROUNDTRIP.value
    for i in range(len(rows)):
        q1, qd1 = mujoco_to_paper_state(qpos[i], qvel[i], tw.ipos, tw.iquat)
        qdd1 = mujoco_to_paper_acc(qpos[i], qvel[i], qacc[i], tw.ipos, tw.iquat)
        for a, b in ((Q[i], q1), (QD[i], qd1), (QDD[i], qdd1), (W[i], tw.R_I.T @ qvel[i, 3:6])):
            assert np.max(np.abs(a - b)) <= tol * np.max(np.abs(b))


def test_model_level_state_maps_read_the_inertial_frame():
    """to_mujoco / to_paper on a model whose BR frame is offset from C agree with the Twin's."""
    from mj_bridge import to_mujoco, to_paper, to_paper_acc

    scene = paper_scene("paper_example1")
    tw = Twin(scene, body_frame=_offset_frame())
    _, q, qd = random_state(np.random.default_rng(8), scene)
    qpos, qvel = to_mujoco(tw.m, q, qd)
    q2, qd2 = to_paper(tw.m, qpos, qvel)
    assert (
        _rel(q2, q) <= th.STATE_MAP_ROUNDTRIP.value
        and _rel(qd2, qd) <= th.STATE_MAP_ROUNDTRIP.value
    )
    ref, _ = TumblingModel(scene).acceleration(0.0, q, qd)
    tw.forward(0.0, q, qd)
    assert (
        _rel(to_paper_acc(tw.m, tw.d.qpos, tw.d.qvel, tw.d.qacc), ref)
        <= th.POINTWISE_QDDOT_REL.value
    )


def test_state_map_functions_exported():
    scene = paper_scene("paper_example2")
    q, qd = scene.initial.q0(), scene.initial.qdot0()
    qpos, qvel = paper_to_mujoco_state(q, qd, np.zeros(3), np.array([1.0, 0, 0, 0]))
    np.testing.assert_array_equal(qpos[:3], q[:3])  # exact: a zero offset, R - Rb @ 0 = R
    np.testing.assert_allclose(qvel[3:6], scene.initial.omega, rtol=th.ULP_REL.value)
    q2, _ = mujoco_to_paper_state(qpos, qvel, np.zeros(3), np.array([1.0, 0, 0, 0]))
    np.testing.assert_allclose(q2, q, rtol=0, atol=th.ULP_REL.value)


# ------------------------------------------------------------------------------------------------
# Test 1: pointwise q̈ and controller
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("label", "scene"), POINTWISE, ids=[c[0] for c in POINTWISE])
def test_pointwise_qddot_matches_analytic(label, scene):
    model = TumblingModel(scene)
    tw = Twin(scene)
    tw_off = Twin(scene, body_frame=_offset_frame())
    rng = np.random.default_rng(zlib.crc32(label.encode()))
    for _ in range(4):
        t, q, qd = random_state(rng, scene)
        ref, _ = model.acceleration(t, q, qd)
        assert _rel(tw.acceleration(t, q, qd), ref) <= th.POINTWISE_QDDOT_REL.value
        assert _rel(tw_off.acceleration(t, q, qd), ref) <= th.POINTWISE_QDDOT_REL.value


@pytest.mark.parametrize(
    ("label", "scene"),
    [c for c in POINTWISE if c[1].controlled],
    ids=[c[0] for c in POINTWISE if c[1].controlled],
)
def test_pointwise_controllers_agree(label, scene):
    """The analytic controller (paper coordinates, quaternion constraint) and Udwadia–Kalaba from
    MuJoCo's own M and forces (MuJoCo coordinates) give the same torque and rod forces."""
    model = TumblingModel(scene)
    tw = Twin(scene)
    tw_off = Twin(scene, body_frame=_offset_frame())
    rng = np.random.default_rng(zlib.crc32(label.encode()) + 1)
    for _ in range(4):
        t, q, qd = random_state(rng, scene)
        qdd, c = model.acceleration(t, q, qd)
        for twin in (tw, tw_off):
            mc = twin.mujoco_control(t, q, qd)
            ref = np.concatenate([c.torque, c.rod_forces])
            got = np.concatenate([mc.torque, mc.rod_forces])
            assert np.max(np.abs(got - ref)) <= th.POINTWISE_CONTROL_REL.value * np.max(np.abs(ref))
            assert np.max(np.abs(mc.residual)) <= th.POINTWISE_QDDOT_REL.value * np.max(np.abs(qdd))


def test_spring_actuator_trajectory_matches_tendon_springs():
    """Spring actuators (user-bias cubic term at every RK4 stage) vs native tendon springs along
    a run: the same motion to round-off."""
    from analytic.scene import MujocoSettings

    base = paper_scene("paper_example2_controlled")
    alt = base.replace(mujoco=MujocoSettings(spring_model="actuator"))
    a = simulate(base, dt=5e-3, t_end=0.5)
    b = simulate(alt, dt=5e-3, t_end=0.5)
    assert b.info["spring_model"] == "actuator"
    assert _rel(b.q, a.q) <= th.SPRING_ACTUATOR_VS_TENDON_REL.value
    assert _rel(b.qdot, a.qdot) <= th.SPRING_ACTUATOR_VS_TENDON_REL.value
    c = simulate(alt, dt=5e-3, t_end=0.5, controller=ControllerSource.MUJOCO)
    assert _rel(c.q, a.q) <= th.CONTROLLER_SOURCES_TRAJ_REL.value


def test_control_above_mjmaxval_is_applied():
    """Rod forces above mjMAXVAL (1e10 N, where MuJoCo zeroes every ctrl) still reach the plant:
    the control actuators' power-of-two gear keeps ctrl small (hard case: masses 1e3 x m_BR)."""
    from analytic.scene import load_scene
    from validation.scenes import HARD_DIR

    scene = load_scene(HARD_DIR / "heavy_masses.toml")
    q, qd = scene.initial.q0(), scene.initial.qdot0()
    ref, c = TumblingModel(scene).acceleration(0.0, q, qd)
    assert np.max(np.abs(c.rod_forces)) > mujoco.mjMAXVAL
    assert _rel(Twin(scene).acceleration(0.0, q, qd), ref) <= th.POINTWISE_QDDOT_REL.value


def test_mujoco_bad_warning_is_an_error_not_silence():
    """A ctrl MuJoCo refuses (it would zero every control) raises instead of passing silently."""
    scene = paper_scene("paper_example1_controlled")
    tw = Twin(scene, controller=ControllerSource.ANALYTIC)
    model = tw.model

    def huge(t, q, qd):
        qdd, c = model.acceleration(t, q, qd)
        return qdd, c.__class__(
            QC=c.QC, torque=c.torque * 1e30, rod_forces=c.rod_forces, force_at_C=c.force_at_C,
            residual=c.residual, rank=c.rank,
        )  # fmt: skip

    tw.stages.controller_fn = huge
    with pytest.raises(RuntimeError, match="mjWARN_BADCTRL"):
        tw.forward(0.0, scene.initial.q0(), scene.initial.qdot0())


def test_simulate_reports_mujoco_bad_warning_as_failed(monkeypatch):
    """The same refusal during a run ends it with status failed, naming the warning."""
    import sys

    sim = sys.modules["mj_bridge.simulate"]
    twin_module = sys.modules["mj_bridge.twin"]  # simulate() takes Twin from there when it runs

    class HugeTwin(Twin):
        def __init__(self, *a, **kw):
            kw["controller"] = ControllerSource.ANALYTIC
            super().__init__(*a, **kw)
            model = self.model

            def huge(t, q, qd):
                qdd, c = model.acceleration(t, q, qd)
                scale = 1.0 if t < 0.05 else 1e30
                return qdd, c.__class__(
                    QC=c.QC, torque=c.torque * scale, rod_forces=c.rod_forces,
                    force_at_C=c.force_at_C, residual=c.residual, rank=c.rank,
                )  # fmt: skip

            self.stages.controller_fn = huge

    monkeypatch.setattr(twin_module, "Twin", HugeTwin)
    tr = sim.simulate(paper_scene("paper_example1_controlled"), dt=5e-3, t_end=0.2)
    assert tr.status.value == "failed"
    assert "mjWARN_BADCTRL" in tr.message
    assert 0.04 <= tr.t[-1] < 0.2


def test_an_unstable_run_fails_with_mujocos_instability_not_the_call_count(monkeypatch):
    """A control that blows up in finite time (a singular control) without making ``ctrl`` bad:
    a force at C (``xfrc_applied``, which MuJoCo does not check) of 1e17 N from t = 0.02 s makes
    qacc huge, MuJoCo warns (bad qacc: "the simulation is unstable"), resets the state and
    evaluates it again, one controller call more than RK4's four per step. The run must end
    failed with that warning named, not raise about the controller's call count."""
    import sys

    sim = sys.modules["mj_bridge.simulate"]
    twin_module = sys.modules["mj_bridge.twin"]  # simulate() takes Twin from there when it runs

    class BlowUpTwin(Twin):
        def __init__(self, *a, **kw):
            kw["controller"] = ControllerSource.ANALYTIC
            super().__init__(*a, **kw)
            model = self.model

            def blow_up(t, q, qd):
                qdd, c = model.acceleration(t, q, qd)
                extra = 0.0 if t < 0.02 else 1e17  # N: qacc ~ 1e17 / 4.6e5 kg, above mjMAXVAL
                return qdd, c.__class__(
                    QC=c.QC, torque=c.torque, rod_forces=c.rod_forces,
                    force_at_C=c.force_at_C + extra, residual=c.residual, rank=c.rank,
                )  # fmt: skip

            self.stages.controller_fn = blow_up

    monkeypatch.setattr(twin_module, "Twin", BlowUpTwin)
    with pytest.warns(UserWarning, match="unstable"):
        tr = sim.simulate(paper_scene("paper_example1_controlled"), dt=1e-3, t_end=0.1)
    assert tr.status.value == "failed"
    assert "mjWARN_BADQACC" in tr.message and "unstable" in tr.message, tr.message
    assert "controller called" not in tr.message
    assert 0.01 <= tr.t[-1] <= 0.02


def test_module_level_functions():
    scene = paper_scene("paper_example2_controlled")
    q, qd = scene.initial.q0(), scene.initial.qdot0()
    ref, c = TumblingModel(scene).acceleration(0.5, q, qd)
    assert _rel(acceleration(scene, 0.5, q, qd), ref) <= th.POINTWISE_QDDOT_REL.value
    assert (
        _rel(mujoco_control(scene, 0.5, q, qd).torque, c.torque) <= th.POINTWISE_CONTROL_REL.value
    )


# ------------------------------------------------------------------------------------------------
# Callbacks
# ------------------------------------------------------------------------------------------------


def test_callbacks_removed_after_run_and_on_exception():
    scene = paper_scene("paper_example2_controlled")
    simulate(scene, dt=5e-3, t_end=0.02)
    assert not any_installed()
    build_spec(scene).compile()  # compiling works again

    tw = Twin(scene, controller=ControllerSource.ANALYTIC)

    class Boom(RuntimeError):
        pass

    def explode(*_):
        raise Boom("in callback")

    tw.stages.controller_fn = explode
    with pytest.raises(Boom):
        tw.forward(0.0, scene.initial.q0(), scene.initial.qdot0())
    assert not any_installed()
    with pytest.raises(RuntimeError, match="already installed"):
        with installed(control=lambda m, d: None):
            with installed(control=lambda m, d: None):
                pass
    assert not any_installed()
    mujoco.set_mjcb_control(lambda m, d: None)  # somebody else's callback is never replaced
    try:
        with pytest.raises(RuntimeError, match="other code"):
            with installed(control=lambda m, d: None):
                pass
    finally:
        mujoco.set_mjcb_control(None)


def test_controller_runs_at_every_rk4_stage():
    """The callback sees the four RK4 stage times t, t+h/2, t+h/2, t+h."""
    scene = paper_scene("paper_example1_controlled")
    tw = Twin(scene, dt=1e-3)
    seen = []
    inner = tw.control_callback

    def spy(m, d):
        seen.append(d.time)
        inner(m, d)

    tw.set_state(0.0, scene.initial.q0(), scene.initial.qdot0())
    with installed(control=spy):
        mujoco.mj_step(tw.m, tw.d)
    np.testing.assert_allclose(seen, [0.0, 5e-4, 5e-4, 1e-3], rtol=0, atol=1e-18)


def test_bad_arguments_raise_value_error_naming_field():
    scene = paper_scene("paper_example1")
    with pytest.raises(ValueError, match="integrator"):
        simulate(scene, integrator="RK5")
    with pytest.raises(ValueError, match="dt"):
        simulate(scene, dt=3e-3, t_end=0.1)
    with pytest.raises(ValueError, match="dt"):
        simulate(scene, dt=-1e-3)
    with pytest.raises(ValueError, match="t_end"):
        simulate(scene, t_end=-1.0)


# ------------------------------------------------------------------------------------------------
# Test 2: convergence orders (the test that catches a controller held over the step)
# ------------------------------------------------------------------------------------------------


def _final_state(tr) -> np.ndarray:
    return np.concatenate([tr.q[-1, :3], tr.q[-1, 7:], tr.qdot[-1, :3], tr.qdot[-1, 7:]])


def _observed_order(runs) -> float:
    """Order from three runs at h, h/2, h/4: log2(|y_h - y_h/2| / |y_h/2 - y_h/4|), with the
    attitude difference measured as an angle."""

    def diff(a, b):
        x = np.max(np.abs(_final_state(a) - _final_state(b)))
        ang = float(attitude_angle(a.q[-1, 3:7], b.q[-1, 3:7]))
        return max(x / max(1.0, np.max(np.abs(_final_state(b)))), ang)

    return float(np.log2(diff(runs[0], runs[1]) / diff(runs[1], runs[2])))


@pytest.mark.parametrize(
    ("name", "t_end", "dt0"),
    [
        ("paper_example1", 2.0, 1e-2),
        ("paper_example1_controlled", 0.5, 1e-2),
        # Example 2's stiffest spring mode (~40 rad/s) needs ωh < 0.2 to be asymptotic
        ("paper_example2", 1.0, 5e-3),
        ("paper_example2_controlled", 0.5, 1e-2),
    ],
)
def test_rk4_convergence_order_is_four(name, t_end, dt0):
    """Test 2: dt-halving order 4 ± 0.3, uncontrolled and controlled (the controller runs at every
    RK4 stage; see test_order_test_detects_a_held_controller for what holding it does)."""
    scene = paper_scene(name)
    runs = [simulate(scene, dt=dt, t_end=t_end) for dt in (dt0, dt0 / 2, dt0 / 4)]
    order = _observed_order(runs)
    assert abs(order - th.CONVERGENCE_ORDER.value) <= th.CONVERGENCE_ORDER_TOL.value, order


def _held_controller_run(scene, dt, t_end):
    """RK4 with the controller evaluated once per step from Python and held (the trap)."""
    tw = Twin(scene, dt=dt)
    tw.set_state(0.0, scene.initial.q0(), scene.initial.qdot0())
    for _ in range(round(t_end / dt)):
        q, qd = tw.state()
        _, c = tw.model.acceleration(tw.d.time, q, qd)
        tw.stages.write_controls(tw.d, c.torque, c.rod_forces, c.force_at_C)
        mujoco.mj_step(tw.m, tw.d)

    class R:
        pass

    r = R()
    q, qd = tw.state()
    r.q, r.qdot = q[None], qd[None]
    return r


def test_order_test_detects_a_held_controller():
    """The order test is sensitive: holding the controller over the step makes RK4 first order."""
    scene = paper_scene("paper_example2_controlled")
    runs = [_held_controller_run(scene, dt, 0.5) for dt in (2.5e-3, 1.25e-3, 6.25e-4)]
    order = _observed_order(runs)
    assert abs(order - 1.0) < th.CONVERGENCE_ORDER_TOL.value, order


# ------------------------------------------------------------------------------------------------
# Test 3: control in MuJoCo, closed-form error dynamics, rod forces
# ------------------------------------------------------------------------------------------------


def _closed_form_errors(scene, t, e_w0, e_p0, e_pd0):
    """docs/errata.md, item 3: e_ω(t) = e_ω(0) e^{-γt}; e_p solves ë + αė + βe = 0 (underdamped for the paper)."""
    model = TumblingModel(scene)
    gamma = np.diag(model.omega_track.gain)
    e_w = e_w0[None] * np.exp(-np.outer(t, gamma))
    mt = model.mass_track
    alpha, beta = np.asarray(mt.alpha), np.asarray(mt.beta)
    w = np.sqrt(beta - alpha**2 / 4)
    sig = alpha / 2
    e_p = np.exp(-np.outer(t, sig)) * (
        e_p0 * np.cos(np.outer(t, w)) + (e_pd0 + sig * e_p0) / w * np.sin(np.outer(t, w))
    )
    return e_w, e_p


@pytest.mark.parametrize("controller", list(ControllerSource))
def test_controlled_example2_follows_closed_form_error_dynamics(controller):
    scene = paper_scene("paper_example2_controlled")
    tr = simulate(scene, dt=2e-3, t_end=1.0, controller=controller)
    model = TumblingModel(scene)
    idx = model._p_idx
    req = model.requirements(0.0)
    e_pd0 = np.asarray(scene.initial.pdot)[idx] - req["p_bar_dot"]
    e_w, e_p = _closed_form_errors(scene, tr.t, tr.tracking.e_omega[0], tr.tracking.e_p[0], e_pd0)
    tol = th.CLOSED_FORM_ERROR_REL.value
    np.testing.assert_allclose(tr.tracking.e_omega, e_w, rtol=0, atol=tol * np.abs(e_w).max())
    np.testing.assert_allclose(tr.tracking.e_p, e_p, rtol=0, atol=tol * np.abs(e_p).max())
    # Gauss's weighting: no rod force on the untracked masses (3 and 5), none at C
    untracked = [i for i in range(scene.n) if i not in idx]
    rod = tr.rod_forces
    assert (
        np.max(np.abs(rod[:, untracked])) <= th.UNCONTROLLED_ROD_FORCE_REL.value * np.abs(rod).max()
    )
    assert np.max(np.abs(tr.force_at_C)) == 0.0  # structural: written as 0 by every source


def test_controller_sources_give_the_same_trajectory():
    """Compiled analytic (default), numpy analytic and MuJoCo-matrix Udwadia–Kalaba controllers
    drive MuJoCo along the same trajectory, with the same work and impulses."""
    scene = paper_scene("paper_example1_controlled")
    runs = {src: simulate(scene, dt=5e-3, t_end=0.5, controller=src) for src in ControllerSource}
    ref = runs[ControllerSource.ANALYTIC]
    for src, tr in runs.items():
        assert tr.info["controller"] == src.value
        tol = th.CONTROLLER_SOURCES_TRAJ_REL.value
        assert _rel(tr.q, ref.q) <= tol
        assert _rel(tr.qdot, ref.qdot) <= tol
        assert _rel(tr.torque, ref.torque) <= tol
        assert _rel(tr.invariants.work, ref.invariants.work) <= tol
        assert _rel(tr.invariants.angular_impulse, ref.invariants.angular_impulse) <= tol


@pytest.mark.parametrize("weighting", ["M^-1", "M^-2", "identity"])
def test_balances_with_given_torque_and_other_weightings(weighting):
    """A random controlled scene with a given torque: energy, angular and linear momentum balances
    hold with the stage-integrated work and impulses (the compiled stage, as a native callback,
    for every weighting; M⁻² and identity also put a force at C)."""
    import dataclasses

    from analytic.effects import Weighting

    rng = np.random.default_rng(99)
    scene = random_scene(rng, 3, controlled=True, external_torque=True)
    scene = scene.replace(
        control=dataclasses.replace(scene.control, weighting=Weighting(weighting))
    )
    tr = simulate(scene, dt=2e-3, t_end=1.0)
    assert tr.info["native_callback"] and tr.info["native_redos"] == 0
    inv = tr.invariants
    E_scale = np.max(np.abs(inv.energy)) + np.max(np.abs(inv.work))
    L_scale = np.max(np.linalg.norm(inv.angular_momentum, axis=1))
    P_scale = np.max(np.abs(inv.linear_momentum))
    assert np.max(np.abs(inv.energy_balance())) <= th.BALANCE_REL_CONTROLLED.value * E_scale
    assert (
        np.max(np.abs(inv.angular_momentum_balance())) <= th.BALANCE_REL_CONTROLLED.value * L_scale
    )
    assert (
        np.max(np.abs(inv.linear_momentum_balance())) <= th.BALANCE_REL_CONTROLLED.value * P_scale
    )
    if weighting == "identity":
        assert np.max(np.abs(tr.force_at_C)) > 0  # the case the force-at-C moment is for


def test_controlled_balances_with_stage_integrated_work():
    """Energy and angular momentum change only by the control's work and moment (integrated by
    the same RK4 stages as the motion)."""
    scene = paper_scene("paper_example1_controlled")
    tr = simulate(scene, dt=2e-3, t_end=1.0)
    inv = tr.invariants
    E_scale = np.max(np.abs(inv.energy))
    L_scale = np.max(np.linalg.norm(inv.angular_momentum, axis=1))
    assert np.max(np.abs(inv.energy_balance())) <= th.BALANCE_REL_CONTROLLED.value * E_scale
    assert (
        np.max(np.abs(inv.angular_momentum_balance())) <= th.BALANCE_REL_CONTROLLED.value * L_scale
    )
    P_scale = np.max(np.abs(inv.linear_momentum))
    assert (
        np.max(np.abs(inv.linear_momentum_balance())) <= th.BALANCE_REL_CONTROLLED.value * P_scale
    )


@pytest.fixture(scope="module")
def mj_runs_20s():
    """Uncontrolled 20 s runs of both examples at dt = 1e-3 (no callback: fast)."""
    out = {}
    for name in ("paper_example1", "paper_example2"):
        out[name] = {
            integ: simulate(paper_scene(name), integrator=integ, dt=1e-3)
            for integ in ("RK4", "Euler", "implicitfast")
        }
    return out


def _drift(tr) -> dict[str, float]:
    """Largest relative change over the run of energy, angular momentum about the system CoM, and
    of linear momentum against P(0) + m_T g t."""
    inv = tr.invariants
    E, L = inv.energy, inv.angular_momentum
    return {
        "energy": float(np.max(np.abs(E - E[0])) / np.abs(E[0])),
        "angular_momentum": float(np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0])),
        "linear_momentum": float(
            np.max(np.abs(inv.linear_momentum_balance())) / np.max(np.abs(inv.linear_momentum))
        ),
    }


@pytest.mark.parametrize("name", ["paper_example1", "paper_example2"])
def test_invariant_drift_20s_by_integrator(mj_runs_20s, name, record_property):
    """Test 4: RK4 at dt = 1e-3 conserves energy and momentum over 20 s; Euler and implicitfast
    drift (recorded, and asserted to be far worse than RK4, not hidden).

    Example 1 meets 1e-10 at dt = 1e-3. Example 2's stiffest spring mode (k up to 8 MN/m on
    1e4 kg masses, ~40 rad/s) leaves RK4 a truncation drift of ~5e-8 at dt = 1e-3; that it is
    truncation (not a modelling error) is shown by its h^5 convergence here, and the 1e-10 bound at
    the scene's own dt = 2.5e-4 is the slow test below.
    """
    drift = {integ: _drift(tr) for integ, tr in mj_runs_20s[name].items()}
    for integ, v in drift.items():
        record_property(f"{name}.{integ}", v)
    print(name, drift)
    if name == "paper_example1":
        for key, value in drift["RK4"].items():
            assert value <= th.RK4_INVARIANT_DRIFT_REL.value, (key, value)
    else:
        half = _drift(simulate(paper_scene(name), integrator="RK4", dt=5e-4))
        for key in ("energy", "angular_momentum"):
            ratio = drift["RK4"][key] / half[key]
            assert ratio >= 2**4, (key, ratio)
    for integ in ("Euler", "implicitfast"):
        assert drift[integ]["energy"] > 1e4 * drift["RK4"]["energy"]
        assert drift[integ]["angular_momentum"] > 1e4 * drift["RK4"]["angular_momentum"]


@pytest.mark.slow
def test_example2_rk4_conserves_at_scene_timestep():
    tr = simulate(paper_scene("paper_example2"), integrator="RK4")  # dt = 2.5e-4
    for key, value in _drift(tr).items():
        assert value <= th.RK4_INVARIANT_DRIFT_REL.value, (key, value)


@pytest.mark.parametrize("name", ["paper_example1", "paper_example2"])
def test_mujoco_energy_and_momentum_match_paper_formulas(mj_runs_20s, name):
    """MuJoCo's own d.energy and subtree angular momentum vs the paper-coordinate invariants."""
    tr = mj_runs_20s[name]["RK4"]
    E_mj = np.array(tr.info["mujoco_energy"])
    np.testing.assert_allclose(
        E_mj,
        tr.invariants.energy,
        rtol=0,
        atol=th.MJ_ENERGY_VS_PAPER_REL.value * np.abs(E_mj).max(),
    )
    scene = paper_scene(name)
    tw = Twin(scene)
    for i in range(0, len(tr.t), 400):
        tw.set_state(tr.t[i], tr.q[i], tr.qdot[i])
        mujoco.mj_forward(tw.m, tw.d)
        mujoco.mj_subtreeVel(tw.m, tw.d)
        L_mj = tw.d.subtree_angmom[tw.body_id]
        L = tr.invariants.angular_momentum[i]
        assert np.max(np.abs(L_mj - L)) <= th.MJ_ANGMOM_VS_PAPER_REL.value * np.linalg.norm(L)


# ------------------------------------------------------------------------------------------------
# Slow: 20 s against the analytic engine
# ------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def analytic_ex1():
    from analytic.simulate import simulate as analytic_simulate

    return analytic_simulate(paper_scene("paper_example1"), rtol=1e-12, atol=1e-13)


@pytest.mark.slow
def test_example1_20s_rk4_matches_analytic(analytic_ex1):
    """Test 2: positions of C and every mass within 1e-9 m, attitude within 1e-9 rad."""
    scene = paper_scene("paper_example1")
    tr = simulate(scene, integrator="RK4", dt=2.5e-4)
    ref = analytic_ex1
    model = TumblingModel(scene)
    err_C = np.max(np.abs(tr.q[:, :3] - ref.q[:, :3]))
    err_m = max(
        np.max(np.abs(model.positions(a) - model.positions(b)))
        for a, b in zip(tr.q, ref.q, strict=True)
    )
    err_att = np.max(attitude_angle(tr.q[:, 3:7], ref.q[:, 3:7]))
    print(f"C {err_C:.3e} m, masses {err_m:.3e} m, attitude {err_att:.3e} rad")
    assert err_C <= th.EX1_POSITION_ABS_M.value
    assert err_m <= th.EX1_POSITION_ABS_M.value
    assert err_att <= th.EX1_ATTITUDE_RAD.value


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper_example1_controlled", "paper_example2_controlled"])
def test_controlled_20s_tracking_within_factor_of_analytic(name):
    from analytic.simulate import simulate as analytic_simulate

    scene = paper_scene(name)
    ref = analytic_simulate(scene)
    tr = simulate(scene)
    for key in ("e_omega", "e_p"):
        e_mj = np.max(np.abs(getattr(tr.tracking, key)[-1]))
        e_an = np.max(np.abs(getattr(ref.tracking, key)[-1]))
        print(f"{name} {key}(20 s): mujoco {e_mj:.3e}, analytic {e_an:.3e}")
        assert e_mj <= th.TRACKING_FACTOR.value * e_an
    idx = TumblingModel(scene)._p_idx
    untracked = [i for i in range(scene.n) if i not in idx]
    if untracked:
        rod = tr.rod_forces
        assert (
            np.max(np.abs(rod[:, untracked]))
            <= th.UNCONTROLLED_ROD_FORCE_REL.value * np.abs(rod).max()
        )


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper_example1", "paper_example2_controlled"])
def test_convergence_order_longer_horizon(name):
    """Order 4 over a longer horizon and smaller steps (uncontrolled and controlled)."""
    scene = paper_scene(name)
    runs = [simulate(scene, dt=dt, t_end=5.0) for dt in (5e-3, 2.5e-3, 1.25e-3)]
    order = _observed_order(runs)
    assert abs(order - th.CONVERGENCE_ORDER.value) <= th.CONVERGENCE_ORDER_TOL.value, order


def test_effect_gravity_off_gives_free_fall_free_motion():
    """Without gravity the centre of mass of the whole system moves uniformly (closed form)."""
    scene = paper_scene("paper_example2")
    scene = scene.with_effects(scene.effects - {Effect.GRAVITY})
    tr = simulate(scene, dt=2e-3, t_end=1.0)
    P = tr.invariants.linear_momentum
    np.testing.assert_allclose(
        P,
        np.repeat(P[:1], len(P), axis=0),
        rtol=0,
        atol=th.FREE_MOTION_MOMENTUM_REL.value * np.abs(P).max(),
    )
