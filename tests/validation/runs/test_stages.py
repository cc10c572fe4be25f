"""The executor of a job's stages (:mod:`validation.runs.stages`), on its own: helpers give the same
results here and in workers, an error is the helper's result, a lost worker is redone here, a
file that cannot be written is an ``OutputError``, and leaving the pool ends every helper."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from validation.runs import workers
from validation.runs.atomic import OutputError
from validation.runs.stages import Helper, HelperResults, StagePool


def _square(x, *, report):
    return x * x


def _fail(*, report):
    raise ZeroDivisionError("on purpose")


def _full_disk(*, report):
    raise OutputError("/nowhere/file", OSError(28, "No space left on device"))


def test_helpers_here_give_their_results_in_order_and_an_error_as_a_result():
    """``concurrent=False``: every helper runs here, one after the other, when its results are
    asked for; a helper's error is its result, the others' are kept."""
    prepared: list[str] = []
    helpers = [
        Helper("a", _square, prepare=lambda: prepared.append("a")),
        Helper("b", lambda *, report: _fail(report=report)),
        Helper("c", _square),
    ]
    with StagePool(False, helpers) as pool:
        assert not pool.fork
        got = pool.run_helpers([(3,), (), (4,)], order=[2, 1, 0])
    assert isinstance(got, HelperResults)
    assert got.results[0] == 9 and got.results[2] == 16
    assert isinstance(got.results[1], ZeroDivisionError)
    assert got.redone == () and prepared == ["a"]


def test_a_helper_that_cannot_write_a_file_raises_output_error():
    with StagePool(False, [Helper("disk", _full_disk)]) as pool:
        with pytest.raises(OutputError, match="No space left on device"):
            pool.run_helpers([()])


SCRIPT = """
import json, os, signal, sys
from validation.runs import workers
from validation.runs.stages import Helper, StagePool
assert workers.can_fork(), "a fresh interpreter with one thread should fork"
parent = os.getpid()

def square(x, *, report):
    return x * x, os.getpid() != parent

def killed(x, *, report):
    if os.getpid() != parent:
        os.kill(os.getpid(), signal.SIGKILL)
    return x + 1, False

def fail(*, report):
    raise ZeroDivisionError("on purpose")

helpers = [Helper("square", square), Helper("killed", killed), Helper("fail", fail)]
with StagePool(True, helpers) as pool:
    got = pool.run_helpers([(3,), (4,), ()])
    jobs = list(pool._jobs)
print(json.dumps({
    "fork": pool.fork,
    "square": list(got.results[0]),
    "killed": list(got.results[1]),
    "fail": [type(got.results[2]).__name__, str(got.results[2])],
    "redone": list(got.redone),
    "alive": [j.process.is_alive() for j in jobs],
}))
"""


@pytest.mark.skipif(
    not (sys.platform.startswith("linux") and workers.available_cpus() > 1),
    reason="workers fork only on Linux with more than one CPU",
)
def test_helpers_in_workers_a_lost_one_redone_here_and_none_left_running():
    """In workers (a fresh interpreter, so it may fork): the results come back from the children;
    a helper whose worker is killed is redone here, and said so; a helper's error comes back as a
    ``RuntimeError`` naming it; leaving the pool leaves no child running."""
    env = dict(os.environ)
    env.pop(workers.ENV_SWITCH, None)
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.splitlines()[-1])
    assert out["fork"] is True
    assert out["square"] == [9, True]
    assert out["killed"] == [5, False]  # made here: its worker was killed
    assert len(out["redone"]) == 1 and "killed" in out["redone"][0]
    assert "made again in the main process" in out["redone"][0]
    assert out["fail"] == ["RuntimeError", "ZeroDivisionError: on purpose"]
    assert out["alive"] == [False, False, False]
