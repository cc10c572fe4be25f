"""report.md / report.json / figures: verdict first, planted failures reported exactly, atomic."""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.scene import load_scene
from analytic.simulate import simulate
from analytic.trajectory import Engine, RunStatus
from validation.compare.checks import Check, Subject, compare
from validation.compare.summary import check_sentence, summary_table
from validation.report.report import versions, write_atomic, write_report
from validation.runs import atomic as atomic_mod

SCENES = Path(__file__).resolve().parents[3] / "analytic" / "scenes"
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


def test_planted_offset_fails_with_its_exact_value(planted, traj, scene):
    out, _ = planted
    other_q = traj.q.copy()
    other_q[:, :3] += np.array([0.0, 3e-5, 4e-5])
    other = dataclasses.replace(traj, q=other_q)
    doc = json.loads((out / "report.json").read_text())
    assert doc["verdict"] == "FAILED" and doc["passed"] is False
    by = {(c["subject"], c["name"]): c for c in doc["checks"]}
    c = by[("analytic vs mujoco", "position_C")]
    assert c["value"] == pytest.approx(5e-5, rel=1e-9)
    assert c["verdict"] == "FAIL" and c["passed"] is False and c["reason"]
    # the bound: 1e-6 m plus rtol × C's largest departure from its uniformly accelerated motion
    # R(0) + Ṙ(0) t + ½ g t² over the two runs (a few m here: the absolute part decides, and the
    # report says so)
    g = np.asarray(scene.gravity, float) if scene.has(Effect.GRAVITY) else np.zeros(3)
    t = (traj.t - traj.t[0])[:, None]

    def departure(q):
        ballistic = q[0, :3] + traj.qdot[0, :3] * t + 0.5 * g * t * t
        return np.linalg.norm(q[:, :3] - ballistic, axis=1).max()

    size = max(departure(traj.q), departure(other.q))
    assert c["absolute_part"] == 1e-6 and c["unit"] == "m" and c["decided_by"] == "absolute"
    assert c["magnitude"] == pytest.approx(size, rel=1e-12)
    assert c["relative_part"] == pytest.approx(1e-7 * size, rel=1e-12)
    assert c["threshold"] == pytest.approx(1e-6 + 1e-7 * size, rel=1e-12)
    assert doc["thresholds"]["position_C"]["rtol"] == 1e-7
    # every other comparison check passes (the copy is otherwise identical)
    others = [v for k, v in by.items() if k != ("analytic vs mujoco", "position_C")]
    assert all(v["passed"] for v in others)
    assert doc["summaries"]["diff.position_C"]["max_abs"] == pytest.approx(5e-5, rel=1e-9)
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


# ----------------------------------------------------------------------------------------------
# Numbers that do not mislead
# ----------------------------------------------------------------------------------------------


def test_report_states_the_largest_rod_force_magnitude(scene, traj, tmp_path):
    """The rod force on mass 2 made negative throughout: report.json and report.md give its
    largest |F_2|, not its largest (negative) value."""
    F = traj.rod_forces.copy()
    F[:, 1] = -np.abs(F[:, 1]) - 1.0
    tr = dataclasses.replace(traj, rod_forces=F)
    cmp = compare(tr, None, scene, t_end=T_END)
    write_report(tmp_path, cmp, [tr], {"scene": {"name": scene.name}})
    doc = json.loads((tmp_path / "report.json").read_text())
    s = doc["summaries"]["analytic.rod_force_2"]
    peak = float(np.max(np.abs(F[:, 1])))
    assert s["max_abs"] == pytest.approx(peak, rel=1e-12) and s["max_abs"] > 0 > np.max(F[:, 1])
    assert s["t_max_abs"] == pytest.approx(traj.t[np.argmax(np.abs(F[:, 1]))])
    assert "max" not in s  # one definition, named
    md = (tmp_path / "report.md").read_text()
    row = next(r for r in md.splitlines() if r.startswith("| rod force on mass 2 |"))
    assert float(row.split("|")[3]) == pytest.approx(peak, rel=1e-3)


def test_simulate_summary_names_the_torque_norm(traj):
    """``tumble simulate`` prints max ‖τ‖₂ (the norm the report uses), not the largest component."""
    line = next(x for x in summary_table(traj).splitlines() if "control:" in x)
    norm = float(np.max(np.linalg.norm(traj.torque, axis=1)))
    component = float(np.max(np.abs(traj.torque)))
    assert norm > component * (1 + 1e-3)  # they differ here, so the test can tell them apart
    printed = float(line.split("max ‖τ‖₂")[1].split()[0])
    assert printed == pytest.approx(norm, rel=1e-3)


def test_an_interrupted_run_says_where_it_stopped(scene, tmp_path):
    """Ctrl-C at 0.15 s of a 0.3 s run: 'stopped at 0.15 s of 0.3 s', not '1.500e-01 > 3.000e-01'."""

    def ctrl_c(t):
        if t >= 0.15:
            raise KeyboardInterrupt

    short = simulate(scene, t_end=T_END, rtol=1e-8, progress=ctrl_c)
    assert short.status is RunStatus.INTERRUPTED
    reached = float(short.t[-1])
    cmp = compare(short, None, scene, t_end=T_END)
    c = cmp.check("analytic.completed")
    assert not c.passed
    text = check_sentence(c)
    assert text.startswith(f"analytic: stopped at {reached:.3g} s of {T_END:g} s (")
    write_report(tmp_path, cmp, [short], {"scene": {"name": scene.name}})
    assert f"stopped at {reached:.3g} s of {T_END:g} s" in (tmp_path / "report.md").read_text()
    planted = Check("completed", Subject.ANALYTIC, 9.37, 20.0, "s", False, "interrupted")
    assert check_sentence(planted) == "analytic: stopped at 9.37 s of 20 s (interrupted)"


@pytest.fixture(scope="module")
def far(scene, traj, tmp_path_factory):
    """Both runs with every mass 10 km along the rod (|p_i| ≈ 1e4 m, so the rod positions'
    bound has a relative part 1e-7 × 1e4 = 1e-3 m, a thousand times its absolute part), the
    second's masses displaced by 5e-4 m (passes by the relative part) and its C by 5e-6 m
    (fails: C's departure from its uniformly accelerated motion is a few m, so the absolute
    part, 1e-6 m, decides)."""
    qa = traj.q.copy()
    qa[:, 7:] += 1e4
    qb = qa.copy()
    qb[:, 7:] += 5e-4
    qb[:, :3] += np.array([3e-6, 4e-6, 0.0])  # 5e-6 m
    a = dataclasses.replace(traj, q=qa)
    b = dataclasses.replace(traj, engine=Engine.MUJOCO, q=qb)
    cmp = compare(a, b, scene, t_end=T_END)
    out = tmp_path_factory.mktemp("far")
    write_report(out, cmp, [a, b], {"scene": {"name": scene.name}, "versions": versions()})
    return out, cmp, qa, qb


def test_report_json_names_the_relative_part_when_it_decides(far):
    out, _, qa, qb = far
    doc = json.loads((out / "report.json").read_text())
    by = {(c["subject"], c["name"]): c for c in doc["checks"]}
    c = by[("analytic vs mujoco", "rod_positions")]
    size = max(np.abs(q[:, 7:]).max() for q in (qa, qb))
    assert size == pytest.approx(1e4, rel=1e-2)  # 1e4 m and the masses' own travel
    assert c["passed"] and c["value"] == pytest.approx(5e-4, rel=1e-6)
    assert c["value"] > c["absolute_part"] == 1e-6  # the absolute part alone would fail it
    assert c["decided_by"] == "relative" and c["magnitude"] == pytest.approx(size, rel=1e-12)
    assert c["threshold"] == pytest.approx(1e-6 + 1e-7 * size, rel=1e-12)
    pos = by[("analytic vs mujoco", "position_C")]
    assert not pos["passed"] and pos["value"] == pytest.approx(5e-6, rel=1e-6)
    assert pos["decided_by"] == "absolute" and pos["magnitude"] < 10.0


def test_markdown_and_text_state_the_deciding_part(far):
    out, cmp, _, _ = far
    md = (out / "report.md").read_text()
    row = next(line for line in md.splitlines() if line.startswith("| rod_positions |"))
    assert "| relative (1e-07 × 1e+04) |" in row
    att = next(line for line in md.splitlines() if line.startswith("| attitude |"))
    assert "relative" not in att and "absolute" not in att  # no relative part
    ch = cmp.check("rod_positions")
    text = check_sentence(ch, reason=False)
    assert text.startswith(f"rod_positions = 5.000e-04 m ≤ threshold {ch.threshold:.3e} m")
    assert (
        f"(decided by the relative part 1e-07 × scale {ch.magnitude:.3e} m; absolute part "
        "1.000e-06 m)" in text
    )
    # a check the absolute part decides reads as before: the velocity of C, whose departure
    # from its uniformly accelerated motion over 0.3 s makes a relative part under 1e-5 m/s
    v = cmp.check("velocity_C")
    assert v.magnitude < 100 and v.decided_by == "absolute"
    assert check_sentence(v, reason=False).endswith(f"threshold {v.threshold:.3e} m/s")
    vrow = next(line for line in md.splitlines() if line.startswith("| velocity_C |"))
    assert "| absolute |" in vrow


def test_writes_are_atomic(tmp_path, monkeypatch):
    target = tmp_path / "report.json"
    write_atomic(target, "old")

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(atomic_mod.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        write_atomic(target, "new")
    monkeypatch.undo()
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["report.json"]  # no temporary file left behind


# ----------------------------------------------------------------------------------------------
# run_validation end to end (short horizon)
# ----------------------------------------------------------------------------------------------


def test_run_validation_with_both_plants(tmp_path):
    from validation.validate import run_validation

    res = run_validation("paper_example1_controlled", tmp_path, t_end=0.1, plants="analytic,mujoco")
    assert dataclasses.is_dataclass(res)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.passed = False  # type: ignore[misc]
    doc = json.loads((tmp_path / "report.json").read_text())
    assert doc["passed"] is res.passed
    assert {p["engine"] for p in doc["plants"]} == {"analytic", "mujoco"}
    assert len(doc["checks"]) == len(res.checks) > 10
    assert doc["run"]["mujoco_settings"]["integrator"] == "RK4"
    assert set(doc["run"]["wall_times_s"]) >= {"analytic", "mujoco", "compare", "recording"}
    for name in ("report.md", "report.json", "run.rrd", "errors.png", "control.png"):
        assert (tmp_path / name).exists(), name
    # the same controller in both plants: they agree to the default thresholds over 0.1 s
    assert res.passed, [c.label for c in res.failed_checks]


def test_run_validation_without_the_mujoco_twin_is_failed_not_crashed(tmp_path, monkeypatch):
    from mj_bridge.plants import MujocoPlant
    from validation import validate

    def missing(*args, **kwargs):
        raise ImportError("the MuJoCo twin (mj_bridge) is not available: planted")

    monkeypatch.setattr(MujocoPlant, "_simulate", missing)
    res = validate.run_validation(
        "paper_example1_controlled", tmp_path, t_end=0.1, plants="analytic,mujoco"
    )
    assert not res.passed and "mj_bridge" in res.failure
    md = (tmp_path / "report.md").read_text()
    assert "FAILED" in md.splitlines()[0] and "mj_bridge" in md
    assert json.loads((tmp_path / "report.json").read_text())["verdict"] == "FAILED"
    # the analytic plant's own checks are still there
    assert any(c.label == "analytic.energy" for c in res.checks)


def test_progress_accepts_both_callback_forms():
    from validation.validate import _stage_progress

    seen = []
    _stage_progress(lambda stage, t: seen.append((stage, t)), "mujoco")(1.5)
    _stage_progress(lambda t: seen.append(t), "analytic")(0.5)
    assert seen == [("mujoco", 1.5), 0.5]
    assert _stage_progress(lambda t: None, "mujoco") is None
    assert _stage_progress(None, "analytic") is None
