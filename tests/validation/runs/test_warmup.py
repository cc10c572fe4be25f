"""The first run says what it does: ``tumble warmup`` and a first ``tumble validate`` compile every
kernel in worker processes, one line per kernel with its time, after one line announcing the
one-time compile with its measured estimate; later runs are silent (the warm stamp); progress on
stderr reads in a log (one line per event, no carriage returns) as well as on a terminal."""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from mj_bridge.plants import installed_plants
from tests.support import tolerances as tol
from validation.runs import warm_jobs, warm_plan, warmup
from validation.runs.progress import Progress, StageProgress, Status
from validation.runs.warm_jobs import Job, Task
from validation.scenes import resolve_scene

ROOT = Path(__file__).resolve().parents[3]
SCENE = "paper_example1_controlled"


STAMP_PROBE = """
import json, sys
from validation.runs import warmup
from validation.scenes import resolve_scene

res = warmup.warm_up([resolve_scene("paper_example1_controlled")], ["analytic", "mujoco"])
print(json.dumps([len(res.stages), "numba" in sys.modules, "mujoco" in sys.modules]))
"""


def test_a_run_after_a_warm_up_does_not_import_the_engines_to_check_again():
    """Once a warm-up compiled a scene's kernels, the stamp beside numba's cache lets the next run
    skip it: the process that starts the plants imports neither numba nor MuJoCo, and says
    nothing."""
    sc = resolve_scene(SCENE)
    warmup.warm_up([sc], ["analytic", "mujoco"])  # compiles (or loads) what is needed, stamps
    assert warmup.is_stamped_warm(warmup.warm_keys(["analytic", "mujoco"], sc))
    heard: list[str] = []
    assert warmup.warm_up([sc], ["analytic", "mujoco"], heard.append).stages == ()
    assert heard == []
    proc = subprocess.run(
        [sys.executable, "-c", STAMP_PROBE], capture_output=True, text=True, env=_env(), timeout=600
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout.splitlines()[-1]) == [0, False, False]


def test_the_warm_key_follows_what_the_compiled_code_depends_on(tmp_path, monkeypatch):
    """The same inputs give the same keys; a changed source, CPU, numba setting, plant or
    weighting gives another (the next run then warms up again)."""
    sc = resolve_scene(SCENE)
    src = tmp_path / "pkg"
    src.mkdir()
    (src / "mod.py").write_text("x = 1\n")
    monkeypatch.setattr(warmup, "_source_roots", lambda: [src])
    monkeypatch.delenv("NUMBA_OPT", raising=False)
    [key] = warmup.warm_keys(["analytic"], sc)
    assert warmup.warm_keys(["analytic"], sc) == [key]
    others = []
    (src / "mod.py").write_text("x = 2\n")
    others += warmup.warm_keys(["analytic"], sc)
    (src / "mod.py").write_text("x = 1\n")
    assert warmup.warm_keys(["analytic"], sc) == [key]
    others += warmup.warm_keys(["mujoco"], sc)
    m2 = sc.replace(control=dataclasses.replace(sc.control, weighting="M^-2"))
    others += warmup.warm_keys(["analytic"], m2)
    monkeypatch.setenv("NUMBA_OPT", "0")
    others += warmup.warm_keys(["analytic"], sc)
    monkeypatch.delenv("NUMBA_OPT")
    monkeypatch.setattr(warmup, "_cpu_identity", lambda: "another CPU")
    others += warmup.warm_keys(["analytic"], sc)
    assert len({key, *others}) == 1 + len(others)


def test_a_damaged_stamp_counts_as_no_stamp_and_is_rewritten(tmp_path, monkeypatch):
    stamp = tmp_path / warmup.WARM_STAMP
    monkeypatch.setattr(warmup, "_stamp_path", lambda: stamp)
    stamp.write_text("{not json", encoding="utf-8")
    assert not warmup.is_stamped_warm(["k0"])
    for i in range(warmup.STAMP_KEYS_KEPT + 3):
        warmup.stamp_warm([f"k{i}"])
    kept = json.loads(stamp.read_text(encoding="utf-8"))["warm_keys"]
    assert len(kept) == warmup.STAMP_KEYS_KEPT and kept[-1] == f"k{warmup.STAMP_KEYS_KEPT + 2}"
    assert warmup.is_stamped_warm(kept[:2]) and not warmup.is_stamped_warm([kept[0], "k0"])


def test_the_estimate_is_the_measured_costs_scheduled_over_the_workers():
    """One worker: every cost in turn. As many workers as jobs: the longest chain (a plant after
    the longest of its kernels). Two workers: between the two bounds a schedule must respect (half
    the work, the longest chain) and the work itself; each job once, after what it needs."""
    sc = resolve_scene(SCENE)
    c = warm_plan.COST_S
    jobs = (Job.SYSTEM, Job.SOLVE, Job.RHS, Job.MUJOCO_STAGE)
    tasks = [Task(j, 0, sc) for j in jobs] + [
        Task(Job.PLANT, 0, sc, e) for e in ("analytic", "mujoco")
    ]
    work = sum(c[j] for j in jobs) + 2 * c[Job.PLANT]
    start = warm_plan.POOL_START_S
    assert warm_plan.estimate_s(tasks, 1) == pytest.approx(start + work)
    chain = max(c[j] for j in jobs) + c[Job.PLANT]
    assert warm_plan.estimate_s(tasks, len(tasks)) == pytest.approx(start + chain)
    two = warm_plan.estimate_s(tasks, 2) - start
    assert max(work / 2, chain) - 1e-12 <= two <= work
    plan = warm_plan.schedule(tasks, 2)
    assert sorted(t.key for t, _s, _e in plan) == sorted(t.key for t in tasks)
    ends = {t.key: e for t, _s, e in plan}
    for t, begin, _e in plan:
        assert all(ends[k] <= begin + 1e-12 for k in warm_plan.needs(t, tasks))


def test_a_plant_starts_only_after_its_kernels_and_the_pinocchio_stage_after_the_halves(
    monkeypatch,
):
    """Jobs run side by side, each as soon as what it needs is done: a plant's interval would
    otherwise compile its kernels again; the Pinocchio stage binds the halves' addresses. Run on
    two threads with jobs that only record when they start and end."""
    sc = resolve_scene(SCENE)
    events: list[tuple[str, str]] = []
    lock = threading.Lock()

    def fake(task: Task) -> warm_jobs.StageTime:
        name = f"{task.job.value}/{task.engine}"
        with lock:
            events.append(("start", name))
        time.sleep(0.02 * warm_plan.COST_S[task.job])
        with lock:
            events.append(("end", name))
        return warm_jobs.StageTime(name, 0.0)

    monkeypatch.setattr(warmup, "run_task", fake)
    kernels, plants = [], []
    for e in ("analytic", "mujoco", "pinocchio"):
        kernels += [Task(j, 0, sc) for j in warm_jobs.KERNELS[e]]
        plants.append(Task(Job.PLANT, 0, sc, e))
    kernels = warmup._unique(kernels)
    heard: list[warm_jobs.StageTime] = []
    with ThreadPoolExecutor(2) as pool:
        warmup._run_all(pool, 2, [*kernels, *plants], heard.append)
    order = {ev: k for k, ev in enumerate(events)}
    assert len(heard) == len(kernels) + len(plants) == 8  # each job once
    for e in ("analytic", "mujoco", "pinocchio"):
        for j in warm_jobs.KERNELS[e]:
            assert order["end", f"{j.value}/"] < order["start", f"plant/{e}"]
    for j in warm_plan.HALVES:
        assert order["end", f"{j.value}/"] < order["start", "pinocchio-stage/"]
    starts = [name for what, name in events if what == "start"]
    assert set(starts[:2]) == {"system/", "solve/"}  # what the most others wait for goes first


def _crash(task: Task) -> warm_jobs.StageTime:  # module level: a forked worker finds it by name
    os._exit(3)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux")
def test_a_worker_that_dies_fails_its_line_not_the_run(tmp_path, monkeypatch):
    """A worker killed mid-compile (a crash in compiled code): the warm-up reports it on one line,
    stamps nothing (the next run warms up again) and returns; the run compiles what is missing."""
    monkeypatch.setattr(warmup, "_stamp_path", lambda: tmp_path / warmup.WARM_STAMP)
    monkeypatch.setattr(warmup, "run_task", _crash)
    monkeypatch.setattr(
        warmup,
        "_pool",
        lambda n, fork=None: warmup.ProcessPoolExecutor(
            1, mp_context=warmup.multiprocessing.get_context("fork")
        ),
    )
    lines: list[str] = []
    sc = resolve_scene(SCENE)
    res = warmup.warm_up([sc], ["analytic"], lines.append, force=True)
    assert any("failed: BrokenProcessPool" in line for line in lines), lines
    assert res.stages and not warmup.is_stamped_warm(warmup.warm_keys(["analytic"], sc))


def test_tumble_warmup_lists_every_kernel_once_for_every_scene(tmp_path, monkeypatch):
    """``tumble warmup`` without a scene: every built-in scene, one announcement per group of
    plants and one line per kernel, none twice (the kernels depend on the weighting's solve, not
    on the scene), jobs faked on threads."""
    monkeypatch.setattr(warmup, "_stamp_path", lambda: tmp_path / warmup.WARM_STAMP)
    monkeypatch.setattr(warmup, "_pool", lambda n, fork=None: ThreadPoolExecutor(n))
    monkeypatch.setattr(warmup, "run_task", lambda t: warm_jobs.StageTime(t.title, 0.01))
    lines: list[str] = []
    assert warmup.warm_up_command(warmup.builtin_scenes(), ["analytic", "mujoco"], lines.append)
    said = [line.split(": ")[0] for line in lines if line.startswith("  ") and "ready" not in line]
    assert len(said) == len(set(said)) == 6, lines  # system, solve, rhs, stage; two plants
    assert sum(line.startswith("compiling ") for line in lines) == 1, lines
    assert re.fullmatch(
        r"compiling \(or loading\) 4 numba kernels once per machine \(~\d+ s with \d workers?, as "
        r"measured on 2 cores; later runs load them from numba's cache\):",
        lines[0],
    ), lines[0]


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
    """A terminal: one tqdm bar, redrawn in place (carriage returns), named after the stages
    running, with the share of the stages' simulated time done, kept on screen at the end."""
    buf = _Tty()
    p = StageProgress("validate x", 2.0, stream=buf, delay=0.0, stages=1)
    p("analytic", 1.0)
    p.close()
    text = buf.getvalue()
    assert text.startswith("\rvalidate x [analytic]: ") and text.endswith("\n")
    assert " 50%|" in text and "analytic 1 s" in text
    assert text.count("\n") == 1


def test_status_lines():
    log, tty = io.StringIO(), _Tty()
    Status(log)("compiling")
    Status(tty)("compiling")
    assert log.getvalue() == "tumble: compiling\n" and tty.getvalue() == "compiling\n"


def test_progress_in_a_log_is_plain_lines():
    """Not a terminal: plain ``tumble: `` lines, no carriage return (the interval and the ETA:
    tests/validation/runs/test_progress.py)."""
    buf = io.StringIO()
    p = Progress("simulate x", 1.0, delay=0.0, stream=buf)
    p(0.5)
    p.close()
    lines = buf.getvalue().splitlines()
    assert "\r" not in buf.getvalue() and len(lines) == 2, lines
    assert lines[0].startswith("tumble: simulate x: t = 0.500 / 1 s (50 %), ")
    assert lines[1].startswith("tumble: simulate x: stopped at t = 0.500 / 1 s after ")


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
    """A fresh numba cache: the first run announces the one-time compile in one line (how many
    kernels, the measured estimate), then one line per kernel, each once, with its time, and the
    total; the second run in the same cache says nothing about it; ``tumble warmup`` there loads
    every kernel (each listed once) and exits 0."""
    env = _env(NUMBA_CACHE_DIR=str(tmp_path / "numba_cache"))
    first = _validate(tmp_path, env, timeout=1800)
    assert first.returncode == 0, first.stderr
    lines = first.stderr.splitlines()
    plants = list(installed_plants())  # validate's default: every installed plant
    n_kernels = len({j for p in plants for j in warm_jobs.KERNELS[p]})
    head = f"tumble: compiling {n_kernels} numba kernels once per machine (~"
    assert lines[0].startswith(head), lines
    assert sum("compiling" in line for line in lines) == 1, lines
    jobs = [line.split(": ")[1] for line in lines if line.startswith("tumble:   ")]
    assert jobs[-1].startswith("  kernels ready in "), lines
    kernels = jobs[:-1]
    assert len(kernels) == len(set(kernels)) == n_kernels + len(plants), lines
    assert not any("failed" in line or "helper" in line for line in lines), lines
    second = _validate(tmp_path, env, timeout=600)
    assert second.returncode == 0, second.stderr
    assert "compiling" not in second.stderr and "kernels ready" not in second.stderr
    proc = subprocess.run(
        [sys.executable, "-m", "validation", "warmup", SCENE],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout.splitlines()
    timed = [line for line in out if re.fullmatch(r"  .+: \d+\.\d s", line)]
    assert len(timed) == len({t.split(": ")[0] for t in timed}) == n_kernels + len(plants), out


CALLERS_PROBE = """
import json, sys
import numpy as np
from analytic import load_scene
from analytic.fast import FastModel
from analytic.kernel import halves
from validation.runs import warm_jobs, warmup

sc = load_scene(sys.argv[1])
solver = warmup.compiled_solver(sc)
for job in (warm_jobs.Job.RHS, warm_jobs.Job.MUJOCO_STAGE):  # the analytic and the MuJoCo callers
    st = warm_jobs.run_task(warm_jobs.Task(job, solver, sc))
    assert not st.error, st.error
before = halves._compile.cache_info().currsize  # halves made in this process so far
fm = FastModel(sc)  # compiles the halves its scene needs, once
q, qd = sc.initial.q0(), sc.initial.qdot0()
qdd = fm.acceleration(0.0, q, qd)[0]
ref = fm.model.acceleration(0.0, q, qd)[0]
print(json.dumps([before, fm.fallbacks, float(np.max(np.abs(qdd - ref)) / np.max(np.abs(ref)))]))
"""


def test_the_kernels_callers_compile_before_its_halves(tmp_path):
    """A warm-up compiles the kernel's two halves and the plants' compiled callers side by side:
    that works only if a caller's compile needs neither half (they are called by address). In a
    fresh cache, the right-hand side and the MuJoCo stage and callback compile while no half is
    made; the halves then compile once and the kernel agrees with the numpy model."""
    env = _env(NUMBA_CACHE_DIR=str(tmp_path / "numba_cache"))
    proc = subprocess.run(
        [sys.executable, "-c", CALLERS_PROBE, SCENE],
        capture_output=True,
        text=True,
        timeout=1200,
        env=env,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    before, fallbacks, err = json.loads(proc.stdout.splitlines()[-1])
    assert before == 0 and fallbacks == 0
    assert err < tol.FAST_VS_NUMPY_REL.value


def test_spawned_workers_import_this_copy_not_the_working_directorys(tmp_path, monkeypatch):
    """``pip install .`` in a clone, then ``tumble validate`` in it: a spawned worker must compile
    the installed copy (the one this process runs), not the checkout in the working directory."""
    fake = tmp_path / "validation"
    fake.mkdir()
    (fake / "__init__.py").write_text("raise ImportError('the working directory copy')\n")
    monkeypatch.chdir(tmp_path)
    sc = resolve_scene(SCENE)
    with warmup._pool(1, fork=False) as pool:
        st = pool.submit(warm_jobs.run_task, Task(Job.PLANT, 0, sc, "analytic")).result(timeout=600)
    assert st.error == "", st.error
