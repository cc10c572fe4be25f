"""The mjx plant (mj_bridge/mjx_plugin.py, mjx_plant.py): MJX float64 is the C plant to round-off
on Example 1 with linear springs (the same twin, the same RK4, the same controller), uncontrolled
and controlled, and within the C plant's own distance of the analytic plant; its pointwise q̈ is
the C engine's; the JAX controller is the numpy controller; float32 stays within its round-off
floor; a batch is the loop; what MJX cannot run is refused in one line naming the field.

Cost: the default tests start one isolated process for the controlled scene (JAX's import, one
engine's trace and compile, 200 steps: measured 25 s with JAX's persistent cache on a machine at
load 10, several times that without it at load 18) and a few cheap ones; the uncontrolled scene,
the 2 s goal, float32, the batch and the host controller are ``slow`` (one process each).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.model import TumblingModel
from analytic.plant import AnalyticPlant
from analytic.scene import load_scene, modified_scene
from analytic.scene.builtin import builtin_scene_path
from mj_bridge.accelerated import ENERGY_OFF, run_isolated
from mj_bridge.mjx_plugin import MjxPlant
from mj_bridge.mjx_settings import MjxSettings, mjx_unavailable
from mj_bridge.plants import MujocoPlant
from mj_bridge.twin import Twin
from tests.support import tolerances as tol

needs_mjx = pytest.mark.skipif(bool(mjx_unavailable()), reason=mjx_unavailable() or "")

SHORT = 0.05
"""The default suite's horizon, s: 200 RK4 steps of 2.5e-4 s, five output intervals."""


def linear_only(name: str, t_end: float):
    """Example 1 with its cubic springs off (MJX 3.17 drops the cubic tendon stiffness)."""
    scene = load_scene(builtin_scene_path(name))
    effects = sorted(e.value for e in scene.effects if e is not Effect.SPRINGS_CUBIC)
    # (the loader's one-line warning that k_cubic is ignored is filtered by pyproject.toml)
    return modified_scene(scene, {"scene": {"effects": effects}, "output": {"t_end": t_end}})


def states(scene, count: int = 3, seed: int = 0):
    """The initial state and ``count`` random ones near it (unit quaternions), with times."""
    rng = np.random.default_rng(seed)
    q0, qd0 = scene.initial.q0(), scene.initial.qdot0()
    q = np.stack([q0] + [q0 + 0.05 * rng.normal(size=q0.shape) for _ in range(count)])
    q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    qd = np.stack([qd0] + [qd0 + 0.2 * rng.normal(size=qd0.shape) for _ in range(count)])
    return np.linspace(0.0, 0.3, count + 1), q, qd


# -- what the isolated process runs ------------------------------------------------------------


def run_and_probe(scenes, settings, t_end, probes):
    """In one process: each scene's run and MJX's q̈ at its probe states (one engine each), and
    the JAX controller (float64, jit) at those states."""
    import jax

    from analytic import array_model as am
    from mj_bridge import mjx_plant

    out = []
    for scene, (t, q, qd) in zip(scenes, probes, strict=True):
        eng = mjx_plant.engine([scene], settings)  # sets x64 before any array exists
        run = mjx_plant.run_engine(eng, t_end)[0]
        qdd = mjx_plant.pointwise_on(eng, t, q, qd)
        jnp = jax.numpy
        st = am.structure_of(scene)
        p = am.parameters(scene, jnp, eng.dtype)
        f = jax.jit(
            jax.vmap(lambda t, q, qd, st=st, p=p, xp=jnp: am.control_forces(xp, st, p, t, q, qd))
        )
        control = [np.asarray(x) for x in f(jnp.asarray(t), jnp.asarray(q), jnp.asarray(qd))]
        out.append((run, qdd, control))
    return out


def batch_and_loop(scenes, settings, t_end):
    """The scenes as one batch, and each alone, in one process."""
    from mj_bridge import mjx_plant

    batch = mjx_plant.simulate_runs(scenes, settings, t_end)
    loop = [mjx_plant.simulate_runs([s], settings, t_end)[0] for s in scenes]
    return batch, loop


# -- agreement ---------------------------------------------------------------------------------


def _max_position_error(a, b) -> float:
    """Largest distance of C and of the masses' rod positions between two runs, m."""
    return float(max(np.abs(a.q[:, :3] - b.q[:, :3]).max(), np.abs(a.q[:, 7:] - b.q[:, 7:]).max()))


def _check_against_references(run, scene, bound):
    c_plant = MujocoPlant().simulate(scene, t_end=run.t[-1])
    analytic = AnalyticPlant().simulate(scene, t_end=run.t[-1])
    assert run.status.value == "ok", run.message
    assert run.engine == "mjx"
    np.testing.assert_array_equal(run.t, c_plant.t)
    vs_c = _max_position_error(run, c_plant)
    assert vs_c <= bound, f"mjx vs C plant: {vs_c:.3g} m"
    # the analytic plant: as near as the C plant itself is, up to the same bound
    vs_analytic = _max_position_error(run, analytic)
    c_vs_analytic = _max_position_error(c_plant, analytic)
    assert vs_analytic <= c_vs_analytic + bound, (vs_analytic, c_vs_analytic)
    return vs_c, vs_analytic


SHORT_SCENES = {
    "controlled": ("paper_example1_controlled", ()),
    "uncontrolled": ("paper_example1", (pytest.mark.slow,)),
}
"""The default suite runs the controlled scene (every stage's controller on the engine's state);
the uncontrolled one is a second engine to compile, so ``slow``."""


@pytest.fixture(scope="module")
def short_run(request):
    name = SHORT_SCENES[request.param][0]
    scene = linear_only(name, SHORT)
    probes = states(scene)
    (result,) = run_isolated(run_and_probe, [scene], MjxSettings(), None, [probes])
    return scene, probes, result


def _cases():
    return [pytest.param(k, marks=marks, id=k) for k, (_, marks) in SHORT_SCENES.items()]


@needs_mjx
@pytest.mark.parametrize("short_run", _cases(), indirect=True)
def test_float64_is_the_c_plant_over_a_short_horizon(short_run):
    scene, _, (run, _, _) = short_run
    _check_against_references(run, scene, tol.MJX_F64_SHORT.value)
    assert run.info["changed_fields"] == [ENERGY_OFF]
    assert run.info["precision"] == "float64" and run.info["controller"] == "jax"
    # the balances the comparison checks close as the C plant's do: the same quadratures
    c_plant = MujocoPlant().simulate(scene, t_end=SHORT)
    scale = max(1.0, float(np.abs(c_plant.invariants.work).max()))
    np.testing.assert_allclose(
        run.invariants.work, c_plant.invariants.work, rtol=0, atol=tol.RK4_MIRROR_RUN.value * scale
    )


@needs_mjx
@pytest.mark.parametrize("short_run", _cases(), indirect=True)
def test_pointwise_is_the_c_engine_and_the_jax_controller_the_numpy_one(short_run):
    scene, (t, q, qd), (_, qdd, control) = short_run
    twin = Twin(scene)
    ref = np.stack([twin.acceleration(t[i], q[i], qd[i]) for i in range(len(t))])
    rel = np.abs(qdd - ref).max() / np.abs(ref).max()
    assert rel <= tol.MJX_POINTWISE_F64.value, rel
    model = TumblingModel(scene)
    for i in range(len(t)):
        _, c = model.acceleration(t[i], q[i], qd[i])
        for got, want in zip(control, (c.torque, c.rod_forces, c.force_at_C), strict=True):
            scale = max(np.abs(want).max(), 1e-300)
            if scene.controlled:
                assert np.abs(got[i] - want).max() <= tol.JAX_CONTROLLER_F64.value * scale
            else:
                assert not np.any(got[i])  # uncontrolled: no control at all


def test_plugin_module_imports_no_jax():
    code = "import sys, mj_bridge.mjx_plugin; sys.exit('jax' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


# -- refusals and settings (no JAX) ------------------------------------------------------------


def test_refusals_name_the_field():
    plant = MjxPlant()
    base = load_scene(builtin_scene_path("paper_example1"))
    with pytest.raises(ValueError, match=r"^mujoco\.integrator: .*RK4 only.*'Euler'"):
        plant.check_scene(modified_scene(base, {"mujoco": {"integrator": "Euler"}}))
    with pytest.raises(ValueError, match=r"^mujoco\.spring_model: 'actuator' with cubic"):
        plant.check_scene(modified_scene(base, {"mujoco": {"spring_model": "actuator"}}))
    plant.check_scene(base)  # the cubic springs on tendons: run (and the difference reported)
    from mj_bridge.mjx_plant import _refusal

    line = _refusal(NotImplementedError("mjtEnableBit.mjENBL_ENERGY"))
    assert line.startswith("opt.enableflags: MJX cannot run this scene's twin")


def test_settings_from_the_mjx_table():
    plant = MjxPlant()
    base = load_scene(builtin_scene_path("paper_example1"))
    s = plant.default_settings(base)
    assert (s.precision.value, s.device, s.timestep, s.controller.value) == (
        "float64", "", base.mujoco.timestep, "jax",
    )  # fmt: skip
    scene = modified_scene(base, {"mjx": {"precision": "float32", "controller": "host"}})
    s = plant.default_settings(scene)
    assert (s.precision.value, s.controller.value) == ("float32", "host")
    assert "float32" in plant.describe(s) and "RK4 dt 0.00025 s" in plant.describe(s)
    assert plant.tightened(scene, s).timestep == pytest.approx(s.timestep / 4)
    for table, match in (
        ({"precision": "float16"}, r"^mjx\.precision: must be one of"),
        ({"bogus": 1}, r"^mjx\.bogus: not a key"),
        ({"device": "CPU!"}, r"^mjx\.device: "),
        ({"timestep": -1.0}, r"^mjx\.timestep: "),
    ):
        with pytest.raises(ValueError, match=match):
            plant.default_settings(modified_scene(base, {"mjx": table}))
    assert plant.batched and not plant.default


# -- slow: the goals ---------------------------------------------------------------------------


@needs_mjx
@pytest.mark.slow
def test_float64_two_second_goal():
    """Example 1 with linear springs, 2 s, uncontrolled and controlled: ≤ 1e-7 m from the C plant
    and within the C plant's distance (+1e-7 m) of the analytic plant."""
    scenes = [linear_only("paper_example1", 2.0), linear_only("paper_example1_controlled", 2.0)]
    probes = [states(s, 0) for s in scenes]
    results = run_isolated(run_and_probe, scenes, MjxSettings(), None, probes)
    for scene, (run, _, _) in zip(scenes, results, strict=True):
        _check_against_references(run, scene, tol.MJX_F64_GOAL.value)


@needs_mjx
@pytest.mark.slow
def test_float32_within_its_roundoff_floor():
    scene = linear_only("paper_example1_controlled", SHORT)
    settings = MjxSettings(precision="float32")
    (run, _, _), = run_isolated(run_and_probe, [scene], settings, None, [states(scene, 0)])  # fmt: skip
    c_plant = MujocoPlant().simulate(scene, t_end=SHORT)
    steps = round(SHORT / scene.mujoco.timestep)
    bound = tol.MJX_F32_FACTOR.value * tol.EPS32 * np.abs(c_plant.q).max() * np.sqrt(steps)
    assert run.info["precision"] == "float32"
    assert _max_position_error(run, c_plant) <= bound


@needs_mjx
@pytest.mark.slow
def test_batch_is_the_loop():
    """Two controlled scenes of one structure (other masses, initial spin and name) as one
    vmapped batch give what each gives alone."""
    a = linear_only("paper_example1_controlled", SHORT)
    b = modified_scene(
        a,
        {
            "scene": {"name": "another_name_of_other_length"},
            "masses": {"mass": [4.0e5, 5.0e5]},
            "initial": {"omega": [0.5, 1.0, -1.0]},
        },
    )
    batch, loop = run_isolated(batch_and_loop, [a, b], MjxSettings(), None)
    assert _max_position_error(batch[0], batch[1]) > 1e-3  # the scenes do differ
    for x, y in zip(batch, loop, strict=True):
        assert x.info["nworld"] == 2 and y.info["nworld"] == 1
        assert _max_position_error(x, y) <= tol.MJX_F64_SHORT.value


@needs_mjx
@pytest.mark.slow
def test_host_controller_is_the_jax_controller():
    scene = linear_only("paper_example1_controlled", SHORT)
    (run, _, _), = run_isolated(run_and_probe, [scene], MjxSettings(controller="host"), None, [states(scene, 0)])  # fmt: skip
    c_plant = MujocoPlant().simulate(scene, t_end=SHORT)
    assert run.info["controller"] == "host"
    assert _max_position_error(run, c_plant) <= tol.MJX_F64_SHORT.value
