"""model_xml.coordinates: the one module of maps between the paper's coordinates and each engine's.

References: the identity (round trips paper -> engine -> paper and engine -> paper -> engine, at
random states of random scenes, on the manifold |u| = 1, u̇ ⊥ u where the paper's coordinates are
redundant), each sample alone (a batch gives every sample exactly what it gives alone), the general
frame formulas (the shortcut for a body frame at C), and the numpy maps themselves for the compiled
stages that carry their own copy for numba (:mod:`mj_bridge.fast_stage`, the Pinocchio plant's).
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.kinematics import S, omega_of
from analytic.runtime.jit import HAVE_NUMBA
from mj_bridge.twin import Twin
from model_xml import BodyFrame
from model_xml import coordinates as co
from model_xml.rotations import quat_to_mat
from tests.support import tolerances as th
from tests.support.mj_scenes import paper_scene
from tests.support.mj_scenes import random_scene as mj_random_scene
from tests.support.mj_scenes import random_state as manifold_state
from tests.support.scene_strategies import random_scene

MAP_ABS = 1e-13
"""Round trips of O(1..10) states through a few rotations and cross products, per component."""

COMPILED_REL = 1e-15
"""A compiled stage's copy of a map against the numpy map: the same formulas, grouped differently
for numba (``(½/|u|²)·x`` against ``(½·x)/|u|²``, a reciprocal square root against a division), so
a few roundings apart, relative to the largest component: seen 1.7e-16 (the MuJoCo stage) and 6.6e-16
(the Pinocchio stage, whose ``v = Sᵀ Ṙ`` is three products summed)."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _frames(rng: np.random.Generator):
    """``(label, ipos, iquat)``: at C, and two body frames offset and turned from C."""
    out = [("at C", co.IPOS_AT_C, co.IQUAT_AT_C)]
    for k in range(2):
        pos = rng.normal(size=3) * (1 + k)
        out.append((f"offset{k}", *co.frame_to_inertial(pos, _unit(rng.normal(size=4)))))
    return out


def _scenes():
    rng = np.random.default_rng(2024)
    scenes = [paper_scene("paper_example1"), paper_scene("paper_example2_controlled")]
    scenes += [mj_random_scene(rng, n) for n in (1, 3, 6)]
    scenes += [random_scene(rng, n) for n in (0, 2)]
    return scenes


SCENES = _scenes()


def _states(scene, rng, count=8):
    """Manifold states of ``scene``: unit u, u̇ = ¼Hᵀω (so u̇ ⊥ u)."""
    out = [manifold_state(rng, scene, scale=3.0)[1:] for _ in range(count)]
    return np.array([q for q, _ in out]), np.array([qd for _, qd in out])


def _close(a, b, tol=MAP_ABS):
    np.testing.assert_allclose(a, b, rtol=0, atol=tol * max(1.0, float(np.max(np.abs(b)))))


# ----------------------------------------------------------------------------------------------
# MuJoCo
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("scene", SCENES, ids=lambda s: f"{s.name}")
def test_mujoco_round_trips(scene):
    """paper -> MuJoCo -> paper and MuJoCo -> paper -> MuJoCo are the identity, for BR's body frame
    at C and offset and turned from C, batched and one sample at a time."""
    rng = np.random.default_rng(scene.n + 7)
    Q, QD = _states(scene, rng)
    for label, ipos, iquat in _frames(rng):
        qpos, qvel = co.paper_to_mujoco_state(Q, QD, ipos, iquat)
        assert qpos.shape == (len(Q), scene.n + 7) and qvel.shape == (len(Q), scene.n + 6), label
        q2, qd2 = co.mujoco_to_paper_state(qpos, qvel, ipos, iquat)
        _close(q2, Q)
        _close(qd2, QD)
        qpos2, qvel2 = co.paper_to_mujoco_state(q2, qd2, ipos, iquat)
        _close(qpos2, qpos)
        _close(qvel2, qvel)
        # q̈ through MuJoCo's qacc: q̈ -> (R̈, ω̇, p̈) -> q̈ on the manifold (ü with Ḣ u̇ = 0)
        q3, qd3, qdd3, omega = co.mujoco_to_paper_batch(qpos, qvel, qvel * 0.7, ipos, iquat)
        _close(q3, q2, 0)
        _close(qd3, qd2, 0)
        _close(omega, omega_of(Q[:, 3:7], QD[:, 3:7]))
        omega_dot = 0.7 * qvel[:, 3:6] @ quat_to_mat(iquat)  # R_Iᵀ ω̇_b, row-wise
        _close(omega_of(q3[:, 3:7], qdd3[:, 3:7]), omega_dot)


def test_mujoco_maps_against_a_compiled_twin():
    """The maps with a twin's own inertial frame (a BodyFrame offset from C) put C, S(u) and Ṙ where
    MuJoCo's kinematics has them (test_mj_bridge checks more of MuJoCo's own kinematics)."""
    import mujoco

    scene = paper_scene("paper_example1")
    q = np.array([0.8, 0.2, -0.4, 0.4])
    frame = BodyFrame(pos=np.array([0.7, -1.3, 2.1]), quat=_unit(q))
    tw = Twin(scene, body_frame=frame)
    ipos, iquat = co.frame_to_inertial(frame.pos, frame.quat)
    _close(ipos, tw.ipos, 1e-15)
    _close(iquat, tw.iquat, 1e-15)
    rng = np.random.default_rng(5)
    Q, QD = _states(scene, rng, 4)
    for q, qd in zip(Q, QD, strict=True):
        tw.set_state(0.0, q, qd)
        mujoco.mj_forward(tw.m, tw.d)
        _close(tw.d.xipos[tw.body_id], q[:3], th.KINEMATICS_REL.value)
        _close(tw.d.ximat[tw.body_id].reshape(3, 3), S(q[3:7]), th.KINEMATICS_REL.value)


def test_paper_to_mujoco_normalises_u_and_keeps_omega():
    """A paper state off the unit sphere: MuJoCo gets the unit quaternion, and ω = H(u) u̇ of the
    state as given (what the analytic model's ω is there)."""
    rng = np.random.default_rng(3)
    for _ in range(10):
        u = rng.normal(size=4) * rng.uniform(0.5, 2.0)
        q = np.concatenate([rng.normal(size=3), u, rng.normal(size=2)])
        qd = rng.normal(size=9)
        qpos, qvel = co.paper_to_mujoco_state(q, qd)
        np.testing.assert_allclose(np.linalg.norm(qpos[3:7]), 1.0, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(qvel[3:6], omega_of(u, qd[3:7]))
        np.testing.assert_array_equal(qpos[:3], q[:3])


def test_shortcut_at_C_is_the_general_map():
    """With BR's body frame at C the frame terms are skipped; the same frame written as iquat = -1
    takes the general path and gives the same numbers, the quaternion negated (the same attitude)."""
    rng = np.random.default_rng(9)
    scene = SCENES[3]
    Q, QD = _states(scene, rng)
    minus = -co.IQUAT_AT_C
    qpos, qvel = co.paper_to_mujoco_state(Q, QD)
    qpos_g, qvel_g = co.paper_to_mujoco_state(Q, QD, co.IPOS_AT_C, minus)
    np.testing.assert_array_equal(qpos_g[:, 3:7], -qpos[:, 3:7])
    np.testing.assert_array_equal(np.delete(qpos_g, np.s_[3:7], 1), np.delete(qpos, np.s_[3:7], 1))
    np.testing.assert_array_equal(qvel_g, qvel)
    qacc = rng.normal(size=qvel.shape)
    a = co.mujoco_to_paper_batch(qpos, qvel, qacc)
    b = co.mujoco_to_paper_batch(qpos, qvel, qacc, co.IPOS_AT_C, minus)
    flip = np.ones(scene.n + 7)
    flip[3:7] = -1
    for x, y in zip(a[:3], b[:3], strict=True):
        np.testing.assert_array_equal(y, x * flip)
    np.testing.assert_array_equal(a[3], b[3])


# ----------------------------------------------------------------------------------------------
# Pinocchio
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("scene", SCENES, ids=lambda s: f"{s.name}")
def test_pinocchio_round_trips(scene):
    """paper -> Pinocchio -> paper, Pinocchio -> paper -> Pinocchio and paper -> the Pinocchio
    plant's state -> paper are the identity; the quaternion is scalar last, v = Sᵀ Ṙ is local."""
    rng = np.random.default_rng(scene.n + 17)
    Q, QD = _states(scene, rng)
    q_pin, v_pin = co.paper_to_pinocchio(Q, QD)
    _close(q_pin[:, 3:7], Q[:, [4, 5, 6, 3]])
    for i in range(len(Q)):
        _close(v_pin[i, :3], S(Q[i, 3:7]).T @ QD[i, :3])
    q2, qd2 = co.pinocchio_to_paper(q_pin, v_pin)
    _close(q2, Q)
    _close(qd2, QD)
    q_pin2, v_pin2 = co.paper_to_pinocchio(q2, qd2)
    _close(q_pin2, q_pin)
    _close(v_pin2, v_pin)
    x = co.paper_to_pinocchio_plant(Q, QD)
    assert x.shape == (len(Q), 2 * scene.n + 13)
    np.testing.assert_array_equal(x[:, scene.n + 7 : scene.n + 10], QD[:, :3])  # Ṙ, inertial
    q3, qd3 = co.pinocchio_plant_to_paper(x)
    _close(q3, Q)
    _close(qd3, QD)
    q_pin3, v_pin3 = co.pinocchio_plant_to_pinocchio(x)
    _close(q_pin3, q_pin)
    _close(v_pin3, v_pin)
    # Pinocchio's accelerations: R̈ = S (v̇ + ω × v), ω̇ and p̈ as they are
    a_pin = rng.normal(size=v_pin.shape)
    qdd = co.pinocchio_to_paper_acc(q_pin, v_pin, a_pin)
    for i in range(len(Q)):
        Rdd = S(Q[i, 3:7]) @ (a_pin[i, :3] + np.cross(v_pin[i, 3:6], v_pin[i, :3]))
        _close(qdd[i, :3], Rdd)
    _close(omega_of(Q[:, 3:7], qdd[:, 3:7]), a_pin[:, 3:6])
    np.testing.assert_array_equal(qdd[:, 7:], a_pin[:, 6:])


def test_pinocchio_and_mujoco_maps_agree():
    """The Pinocchio plant's velocity ``[Ṙ, ω, ṗ]`` is MuJoCo's qvel for a body frame at C, and
    Pinocchio's configuration is MuJoCo's qpos with the quaternion scalar last."""
    rng = np.random.default_rng(12)
    scene = SCENES[4]
    Q, QD = _states(scene, rng)
    qpos, qvel = co.paper_to_mujoco_state(Q, QD)
    x = co.paper_to_pinocchio_plant(Q, QD)
    nq = scene.n + 7
    np.testing.assert_array_equal(x[:, nq:], qvel)
    np.testing.assert_array_equal(x[:, [0, 1, 2, 6, 3, 4, 5]], qpos[:, :7])
    np.testing.assert_array_equal(x[:, 7:nq], qpos[:, 7:])


# ----------------------------------------------------------------------------------------------
# Batched against one sample at a time
# ----------------------------------------------------------------------------------------------


def _each_sample_alone(fn, *arrays):
    """``fn`` on each sample alone, stacked like the batched result."""
    rows = [fn(*(a[i] for a in arrays)) for i in range(len(arrays[0]))]
    if isinstance(rows[0], tuple):
        return tuple(np.array(r) for r in zip(*rows, strict=True))
    return np.array(rows)


@pytest.mark.parametrize("frame", [0, 1, 2])
def test_batch_gives_each_sample_what_it_gives_alone(frame):
    """Every map, batched, equals the map applied to each sample alone, to the last bit (the
    rotations are per-sample products), with the body frame at C and offset from C; states off the
    manifold too (non-unit u, any u̇)."""
    rng = np.random.default_rng(31 + frame)
    _, ipos, iquat = _frames(rng)[frame]
    N, n = 25, 3
    Q = np.concatenate(
        [rng.normal(size=(N, 3)), rng.normal(size=(N, 4)), rng.normal(size=(N, n))], 1
    )
    QD = rng.normal(size=(N, n + 7))
    qpos, qvel = co.paper_to_mujoco_state(Q, QD, ipos, iquat)
    qpos[:, 3:7] *= rng.uniform(0.9, 1.1, (N, 1))  # MuJoCo's quaternion a little off unit
    qacc = rng.normal(size=(N, n + 6))
    cases = [
        (lambda q, qd: co.paper_to_mujoco_state(q, qd, ipos, iquat), (Q, QD)),
        (lambda a, b: co.mujoco_to_paper_state(a, b, ipos, iquat), (qpos, qvel)),
        (lambda a, b, c: co.mujoco_to_paper_acc(a, b, c, ipos, iquat), (qpos, qvel, qacc)),
        (lambda a, b, c: co.mujoco_to_paper_batch(a, b, c, ipos, iquat), (qpos, qvel, qacc)),
        (co.paper_to_pinocchio, (Q, QD)),
        (co.pinocchio_to_paper, co.paper_to_pinocchio(Q, QD)),
        (co.pinocchio_to_paper_acc, (*co.paper_to_pinocchio(Q, QD), qacc)),
        (co.pinocchio_to_paper_batch, (*co.paper_to_pinocchio(Q, QD), qacc)),
        (co.paper_to_pinocchio_plant, (Q, QD)),
        (co.pinocchio_plant_to_paper, (co.paper_to_pinocchio_plant(Q, QD),)),
        (co.pinocchio_plant_to_pinocchio, (co.paper_to_pinocchio_plant(Q, QD),)),
    ]
    for k, (fn, args) in enumerate(cases):
        batched = fn(*args)
        alone = _each_sample_alone(fn, *args)
        for b, a in zip(
            batched if isinstance(batched, tuple) else (batched,),
            alone if isinstance(alone, tuple) else (alone,),
            strict=True,
        ):
            np.testing.assert_array_equal(b, a, err_msg=f"case {k}")


# ----------------------------------------------------------------------------------------------
# The compiled stages' copies of the maps
# ----------------------------------------------------------------------------------------------

needs_numba = pytest.mark.skipif(not HAVE_NUMBA, reason="the compiled stages need numba")


def _rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@needs_numba
@pytest.mark.parametrize("name", ["paper_example1_controlled", "paper_example2_controlled"])
def test_compiled_mujoco_stage_maps_as_numpy(name):
    """The MuJoCo stage (mj_bridge.fast_stage, also inside the native callback) maps (qpos, qvel)
    to the paper's (q, q̇) as mujoco_to_paper_state does, at states with a non-unit quaternion."""
    from mj_bridge import fast_stage
    from mj_bridge.stages import INV_GEAR

    scene = paper_scene(name)
    tw = Twin(scene)
    assert tw.stages.compiled
    arr = tw.stages.native_arrays()
    args = [arr[k] for k in ("tq_ids", "f_ids", "fp", "ip", "out", "q", "qd", "tau_g", "geo")]
    rng = np.random.default_rng(1)
    for _ in range(20):
        _, q, qd = manifold_state(rng, scene, scale=3.0)
        qpos, qvel = tw.to_mujoco(q, qd)
        qpos[3:7] *= rng.uniform(0.99, 1.01)
        ctrl = np.zeros(tw.m.nu)
        stage = fast_stage.stage_for(arr["ip"])
        status = stage(0.3, qpos, qvel, ctrl, *args, INV_GEAR, 0.0, np.zeros(7))
        assert status == 0
        q_ref, qd_ref = co.mujoco_to_paper_state(qpos, qvel)
        np.testing.assert_array_equal(arr["q"], q_ref)
        assert _rel(arr["qd"], qd_ref) <= COMPILED_REL


@needs_numba
@pytest.mark.parametrize("n", [0, 1, 4])
def test_compiled_pinocchio_stage_maps_as_numpy(n):
    """The Pinocchio plant's compiled stage maps its state x to aba's (q_pin, v_pin) and to the
    controller's paper (q, q̇) as pinocchio_plant_to_pinocchio / pinocchio_plant_to_paper do, at
    states whose quaternion is off unit (as the integrated one drifts)."""
    from analytic.fast import FastModel
    from mj_bridge import scipy_stage as pp

    scene = random_scene(np.random.default_rng(40 + n), n)
    fm = FastModel(scene)
    lay = pp.work_layout(n, fm.model.k)
    work = np.zeros(max(b for _, b in lay.values()))
    rng = np.random.default_rng(n)
    nq = n + 7
    for _ in range(20):
        q = np.concatenate([rng.normal(size=3), _unit(rng.normal(size=4)), rng.normal(size=n)])
        x = co.paper_to_pinocchio_plant(q, rng.normal(size=nq))
        x[3:7] *= rng.uniform(0.99, 1.01)
        y = np.concatenate([x, np.zeros(7)])
        assert pp.stage(0.2, y, fm.fp, fm.ip, work, np.empty(len(y)), pp.MODE_MAP) == 0
        part = {k: work[a:b] for k, (a, b) in lay.items()}
        q_pin, v_pin = co.pinocchio_plant_to_pinocchio(x)
        q_ref, qd_ref = co.pinocchio_plant_to_paper(x)
        for got, ref in ((part["qpin"], q_pin), (part["vpin"], v_pin), (part["q"], q_ref)):
            assert _rel(got, ref) <= COMPILED_REL
        assert _rel(part["qd"], qd_ref) <= COMPILED_REL
