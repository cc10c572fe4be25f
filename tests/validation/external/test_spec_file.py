"""The ``[judge]`` table of a test_*.toml (validation/external/spec_file.py) and the pytest plugin's
judge form (validation/testing/pytest_plugin.py, JudgeFile): paths stay inside the TOML's
directory; the judge's checks are the items, a check the file cannot support skipped as not
judged."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from analytic.scene import load_scene
from analytic.scene.dump import scene_to_toml
from mj_bridge.plants import plant
from validation.external import ColumnGroup
from validation.external.columns import OPTIONAL_GROUPS
from validation.external.spec_file import parse_spec
from validation.external.write import write_trajectory
from validation.scenes import builtin_names

BUILTIN = builtin_names()


def _spec(text: str, base: Path):
    return parse_spec(text.encode(), base, BUILTIN)


def test_a_table_with_relative_paths_inside_its_directory(tmp_path):
    (tmp_path / "runs").mkdir()
    spec = _spec(
        '[judge]\nscene = "paper_example1"\ntrajectory = "runs/a.csv"\nlabel = "mine"\n', tmp_path
    )
    assert spec.scene == "paper_example1"  # a built-in name is not a path
    assert spec.trajectory == tmp_path / "runs" / "a.csv"
    assert spec.label == "mine" and spec.plants is None and spec.reference is None
    spec = _spec('[judge]\nscene = "s.toml"\ntrajectory = "a.csv"\nreference = "pack"\n', tmp_path)
    assert spec.scene == tmp_path / "s.toml" and spec.reference == tmp_path / "pack"
    assert spec.t_end is None and spec.up_to_file_end is False
    spec = _spec(
        '[judge]\nscene = "s.toml"\ntrajectory = "a.csv"\nt_end = 2\nup_to_file_end = true\n',
        tmp_path,
    )
    assert spec.t_end == 2.0 and spec.up_to_file_end is True


@pytest.mark.parametrize(
    ("body", "said"),
    [
        ('trajectory = "/etc/passwd"', "judge.trajectory: '/etc/passwd' must be relative"),
        ('trajectory = "C:\\\\x.csv"', "must be relative"),
        ('trajectory = "../x.csv"', "judge.trajectory: '../x.csv' must not contain '..'"),
        ('trajectory = "a/../../x.csv"', "must not contain '..'"),
        ("trajectory = 3", "judge.trajectory: must be a non-empty path string (got 3)"),
        ('trajectory = "a.csv"\nlabel = 1', "judge.label: must be a string"),
        ('trajectory = "a.csv"\ncommand = "rm -rf"', "judge.command: unknown key"),
        ('label = "x"', "judge.trajectory: missing"),
        ('trajectory = "a.csv"\nt_end = "2"', "judge.t_end: must be a positive number of seconds"),
        ('trajectory = "a.csv"\nt_end = -1.0', "judge.t_end: must be a positive number of seconds"),
        ('trajectory = "a.csv"\nt_end = true', "judge.t_end: must be a positive number of seconds"),
        ('trajectory = "a.csv"\nup_to_file_end = 1', "judge.up_to_file_end: must be true or false"),
    ],
)
def test_bad_tables_are_refused_naming_the_key(tmp_path, body, said):
    with pytest.raises(ValueError, match=re.escape(said)):
        _spec(f'[judge]\nscene = "paper_example1"\n{body}\n', tmp_path)


def test_other_tables_and_links_out_are_refused(tmp_path):
    with pytest.raises(ValueError, match=re.escape("scene: a judge file holds only a [judge]")):
        _spec('[scene]\nname = "x"\n[judge]\nscene = "a"\ntrajectory = "b.csv"\n', tmp_path)
    outside = tmp_path / "outside.csv"
    outside.write_text("t\n")
    inner = tmp_path / "inner"
    inner.mkdir()
    os.symlink(outside, inner / "link.csv")
    with pytest.raises(ValueError, match="resolves outside the TOML file's directory"):
        _spec('[judge]\nscene = "paper_example1"\ntrajectory = "link.csv"\n', inner)


def test_the_plugin_makes_the_judges_checks_items(pytester: pytest.Pytester) -> None:
    sc = load_scene("paper_example1_controlled")
    sc = sc.replace(output=sc.output.with_t_end(0.05))
    (pytester.path / "short.toml").write_text(scene_to_toml(sc))
    groups = OPTIONAL_GROUPS - {ColumnGroup.ANGULAR_VELOCITY}
    write_trajectory(pytester.path / "mine.csv", sc, plant("mujoco").simulate(sc), groups=groups)
    pytester.makefile(
        ".toml",
        test_mine='[judge]\nscene = "short.toml"\ntrajectory = "mine.csv"\nplants = "analytic"\n',
        test_escape='[judge]\nscene = "short.toml"\ntrajectory = "../mine.csv"\n',
    )
    r = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-rA", "--continue-on-collection-errors")
    text = r.stdout.str()
    assert re.search(r"PASSED test_mine\.toml::analytic_vs_mine\.attitude", text)
    assert re.search(r"PASSED test_mine\.toml::run", text)
    assert re.search(
        r"SKIPPED .*mine\.tracking_omega: not applicable \(not judged: no omega columns\)", text
    )
    assert "test_escape.toml: judge.trajectory: '../mine.csv' must not contain '..'" in text
    outcome = r.parseoutcomes()
    assert outcome["skipped"] == 5 and outcome["errors"] == 1 and "failed" not in outcome
