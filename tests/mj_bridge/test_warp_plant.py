"""The MuJoCo Warp plant (``mjwarp``): MuJoCo Warp on the C plant's twin in float32, against
MuJoCo's C engine and the analytic model.

References: the C engine's forward dynamics at a state (:func:`mj_bridge.twin.acceleration`), the
analytic model's (``TumblingModel.acceleration``), the C plant's runs (same twin, same controller
in every stage, float64). Thresholds: ``tests/support/tolerances.py`` (``WARP_*``), derived from
float32's ε = 1.19e-7 times a stated scale.

Cost: Warp on the CPU takes ~20-50 ms per step, and its first use compiles ~60 kernels (~40 s;
Warp caches them on disk, so a later process loads them in ~1 s). The engine work of the default
tests runs in two processes: :func:`_engine_checks` (one ``run_isolated`` call: the pointwise
q̈ at several states, the batch of two scenes against each alone, a refused twin) and one batched
run through the plant (two scenes, 8 steps each).
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from analytic.effects import Precision
from analytic.model import TumblingModel
from analytic.plant import TIGHTER_STEP
from analytic.scene import modified_scene
from analytic.scene.random_scenes import random_state
from mj_bridge.plants import MujocoPlant
from mj_bridge.warp_plugin import WarpPlant, WarpSettings, warp_unavailable
from tests.support import tolerances as tol
from tests.support.mj_scenes import paper_scene

needs_warp = pytest.mark.skipif(bool(warp_unavailable()), reason=warp_unavailable() or "ok")

EPS32 = float(np.finfo(np.float32).eps)
FEW_STEPS_T = 0.002
"""The default tests' horizon, s: 8 steps of the scenes' 2.5e-4 s."""


def _second_scene(scene):
    """``scene`` with other parameters and another initial state (same structure)."""
    return modified_scene(
        scene,
        {
            "body": {"mass": 1.3 * scene.body.mass, "inertia": list(1.2 * scene.body.inertia)},
            "masses": {"mass": list(0.8 * np.asarray(scene.masses.mass))},
            "springs": {"k_linear": list(1.5 * np.asarray(scene.springs.k_linear))},
            "initial": {"omega": list(np.add(scene.initial.omega, [0.2, -0.1, 0.3]))},
        },
    )


def _actuator_springs(scene):
    return modified_scene(scene, {"mujoco": {"spring_model": "actuator"}})


def _engine_checks(seed: int) -> dict:
    """The engine's share of the default tests, in the one process that owns Warp."""
    from mj_bridge.warp_plant import pointwise_qddot, run_batch

    rng = np.random.default_rng(seed)
    out: dict = {"pointwise": {}}
    for name in ("paper_example1", "paper_example1_controlled"):
        scene = paper_scene(name)
        draws = [random_state(rng, scene) for _ in range(3)]
        t = np.array([0.0] + [d[0] for d in draws])
        q = np.array([scene.initial.q0()] + [d[1] for d in draws])
        qd = np.array([scene.initial.qdot0()] + [d[2] for d in draws])
        out["pointwise"][name] = (t, q, qd, pointwise_qddot(scene, None, "cpu", t, q, qd))
    s1 = paper_scene("paper_example1_controlled")
    s2 = _second_scene(s1)
    out["batch"] = run_batch([s1, s2], None, "cpu", FEW_STEPS_T)
    out["alone"] = [run_batch([s], None, "cpu", FEW_STEPS_T)[0] for s in (s1, s2)]
    act = _actuator_springs(s1)  # what check_scene refuses, run anyway at the engine level
    t0, q0, qd0 = np.zeros(1), act.initial.q0()[None], act.initial.qdot0()[None]
    out["user_bias"] = (t0, q0, qd0, pointwise_qddot(act, None, "cpu", t0, q0, qd0))
    return out


@pytest.fixture(scope="module")
def engine() -> dict:
    from mj_bridge.accelerated import run_isolated

    return run_isolated(_engine_checks, 7)


def _rel(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.abs(x - ref).max() / np.abs(ref).max())


# -- without Warp -------------------------------------------------------------------------------


def test_plugin_module_imports_no_engine():
    code = (
        "import sys, mj_bridge.warp_plugin as p; p.WarpPlant().describe(p.WarpSettings());"
        "bad = [m for m in ('warp', 'mujoco_warp', 'jax') if m in sys.modules];"
        "sys.exit(f'imported {bad}' if bad else 0)"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_settings_refused_naming_the_field():
    with pytest.raises(ValueError, match=r"^timestep: .*-1"):
        WarpSettings(timestep=-1.0)
    with pytest.raises(ValueError, match=r"^device: .*'gpu'"):
        WarpSettings(device="gpu")
    assert WarpSettings(device="cuda:1").precision is Precision.FLOAT32


def test_describe_defaults_and_tightened():
    plant = WarpPlant()
    scene = paper_scene("paper_example1")
    settings = plant.default_settings(scene)
    assert settings.timestep == scene.mujoco.timestep
    line = plant.describe(settings)
    assert line.startswith("MuJoCo Warp ") and "float32" in line and "dt 0.00025 s" in line
    assert "cpu" in plant.describe(WarpSettings(device="cpu"))
    tight = plant.tightened(scene, settings)
    assert tight.timestep == settings.timestep / TIGHTER_STEP
    assert plant.precision is Precision.FLOAT32 and plant.batched and not plant.default


def test_refuses_actuator_springs_with_a_cubic_term():
    plant = WarpPlant()
    scene = paper_scene("paper_example1_controlled")
    act = _actuator_springs(scene)
    with pytest.raises(ValueError, match=r"^mujoco\.spring_model: .*cubic"):
        plant.check_scene(act)
    with pytest.raises(ValueError, match=r"^scenes\[1\]: mujoco\.spring_model: "):
        plant.simulate_batch([scene, act], t_end=FEW_STEPS_T)
    effects = [e.value for e in act.effects if e.value != "springs.cubic"]
    linear = modified_scene(act, {"scene": {"effects": effects}})
    plant.check_scene(linear)  # an affine spring actuator is Warp's own: accepted


# -- the engine (one process: _engine_checks) ----------------------------------------------------


@needs_warp
@pytest.mark.parametrize("name", ["paper_example1", "paper_example1_controlled"])
def test_pointwise_qddot_is_the_c_engine_and_the_model_at_float32(engine, name):
    from mj_bridge.twin import Twin

    scene = paper_scene(name)
    t, q, qd, warp = engine["pointwise"][name]
    twin, model = Twin(scene), TumblingModel(scene)
    for i in range(len(t)):
        c = twin.acceleration(t[i], q[i], qd[i])
        a = model.acceleration(t[i], q[i], qd[i])[0]
        assert _rel(warp[i], c) <= tol.WARP_QDDOT_REL.value, (name, i)
        assert _rel(warp[i], a) <= tol.WARP_QDDOT_REL.value, (name, i)


@needs_warp
def test_the_user_bias_warp_leaves_out_is_why_the_scene_is_refused(engine):
    from mj_bridge.twin import Twin

    t, q, qd, warp = engine["user_bias"]
    act = _actuator_springs(paper_scene("paper_example1_controlled"))
    c = Twin(act).acceleration(t[0], q[0], qd[0])
    assert _rel(warp[0], c) > 1e3 * tol.WARP_QDDOT_REL.value  # the springs are gone, not rounded


@needs_warp
def test_a_batch_is_each_scene_alone(engine):
    batch, alone = engine["batch"], engine["alone"]
    assert [tr.info["nworld"] for tr in batch] == [2, 2]
    for b, a in zip(batch, alone, strict=True):
        assert b.status.value == "ok" and b.engine == "mjwarp" and b.scene == a.scene
        bound = tol.WARP_BATCH_REL.value * np.abs(a.q).max()
        assert np.abs(b.q - a.q).max() <= bound
        assert np.abs(b.qdot - a.qdot).max() <= tol.WARP_BATCH_REL.value * np.abs(a.qdot).max()
    # the worlds carried their own parameters and states: the two scenes moved apart
    assert np.abs(batch[0].q[-1] - batch[1].q[-1]).max() > 100 * bound


# -- the plant (its own process) ------------------------------------------------------------------


@needs_warp
def test_few_steps_of_a_batch_follow_the_c_plant():
    s1 = paper_scene("paper_example1_controlled")
    s2 = _second_scene(s1)
    seen: list[float] = []
    runs = WarpPlant().simulate_batch([s1, s2], t_end=FEW_STEPS_T, progress=seen.append)
    assert seen and seen[-1] == pytest.approx(FEW_STEPS_T)
    steps = round(FEW_STEPS_T / s1.mujoco.timestep)
    for scene, run in zip((s1, s2), runs, strict=True):
        ref = MujocoPlant().simulate(scene, t_end=FEW_STEPS_T)
        assert run.status.value == "ok" and run.info["device"] == "cpu"
        assert np.array_equal(run.t, ref.t)
        per = tol.WARP_RUN_REL_PER_STEP.value * steps
        assert np.abs(run.q - ref.q).max() <= per * np.abs(ref.q).max()
        assert np.abs(run.qdot - ref.qdot).max() <= per * np.abs(ref.qdot).max()
        work = np.abs(run.invariants.work - ref.invariants.work).max()
        assert work <= per * np.abs(ref.invariants.energy).max()


@needs_warp
@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper_example1", "paper_example1_controlled"])
def test_two_seconds_follow_the_c_plant_to_the_float32_floor(name):
    scene = paper_scene(name)
    run = WarpPlant().simulate(scene, t_end=2.0)
    ref = MujocoPlant().simulate(scene, t_end=2.0)
    assert run.status.value == "ok"
    steps = round(2.0 / scene.mujoco.timestep)
    bound = tol.WARP_DRIFT_REL_PER_SQRT_STEP.value * math.sqrt(steps)
    assert np.abs(run.q[:, :3] - ref.q[:, :3]).max() <= bound * np.abs(ref.q[:, :3]).max()
    assert np.abs(run.q[:, 7:] - ref.q[:, 7:]).max() <= bound * np.abs(ref.q[:, 7:]).max()
    assert np.abs(run.q[:, 3:7] - ref.q[:, 3:7]).max() <= bound
