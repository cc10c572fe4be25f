"""The first run says what it does: numba's cache state read without compiling
(validation.warmup.cache_state), the warm-up silent when every kernel is cached, and progress on
stderr that reads in a log (one line per event, no carriage returns) as well as on a terminal."""

from __future__ import annotations

import dataclasses
import importlib
import io
import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests import tolerances as tol
from validation import warmup
from validation.progress import Progress, StageProgress, Status
from validation.scenes import resolve_scene
from validation.warmup import CacheState, cache_state, engine_is_cold

ROOT = Path(__file__).resolve().parents[1]
S = CacheState


def test_cache_state_follows_numbas_disk_cache(tmp_path, monkeypatch):
    """No index before the first call; cached after it; stale once the source changes; a function
    compiled without a disk cache is reported so."""
    src = """
        import numba

        @numba.njit(cache=True)
        def f(x):
            return x + 1.0

        @numba.njit(cache=False)
        def g(x):
            return x - 1.0
    """
    (tmp_path / "warmup_probe_mod.py").write_text(textwrap.dedent(src), encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    mod = importlib.import_module("warmup_probe_mod")
    try:
        assert cache_state(mod.f) is S.ABSENT
        assert mod.f(1.0) == 2.0
        assert cache_state(mod.f) is S.CACHED
        assert cache_state(mod.g) is S.NO_CACHE
        # another source (numba's stamp is the file's mtime and size): the index no longer applies
        path = tmp_path / "warmup_probe_mod.py"
        path.write_text(path.read_text() + "\n# edited\n", encoding="utf-8")
        mod = importlib.reload(mod)
        assert cache_state(mod.f) is S.STALE
        assert mod.f(1.0) == 2.0
        assert cache_state(mod.f) is S.CACHED
    finally:
        sys.modules.pop("warmup_probe_mod", None)


def test_cache_state_unknown_for_what_it_cannot_read():
    assert cache_state(object()) is S.UNKNOWN


@pytest.mark.parametrize(
    ("states", "cold"),
    [
        ([S.CACHED, S.CACHED], False),
        ([S.CACHED, S.ABSENT], False),  # a function no run calls
        ([S.ABSENT, S.ABSENT], True),  # a fresh install
        ([S.CACHED, S.STALE], True),  # an edited source, another numba or CPU
        ([S.CACHED, S.NO_CACHE], True),  # no writable cache: compiled in every process
        ([S.CACHED, S.UNKNOWN], True),
        ([], False),  # nothing compiled at all (numba missing)
    ],
)
def test_engine_is_cold(states, cold):
    assert engine_is_cold(states) is cold


def test_warm_up_is_silent_when_every_kernel_is_cached():
    """After one warm-up (which compiles whatever is cold), a second finds nothing to do, says
    nothing and compiles nothing. (That the check itself then finds every kernel on disk is
    asserted in a fresh cache, :func:`test_first_run_compiles_once_and_says_so`: a working tree's
    own cache may hold stale entries of functions no run calls, edited since they were compiled,
    which the check counts as cold until the stamp covers them.)"""
    from mj_bridge.plants import installed_plants

    sc = resolve_scene("paper_example1_controlled")
    plants = installed_plants()
    warmup.warm_up(sc, plants)
    heard: list[str] = []
    res = warmup.warm_up(sc, plants, heard.append)
    assert heard == [] and res.stages == () and res.cold == ()


STAMP_PROBE = """
import json, sys
from validation import warmup
from validation.scenes import resolve_scene

res = warmup.warm_up(resolve_scene("paper_example1_controlled"), ["analytic", "mujoco"])
print(json.dumps([list(res.cold), "numba" in sys.modules, "mujoco" in sys.modules]))
"""


def test_a_run_after_a_warm_check_does_not_import_the_engines_to_check_again():
    """Once numba's cache was found warm (or warmed up), the stamp beside it lets the next run
    skip the check: the process that starts the plants imports neither numba nor MuJoCo."""
    sc = resolve_scene("paper_example1_controlled")
    warmup.warm_up(sc, ["analytic", "mujoco"])  # compiles what is cold, then stamps
    assert warmup.is_stamped_warm(warmup.warm_key(["analytic", "mujoco"], sc))
    proc = subprocess.run(
        [sys.executable, "-c", STAMP_PROBE], capture_output=True, text=True, env=_env(), timeout=600
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout.splitlines()[-1]) == [[], False, False]


def test_the_warm_key_follows_what_the_compiled_code_depends_on(tmp_path, monkeypatch):
    """The same inputs give the same key; a changed source, CPU, numba setting, engine list or
    weighting gives another (the next run then checks numba's cache again)."""
    sc = resolve_scene("paper_example1_controlled")
    src = tmp_path / "pkg"
    src.mkdir()
    (src / "mod.py").write_text("x = 1\n")
    monkeypatch.setattr(warmup, "_source_roots", lambda: [src])
    monkeypatch.delenv("NUMBA_OPT", raising=False)
    key = warmup.warm_key(["analytic"], sc)
    assert warmup.warm_key(["analytic"], sc) == key
    others = []
    (src / "mod.py").write_text("x = 2\n")
    others.append(warmup.warm_key(["analytic"], sc))
    (src / "mod.py").write_text("x = 1\n")
    assert warmup.warm_key(["analytic"], sc) == key
    others.append(warmup.warm_key(["analytic", "mujoco"], sc))
    m2 = sc.replace(control=dataclasses.replace(sc.control, weighting="M^-2"))
    others.append(warmup.warm_key(["analytic"], m2))
    monkeypatch.setenv("NUMBA_OPT", "0")
    others.append(warmup.warm_key(["analytic"], sc))
    monkeypatch.delenv("NUMBA_OPT")
    monkeypatch.setattr(warmup, "_cpu_identity", lambda: "another CPU")
    others.append(warmup.warm_key(["analytic"], sc))
    assert len({key, *others}) == 1 + len(others)


def test_a_damaged_stamp_counts_as_no_stamp_and_is_rewritten(tmp_path, monkeypatch):
    stamp = tmp_path / warmup.WARM_STAMP
    monkeypatch.setattr(warmup, "_stamp_path", lambda: stamp)
    stamp.write_text("{not json", encoding="utf-8")
    assert not warmup.is_stamped_warm("k0")
    for i in range(warmup.STAMP_KEYS_KEPT + 3):
        warmup.stamp_warm(f"k{i}")
    kept = json.loads(stamp.read_text(encoding="utf-8"))["warm_keys"]
    assert len(kept) == warmup.STAMP_KEYS_KEPT and kept[-1] == f"k{warmup.STAMP_KEYS_KEPT + 2}"
    assert warmup.is_stamped_warm(kept[0]) and not warmup.is_stamped_warm("k0")


def test_stage_progress_in_a_log_is_one_plain_line_per_stage():
    buf = io.StringIO()  # not a terminal
    p = StageProgress("validate x", 2.0, stream=buf)
    for stage in ("analytic", "mujoco"):
        for t in (0.0, 1.0, 2.0):
            p(stage, t)
    p.close()
    lines = buf.getvalue().splitlines()
    assert "\r" not in buf.getvalue() and "\x1b" not in buf.getvalue()
    assert lines[:2] == [
        "tumble: validate x: analytic plant, 0 -> 2 s",
        "tumble: validate x: mujoco plant, 0 -> 2 s",
    ]
    assert len(lines) == 3 and lines[2].startswith("tumble: validate x: stages done (analytic ")


def test_stage_progress_of_plants_side_by_side_announces_each_once():
    """Plants running in workers report interleaved: each is announced once, each wall runs from
    its own first report to its own last."""
    buf = io.StringIO()
    p = StageProgress("validate x", 2.0, stream=buf)
    for t in (0.0, 1.0, 2.0):
        p("analytic", t)
        p("mujoco", t)
    walls = dict(p.walls)
    p.close()
    lines = buf.getvalue().splitlines()
    assert lines[:2] == [
        "tumble: validate x: analytic plant, 0 -> 2 s",
        "tumble: validate x: mujoco plant, 0 -> 2 s",
    ]
    assert len(lines) == 3 and set(walls) == {"analytic", "mujoco"}


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_stage_progress_on_a_terminal_is_one_updating_line():
    buf = _Tty()
    p = StageProgress("validate x", 2.0, stream=buf, delay=0.0)
    p("analytic", 1.0)
    p.close()
    text = buf.getvalue()
    assert text.startswith("\rvalidate x [analytic]: t =") and text.endswith("%)\n")
    assert text.count("\n") == 1


def test_status_lines():
    log, tty = io.StringIO(), _Tty()
    Status(log)("compiling")
    Status(tty)("compiling")
    assert log.getvalue() == "tumble: compiling\n" and tty.getvalue() == "compiling\n"


def test_progress_stays_silent_in_a_log():
    buf = io.StringIO()
    p = Progress("simulate x", 1.0, delay=0.0, stream=buf)
    p(0.5)
    p.close()
    assert buf.getvalue() == ""


def _validate(tmp_path: Path, env: dict[str, str], timeout: float):
    return subprocess.run(
        [sys.executable, "-m", "validation", "validate", "--t-end", "0.05", "--out", "out"],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        cwd=tmp_path,
    )


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env.update(extra)
    return env


def test_validate_in_a_log_says_what_it_does(tmp_path):
    """stderr a pipe: one plain line per stage, each starting with ``tumble: ``."""
    proc = _validate(tmp_path, _env(), timeout=600)
    assert proc.returncode == 0, proc.stderr
    err = proc.stderr
    assert "\r" not in err and "\x1b" not in err
    lines = err.splitlines()
    assert all(line.startswith("tumble: ") for line in lines), err
    for plant in ("analytic", "mujoco"):
        assert f"tumble: validate paper_example1_controlled: {plant} plant, 0 -> 0.05 s" in lines
    # the closing line states each plant's own wall time, as report.json records it
    done = next(line for line in lines if ": stages done (" in line)
    said = dict(re.findall(r"(\w+) ([0-9.e+-]+) s", done.split("stages done (", 1)[1]))
    walls = json.loads((tmp_path / "out" / "report.json").read_text())["run"]["wall_times_s"]
    assert set(said) == {k for k in walls if k in ("analytic", "mujoco", "pinocchio")}
    for plant, text in said.items():
        assert float(text) == pytest.approx(walls[plant], rel=5e-3), (plant, done)  # 3 digits


def test_first_run_compiles_once_and_says_so(tmp_path):
    """A fresh numba cache: the first run names what it compiles and how long each stage took;
    the second run in the same cache compiles nothing and says nothing about it.

    In the default suite (about 15 s) although it compiles everything: a warm run that warmed up
    again, announcing it each time, once went unnoticed while this test was marked slow."""
    env = _env(NUMBA_CACHE_DIR=str(tmp_path / "numba_cache"))
    before = _cold_probe(env)
    # the kernel's halves are seen cold without importing any plant (the full check is skipped)
    assert before == {"halves": ["absent", "absent"], "imported": []}, before
    first = _validate(tmp_path, env, timeout=1800)
    assert first.returncode == 0, first.stderr
    lines = first.stderr.splitlines()
    assert lines[0].startswith("tumble: compiling the fast kernels (once per machine"), lines
    assert any(line.startswith("tumble:   the analytic kernel (analytic.fast): ") for line in lines)
    assert any(line.startswith("tumble:   kernels ready in ") for line in lines)
    assert not any("will compile in the run instead" in line for line in lines), lines
    if warmup.free_cpus() >= 2:
        # the kernel's halves in two processes; the analytic plant's own kernels in the helper
        # while the MuJoCo plant runs (reported once the plants are done)
        helped = [line for line in lines if line.endswith("(helper process)")]
        assert any("stages 1-6" in line for line in helped), lines
        rhs = [k for k, line in enumerate(lines) if "compiled right-hand side" in line]
        done = [k for k, line in enumerate(lines) if "stages done" in line]
        assert rhs and done and rhs[0] > done[0] and lines[rhs[0]] in helped, lines
    second = _validate(tmp_path, env, timeout=600)
    assert second.returncode == 0, second.stderr
    assert "compiling" not in second.stderr and "kernels ready" not in second.stderr
    after = _cold_probe(env, every_engine=True)  # the checks themselves, without the stamp
    assert after == {"halves": ["cached", "cached"], "cold": []}, after


def _cold_probe(env: dict[str, str], every_engine: bool = False) -> dict:
    proc = subprocess.run(
        [sys.executable, "-c", COLD_PROBE, "1" if every_engine else ""],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


COLD_PROBE = """
import json, sys
from validation import warmup
from validation.scenes import DEFAULT_SCENE, resolve_scene

got = {"halves": [s.value for s in warmup.kernel_halves_state(resolve_scene(DEFAULT_SCENE))]}
if sys.argv[1]:
    from mj_bridge.plants import installed_plants

    got["cold"] = list(warmup.cold_engines([p.value for p in installed_plants()]))
else:  # nothing but the kernel was imported to tell
    got["imported"] = sorted(m for m in ("mujoco", "mj_bridge.native") if m in sys.modules)
    assert not got["imported"], got
print(json.dumps(got))
"""


CALLERS_PROBE = """
import json, sys
import numpy as np
from analytic import load_scene
from analytic.fast import FastModel
from analytic.kernel import halves
from validation import warmup

sc = load_scene(sys.argv[1])
warmup.compile_rhs(sc)  # the analytic plant's compiled right-hand side
warmup.compile_native(sc)  # the MuJoCo native callback
before = [cf.address is None for cf in (halves.SYSTEM, halves.SOLVE_GAUSS, halves.SOLVE_MINV2)]
fm = FastModel(sc)  # compiles the halves its scene needs, once
q, qd = sc.initial.q0(), sc.initial.qdot0()
qdd = fm.acceleration(0.0, q, qd)[0]
ref = fm.model.acceleration(0.0, q, qd)[0]
print(json.dumps([before, fm.fallbacks, float(np.max(np.abs(qdd - ref)) / np.max(np.abs(ref)))]))
"""


def test_the_kernels_callers_compile_before_its_halves(tmp_path):
    """The first run compiles the kernel's two halves in two processes while the plants' compiled
    callers compile beside them: that works only if a caller's compile needs neither half (they are
    called by address). In a fresh cache, the right-hand side and the MuJoCo callback compile while
    no half is compiled; the halves then compile once and the kernel agrees with the numpy model."""
    env = _env(NUMBA_CACHE_DIR=str(tmp_path / "numba_cache"))
    proc = subprocess.run(
        [sys.executable, "-c", CALLERS_PROBE, "paper_example1_controlled"],
        capture_output=True,
        text=True,
        timeout=1200,
        env=env,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    before, fallbacks, err = json.loads(proc.stdout.splitlines()[-1])
    assert before == [True, True, True] and fallbacks == 0
    assert err < tol.FAST_VS_NUMPY_REL.value


def test_a_helper_without_a_job_ends_quietly():
    """A spawned helper starts before numba's cache is checked; when the check finds nothing to
    do it gets an empty job (or is stopped) and ends without output or error. A forked one is
    only made with its job: never given one, there is nothing to stop."""
    unborn = warmup._Helper(fork=True)
    unborn.stop()
    assert unborn.proc is None
    helper = warmup._Helper(fork=False)
    try:
        helper.proc.stdin.write(b"\n")
        helper.proc.stdin.close()
        out, err = helper.proc.stdout.read(), helper.proc.stderr.read()
        assert helper.proc.wait(timeout=120) == 0, err
    finally:
        helper.proc.stdin = None
        helper.stop()
    assert out == b"" and err == b""


def test_the_compiling_helper_imports_this_copy_not_the_working_directorys(tmp_path, monkeypatch):
    """``pip install .`` in a clone, then ``tumble validate`` in it: the helper process must
    compile the installed copy (the one this process runs), not the checkout in the working
    directory (``python -c`` puts that first on sys.path)."""
    fake = tmp_path / "validation"
    fake.mkdir()
    (fake / "__init__.py").write_text("raise ImportError('the working directory copy')\n")
    monkeypatch.chdir(tmp_path)
    st = _plant_in(warmup._Helper(fork=False), resolve_scene("paper_example1_controlled"))
    assert st.error == "", st.error


def _plant_in(helper: warmup._Helper, sc) -> warmup.StageTime:
    """The analytic plant's first interval compiled by ``helper`` (then stopped)."""
    try:
        helper.send(sc, "analytic", [])
        helper.go()
        return helper.result()
    finally:
        helper.stop()


FORKED_PROBE = """
import dataclasses, json
from validation import warmup, workers
from validation.scenes import resolve_scene
sc = resolve_scene("paper_example1_controlled")
can = workers.can_fork()
helper = warmup._Helper()
made_late = helper.fork and helper.proc is None
try:
    helper.send(sc, "analytic", [])
    forked = type(helper.proc).__name__ == "_ForkedProcess"
    helper.go()
    st = helper.result()
finally:
    helper.stop()
orphan = warmup._Helper()
try:
    orphan.send(sc, "analytic", [])
    orphan.proc.stdin.close()  # no go line will ever come
    code = orphan.proc.wait(timeout=120)
    late = orphan.result()
finally:
    orphan.stop()
print(json.dumps([can, made_late, forked, dataclasses.asdict(st), code, late.error]))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux")
def test_a_forked_helper_runs_its_job_and_ends_when_this_process_lets_go():
    """Forked (the default where forking is safe), the helper runs the same job through pipes:
    the engine's plant after ``go``, its time reported; without ``go`` (this process closed its
    end: it stopped or died) it ends on its own instead of waiting forever. In a new process:
    this one may run threads (forking is then refused and the helper spawned)."""
    proc = subprocess.run(
        [sys.executable, "-c", FORKED_PROBE],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    can, made_late, forked, st, code, late = json.loads(proc.stdout.splitlines()[-1])
    if not can:
        pytest.skip("forking is not safe here (validation.workers.can_fork)")
    assert made_late and forked  # made with its job, by fork
    assert st["error"] == "" and st["where"] == "helper process" and st["seconds"] > 0, st
    assert code == 0 and late.startswith("helper failed")  # nothing was compiled


def test_a_helper_result_written_before_the_last_stage_is_read_is_not_lost():
    """The helper prints one JSON line per stage; when all of them are in the pipe before the
    parent reads the first (the plants ran meanwhile), reading one line buffers the rest, and the
    engine's result must come from that buffer, not be reported as a helper failure."""
    import dataclasses
    import time

    lines = [
        warmup.StageTime("rates", 0.5, "helper process"),
        warmup.StageTime("the Pinocchio stage", 2.0, "helper process"),
    ]
    code = "import sys; sys.stdout.write(sys.argv[1]); sys.stdout.flush()"
    text = "".join(json.dumps(dataclasses.asdict(st)) + "\n" for st in lines)
    helper = warmup._Helper.__new__(warmup._Helper)
    helper.proc = subprocess.Popen(
        [sys.executable, "-c", code, text],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    helper.first, helper.engine = ["rhs"], warmup.PINOCCHIO
    try:
        helper.proc.wait(timeout=60)  # both lines are in the pipe before the first is read
        time.sleep(0.1)
        got = [helper.next(), helper.result()]
    finally:
        helper.stop()
    assert got == lines
