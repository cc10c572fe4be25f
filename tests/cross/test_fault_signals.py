"""Signals at any moment of any long command: exit 143 (SIGTERM) / 130 (SIGINT), one line, the
output set marked interrupted, within about a second.

Each command runs under one mechanism (:mod:`validation.runs.interrupts`, installed by
:func:`validation.cli.main`): a signal is noted, and an exception it caused (an import it cut, as
a C extension's initialisation cut by it fails with ``ImportError: initialization failed``) or a
plant's run that caught it ends the command as interrupted. The import cut is made by
``tests/support/cut_import.py``; the other faults are real signals sent to a real process.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from analytic.scene.builtin import builtin_scene_path

pytestmark = pytest.mark.faults

REPO = Path(__file__).resolve().parents[2]
CUT = REPO / "tests" / "support" / "cut_import.py"
STATUS = {"SIGTERM": 143, "SIGINT": 130}


def _env(**extra: str) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(REPO), **extra)


def _state(out: Path) -> str | None:
    try:
        return json.loads((out / "manifest.json").read_text())["state"]
    except FileNotFoundError:
        return None


def _cut(module: str, sig: str, *args: str, after: Path | None = None, cwd: Path):
    """``tumble ARGS`` with ``sig`` cutting the import of ``module``; (process, seconds from the
    cut to the exit, stderr lines other than the cut's)."""
    env = _env(**({"CUT_AFTER_PARTIAL": str(after)} if after else {}))
    proc = subprocess.run(
        [sys.executable, str(CUT), module, sig, *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=cwd,
        timeout=600,
    )
    end = time.monotonic()
    cut = [x for x in proc.stderr.splitlines() if x.startswith("cut import ")]
    rest = [x for x in proc.stderr.splitlines() if not x.startswith("cut import ")]
    took = end - float(cut[0].rsplit(" at ", 1)[1]) if cut else None
    return proc, took, rest


ENDINGS = ("tumble: error", "tumble: terminated", "tumble: interrupted")
"""How the lines start that say how a command ended; any other ``tumble: `` line off a terminal
is a warning, a progress line or a notice (``docs/cli.md``, *Progress and messages*)."""


def _said(lines: list[str]) -> list[str]:
    """The lines other than warnings, progress and notices: how the command ended, and anything
    that is not the tool's own line (a traceback)."""
    return [
        x for x in lines if x.strip() and (x.startswith(ENDINGS) or not x.startswith("tumble: "))
    ]


def _one_interrupted_line(lines: list[str], sig: str) -> None:
    """Exactly one line besides warnings: terminated / interrupted; no traceback."""
    word = "terminated" if sig == "SIGTERM" else "interrupted"
    said = _said(lines)
    assert len(said) == 1 and said[0].startswith(f"tumble: {word}"), lines


def _handler_set(pid: int) -> bool:
    """Whether process ``pid`` catches SIGTERM yet (Linux: ``SigCgt`` in /proc/PID/status)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    caught = next(x for x in status.splitlines() if x.startswith("SigCgt:"))
    return bool(int(caught.split()[1], 16) >> (signal.SIGTERM - 1) & 1)


def _terminate_into(args: list[str], wait_s: float, cwd: Path) -> tuple[subprocess.Popen, float, str]:
    """``tumble ARGS`` sent SIGTERM ``wait_s`` after its handler is set; (process, seconds from
    the signal to the exit, stderr)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "validation", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(),
        cwd=cwd,
    )
    try:
        if not Path(f"/proc/{proc.pid}/status").exists():
            pytest.skip("needs /proc to see when the command's handler is set")
        deadline = time.monotonic() + 60
        while not _handler_set(proc.pid) and time.monotonic() < deadline:
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.01)
        time.sleep(wait_s)
        assert proc.poll() is None, "the command ended before the signal"
        proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc, time.monotonic() - t0, err


@pytest.mark.parametrize("wait_s", [0.5, 2.0, 4.0])
def test_sigterm_while_reference_runs_leaves_the_pack_interrupted(tmp_path, wait_s):
    """SIGTERM into ``tumble reference`` (at 2 and 4 s: while it computes its reference run;
    exit 0 or a RuntimeError traceback before) -> exit 143 within a few seconds, one line, the
    pack's directory (begun before the runs) marked interrupted, no reference.csv."""
    scene = tmp_path / "long.toml"
    text = builtin_scene_path("paper_example1_controlled").read_text()
    scene.write_text(re.sub(r"(?m)^t_end = .*$", "t_end = 3000.0", text, count=1))
    out = tmp_path / "ref"
    proc, took, err = _terminate_into(["reference", str(scene), "--out", str(out)], wait_s, tmp_path)
    assert proc.returncode == 143, err
    assert took < 5.0, f"{took:.1f} s to stop"
    _one_interrupted_line(err.strip().splitlines(), "SIGTERM")
    assert _state(out) in ((None, "interrupted") if wait_s < 4 else ("interrupted",))
    assert not (out / "reference.csv").exists() and not (out / "reference.json").exists()


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT"])
def test_a_signal_cutting_mujocos_import_in_demo_is_interrupted(tmp_path, sig):
    """SIGTERM / SIGINT cutting MuJoCo's initialisation in ``tumble demo`` (a 33-line ImportError
    traceback and a set committed failed before) -> exit 143 / 130 within about a second, one
    line, the demo's directory marked interrupted."""
    proc, took, rest = _cut("mujoco", sig, "demo", "--out", "d", after=tmp_path, cwd=tmp_path)
    assert proc.returncode == STATUS[sig], proc.stderr
    assert took is not None and took < 3.0, f"{took} s from the cut to the exit"
    _one_interrupted_line(rest, sig)
    assert _state(tmp_path / "d") == "interrupted"


def test_a_signal_cutting_an_import_inside_a_hard_case_stops_the_suite(tmp_path):
    """SIGTERM cutting an engine's import inside a hard case (an ERROR row, and the suite ran on
    and exited 1, before) -> exit 143 within about a second, one line, the table marked
    incomplete and the directory interrupted."""
    proc, took, rest = _cut(
        "pinocchio", "SIGTERM", "hard-cases", "--fast", "--out", "h", after=tmp_path, cwd=tmp_path
    )
    assert proc.returncode == 143, proc.stderr
    assert took is not None and took < 3.0, f"{took} s from the cut to the exit"
    _one_interrupted_line(rest, "SIGTERM")
    assert _state(tmp_path / "h") == "interrupted"
    table = json.loads((tmp_path / "h" / "hard_cases.json").read_text())
    assert table["complete"] is False and "interrupted" in table["message"]
    assert all(r["verdict"] != "ERROR" for r in table["rows"])


@pytest.mark.parametrize("wait_s", [0.1, 0.3, 0.5, 1.0])
def test_sigterm_half_a_second_into_hard_cases_stops_it_at_once(tmp_path, wait_s):
    """SIGTERM a moment (0.1 to 1 s) after ``tumble hard-cases --fast`` has set its handler, while
    it imports and starts its cases (lost before: the suite ran on for up to 39 s and exited 1, or
    a traceback) -> exit 143 within about a second, one line, any directory begun interrupted."""
    out = tmp_path / "h"
    proc, took, err = _terminate_into(["hard-cases", "--fast", "--out", str(out)], wait_s, tmp_path)
    assert proc.returncode == 143, err
    assert took < 3.0, f"{took:.1f} s to stop"
    _one_interrupted_line(err.strip().splitlines(), "SIGTERM")
    assert _state(out) in (None, "interrupted")


@pytest.mark.parametrize("value", ["", ",", " , "])
@pytest.mark.parametrize("command", ["hard-cases", "validate", "judge", "fuzz"])
def test_an_empty_plants_list_is_refused(tmp_path, command, value):
    """``--plants ''`` (or only commas; hard-cases ran the default plants before) -> exit 2, one
    line naming --plants and the value, nothing written, for every command with --plants."""
    extra = ["--trajectory", str(tmp_path / "t.csv")] if command == "judge" else []
    proc = subprocess.run(
        [sys.executable, "-m", "validation", command, "--plants", value, *extra, "--out", "o"],
        capture_output=True,
        text=True,
        env=_env(),
        cwd=tmp_path,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"tumble {command}: error: --plants"), lines
    assert repr(value) in lines[0]
    assert not (tmp_path / "o").exists()


SURVEY = {
    "simulate": ["simulate", "--t-end", "0.2", "--out", "o"],
    "validate": ["validate", "--t-end", "0.2", "--out", "o"],
    "reference": ["reference", "--out", "o"],
    "demo": ["demo", "--out", "o"],
    "hard-cases": ["hard-cases", "--fast", "--out", "o"],
    "sweep": ["sweep", "--quick", "--t-end", "0.2", "--out", "o"],
    "warmup": ["warmup", "paper_example1"],
    "bench": ["bench", "--skip-long"],
    "scene-reference": ["scene-reference", "--out", "o.md"],
}
"""Every long command, on a short horizon."""


@pytest.mark.slow
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT"])
@pytest.mark.parametrize("command", sorted(SURVEY))
def test_a_signal_cutting_the_first_import_of_any_command_is_interrupted(tmp_path, command, sig):
    """SIGTERM / SIGINT cutting the first import a command makes once its handler is set (its
    heavy imports: numpy, MuJoCo, numba ...) -> exit 143 / 130 within about a second, one line, no
    traceback, and any output set it began marked interrupted."""
    proc, took, rest = _cut("*", sig, *SURVEY[command], cwd=tmp_path)
    assert proc.returncode == STATUS[sig], proc.stderr
    assert took is not None and took < 3.0, f"{took} s from the cut to the exit"
    _one_interrupted_line(rest, sig)
    assert _state(tmp_path / "o") in (None, "interrupted")
    assert not (tmp_path / "o.md").exists()


@pytest.mark.slow
@pytest.mark.parametrize("command", ["simulate", "reference", "demo", "hard-cases", "sweep"])
def test_a_signal_cutting_an_import_once_the_output_set_is_staged_is_interrupted(tmp_path, command):
    """SIGTERM cutting the first import a command makes once its output set is being staged ->
    exit 143 within about a second, one line, the set marked interrupted (never complete or
    failed)."""
    proc, took, rest = _cut("*", "SIGTERM", *SURVEY[command], after=tmp_path, cwd=tmp_path)
    assert proc.returncode == 143, proc.stderr
    assert took is not None and took < 3.0, f"{took} s from the cut to the exit"
    _one_interrupted_line(rest, "SIGTERM")
    assert _state(tmp_path / "o") == "interrupted"


def _children(pid: int) -> set[int]:
    """The live children of process ``pid`` (Linux ``/proc/PID/task/*/children``)."""
    out: set[int] = set()
    for f in Path(f"/proc/{pid}/task").glob("*/children"):
        try:
            out |= {int(x) for x in f.read_text().split()}
        except OSError:
            pass
    return out


@pytest.mark.parametrize(
    "args",
    [["sweep", "--quick", "--t-end", "60", "--out", "sw"],
     ["fuzz", "--budget", "4", "--horizon", "30", "--out", "fz"]],
    ids=["sweep", "fuzz"],
)
def test_sigterm_while_a_process_pool_runs_stops_at_once(tmp_path, args):
    """SIGTERM into ``tumble sweep`` / ``tumble fuzz`` while their process pool runs long tasks
    (seconds to stop before: the pool's shutdown waited for the running tasks) -> exit 143 within a second,
    one line, the output marked interrupted, and every worker of the pool gone within seconds."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "validation", *args], stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, env=_env(), cwd=tmp_path,
    )  # fmt: skip
    try:
        if not Path(f"/proc/{proc.pid}/task").exists():
            pytest.skip("needs /proc to see the command's pool")
        deadline = time.monotonic() + 120
        while len(_children(proc.pid)) < 2 and time.monotonic() < deadline:
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        time.sleep(2.0)  # the pool's tasks under way
        workers = _children(proc.pid)
        assert proc.poll() is None and workers, "no pool to interrupt"
        proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143, err
    assert took < 1.5, f"{took:.1f} s to stop"
    _one_interrupted_line(err.strip().splitlines(), "SIGTERM")
    assert _state(tmp_path / args[-1]) == "interrupted"
    deadline = time.monotonic() + 10
    while any(Path(f"/proc/{w}").exists() for w in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = [w for w in workers if Path(f"/proc/{w}").exists()]
    assert not left, f"workers left running: {left}"
