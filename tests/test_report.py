"""report.md / report.json / figures: verdict first, planted failures reported exactly, atomic."""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np
import pytest

from analytic.scene import load_scene
from analytic.simulate import simulate
from analytic.trajectory import Engine
from validation import report as report_mod
from validation.compare import compare
from validation.report import versions, write_atomic, write_report

SCENES = Path(__file__).resolve().parents[1] / "validation" / "scenes"
T_END = 0.3
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENES / "paper_example1_controlled.toml")


@pytest.fixture(scope="module")
def traj(scene):
    return simulate(scene, t_end=T_END, rtol=1e-10)


@pytest.fixture(scope="module")
def planted(scene, traj, tmp_path_factory):
    """A 'MuJoCo' copy with C displaced by exactly 5e-5 m: one check must fail with that value."""
    q = traj.q.copy()
    q[:, :3] += np.array([0.0, 3e-5, 4e-5])
    other = dataclasses.replace(traj, engine=Engine.MUJOCO, q=q)
    cmp = compare(traj, other, scene, t_end=T_END)
    out = tmp_path_factory.mktemp("planted")
    files = write_report(
        out, cmp, [traj, other], {"scene": {"name": scene.name}, "versions": versions()}
    )
    return out, files


def test_planted_offset_fails_with_its_exact_value(planted):
    out, _ = planted
    doc = json.loads((out / "report.json").read_text())
    assert doc["verdict"] == "FAILED" and doc["passed"] is False
    by = {(c["subject"], c["name"]): c for c in doc["checks"]}
    c = by[("analytic vs mujoco", "position_C")]
    assert c["value"] == pytest.approx(5e-5, rel=1e-9)
    assert c["verdict"] == "FAIL" and c["passed"] is False and c["reason"]
    assert c["threshold"] == 1e-6 and c["unit"] == "m"
    # every other comparison check passes (the copy is otherwise identical)
    others = [v for k, v in by.items() if k != ("analytic vs mujoco", "position_C")]
    assert all(v["passed"] for v in others)
    assert doc["summaries"]["diff.position_C"]["max"] == pytest.approx(5e-5, rel=1e-9)
    assert doc["run"]["versions"]["numpy"] == np.__version__


def test_markdown_puts_the_verdict_first_and_embeds_the_figures(planted):
    out, files = planted
    md = (out / "report.md").read_text()
    first = md.splitlines()[0]
    assert first.startswith("# ") and "FAILED" in first
    head = md.split("## Checks")[0]
    assert "position_C" in head  # the failed check is named before the tables
    for f in files.figures:
        assert f"]({f.name})" in md
        assert f.read_bytes().startswith(PNG)
    assert {f.name for f in files.figures} == {
        "errors.png",
        "tracking.png",
        "invariants.png",
        "control.png",
    }


def test_self_comparison_report_passes(scene, traj, tmp_path):
    other = dataclasses.replace(traj, engine=Engine.MUJOCO)
    cmp = compare(traj, other, scene, t_end=T_END)
    write_report(tmp_path, cmp, [traj, other], {"scene": {"name": scene.name}})
    doc = json.loads((tmp_path / "report.json").read_text())
    assert doc["verdict"] == "PASSED" and all(c["passed"] for c in doc["checks"])
    assert (tmp_path / "report.md").read_text().splitlines()[0].endswith("PASSED")


def test_a_failed_run_writes_what_it_has_marked_failed(scene, traj, tmp_path):
    write_report(tmp_path, None, [traj], {"scene": {"name": scene.name}}, failure="MuJoCo exploded")
    doc = json.loads((tmp_path / "report.json").read_text())
    assert doc["verdict"] == "FAILED" and doc["failure"] == "MuJoCo exploded"
    md = (tmp_path / "report.md").read_text()
    assert "FAILED" in md.splitlines()[0] and "MuJoCo exploded" in md
    assert (tmp_path / "control.png").read_bytes().startswith(PNG)


def test_writes_are_atomic(tmp_path, monkeypatch):
    target = tmp_path / "report.json"
    write_atomic(target, "old")

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(report_mod.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        write_atomic(target, "new")
    monkeypatch.undo()
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["report.json"]  # no temporary file left behind
