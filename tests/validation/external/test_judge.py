"""judge (validation/external/judge.py) and ``tumble judge``: a built-in plant's run written to a file
gets that plant's verdicts; a run of a scene with a perturbed inertia is named the outlier; columns
a file lacks make their checks "not judged", never passed; a bad file is one line and exit 2."""

from __future__ import annotations

import dataclasses
import importlib
import json
import math

import numpy as np
import pytest

import validation
from analytic.scene import load_scene
from mj_bridge.plants import installed_plants, plant
from tests.support import tolerances as tol
from tests.support.guards import forbid_plant_runs
from validation.cli import EXIT_USAGE, main
from validation.compare.referee import VerdictKind
from validation.external import ColumnGroup
from validation.external.columns import OPTIONAL_GROUPS
from validation.external.judge import judge, needed_groups, plant_label
from validation.external.write import trajectory_table, write_trajectory
from validation.validate import run_validation

PAIR = (
    "position_C",
    "attitude",
    "rod_positions",
    "velocity_C",
    "rod_velocities",
    "angular_velocity",
    "control_torque",
    "rod_forces",
)


def _scene(name: str = "paper_example1_controlled", t_end: float = 1.0):
    sc = load_scene(name)
    return sc.replace(output=sc.output.with_t_end(t_end))


@pytest.fixture(scope="module")
def scene():
    return _scene()


@pytest.fixture(scope="module")
def mujoco_file(scene, tmp_path_factory):
    """The MuJoCo plant's run of the scene (its own settings), written with the CSV writer."""
    path = tmp_path_factory.mktemp("files") / "mujoco_run.csv"
    write_trajectory(path, scene, plant("mujoco").simulate(scene))
    return path


def test_a_builtin_plants_file_gets_that_plants_verdicts(scene, mujoco_file, tmp_path):
    # the independent expectation: the same plants compared by run_validation
    expected = run_validation(
        scene, tmp_path / "validate", plants="analytic,mujoco", concurrent=False
    )
    res = judge(
        scene, mujoco_file, tmp_path / "judge", plants="analytic", label="ext", concurrent=False
    )
    got = {c.label: c for c in res.checks}
    assert res.passed is expected.passed is True
    for c in expected.checks:
        label = c.label.replace("mujoco", "ext")
        if c.label in PAIR:
            label = f"analytic_vs_ext.{c.label}"
        j = got.pop(label)
        assert j.state is c.state, label
        if c.applicable:
            frac = abs(j.value - c.value) / c.threshold
            assert frac <= tol.JUDGED_FILE_CHECK_FRACTION.value, (label, c.value, j.value)
    assert not got, f"checks judge made that validate did not: {sorted(got)}"


@pytest.mark.skipif("pinocchio" not in installed_plants(), reason="needs the Pinocchio referee")
def test_a_perturbed_inertia_makes_the_file_the_referees_outlier(scene, tmp_path):
    inertia = np.array(scene.body.inertia, float)
    inertia[0] *= 1.0 + 1e-4
    other = scene.replace(body=dataclasses.replace(scene.body, inertia=inertia))
    path = tmp_path / "perturbed.csv"
    write_trajectory(path, other, plant("analytic").simulate(other))
    res = judge(scene, path, tmp_path / "out", plants="analytic,pinocchio", concurrent=False)
    assert not res.passed
    outliers = {v.outlier for v in res.verdicts if v.kind is VerdictKind.OUTLIER}
    assert outliers == {"perturbed"}, [v.text for v in res.verdicts]
    failed = {c.label for c in res.failed_checks}
    assert failed and all("perturbed" in lab for lab in failed), failed


def test_a_file_without_omega_is_not_judged_on_what_needs_omega(scene, tmp_path):
    path = tmp_path / "no_omega.csv"
    groups = OPTIONAL_GROUPS - {ColumnGroup.ANGULAR_VELOCITY}
    write_trajectory(path, scene, plant("analytic").simulate(scene), groups=groups)
    res = judge(scene, path, tmp_path / "out", plants="analytic", concurrent=False)
    idle = {c.label: c for c in res.checks if not c.applicable}
    assert set(idle) == {
        "analytic_vs_no_omega.angular_velocity",
        "no_omega.tracking_omega",
        "no_omega.linear_momentum",
        "no_omega.angular_momentum",
        "no_omega.energy",
    }
    for c in idle.values():
        assert c.reason == "not judged: no omega columns" and math.isnan(c.value)
    judged = {c.label for c in res.checks if c.applicable}
    assert {"analytic_vs_no_omega.attitude", "no_omega.tracking_p", "no_omega.quat_norm"} <= judged
    assert res.passed  # every judged check passes: the file is the analytic plant's own run
    report = (res.out_dir / "report.md").read_text()
    assert "no_omega: not judged: no omega columns (" in report
    record = json.loads((res.out_dir / "report.json").read_text())
    (entry,) = record["run"]["judged_files"]
    assert entry["not_judged"] == ["not judged: no omega columns"]
    assert len(entry["sha256"]) == 64


def test_the_balances_need_the_work_columns_only_when_something_does_work():
    assert ColumnGroup.WORK in needed_groups("energy", _scene("paper_example1_controlled"))
    assert ColumnGroup.WORK not in needed_groups("energy", _scene("paper_example1"))
    assert needed_groups("attitude", _scene("paper_example1")) == ()


def test_labels():
    assert plant_label(None, "runs/My Engine.v2.csv") == "my_engine_v2"
    assert plant_label(None, "2024.csv") == "ext_2024"
    for bad in ("mujoco", "reference", "all"):
        with pytest.raises(ValueError, match="the name of a plant"):
            plant_label(bad, "x.csv")
    with pytest.raises(ValueError, match="label: 'A b' is not a plant name"):
        plant_label("A b", "x.csv")
    with pytest.raises(ValueError, match=r"label \(from the file name 'analytic.csv'\)"):
        plant_label(None, "analytic.csv")


def test_validation_judge_is_the_judge():
    """``validation.judge`` is the judge function, also once the wing's modules are loaded (the
    wing is ``validation.external``, so no package shadows the name)."""
    importlib.import_module("validation.external.read")
    from validation.external.judge import judge

    assert validation.judge is judge


def test_a_bad_file_exits_2_with_one_line_before_any_plant(scene, tmp_path, monkeypatch, capsys):
    tr = plant("analytic").simulate(_scene(t_end=0.05))
    forbid_plant_runs(monkeypatch)
    names, values = trajectory_table(tr, _scene(t_end=0.05))
    values[2, names.index("omega_y")] = math.nan
    path = tmp_path / "run.csv"
    text = ",".join(names) + "\n"
    text += "".join(",".join(repr(float(x)) for x in row) + "\n" for row in values)
    path.write_text(text.replace("nan", "NaN"))
    (tmp_path / "scene.toml").write_text(_toml(_scene(t_end=0.05)))
    out = tmp_path / "out"
    status = main(["judge", str(tmp_path / "scene.toml"), "--trajectory", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == EXIT_USAGE
    assert err.count("\n") == 1
    assert "data row 3 (line 4), column 'omega_y'" in err
    assert not (tmp_path / "out").exists()


def _toml(sc) -> str:
    from analytic.scene.dump import scene_to_toml

    return scene_to_toml(sc)


def test_cli_refusals_exit_2_before_any_plant(scene, mujoco_file, tmp_path, monkeypatch, capsys):
    """Exit 0 and 1 are tested against a reference pack (test_reference_pack.py), without plants."""
    forbid_plant_runs(monkeypatch)
    (tmp_path / "scene.toml").write_text(_toml(scene))
    args = ["judge", str(tmp_path / "scene.toml"), "--trajectory", str(mujoco_file)]
    cases = {
        "--label=mujoco": "label: 'mujoco' is the name of a plant",
        "--label=My-Engine": "label: 'My-Engine' is not a plant name",
        "--plants=nosuch": "plants: unknown plant 'nosuch'",
        f"--reference={tmp_path}": "no reference.json (not a reference pack",
    }
    for option, said in cases.items():
        assert main([*args, option, "--out", str(tmp_path / "out")]) == EXIT_USAGE, option
        err = capsys.readouterr().err
        assert said in err and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists()
