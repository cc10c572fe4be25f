"""The worker processes of ``tumble validate`` (:mod:`validation.runs.workers`): results, messages and
failures come back as they would here, and a run with workers writes what a run without them
writes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from validation.runs import workers

needs_fork = pytest.mark.skipif(
    not (sys.platform.startswith("linux") and workers.available_cpus() > 1),
    reason="workers fork only on Linux with more than one CPU",
)
"""The forking tests run in a new interpreter: this one may have threads by now (rerun's, after a
recording test), and then :func:`validation.runs.workers.can_fork` rightly declines."""

SCRIPT = """
import json, os, sys
from validation.runs import workers
assert workers.can_fork(), "a fresh interpreter with one thread should fork"

def square(x, *, report):
    for k in range(3):
        report(k)
    return x * x, os.getpid()

def fail(*, report):
    raise ZeroDivisionError("on purpose")

def vanish(*, report):
    os._exit(3)

out = {}
heard = []
job = workers.start("square", square, 7, on_message=heard.append)
value, pid = job.result()
out["square"] = [job.forked, value, pid != os.getpid(), heard]
prepared = []
job = workers.start("square", square, later=True, prepare=lambda: prepared.append(1))
job.give(5)
out["later"] = [job.result()[0], prepared]
try:
    workers.start("fail", fail).result()
except workers.WorkerError as exc:
    out["fail"] = [exc.kind, str(exc)]
try:
    workers.start("vanish", vanish).result()
except workers.WorkerLost as exc:
    out["vanish"] = str(exc)
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def forked():
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop(workers.ENV_SWITCH, None)
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


@needs_fork
def test_a_forked_job_returns_its_result_and_forwards_its_messages_in_order(forked):
    is_forked, value, other_pid, heard = forked["square"]
    assert is_forked and value == 49 and other_pid
    assert heard == [0, 1, 2]


@needs_fork
def test_a_job_started_before_its_inputs_runs_when_given_them(forked):
    value, prepared_here = forked["later"]
    assert value == 25
    assert prepared_here == []  # prepare ran in the child, not in the parent


@needs_fork
def test_an_exception_in_the_worker_comes_back_named(forked):
    kind, text = forked["fail"]
    assert kind == "ZeroDivisionError" and text == "ZeroDivisionError: on purpose"


@needs_fork
def test_a_worker_that_dies_is_reported_lost(forked):
    assert "exit 3" in forked["vanish"]


def _square(x, *, report):
    for k in range(3):
        report(k)
    return x * x, os.getpid()


def _fail(*, report):
    raise ZeroDivisionError("on purpose")


def test_switched_off_every_job_runs_here(monkeypatch):
    monkeypatch.setenv(workers.ENV_SWITCH, "0")
    assert not workers.can_fork()
    heard = []
    job = workers.start("square", _square, 3, on_message=heard.append)
    assert not job.forked
    value, pid = job.result()
    assert value == 9 and pid == os.getpid() and heard == [0, 1, 2]
    with pytest.raises(ZeroDivisionError):
        workers.start("fail", _fail).result()


@needs_fork
def test_validate_with_workers_writes_what_validate_without_them_writes(tmp_path):
    """``tumble validate`` with the plants in workers and with every stage in one process: the
    same checks with the same measured values (same machine, same code: the workers only move
    where it runs), the same files."""
    reports = {}
    for mode, switch in (("workers", "1"), ("one", "0")):
        env = dict(os.environ, **{workers.ENV_SWITCH: switch})
        out = tmp_path / mode
        proc = subprocess.run(
            [sys.executable, "-m", "validation", "validate", "--t-end", "0.5", "--out", str(out)],
            capture_output=True,
            text=True,
            env=env,
            timeout=600,
        )
        assert proc.returncode == 0, proc.stderr
        reports[mode] = json.loads((out / "report.json").read_text())
        reports[mode]["files"] = sorted(json.loads((out / "manifest.json").read_text())["files"])
    a, b = reports["workers"], reports["one"]
    assert [c["name"] for c in a["checks"]] == [c["name"] for c in b["checks"]]
    for ca, cb in zip(a["checks"], b["checks"], strict=True):
        assert ca["passed"] and cb["passed"]
        np.testing.assert_allclose(ca["value"], cb["value"], rtol=1e-12, atol=1e-300)
    assert a["files"] == b["files"]
    assert {"recording", "figures"} <= set(a["run"]["wall_times_s"])


@needs_fork
def test_ctrl_c_reaches_the_plants_in_workers_and_keeps_the_partial_set(tmp_path):
    """A terminal's Ctrl-C (SIGINT to the process group) while the plants run in workers: exit 130,
    the output set committed and marked interrupted, as without workers."""
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "v"
    proc = subprocess.Popen(
        [sys.executable, "-m", "validation", "validate", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        for line in proc.stderr:
            if "mujoco plant" in line:
                break
        time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    man = json.loads((out / "manifest.json").read_text())
    assert man["state"] == "interrupted"
    assert set(man["files"]) | {"manifest.json"} == {p.name for p in out.iterdir()}


def _served_square(x, *, report):
    report("started")
    return x * x, os.getpid()


def _served_fail(*, report):
    raise ZeroDivisionError("on purpose")


def _served_hang(pid_file, *, report):
    with open(pid_file, "w") as f:
        f.write(str(os.getpid()))
    while True:  # never reports, never returns: only a signal ends it
        pass


needs_server = pytest.mark.skipif(
    not workers.can_serve(), reason="a fork server needs Linux and workers switched on"
)


@needs_server
def test_a_served_job_works_from_a_thread_and_a_hung_one_is_stopped(tmp_path):
    """From a second thread (this process is multi-threaded, so it must not fork), a fork-server
    child returns its result and its messages, an exception comes back named, and a child that
    spins without reporting is ended by stop() (SIGTERM, then SIGKILL) and reaped."""
    import threading

    from validation.studies.fuzz.judge import SERVER_PRELOAD

    out: dict = {}

    def body():
        heard: list = []
        # the fork server keeps the preload of its first start, for the whole process: start it
        # with the fuzzer's, or every later served plant run of this test process (the fuzz
        # tests') would load its kernels in its own child
        job = workers.start_served(
            "square", _served_square, 6, on_message=heard.append, preload=SERVER_PRELOAD
        )
        value, pid = job.result()
        out["square"] = (job.forked, value, pid, heard)
        try:
            workers.start_served("fail", _served_fail).result()
        except workers.WorkerError as exc:
            out["fail"] = exc.kind
        pid_file = tmp_path / "hang.pid"
        job = workers.start_served("hang", _served_hang, str(pid_file))
        deadline = time.monotonic() + 30.0
        while not pid_file.exists() or not pid_file.read_text():
            assert time.monotonic() < deadline, "the hanging child never started"
            time.sleep(0.01)
        workers.stop([job])
        out["hang"] = (int(pid_file.read_text()), job.process.is_alive())

    t = threading.Thread(target=body)
    t.start()
    t.join(timeout=60)
    assert not t.is_alive()
    forked, value, pid, heard = out["square"]
    assert forked and value == 36 and pid != os.getpid() and heard == ["started"]
    assert out["fail"] == "ZeroDivisionError"
    hung_pid, alive = out["hang"]
    assert not alive
    with pytest.raises(ProcessLookupError):
        os.kill(hung_pid, 0)


def _can_serve_in(conn):
    conn.send(workers.can_serve())


@needs_server
def test_a_daemonic_process_is_not_served_and_a_daemon_free_one_is():
    """multiprocessing refuses children to a daemonic process (a Dask worker by default): there
    can_serve() says no (the run falls back to the limit at progress reports) instead of lifting
    the process's private flag; a non-daemonic child may serve."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    seen = {}
    for daemon in (True, False):
        here, there = ctx.Pipe(duplex=False)
        proc = ctx.Process(target=_can_serve_in, args=(there,), daemon=daemon)
        proc.start()
        there.close()
        assert here.poll(120)
        seen[daemon] = here.recv()
        proc.join(30)
    assert seen == {True: False, False: True}


def _daemonic():
    import multiprocessing as mp

    return mp.current_process().daemon, workers.can_serve()


@needs_server
def test_the_dask_workers_the_tool_starts_may_serve_and_the_setting_is_scoped():
    """``--dask-workers``: the LocalCluster's worker processes are not daemonic (Dask's documented
    ``distributed.worker.daemon``), so a run there may go to the fork server; the user's Dask
    config is as it was after the cluster."""
    dask = pytest.importorskip("dask")
    pytest.importorskip("distributed")
    from validation.studies.sweep.running import executor_for

    before = dask.config.get("distributed.worker.daemon")
    with executor_for(dask_workers=1) as (ex, _width):
        assert ex.submit(_daemonic).result(timeout=120) == (False, True)
    assert dask.config.get("distributed.worker.daemon") == before

LIMIT_SCRIPT = """
import json, os, signal, time
from validation.runs import workers
assert workers.can_fork(), "a fresh interpreter with one thread should fork"

def spin(*, report):
    while True:  # never reports, never returns
        pass

def segv(*, report):
    os.kill(os.getpid(), signal.SIGSEGV)

def killed(*, report):
    os.kill(os.getpid(), signal.SIGKILL)

def vanish(*, report):
    os._exit(0)

out = {}
t0 = time.monotonic()
job = workers.start("spin", spin, time_limit_s=1.0)
try:
    job.result()
except workers.OverTime as exc:
    out["spin"] = [exc.limit_s, time.monotonic() - t0, job.process.is_alive()]
for name, task in (("segv", segv), ("killed", killed), ("vanish", vanish)):
    try:
        workers.start(name, task).result()
    except workers.WorkerLost as exc:
        out[name] = [exc.exitcode, exc.killed]
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def limited():
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop(workers.ENV_SWITCH, None)
    proc = subprocess.run(
        [sys.executable, "-c", LIMIT_SCRIPT], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


@needs_fork
def test_a_forked_job_past_its_time_limit_is_ended_and_says_so(limited):
    limit, took, alive = limited["spin"]
    assert limit == 1.0 and 1.0 <= took < 10.0 and not alive


@needs_fork
def test_a_lost_worker_says_how_it_ended(limited):
    """A crash (SIGSEGV) and an exit are the child's own doing; only SIGKILL reads as killed."""
    assert limited["segv"] == [-11, False]
    assert limited["vanish"] == [0, False]
    assert limited["killed"] == [-9, True]


def _sleep_forever(*, report):
    while True:
        time.sleep(0.01)


def test_a_job_run_here_is_stopped_at_its_time_limit_by_a_timer():
    import signal
    import threading

    if not hasattr(signal, "setitimer") or threading.current_thread() is not threading.main_thread():
        pytest.skip("the timer needs setitimer and the main thread")
    t0 = time.monotonic()
    with pytest.raises(workers.OverTime, match=r"over its time limit of 0\.3 s"):
        workers.start("sleep", _sleep_forever, fork=False, time_limit_s=0.3).result()
    assert time.monotonic() - t0 < 5.0
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert signal.getsignal(signal.SIGALRM) == signal.SIG_DFL


def test_a_job_run_here_leaves_someone_elses_timer_alone():
    """A timer already set (a test runner's timeout) is not replaced, cancelled or mistaken for
    the job's limit: the job runs without a timer of its own."""
    import signal
    import threading

    if not hasattr(signal, "setitimer") or threading.current_thread() is not threading.main_thread():
        pytest.skip("the timer needs setitimer and the main thread")
    fired: list[int] = []

    def theirs(signum, frame):
        fired.append(signum)

    previous = signal.signal(signal.SIGALRM, theirs)
    try:
        signal.setitimer(signal.ITIMER_REAL, 30.0)
        assert workers.start("quick", lambda *, report: 7, fork=False, time_limit_s=0.1).result() == 7
        left, _ = signal.getitimer(signal.ITIMER_REAL)
        assert 0 < left <= 30.0 and signal.getsignal(signal.SIGALRM) is theirs
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert not fired
