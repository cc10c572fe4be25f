"""The compile lock: a process that needs a kernel another process is compiling waits for it
(a first run's helper compiles the analytic plant's right-hand side while the plants start)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from analytic.runtime import compile_lock

ROOT = Path(__file__).resolve().parents[3]

WAITER = """
import sys, time
from analytic.runtime import compile_lock
print("asking", flush=True)
with compile_lock.compiling(compile_lock.RHS):
    print("got", flush=True)
"""

HOLDER = """
from analytic.runtime import compile_lock
assert compile_lock.hold(compile_lock.RHS)
print("held", flush=True)
input()
"""

pytestmark = pytest.mark.skipif(compile_lock.fcntl is None, reason="no fcntl (not POSIX)")


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    yield tmp_path
    compile_lock.release(compile_lock.RHS)


def _python(code: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-c", code],
        cwd=ROOT,
        env=dict(os.environ),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_a_second_process_waits_until_the_holder_releases(cache_dir):
    assert compile_lock.hold(compile_lock.RHS)
    proc = _python(WAITER)
    try:
        assert proc.stdout.readline().strip() == "asking"
        time.sleep(1.0)  # long enough to have taken a free lock many times over
        assert proc.poll() is None, proc.stderr.read()
        compile_lock.release(compile_lock.RHS)
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0 and out.strip() == "got", err
    finally:
        proc.kill()
        proc.wait()


def test_a_holder_that_dies_frees_the_lock(cache_dir):
    proc = _python(HOLDER)
    try:
        assert proc.stdout.readline().strip() == "held", proc.stderr.read()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        t0 = time.monotonic()
        with compile_lock.compiling(compile_lock.RHS):
            pass
        assert time.monotonic() - t0 < 5
    finally:
        proc.kill()
        proc.wait()


def test_a_lock_this_process_holds_is_not_waited_for(cache_dir):
    assert compile_lock.hold(compile_lock.RHS)
    with compile_lock.compiling(compile_lock.RHS):  # would wait forever on its own flock
        pass
    assert compile_lock.RHS in compile_lock._held  # still held: only release() lets go
    compile_lock.release(compile_lock.RHS)
    assert compile_lock.RHS not in compile_lock._held


def test_only_plain_names_make_lock_files(cache_dir):
    """A lock name becomes a file name: anything but lower-case letters, digits and dashes locks
    nothing (and creates no file)."""
    assert not compile_lock.hold("../escape")
    assert compile_lock.hold(compile_lock.RHS)
    assert sorted(p.name for p in cache_dir.iterdir()) == [
        f"tumble-compiling-{compile_lock.RHS}.lock"
    ]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
def test_a_forked_child_does_not_inherit_the_holders_lock(cache_dir):
    """A worker forked while this process holds the lock holds nothing itself: the lock stays
    taken (by the parent) and the child would wait for it like any other process."""
    assert compile_lock.hold(compile_lock.RHS)
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        code = 1
        try:
            f = open(cache_dir / f"tumble-compiling-{compile_lock.RHS}.lock", "ab")
            try:
                compile_lock.fcntl.flock(f, compile_lock.fcntl.LOCK_EX | compile_lock.fcntl.LOCK_NB)
            except BlockingIOError:
                code = 0 if not compile_lock._held else 2
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    compile_lock.release(compile_lock.RHS)
    with compile_lock.compiling(compile_lock.RHS):  # the child's copy did not keep it either
        pass
