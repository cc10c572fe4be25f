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
from tests.support.mj_scenes import paper_scene, random_scene

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


@pytest.mark.parametrize("weighting", ["M^-2", "identity"])
def test_native_with_a_force_at_C(weighting):
    """The M⁻² and identity weightings' control has a force at C: the native stage writes it to
    BR's xfrc_applied as the Python stage does."""
    import dataclasses

    from analytic.effects import Weighting

    sc = random_scene(np.random.default_rng(3), 3, external_torque=True)
    sc = sc.replace(control=dataclasses.replace(sc.control, weighting=Weighting(weighting)))
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
from tests.support.mj_scenes import paper_scene
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

    root = Path(__file__).resolve().parents[2]
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


_KERNEL_CHILD = """
import json, sys
import numpy as np
from analytic.aux_rates import aux_rates
from analytic.fast import FastModel
from analytic.fast_rhs import rhs_for
from analytic.kernel import gauss
from analytic.runtime import jit
from analytic.scene import load_scene

sc = load_scene(sys.argv[1])
fm = FastModel(sc)
q, qd = sc.initial.q0(), sc.initial.qdot0()
if sys.argv[2] == "aux":  # the smallest cached entry point: only the work and impulse rates
    m = fm.model
    out = np.empty(7)
    args = (q, qd, np.ones(3), np.ones(m.n), np.ones(3), m.a, m.d, m.m, m.mu0, m.m_T, out)
    aux_rates(*args)
    print(json.dumps({"ydot": out.tolist(), "note": jit.cache_dir_note(),
                      "hits": sum(aux_rates.stats.cache_hits.values())}))
    sys.exit()
rhs = rhs_for(fm.ip)
y = np.concatenate([q, qd, np.zeros(7)])
out, work = np.empty(2 * fm.nq + 7), np.empty(2 * fm.nq + 3 + fm.k)
status = int(rhs(0.3, y, fm.fp, fm.ip, work, out))
qdd = fm.qddot(0.3, q, qd)
print(json.dumps({
    "status": status, "ydot": out.tolist(), "qdd": qdd.tolist(),
    "rhs_hits": sum(rhs.stats.cache_hits.values()),
    "rhs_misses": sum(rhs.stats.cache_misses.values()),
    "kernel_hits": sum(gauss.evaluate.stats.cache_hits.values()),
}))
"""


def _copy_analytic(dest, *, with_numba_cache: bool):
    """The ``analytic`` package (and a scene file) copied under ``dest``; with the numba cache files
    of this tree when asked (a warm start), never Python's bytecode."""
    import shutil
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    keep = ("*.nbi", "*.nbc") if with_numba_cache else ()

    def ignore(folder, names):
        if Path(folder).name == "__pycache__":
            return [n for n in names if not any(Path(n).match(k) for k in keep)]
        return []

    shutil.copytree(root / "analytic", dest / "analytic", ignore=ignore)
    shutil.copy(root / "analytic" / "scenes" / "paper_example1.toml", dest / "scene.toml")
    return dest


def _run_child(tree, env_extra=None, prefix=(), mode="rhs"):
    """Run :data:`_KERNEL_CHILD` on the copy ``tree`` (``prefix``: a command that wraps it);
    returns its JSON line and its stderr."""
    import json
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(tree), **(env_extra or {}))
    r = subprocess.run(
        [*prefix, sys.executable, "-c", _KERNEL_CHILD, str(tree / "scene.toml"), mode],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1]), r.stderr


def test_an_edited_stage_recompiles_the_cached_callers(tmp_path):
    """numba's disk cache checks only a function's own file, yet a cached entry point embeds the
    kernel's stages from other files. Edit a stage (forces.rod_pass: every rod row of Q gains
    +m_i·1 N/kg) in a copy of the package whose cache is populated: the next process must refuse
    the cached right-hand side and kernel, recompile them and show the edit, rather than run the
    stale copy. (An uncontrolled scene, so q̈ of the rods moves with Q_p.)"""
    tree = _copy_analytic(tmp_path, with_numba_cache=True)
    before, _ = _run_child(tree)  # compiles (or loads this tree's cache) and fills the copy's
    again, _ = _run_child(tree)
    assert before["status"] == again["status"] == 0
    assert again["rhs_hits"] >= 1 and again["rhs_misses"] == 0, "the cache is not reused at all"
    assert again["ydot"] == before["ydot"]

    stage = tree / "analytic" / "kernel" / "forces.py"
    src = stage.read_text()
    line = "Qi = -mi * (sl2 * pdi + sLad * pi + sLdd)"
    assert src.count(line) == 1
    stage.write_text(src.replace(line, line + " + mi"))
    after, _ = _run_child(tree)
    assert after["status"] == 0
    assert after["rhs_misses"] >= 1 and after["rhs_hits"] == 0, "a stale cached rhs was loaded"
    assert after["kernel_hits"] == 0, "a stale cached kernel was loaded"
    n = len(before["qdd"]) - 7
    ydot0, ydot1 = np.array(before["ydot"]), np.array(after["ydot"])
    nq = n + 7
    assert np.all(ydot1[nq + 7 : 2 * nq] != ydot0[nq + 7 : 2 * nq]), "the edit is not in the rhs"
    assert np.all(np.array(after["qdd"])[7:] != np.array(before["qdd"])[7:])


def _read_only_prefix(tree) -> list[str] | None:
    """A command prefix that runs its command with ``tree`` mounted read-only (a user and mount
    namespace: works for root, whom file modes do not stop), or None when namespaces are not
    available here."""
    import shutil
    import subprocess

    if not shutil.which("unshare"):
        return None
    if subprocess.run(["unshare", "-rm", "true"], capture_output=True).returncode != 0:
        return None
    script = 'mount --bind "$0" "$0" && mount -o remount,ro,bind "$0" "$0" && exec "$@"'
    return ["unshare", "-rm", "sh", "-c", script, str(tree)]


def test_a_read_only_install_caches_in_the_user_cache_dir(tmp_path):
    """With the package's ``__pycache__`` not writable (a read-only site-packages), the kernel is
    cached under ``$XDG_CACHE_HOME/tumbling-testbed/numba``, said once on stderr, and the next
    process loads it from there (nothing written into the package)."""
    import os
    import stat

    tree = _copy_analytic(tmp_path / "tree", with_numba_cache=False)
    prefix = _read_only_prefix(tree)
    if prefix is None:
        if os.geteuid() == 0:
            pytest.skip("no mount namespace, and file modes do not stop root")
        prefix = []
        for p in [tree, *tree.rglob("*")]:
            p.chmod(p.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    xdg = tmp_path / "xdg"
    xdg.mkdir()
    env = {"XDG_CACHE_HOME": str(xdg)}
    try:
        first, err1 = _run_child(tree, env, prefix, mode="aux")
        second, err2 = _run_child(tree, env, prefix, mode="aux")
    finally:
        for p in [tree, *tree.rglob("*")]:
            if p.is_dir():
                p.chmod(0o755)
    fallback = xdg / "tumbling-testbed" / "numba"
    for err in (err1, err2):
        said = [ln for ln in err.splitlines() if "CacheFallbackWarning" in ln]
        assert len(said) == 1 and str(fallback) in said[0], err[-2000:]
    assert str(fallback) in first["note"]
    assert list(fallback.rglob("*.nbi")), "nothing cached in the user cache directory"
    assert not list(tree.rglob("*.nbi")), "the read-only package was written to"
    assert first["hits"] == 0 and second["hits"] >= 1, "not loaded from the user cache directory"
    assert second["ydot"] == first["ydot"]


def test_the_stage_compiled_ahead_is_the_one_both_callbacks_use():
    """A warm-up compiles the MuJoCo stage in a worker process ahead of the native callback
    (``fast_stage.compile_for``, for ``fast_stage.argument_types()``); the callback links that
    stage and the Python callback calls it, so both must pass exactly those types: a run through
    either adds no second compiled signature."""
    from analytic.kernel.entry import Solver
    from mj_bridge import fast_stage

    fast_stage.compile_for(Solver.GAUSS)
    want = [fast_stage.argument_types()]
    assert fast_stage.stage_gauss.signatures == want
    sc = paper_scene("paper_example1_controlled")
    simulate(sc, t_end=0.05, native_callback=False)
    simulate(sc, t_end=0.05)  # links the stage into the native callback, verified against Python
    assert fast_stage.stage_gauss.signatures == want
