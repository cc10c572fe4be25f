"""The native (machine-code) ``mjcb_control``: it must be the Python stage callback's exact twin.

Both run the same compiled kernel on the same numbers, so a run with the native callback must be
bit-identical to the run with the Python callback: trajectories, control outputs, work and impulses.
The fault path (the kernel declines a stage) must rerun the batch with the Python callback and end
bit-identical too.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mj_bridge import native
from mj_bridge.callbacks import bad_warnings
from mj_bridge.simulate import simulate
from mj_bridge.twin import Twin
from tests.mj_scenes import paper_scene, random_scene

pytestmark = pytest.mark.skipif(not native.available(), reason="native callback unavailable")

FIELDS = ("t", "q", "qdot", "qddot", "QC", "torque", "rod_forces", "force_at_C", "residual_norm")


def _same(a, b) -> None:
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    for f in ("work", "angular_impulse", "linear_momentum_expected"):
        np.testing.assert_array_equal(getattr(a.invariants, f), getattr(b.invariants, f), f)


def test_verified_once_against_python_before_use():
    """Entering the callbacks the first time runs the verification stage (native vs Python, bit for
    bit); it leaves the state as it was and records the MjData the callback serves."""
    sc = paper_scene("paper_example2_controlled")
    tw = Twin(sc)
    tw.set_state(0.25, sc.initial.q0(), sc.initial.qdot0())
    before = tw.d.qpos.copy(), tw.d.qvel.copy(), tw.d.ctrl.copy(), tw.acc.v.copy()
    assert not tw.stepper.verified
    with tw.callbacks():
        assert tw.native and tw.stepper.verified
        assert tw.stepper.context.data_ptr != 0
        assert tw.d.time == 0.25
        for a, b in zip(before, (tw.d.qpos, tw.d.qvel, tw.d.ctrl, tw.acc.v), strict=True):
            np.testing.assert_array_equal(a, b)
        tw.forward_here()  # the native stage reads MuJoCo's time through mj_getState
        assert tw.stepper.context.time_seen == 0.25
    assert tw.native_redos == 0


def test_a_wrong_binding_falls_back_to_python_with_one_warning(monkeypatch):
    """If the native callback reads anything else than the Python one (here: qacc bound as qvel),
    the verification stage sees it, the twin uses the Python callback, one warning says so, and
    the run is the Python callback's."""
    sc = paper_scene("paper_example1_controlled")
    ref = simulate(sc, t_end=0.1, native_callback=False)
    real = native.data_arrays

    def wrong(d):
        return {**real(d), "qvel": d.qacc}

    monkeypatch.setattr(native, "data_arrays", wrong)
    with pytest.warns(RuntimeWarning, match="disagrees") as record:
        tr = simulate(sc, t_end=0.1)
    assert len([w for w in record if "native" in str(w.message)]) == 1
    assert not tr.info["native_callback"]
    _same(ref, tr)


def test_another_mjdata_is_refused():
    """The callbacks are process-global: while one twin's native callback is installed, a step of
    another MjData reaches it; it touches nothing and counts a failure."""
    sc = paper_scene("paper_example1_controlled")
    tw1, tw2 = Twin(sc), Twin(sc)
    tw1.set_state(0.0, sc.initial.q0(), sc.initial.qdot0())
    tw2.set_state(0.0, sc.initial.q0(), sc.initial.qdot0())
    with tw1.callbacks():
        ctrl1 = tw1.d.ctrl.copy()
        tw1.stepper.context.clear_failures()
        mujoco.mj_forward(tw2.m, tw2.d)
        assert tw1.stepper.context.failures == 1
        np.testing.assert_array_equal(tw1.d.ctrl, ctrl1)
        assert not tw2.d.ctrl.any()


@pytest.mark.parametrize("name", ["paper_example1_controlled", "paper_example2_controlled"])
def test_native_run_is_bit_identical_to_python_callback(name):
    sc = paper_scene(name)
    a = simulate(sc, t_end=0.3, native_callback=False)
    b = simulate(sc, t_end=0.3)
    assert not a.info["native_callback"] and b.info["native_callback"]
    assert b.info["native_redos"] == 0
    _same(a, b)


def test_native_with_a_force_at_C():
    """The M⁻² weighting's control has a force at C: the native stage writes it to BR's
    xfrc_applied as the Python stage does."""
    import dataclasses

    from analytic.effects import Weighting

    sc = random_scene(np.random.default_rng(3), 3, external_torque=True)
    sc = sc.replace(control=dataclasses.replace(sc.control, weighting=Weighting.M_INV2))
    a = simulate(sc, dt=1e-3, t_end=0.2, native_callback=False)
    b = simulate(sc, dt=1e-3, t_end=0.2)
    assert b.info["native_callback"]
    _same(a, b)
    assert np.abs(a.force_at_C).max() > 0.0


@pytest.mark.parametrize("spring_model", ["tendon", "actuator"])
def test_native_with_given_torque_and_python_act_bias(spring_model):
    """A given torque (computed inside the native stage) and the cubic springs' Python act-bias
    callback alongside the native control callback."""
    sc = random_scene(np.random.default_rng(7), 4, external_torque=True, spring_model=spring_model)
    a = simulate(sc, dt=1e-3, t_end=0.2, native_callback=False)
    b = simulate(sc, dt=1e-3, t_end=0.2)
    assert b.info["native_callback"]
    _same(a, b)
    assert np.any(a.torque != 0.0)


def test_declined_stage_reruns_the_batch_with_python(monkeypatch):
    """Fault injection: the 7th native stage call reports a declined kernel (as the compiled stage
    does: a failure counted, ctrl untouched); the batch is rerun from its start with the Python
    callback and the run ends exactly as a clean one."""
    import ctypes

    sc = paper_scene("paper_example1_controlled")
    ref = simulate(sc, t_end=0.1, native_callback=False)
    real = native.compiled().ctypes
    calls = {"n": 0, "decline": 0}

    def flaky(m, d):
        calls["n"] += 1
        if calls["n"] == calls["decline"]:
            native.CTX[native.C_FAILS] += 1
            return
        real(m, d)

    flaky_cb = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)(flaky)
    monkeypatch.setattr(native, "callback", lambda: flaky_cb)
    tw = Twin(sc)
    assert tw.native
    tw.set_state(0.0, sc.initial.q0(), sc.initial.qdot0())
    k = round(0.01 / tw.dt)
    with tw.callbacks():
        calls["n"], calls["decline"] = 0, 7
        tw.forward_here()
        qs = []
        for _ in range(10):
            tw.step(k)
            assert tw.acc.calls == 4 * k
            tw.d.time = round(tw.d.time, 12)
            tw.forward_here()
            qs.append(tw.state()[0])
    assert calls["n"] > 7
    assert tw.native and tw.native_redos == 1
    np.testing.assert_array_equal(np.array(qs), ref.q[1:])
    assert not bad_warnings(tw.d)


def test_context_is_exclusive_and_cleared():
    sc = paper_scene("paper_example1_controlled")
    tw1, tw2 = Twin(sc), Twin(sc)
    with tw1.callbacks():
        assert native.CTX[native.C_ARMED] == 1
        with pytest.raises(RuntimeError, match="already"):
            with tw2.callbacks():
                pass
    assert not native.CTX.any()
    assert mujoco.get_mjcb_control() is None


def test_unarmed_callback_touches_nothing():
    """Installed without a bound context, the callback only counts the call as a failure."""
    sc = paper_scene("paper_example1_controlled")
    tw = Twin(sc)
    tw.set_state(0.0, sc.initial.q0(), sc.initial.qdot0())
    tw.d.ctrl[:] = 0.0
    native.CTX[native.C_FAILS] = 0
    mujoco.set_mjcb_control(native.callback())
    try:
        mujoco.mj_forward(tw.m, tw.d)
    finally:
        mujoco.set_mjcb_control(None)
    assert native.CTX[native.C_FAILS] == 1
    native.CTX[native.C_FAILS] = 0
    assert not tw.d.ctrl.any()


_CHILD = """
import hashlib, sys
from mj_bridge.simulate import simulate
from tests.mj_scenes import paper_scene
from mj_bridge import native
tr = simulate(paper_scene("paper_example2_controlled"), t_end=0.05)
assert tr.info["native_callback"], "native callback not used"
hits = native.compiled().cache_hits
print(hits, hashlib.sha256(tr.q.tobytes() + tr.QC.tobytes()).hexdigest())
"""


def test_disk_cached_callback_finds_the_context():
    """The cfunc refers to CTX by an LLVM symbol resolved at load time: a second process, loading
    the compiled callback from numba's disk cache (CTX at another address), gives the same run as
    the process that compiled it, and as the Python callback."""
    import hashlib
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": str(root)}  # numba's usual cache (warm after the first)
    hits, digests = [], []
    for _ in range(2):
        r = subprocess.run(
            [sys.executable, "-c", _CHILD], env=env, cwd=root, capture_output=True, text=True
        )
        assert r.returncode == 0, r.stderr[-2000:]
        h, dg = r.stdout.split()
        hits.append(int(h))
        digests.append(dg)
    assert hits[1] == 1, "the second process did not load the callback from the disk cache"
    # Hashes of floats are legitimate here: all three runs are on this machine with this build
    # (numba's cache is local, keyed to it), doing the same operations (see the module docstring).
    ref = simulate(paper_scene("paper_example2_controlled"), t_end=0.05, native_callback=False)
    want = hashlib.sha256(ref.q.tobytes() + ref.QC.tobytes()).hexdigest()
    assert digests == [want, want]


def test_compiled_callers_are_keyed_to_the_kernel_source():
    """numba's disk cache checks only a function's own file; the stage and the native callback
    embed the kernel from another file, so they close over the kernel's source fingerprint (numba
    hashes closure variables into its cache key). Editing the kernel then recompiles them."""
    from analytic import fast_kernel as fk
    from mj_bridge import fast_stage

    want = fk.source_fingerprint(fk)
    assert fast_stage.DEPS == want
    assert [c.cell_contents for c in fast_stage.stage.py_func.__closure__] == [want]
    assert native.DEPS == fk.source_fingerprint(fk, fast_stage)
    assert native.DEPS in [c.cell_contents for c in native.native_stage.py_func.__closure__]
