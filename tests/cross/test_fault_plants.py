"""Faults of a plant plugin's own code: an exit, a crash, a hang, a lie, garbage, a scene changed in
place. Each fails that plant alone, in one line naming it: the other plants run and are compared
as without it, the verdict is FAILED (exit 1, never the plugin's exit status or a crash of the
tool), and no staging directory or lock is left. The hostile plugins are
``tests/support/hostile_plugins.py``, installed by entry point into a directory on ``PYTHONPATH``.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest

from tests.support import hostile_plugins
from validation.runs import workers

pytestmark = pytest.mark.faults

SCENE = "paper_example1_controlled"
T_END = "0.2"
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    return hostile_plugins.install(tmp_path_factory.mktemp("hostile") / "site")


def _needs_fork() -> None:
    if not (sys.platform.startswith("linux") and workers.available_cpus() > 1):
        pytest.skip("plant workers fork only on Linux with more than one CPU")


def _validate(
    site: Path, tmp_path: Path, hostile: str, *extra: str, in_process: bool = False
) -> tuple[subprocess.CompletedProcess, Path, float]:
    """``tumble validate`` of the analytic plant, MuJoCo and plugin ``hostile``: the finished
    process, the output directory and the wall time, s. ``in_process``: ``TUMBLE_WORKERS=0``."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT), env.get("PYTHONPATH", "")])
    env.pop(workers.ENV_SWITCH, None)
    if in_process:
        env[workers.ENV_SWITCH] = "0"
    else:
        _needs_fork()
    out = tmp_path / "runs" / "v"
    out.parent.mkdir()
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "validation", "validate", SCENE, "--t-end", T_END,
         "--plants", f"analytic,mujoco,{hostile}", "--out", str(out), *extra],
        capture_output=True, text=True, env=env, timeout=300,
    )
    return proc, out, time.monotonic() - t0


def _fails_alone(proc: subprocess.CompletedProcess, out: Path, label: str, *words: str) -> dict:
    """The run FAILED (exit 1, no traceback), its failure names the plugin ``label`` with
    ``words``, the analytic plant and MuJoCo were compared and agree, and the output directory is
    the only thing beside it (no staging directory, no lock). Returns report.json."""
    said = proc.stdout + proc.stderr
    assert proc.returncode == 1, said[-3000:]
    assert "Traceback" not in said, said[-3000:]
    assert (out / "report.md").read_text().splitlines()[0] == f"# {SCENE}: FAILED"
    doc = json.loads((out / "report.json").read_text())
    assert doc["passed"] is False
    mine = [part for part in doc["failure"].split("; ") if part.startswith(f"{label} plant: ")]
    assert len(mine) == 1 and all(w in mine[0] for w in words), doc["failure"]
    assert all(part.startswith(f"{label} plant: ") for part in doc["failure"].split("; ")), doc[
        "failure"
    ]
    pair = [c for c in doc["checks"] if c["subject"] == "analytic vs mujoco"]
    assert pair and all(c["passed"] for c in pair if c["applicable"]), pair
    assert [p.name for p in out.parent.iterdir()] == [out.name]
    assert json.loads((out / "manifest.json").read_text())["state"] == "failed"
    return doc


def test_plugin_exiting_with_os_exit_0_fails_that_plant_alone(site, tmp_path):
    """A plugin whose run calls ``os._exit(0)`` (in its worker) -> that plant FAILED ("exit 0", by
    its own doing, not run again in the main process), the others compared, exit 1, no staging
    directory or lock left."""
    proc, out, _ = _validate(site, tmp_path, "exit0")
    _fails_alone(proc, out, "Exit0", "exit 0", "own doing", "not run again")


def test_plugin_raising_system_exit_in_process_fails_that_plant_alone(site, tmp_path):
    """``raise SystemExit(0)`` in a plugin's run with ``TUMBLE_WORKERS=0`` (run in the main
    process) -> that plant FAILED naming SystemExit, the others compared, exit 1."""
    proc, out, _ = _validate(site, tmp_path, "sysexit", in_process=True)
    _fails_alone(proc, out, "SysExit", "SystemExit")


def test_plugin_segfault_fails_that_plant_alone(site, tmp_path):
    """A plugin that segfaults in its worker -> that plant FAILED naming SIGSEGV (not run again in
    the main process, which would crash the tool), the others compared, exit 1, no staging
    directory or lock left."""
    proc, out, _ = _validate(site, tmp_path, "segv")
    _fails_alone(proc, out, "Segv", "SIGSEGV", "not run again")


def test_plugin_worker_killed_is_not_run_again_in_the_main_process(site, tmp_path):
    """A plugin's worker killed by SIGKILL -> that plant FAILED ("exit -9", not run again in the
    main process: a built-in's would be, a plugin's crash must not become the tool's), the others
    compared, exit 1."""
    proc, out, _ = _validate(site, tmp_path, "killed")
    doc = _fails_alone(proc, out, "Killed", "exit -9", "SIGKILL", "not run again")
    assert "redone" not in doc["run"]


def test_plugin_naming_its_run_analytic_is_not_compared_as_the_analytic_plant(site, tmp_path):
    """A plugin returning its trajectory under the engine name ``analytic`` -> that plant FAILED
    (it broke the plant contract: not its own name), the real analytic-vs-MuJoCo comparison is
    made, exit 1."""
    proc, out, _ = _validate(site, tmp_path, "liar")
    doc = _fails_alone(proc, out, "Liar", "plant contract", "'analytic'")
    assert [p["engine"] for p in doc["plants"]] == ["analytic", "mujoco"]


def test_plugin_changing_its_scene_in_place_changes_nothing_else(site, tmp_path):
    """A plugin that changes the scene it is given in place (inertia x2 through a writable flag,
    the name and ``t_end`` through ``object.__setattr__``), run in the main process -> only its own
    copy changes: the report's scene, ``scene.toml`` and the analytic-vs-MuJoCo comparison are those
    of the scene as given."""
    proc, out, _ = _validate(site, tmp_path, "mutator", in_process=True)
    assert proc.returncode == 1, proc.stderr[-3000:]  # its own run, at twice the inertia, differs
    doc = json.loads((out / "report.json").read_text())
    assert doc["scene"] == SCENE and hostile_plugins.MUTATED_NAME not in (out / "report.md").read_text()
    ran = tomllib.loads((out / "scene.toml").read_text())
    given = tomllib.loads((ROOT / "analytic" / "scenes" / f"{SCENE}.toml").read_text())
    assert ran["scene"]["name"] == SCENE
    assert ran["body"]["inertia"] == given["body"]["inertia"]
    assert ran["output"]["t_end"] != hostile_plugins.MUTATED_T_END
    pair = [c for c in doc["checks"] if c["subject"] == "analytic vs mujoco"]
    assert pair and all(c["passed"] for c in pair if c["applicable"])


def test_plugin_that_never_returns_is_stopped_at_the_time_limit(site, tmp_path):
    """A plugin whose run never returns nor reports progress, ``--time-limit 12`` -> its worker
    is ended at the limit; that plant FAILED naming the limit, the others compared, exit 1, in
    far less than twice the limit."""
    proc, out, took = _validate(site, tmp_path, "hang", "--time-limit", "12")
    _fails_alone(proc, out, "Hang", "time limit of 12 s")
    assert took < 60, f"took {took:.0f} s"


@pytest.mark.slow
def test_plugin_that_never_returns_in_process_is_stopped_at_the_time_limit(site, tmp_path):
    """The same never-returning plugin with ``TUMBLE_WORKERS=0`` (run in the main process) ->
    stopped at ``--time-limit 12`` by its timer; that plant FAILED naming the limit, the others
    compared, exit 1."""
    proc, out, took = _validate(site, tmp_path, "hang", "--time-limit", "12", in_process=True)
    _fails_alone(proc, out, "Hang", "time limit of 12 s")
    assert took < 60, f"took {took:.0f} s"


def test_a_plugin_has_a_default_time_limit_and_a_built_in_has_none():
    """No ``--time-limit`` given -> a plugin's run still has a finite limit (the one docs/cli.md
    and docs/plugins.md state), a built-in plant's none; a given limit applies to every plant;
    a zero, negative, NaN or infinite one is a ValueError naming ``time_limit``."""
    from validation.validate import check_time_limit, plant_time_limit

    limit = plant_time_limit("someplugin")
    assert limit is not None and 0 < limit < math.inf
    for doc in ("cli.md", "plugins.md"):
        assert f"{limit:g} s" in (ROOT / "docs" / doc).read_text(), doc
    assert all(plant_time_limit(e) is None for e in ("analytic", "mujoco", "pinocchio"))
    assert plant_time_limit("analytic", 3.0) == plant_time_limit("someplugin", 3.0) == 3.0
    for bad in (0, -1.0, math.nan, math.inf, True, "5"):
        with pytest.raises(ValueError, match=r"^time_limit: .*got"):
            check_time_limit(bad)


def test_a_bad_time_limit_on_the_command_line_is_one_line_and_exit_2(tmp_path):
    """``--time-limit 0`` -> one line naming ``--time-limit``, exit 2, nothing written."""
    proc = subprocess.run(
        [sys.executable, "-m", "validation", "validate", SCENE, "--time-limit", "0",
         "--out", str(tmp_path / "v")],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "--time-limit" in proc.stderr
    assert not (tmp_path / "v").exists()


@pytest.mark.parametrize(
    ("hostile", "label", "words"),
    [
        ("badshape", "BadShape", ("plant contract", "q has shape", "(21, 3)")),
        ("returnsnone", "ReturnsNone", ("plant contract", "NoneType")),
        ("checkraises", "CheckRaises", ("check_scene raised RuntimeError", "blew up")),
        ("describeraises", "DescribeRaises", ("describe raised RuntimeError", "blew up")),
    ],
)
def test_plugin_garbage_fails_that_plant_alone(site, tmp_path, hostile, label, words):
    """A plugin returning ``q`` with 3 columns, returning None, whose ``check_scene`` raises
    RuntimeError or whose ``describe`` raises -> that plant FAILED in one line naming it and
    what it did (no traceback, no error from deep in the comparison), the others compared,
    exit 1."""
    proc, out, _ = _validate(site, tmp_path, hostile)
    _fails_alone(proc, out, label, *words)
