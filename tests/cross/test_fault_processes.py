"""Faults: the ``tumble`` process killed with SIGKILL (``subprocess.run(timeout=...)``, a CI runner's
hard kill) while its workers run. No clean-up of the parent runs then; every child it started, and
every child of those (the fork server's), must end by itself (:mod:`validation.runs.lifetime`).

Each test starts the command in a session of its own, waits until its workers exist (found
through ``/proc``), kills the command alone with SIGKILL and requires every process that descended
from it to be gone (or a zombie: dead, waiting for init to reap it) within :data:`GONE_S`. Whatever
is left is killed at the end, so a failure leaves nothing running."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from validation.runs import workers

pytestmark = [
    pytest.mark.faults,
    pytest.mark.skipif(
        not (sys.platform.startswith("linux") and workers.available_cpus() > 1),
        reason="the tool starts worker processes only on Linux with more than one CPU",
    ),
]

GONE_S = 10.0
"""How long the orphaned processes may take to end, s: a killed plant worker ends at once; the
fork server notices its parent's end on a pipe and exits with the interpreter's teardown (about
2 s on the loaded 2-core machine). A worker nothing ends runs on for the whole of its run
(:data:`HORIZON_S` of simulated time, minutes): this bound separates the two, it is no speed goal."""

START_S = 240.0
"""How long the command may take to start its workers (a cold numba cache compiles first), s."""

HORIZON_S = "600"
"""The runs' simulated horizon, s: long enough that no worker ends on its own during a test."""


def _ppid_and_state(pid: int) -> tuple[int, str] | None:
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rpartition(")")[2].split()
    except OSError:
        return None
    return int(fields[1]), fields[0]


def _descendants(root: int) -> set[int]:
    """Every living process below ``root`` now (children, their children, ...)."""
    kids: dict[int, list[int]] = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            info = _ppid_and_state(int(name))
            if info is not None and info[1] not in "ZX":
                kids.setdefault(info[0], []).append(int(name))
    out: set[int] = set()
    todo = [root]
    while todo:
        for child in kids.get(todo.pop(), []):
            if child not in out:
                out.add(child)
                todo.append(child)
    return out


def _alive(pid: int) -> bool:
    info = _ppid_and_state(pid)
    return info is not None and info[1] not in "ZX"


def _depth(root: int, pid: int) -> int:
    """How many parents up from ``pid`` to ``root`` (0 if ``root`` is not an ancestor)."""
    n = 0
    while pid not in (0, 1):
        info = _ppid_and_state(pid)
        if info is None:
            return 0
        pid, n = info[0], n + 1
        if pid == root:
            return n
    return 0


def _kill_and_require_all_gone(cmd: list[str], cwd: Path, ready) -> None:
    """Start ``cmd`` in its own session, wait until ``ready(root, descendants)``, SIGKILL the
    command alone, and assert every descendant is gone within :data:`GONE_S`."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    log = (cwd / "command.log").open("wb")
    proc = subprocess.Popen(
        cmd, cwd=cwd, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True
    )
    seen: set[int] = set()
    try:
        deadline = time.monotonic() + START_S
        while True:
            assert proc.poll() is None, (cwd / "command.log").read_text()[-2000:]
            kids = _descendants(proc.pid)
            if ready(proc.pid, kids):
                break
            assert time.monotonic() < deadline, f"no workers after {START_S} s: {sorted(kids)}"
            time.sleep(0.1)
        seen = _descendants(proc.pid) | kids
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        deadline = time.monotonic() + GONE_S
        while any(_alive(p) for p in seen) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = sorted(p for p in seen if _alive(p))
        assert not left, f"still running {GONE_S} s after the command was killed: {left}"
    finally:
        with_group = [p for p in seen if _alive(p)]
        for pid in with_group:  # never left running by a failure
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except OSError:
            pass
        proc.wait(timeout=30)
        log.close()


def test_validate_killed_with_sigkill_leaves_no_plant_worker(tmp_path):
    """`tumble validate` killed with SIGKILL while its plants run in forked workers -> every
    worker ends with it (PR_SET_PDEATHSIG): none is left running."""
    cmd = [
        sys.executable, "-m", "validation", "validate", "paper_example1_controlled",
        "--t-end", HORIZON_S, "--plants", "analytic,mujoco", "--out", str(tmp_path / "out"),
    ]  # fmt: skip
    _kill_and_require_all_gone(cmd, tmp_path, lambda root, kids: len(kids) >= 2)


def test_fuzz_on_dask_killed_with_sigkill_leaves_no_served_worker(tmp_path):
    """`tumble fuzz --dask-workers 1` killed with SIGKILL while a plant runs in a child of the
    Dask worker's fork server -> the Dask worker, its fork server and the served child all end:
    none is left running."""
    pytest.importorskip("distributed")
    cmd = [
        sys.executable, "-m", "validation", "fuzz", "--dask-workers", "1", "--budget", "50",
        "--horizon", HORIZON_S, "--time-limit", "900", "--plants", "analytic,mujoco",
        "--out", str(tmp_path / "out"),
    ]  # fmt: skip

    def served(root: int, kids: set[int]) -> bool:  # the command, Dask's worker, the server, its child
        return any(_depth(root, p) >= 3 for p in kids)

    _kill_and_require_all_gone(cmd, tmp_path, served)


POOL_SCRIPT = """
import pathlib, time
from validation.studies.sweep.running import default_executor

ex = default_executor()
ex.submit(pathlib.Path("worker-ran").touch).result()  # the pool works (its initializer too)
ex.submit(time.sleep, 600).result()
"""


def _cmdline(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def test_process_pool_parent_killed_with_sigkill_leaves_no_pool_worker(tmp_path):
    """The process pool of a sweep or fuzz campaign (its default executor) with its parent killed
    with SIGKILL while a worker runs a task -> the worker ends with it: none is left running."""

    def started(root: int, kids: set[int]) -> bool:
        ran = (tmp_path / "worker-ran").exists()
        return ran and any("spawn_main" in _cmdline(p) for p in kids)

    _kill_and_require_all_gone([sys.executable, "-c", POOL_SCRIPT], tmp_path, started)


SLOW_SERVER_SCRIPT = """
import os
from validation.runs import workers
assert workers.can_serve()
job = workers.start_served("slow", os.getpid, preload=["tests.support.slow_preload"])
"""


def test_a_fork_server_whose_client_is_killed_during_its_preload_ends(tmp_path):
    """The fork server's client killed with SIGKILL while the server still imports its preload
    (a minute here, as compiling numba's kernels into a cold cache can take; the server watched
    nothing until its loop and ran on to the preload's end) -> the server ends within seconds."""

    def serving(root: int, kids: set[int]) -> bool:
        return any("forkserver" in _cmdline(p) for p in kids)

    root = Path(__file__).resolve().parents[2]
    env_path = os.pathsep.join(p for p in (str(root), os.environ.get("PYTHONPATH")) if p)
    os.environ.setdefault("PYTHONPATH", "")
    old = os.environ["PYTHONPATH"]
    os.environ["PYTHONPATH"] = env_path  # the script and the server import the tests' support
    try:
        _kill_and_require_all_gone([sys.executable, "-c", SLOW_SERVER_SCRIPT], tmp_path, serving)
    finally:
        os.environ["PYTHONPATH"] = old
