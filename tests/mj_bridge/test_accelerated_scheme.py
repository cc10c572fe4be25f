"""The accelerated plants' RK4 (mj_bridge/accelerated_scheme.py) is MuJoCo's own: driven by the C
engine's ``mj_forward`` it reproduces ``mj_step``'s RK4 to round-off, stage by stage (read through
``mjcb_control``) and over many steps, uncontrolled and under the controller, with the C plant's
quadratures. No JAX: numpy is the array namespace here."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from analytic.fast import FastModel
from analytic.scene import load_scene, modified_scene
from analytic.scene.builtin import builtin_scene_path
from mj_bridge import accelerated_scheme as S
from mj_bridge.accelerated import accelerated_twin
from mj_bridge.simulate import simulate
from tests.support import tolerances as tol


def _scene(name: str, t_end: float):
    return modified_scene(load_scene(builtin_scene_path(name)), {"output": {"t_end": t_end}})


def _stage(scene, tm, controlled: bool):
    """The scheme's stage on the C engine: ``mj_forward`` with the ctrl/xfrc the stage writes."""
    m = tm.m
    d = mujoco.MjData(m)
    c = S.StageConstants.of(scene, tm).arrays(np, np.float64)
    fast = FastModel(scene)
    n = scene.n

    def forward(t, qpos, qvel, ctrl, fC):
        d.qpos[:], d.qvel[:], d.ctrl[:], d.time = qpos, qvel, ctrl, t
        d.xfrc_applied[:] = 0.0
        d.xfrc_applied[tm.body_id, :3] = fC
        mujoco.mj_forward(m, d)
        return d.qacc.copy()

    def control(t, q, qd):
        if not controlled:
            return np.zeros(3), np.zeros(n), np.zeros(3)
        _, tau, rod, fC, _ = fast.qddot_and_forces(t, q, qd)
        return tau.copy(), rod.copy(), fC.copy()

    return S.controlled_stage(np, forward, control, fast.model.given_torque, c)


def test_stages_and_step_are_mujocos_rk4_free_body():
    """A free asymmetric body at a large step (0.05 s, 0.19 rad per step): the stage states MuJoCo
    visits (mjcb_control) and its step, reproduced to round-off; the plain sum of the stage
    angular velocities (MuJoCo 3.x's scheme) misses them by far more."""
    xml = """<mujoco><option timestep="0.05" integrator="RK4" gravity="0 0 0"/>
    <worldbody><body><freejoint/><inertial pos="0 0 0" mass="1" diaginertia="1 2 3"/></body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    d.qvel[:] = [0.1, 0.2, 0.3, 1.0, -2.0, 3.0]
    seen = []
    mujoco.set_mjcb_control(lambda m_, d_: seen.append((d_.time, d_.qpos.copy(), d_.qvel.copy())))
    try:
        q0, v0 = d.qpos.copy(), d.qvel.copy()
        mujoco.mj_step(m, d)
    finally:
        mujoco.set_mjcb_control(None)
    ours = []
    d2 = mujoco.MjData(m)

    def stage(t, qpos, qvel):
        ours.append((t, qpos.copy(), qvel.copy()))
        d2.qpos[:], d2.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d2)
        return d2.qacc.copy(), np.zeros(7)

    qpos, qvel, _ = S.rk4_step(np, stage, 0.0, q0, v0, np.zeros(7), m.opt.timestep)
    assert len(seen) == len(ours) == 4
    for (t, a, b), (t2, a2, b2) in zip(seen, ours, strict=True):
        assert t == t2
        np.testing.assert_allclose(a2, a, rtol=0, atol=tol.RK4_MIRROR_ROUNDOFF.value)
        np.testing.assert_allclose(b2, b, rtol=0, atol=tol.RK4_MIRROR_ROUNDOFF.value)
    np.testing.assert_allclose(qpos, d.qpos, rtol=0, atol=tol.RK4_MIRROR_ROUNDOFF.value)
    np.testing.assert_allclose(qvel, d.qvel, rtol=0, atol=tol.RK4_MIRROR_ROUNDOFF.value)
    # the plain sum of the stage velocities is a different scheme: far outside round-off here
    plain = S.integrate_pos(np, q0, sum(b * s[2] for b, s in zip(S.RK4_B, seen, strict=True)), 0.05)
    assert np.abs(plain - d.qpos).max() > 1e3 * tol.RK4_MIRROR_ROUNDOFF.value


@pytest.mark.parametrize("name", ["paper_example1", "paper_example1_controlled"])
def test_scheme_on_the_c_engine_is_the_c_plant(name):
    """0.05 s (200 steps) of Example 1, uncontrolled and controlled: the scheme on the C engine's
    mj_forward equals the C plant's run (mj_step with the controller in mjcb_control) to
    round-off, the quadratures W, I_L, I_P too."""
    scene = _scene(name, 0.05)
    tm = accelerated_twin(scene).tm
    stage = _stage(scene, tm, scene.controlled)
    ref = simulate(scene, native_callback=False)
    qpos, qvel = tm.to_mujoco(scene.initial.q0(), scene.initial.qdot0())
    aux = np.zeros(7)
    times = ref.t
    per = round((times[1] - times[0]) / tm.dt)
    got_q, got_aux = [tm.to_paper(qpos, qvel)[0]], [aux]
    for i in range(1, len(times)):
        t = float(times[i - 1])
        for _ in range(per):
            qpos, qvel, aux = S.rk4_step(np, stage, t, qpos, qvel, aux, tm.dt)
            t += tm.dt
        got_q.append(tm.to_paper(qpos, qvel)[0])
        got_aux.append(aux)
    got_q = np.array(got_q)
    scale = np.abs(ref.q).max()
    np.testing.assert_allclose(got_q, ref.q, rtol=0, atol=tol.RK4_MIRROR_RUN.value * scale)
    inv = ref.invariants
    W = np.array(got_aux)[:, 0]
    np.testing.assert_allclose(
        W, inv.work, rtol=0, atol=tol.RK4_MIRROR_RUN.value * max(1.0, np.abs(inv.work).max())
    )


def test_dexpinv_series_meets_closed_form():
    """The coefficient's series and closed form agree where they meet (the switch is seamless)."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=3)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    below = S.dexpinv(np, axis * (S.DEXPINV_SERIES * (1 - 1e-14)), v)
    above = S.dexpinv(np, axis * (S.DEXPINV_SERIES * (1 + 1e-14)), v)
    # the series' first omitted term, θ⁶/1209600 of c ≈ 1/12, is 1e-11 of c at θ = 0.1
    np.testing.assert_allclose(below, above, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(S.dexpinv(np, np.zeros(3), v), v)  # no rotation: v itself
