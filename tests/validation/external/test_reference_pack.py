"""Reference packs (validation/external/reference_pack.py, ``tumble reference``): written and read
back; the reference agrees with an independent run of the plant; judging against a pack runs no
plant and exits 0 or 1 on the verdict; a pack of another scene, a tampered or linked file, plants
beside a pack are each refused in one line."""

from __future__ import annotations

import dataclasses
import json
import os

import numpy as np
import pytest

from analytic.scene import load_scene
from analytic.scene.dump import scene_to_dict, scene_to_toml
from mj_bridge.plants import plant
from tests.support.guards import forbid_plant_runs
from validation.cli import EXIT_FAILED, main
from validation.compare.checks import compare
from validation.compare.thresholds import thresholds_for
from validation.external.columns import OPTIONAL_GROUPS
from validation.external.judge import judge
from validation.external.reference_pack import ACCURACY_MARGIN, read_pack
from validation.external.write import write_trajectory


def _scene(t_end: float = 1.0):
    sc = load_scene("paper_example1_controlled")
    return sc.replace(output=sc.output.with_t_end(t_end))


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    """``(scene, pack directory)``: the controlled Example 1 over 1 s, written by the command."""
    root = tmp_path_factory.mktemp("pack")
    sc = _scene()
    (root / "scene.toml").write_text(scene_to_toml(sc))
    assert main(["reference", str(root / "scene.toml"), "--out", str(root / "pack")]) == 0
    return sc, root / "pack"


def test_the_pack_holds_the_scene_and_a_reference_within_its_stated_error(pack):
    sc, d = pack
    assert sorted(p.name for p in d.iterdir()) == [
        "README.md",
        "manifest.json",
        "reference.csv",
        "reference.json",
        "scene.toml",
    ]
    assert scene_to_dict(load_scene(d / "scene.toml")) == scene_to_dict(sc)
    ref = read_pack(d, sc)
    assert ref.present == OPTIONAL_GROUPS  # every column: motion, velocities, tau, F, work
    record = json.loads((d / "reference.json").read_text())
    assert record["accurate_enough"] is True
    # the independent check of the stated error: the plant at the scene's own settings (rtol
    # 1e-12, ten times looser than the reference) is within its thresholds of the reference, and
    # the reference's stated estimate is within the margin of every threshold
    own = compare(ref.trajectory, plant("analytic").simulate(sc), sc)
    th = thresholds_for(sc)
    for a in record["accuracy"]:
        assert a["estimate"] is None or a["estimate"] <= ACCURACY_MARGIN * th[a["quantity"]].value
        c = next(c for c in own.checks if c.name == a["quantity"])
        assert c.passed, c
    # the controller's outputs along it are the plant's (torque and rod forces columns)
    tr = plant("analytic").simulate(sc, plant("analytic").default_settings(sc))
    scale = np.max(np.abs(tr.torque))
    assert np.max(np.abs(ref.trajectory.torque - tr.torque)) <= th["control_torque"].value * scale


def test_the_readme_states_controller_errors_and_thresholds(pack):
    sc, d = pack
    text = (d / "README.md").read_text()
    for eq in ("Eq. 89", "Eq. 76", "Eq. 75", "Eq. 81", "Eq. 84", "Eq. 78", "Eq. B10"):
        assert eq in text, eq
    for name, th in thresholds_for(sc).items():
        assert f"| {name} |" in text and f"{th.value:g}" in text, name
    assert "self-convergence" in text and "rtol 1e-14" in text


def test_judging_against_the_pack_runs_no_plant_and_exits_on_the_verdict(
    pack, tmp_path, monkeypatch, capsys
):
    sc, d = pack
    good = tmp_path / "good.csv"
    write_trajectory(good, sc, plant("mujoco").simulate(sc))
    inertia = np.array(sc.body.inertia, float)
    inertia[0] *= 1.0 + 1e-4
    other = sc.replace(body=dataclasses.replace(sc.body, inertia=inertia))
    bad = tmp_path / "bad.csv"
    write_trajectory(bad, other, plant("analytic").simulate(other))
    forbid_plant_runs(monkeypatch)
    scene = str(d / "scene.toml")
    args = ["judge", scene, "--reference", str(d)]
    assert main([*args, "--trajectory", str(good), "--out", str(tmp_path / "a")]) == 0
    assert "PASS: " in capsys.readouterr().out
    assert main([*args, "--trajectory", str(bad), "--out", str(tmp_path / "b")]) == EXIT_FAILED
    out = capsys.readouterr().out
    assert "FAIL: " in out and "bad_vs_reference.control_torque" in out
    record = json.loads((tmp_path / "b" / "report.json").read_text())
    assert [p["engine"] for p in record["plants"]] == ["reference", "bad"]


def test_a_pack_of_another_scene_is_refused(pack, tmp_path):
    sc, d = pack
    with pytest.raises(ValueError, match=r"its reference covers 0-1 s, shorter than the 0-2 s"):
        read_pack(d, _scene(t_end=2.0))
    inertia = np.array(sc.body.inertia, float) * 1.001
    other = sc.replace(body=dataclasses.replace(sc.body, inertia=inertia))
    with pytest.raises(ValueError, match=r"its scene is not the scene .*\(body\.inertia"):
        read_pack(d, other)
    with pytest.raises(ValueError, match="plants: a reference pack is judged against"):
        judge(sc, tmp_path / "x.csv", reference=d, plants="analytic")


def test_a_tampered_or_linked_pack_file_is_refused(pack, tmp_path):
    sc, d = pack
    copy = tmp_path / "copy"
    copy.mkdir()
    for name in ("scene.toml", "reference.json"):
        (copy / name).write_bytes((d / name).read_bytes())
    text = (d / "reference.csv").read_text().splitlines(keepends=True)
    row = text[5].split(",")
    row[1] = repr(float(row[1]) + 1e-3)
    (copy / "reference.csv").write_text("".join([*text[:5], ",".join(row), *text[6:]]))
    with pytest.raises(ValueError, match=r"reference\.csv is not the file reference\.json records"):
        read_pack(copy, sc)
    os.unlink(copy / "reference.csv")
    os.symlink(d / "reference.csv", copy / "reference.csv")
    with pytest.raises(ValueError, match=r"reference\.csv is not a regular file"):
        read_pack(copy, sc)


def test_reference_t_end_writes_a_pack_of_that_horizon_and_refuses_one_off_the_grid(
    pack, tmp_path, capsys
):
    """``tumble reference --t-end 0.2`` of the 1 s scene: a pack whose scene, record and CSV hold
    0-0.2 s (21 samples), the CSV's rows the first 21 of the 1 s pack's to the pack's stated
    error; a --t-end beyond the scene or off its grid is one line and exit 2, nothing written."""
    sc, whole = pack
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_to_toml(sc))
    out = tmp_path / "short"
    assert main(["reference", str(scene), "--t-end", "0.2", "--out", str(out)]) == 0
    record = json.loads((out / "reference.json").read_text())
    assert record["t_end"] == 0.2 and record["samples"] == 21
    assert load_scene(out / "scene.toml").output.t_end == 0.2
    short = read_pack(out, _scene(0.2)).trajectory
    longer = read_pack(whole, _scene(0.2)).trajectory
    np.testing.assert_array_equal(short.t, longer.t)
    bound = ACCURACY_MARGIN * thresholds_for(sc)["position_C"].value
    assert np.max(np.abs(short.q[:, :3] - longer.q[:, :3])) <= bound
    capsys.readouterr()
    for t_end, said in (("2", "not in (0, 1] s"), ("0.205", "not on the output grid")):
        bad = tmp_path / f"bad_{t_end}"
        assert main(["reference", str(scene), "--t-end", t_end, "--out", str(bad)]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and said in err[0] and "--t-end" in err[0], err
        assert not bad.exists()
