"""What the accelerated plants share (mj_bridge/accelerated.py): the twin (the C plant's, only the
energy flag changed and named), the isolated process (its result, its errors in one line, a crash
named by its signal, an interrupt that returns what the child reached or kills it, no process
left behind, a child that dies with its parent) and the diagnostic of silently dropped fields.
No JAX; each isolated call costs one Python start (~1 s)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import mujoco
import numpy as np
import pytest

from analytic.scene import load_scene
from analytic.scene.builtin import builtin_scene_path
from mj_bridge.accelerated import (
    ENERGY_OFF,
    IsolatedError,
    accelerated_twin,
    dropped_fields,
    run_isolated,
)
from mj_bridge.twin_model import TwinModel

# -- functions the isolated process runs (importable by name) ---------------------------------


def double(x):
    return 2 * x


def refuse():
    raise ValueError("masses.mass: refused\n  on two lines")


def fail():
    raise KeyError("k")


def segfault():
    os.kill(os.getpid(), signal.SIGSEGV)


def count(progress=None, stop_at=None):
    """Report progress every 20 ms; on an interrupt return how far it got."""
    i = 0
    try:
        while True:
            time.sleep(0.02)
            i += 1
            progress(float(i))
    except KeyboardInterrupt:
        return ("reached", i)


def stubborn(progress=None):
    """Ignore interrupts: the parent must kill it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    while True:
        time.sleep(0.02)
        progress(1.0)


def my_pid():
    return os.getpid()


# -- the twin ---------------------------------------------------------------------------------


def test_accelerated_twin_is_the_c_plants_with_only_the_energy_flag_off():
    scene = load_scene(builtin_scene_path("paper_example1_controlled"))
    at = accelerated_twin(scene)
    ref = TwinModel.build(scene)
    energy = int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    assert at.changed == (ENERGY_OFF,)
    assert at.tm.m.opt.enableflags & energy  # the C plant's twin untouched
    assert not at.model.opt.enableflags & energy
    assert at.model.opt.enableflags == ref.m.opt.enableflags & ~energy
    for name in ("body_mass", "body_inertia", "tendon_stiffness", "tendon_stiffnesspoly",
                 "actuator_gear", "opt.timestep"):  # fmt: skip
        get = (lambda m, n=name: m.opt.timestep) if name.startswith("opt.") else (
            lambda m, n=name: getattr(m, n))  # fmt: skip
        np.testing.assert_array_equal(get(at.model), get(ref.m))
    assert at.tm.frame_at_C


def test_dropped_fields_names_what_the_engine_lacks_or_never_reads():
    scene = load_scene(builtin_scene_path("paper_example1"))
    m = accelerated_twin(scene).model
    fields = [n for n in dir(m) if not n.startswith("_")]
    assert dropped_fields(m, fields) == ()  # an engine with every field drops nothing
    lacking = [f for f in fields if f != "tendon_stiffnesspoly"]
    assert dropped_fields(m, lacking) == ("tendon_stiffnesspoly",)
    # carried but never read: named too; a field that is zero is not a loss
    read = set(fields) - {"tendon_stiffnesspoly", "jnt_stiffness"}
    assert dropped_fields(m, fields, read) == ("tendon_stiffnesspoly",)


# -- the isolated process ---------------------------------------------------------------------


def test_result_and_one_line_errors():
    assert run_isolated(double, 21) == 42
    with pytest.raises(ValueError, match=r"^masses\.mass: refused on two lines$"):
        run_isolated(refuse)
    with pytest.raises(IsolatedError, match=r"^KeyError: 'k'$") as info:
        run_isolated(fail)
    assert "Traceback" in info.value.child_traceback


def test_a_crash_is_named_by_its_exit_status():
    with pytest.raises(IsolatedError, match=r"ended \(exit -11, SIGSEGV\) without a result"):
        run_isolated(segfault)


def test_spawned_not_forked():
    assert run_isolated(my_pid) != os.getpid()


def test_an_interrupt_returns_what_the_child_reached():
    seen = []

    def progress(t):
        seen.append(t)
        if t >= 5:
            raise KeyboardInterrupt

    kind, reached = run_isolated(count, progress=progress)
    assert kind == "reached" and reached >= 5
    assert seen[-1] == 5.0  # progress is not called again once interrupted


def test_an_interrupt_kills_a_child_that_ignores_it(monkeypatch):
    import mj_bridge.accelerated as acc

    monkeypatch.setattr(acc, "GRACE_S", 0.5)
    pids = []

    def progress(t):
        raise KeyboardInterrupt

    real_start = acc._start

    def start(*a):
        proc, conn = real_start(*a)
        pids.append(proc.pid)
        return proc, conn

    monkeypatch.setattr(acc, "_start", start)
    with pytest.raises(KeyboardInterrupt):
        run_isolated(stubborn, progress=progress)
    with pytest.raises(ProcessLookupError):
        os.kill(pids[0], 0)  # reaped: gone


def test_the_child_dies_with_its_parent(tmp_path):
    """A parent killed with SIGKILL (no clean-up) takes its isolated child with it."""
    pidfile = tmp_path / "child.pid"
    script = textwrap.dedent(
        f"""
        import sys, time
        sys.path[:0] = {sys.path!r}
        from mj_bridge.accelerated import run_isolated
        from tests.mj_bridge.test_accelerated import write_pid_and_sleep
        run_isolated(write_pid_and_sleep, {str(pidfile)!r})
        """
    )
    parent = subprocess.Popen([sys.executable, "-c", script])
    try:
        deadline = time.monotonic() + 60
        while not pidfile.exists() or not pidfile.read_text():
            assert time.monotonic() < deadline, "the child did not start"
            time.sleep(0.05)
        child = int(pidfile.read_text())
        parent.kill()
        parent.wait()
        deadline = time.monotonic() + 10
        while _alive(child):
            assert time.monotonic() < deadline, "the child outlived its parent"
            time.sleep(0.05)
    finally:
        if parent.poll() is None:
            parent.kill()


def write_pid_and_sleep(path):
    with open(path, "w") as f:
        f.write(str(os.getpid()))
    time.sleep(120)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except FileNotFoundError:
        return False
