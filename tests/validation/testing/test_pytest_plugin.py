"""The pytest plugin (validation/testing/pytest_plugin.py) and validation.assert_agree.

Scene files are run inside a nested pytest (the ``pytester`` fixture) on short horizons: the
paper's controlled Example 1 cut to 0.05 s, on the analytic plant and MuJoCo.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import validation
from validation.scenes import SCENES_DIR
from validation.testing import pytest_plugin

TWO = ("--tumble-plants", "analytic,mujoco", "-p", "no:cacheprovider")


def short_scene(t_end: float = 0.05, extra: str = "") -> str:
    text = (SCENES_DIR / "paper_example1_controlled.toml").read_text()
    text, k = re.subn(r"(?m)^t_end = .*$", f"t_end = {t_end}", text)
    assert k == 1
    return text + extra


TIGHT = "\n[thresholds]\nposition_C = 1e-15\n"


@pytest.fixture(scope="module", autouse=True)
def _modules_loaded(tmp_path_factory: pytest.TempPathFactory) -> None:
    """One run in this process first: pytester's in-process runs drop the modules they import
    (numba cannot be imported twice in one process), so every plant's modules must be loaded
    before the first nested pytest."""
    scene = tmp_path_factory.mktemp("warm") / "s.toml"
    scene.write_text(short_scene(t_end=0.01))
    validation.assert_agree(scene, t_end=0.01)


@pytest.fixture
def scenes(pytester: pytest.Pytester) -> pytest.Pytester:
    """A directory with a passing scene, a tightened one, a broken one and other .toml files."""
    pytester.makefile(".toml", test_ok=short_scene())
    pytester.makefile(".toml", test_tight=short_scene(extra=TIGHT))
    broken = short_scene().replace("mass = 4.597e5", "mass = -1.0", 1)
    pytester.makefile(".toml", test_broken=broken)
    pytester.makefile(".toml", test_settings="[tool.something]\nx = 1\n")  # no [scene] table
    pytester.makefile(".toml", settings=short_scene())  # a scene, but not named test_*.toml
    return pytester


def outcomes(result: pytest.RunResult) -> dict[str, str]:
    """nodeid -> PASSED / FAILED / ERROR from the ``-rA`` summary."""
    out = {}
    for line in result.outlines:
        m = re.match(r"^(PASSED|FAILED|ERROR) (\S+)", line)
        if m:
            out[m.group(2)] = m.group(1)
    return out


def test_scene_files_pass_fail_and_error(scenes: pytest.Pytester) -> None:
    pytest_plugin.RUNS.clear()
    r = scenes.runpytest(*TWO, "-rA", "--continue-on-collection-errors")
    got = outcomes(r)
    # every other .toml is left alone
    assert not [k for k in got if "settings" in k], got
    # the passing scene: every check passed, one item per check plus the run itself
    ok = {k: v for k, v in got.items() if k.startswith("test_ok.toml::")}
    assert set(ok.values()) == {"PASSED"}
    assert {"test_ok.toml::position_C", "test_ok.toml::mujoco.energy", "test_ok.toml::run"} <= set(
        ok
    )
    # the tightened check failed, the others of that scene passed
    tight = {k: v for k, v in got.items() if k.startswith("test_tight.toml::")}
    assert tight.pop("test_tight.toml::position_C") == "FAILED"
    assert set(tight.values()) == {"PASSED"}
    # the broken scene: one collection error naming the field
    assert got["test_broken.toml"] == "ERROR"
    r.assert_outcomes(passed=2 * len(ok) - 1, failed=1, errors=1)
    text = r.stdout.str()
    assert "test_broken.toml: body.mass: must be positive (got -1.0)" in text
    # the failure is the report's row: value, threshold, unit, time, reason, the plants' values
    block = text[text.index("test_tight.toml::position_C ___") :]
    m = re.search(r"position_C: (\S+) m > threshold 1e-15 m \(analytic vs mujoco\)", block)
    assert m and float(m.group(1)) > 1e-15
    assert re.search(r"worst at   t = \S+ s", block)
    assert "set by the scene (default 1e-06" in block
    assert re.search(r"analytic vs mujoco +position of C .* m  <- this check", block)
    assert "report: " in block
    # the plants ran once per scene
    assert len(pytest_plugin.RUNS) == 2


def test_k_selects_checks_and_plants_run_once_per_scene(scenes: pytest.Pytester) -> None:
    pytest_plugin.RUNS.clear()
    r = scenes.runpytest(*TWO, "-k", "position_C", "--ignore", "test_broken.toml")
    r.assert_outcomes(passed=1, failed=1)
    assert len(pytest_plugin.RUNS) == 2  # one run per scene file, each selected check reads it


def test_marker_deselects_every_scene_item(scenes: pytest.Pytester) -> None:
    scenes.makepyfile(test_plain="def test_plain():\n    pass\n")
    pytest_plugin.RUNS.clear()
    r = scenes.runpytest(*TWO, "-m", "not tumble", "--ignore", "test_broken.toml")
    r.assert_outcomes(passed=1, deselected=2 * 23)
    assert pytest_plugin.RUNS == []


def test_out_dir_and_ini_globs(pytester: pytest.Pytester, tmp_path: Path) -> None:
    pytester.makeini("[pytest]\ntumble_scenes = scenes/*.toml\n")
    (pytester.path / "scenes").mkdir()
    (pytester.path / "scenes" / "body.toml").write_text(short_scene())
    out = tmp_path / "artefacts"
    r = pytester.runpytest(*TWO, "--tumble-out", str(out), "-k", "position_C")
    r.assert_outcomes(passed=1)
    assert (out / "scenes_body" / "report.md").is_file()
    assert (out / "scenes_body" / "manifest.json").is_file()


def test_bad_plants_option_is_a_collection_error(pytester: pytest.Pytester) -> None:
    pytester.makefile(".toml", test_ok=short_scene())
    r = pytester.runpytest("--tumble-plants", "analytic")
    r.assert_outcomes(errors=1)
    assert "--tumble-plants: give at least two plants" in r.stdout.str()


def test_fixture_shares_the_run_of_collected_items(scenes: pytest.Pytester) -> None:
    scenes.makepyfile(
        test_fixture="""
        def test_uses_fixture(tumble_validation):
            res = tumble_validation("test_ok.toml")
            assert res.passed
            assert res.comparison.check("position_C").passed
        """
    )
    pytest_plugin.RUNS.clear()
    r = scenes.runpytest(*TWO, "--ignore", "test_broken.toml", "--ignore", "test_tight.toml")
    r.assert_outcomes(passed=23 + 1)
    assert len(pytest_plugin.RUNS) == 1


RUN_LOG_CONFTEST = """
import os
import validation.validate as vv

_real = vv.run_validation


def _logged(scene, *args, **kwargs):
    with open(os.environ["TUMBLE_RUN_LOG"], "a") as f:
        f.write(f"{os.getpid()} {scene}\\n")
    return _real(scene, *args, **kwargs)


vv.run_validation = _logged
"""


def test_xdist_results_equal_serial_and_scenes_run_once(
    scenes: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("xdist")
    args = (*TWO, "-rA", "--ignore", "test_broken.toml")
    pytest_plugin.RUNS.clear()
    serial = outcomes(scenes.runpytest(*args))
    assert len(serial) == 2 * 23 and len(pytest_plugin.RUNS) == 2
    scenes.makeconftest(RUN_LOG_CONFTEST)  # the workers log their runs
    log = scenes.path / "runs.log"
    monkeypatch.setenv("TUMBLE_RUN_LOG", str(log))
    for dist in ("loadgroup", "load"):  # load: a scene's items on both workers, run shared
        log.unlink(missing_ok=True)
        par = scenes.runpytest_subprocess(*args, "-n", "2", "--dist", dist)
        assert outcomes(par) == serial, dist
        runs = log.read_text().splitlines()
        scenes_run = [line.split(" ", 1)[1] for line in runs]
        assert sorted(scenes_run) == sorted(set(scenes_run)) and len(scenes_run) == 2, runs


def test_plugin_import_is_light() -> None:
    code = (
        "import sys, validation, validation.testing.pytest_plugin, validation.testing.agree; "
        "print(','.join(m for m in ('numpy', 'mujoco', 'numba', 'scipy', 'rerun') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_entry_point_registered() -> None:
    from importlib.metadata import entry_points

    eps = {e.name: e.value for e in entry_points(group="pytest11")}
    assert eps.get("tumble") == "validation.testing.pytest_plugin"


def test_public_names() -> None:
    for name in validation.__all__:
        assert getattr(validation, name) is not None


# ---- assert_agree --------------------------------------------------------------------------


def test_assert_agree_lists_the_failed_checks(tmp_path: Path) -> None:
    scene = tmp_path / "s.toml"
    scene.write_text(short_scene())
    with pytest.raises(AssertionError) as exc:
        validation.assert_agree(
            scene, plants="analytic,mujoco", position_C=1e-15, attitude={"value": 0, "reason": "x"}
        )
    msg = str(exc.value)
    assert msg.startswith("2 of 22 checks failed for scene 'paper_example1_controlled'")
    assert re.search(r"(?m)^  position_C +\S+ +1e-15 +m +\S+$", msg)
    assert re.search(r"(?m)^  attitude +\S+ +0 +rad +\S+$", msg)
    assert "position_C: " in msg and "reason     x (default 1e-06" in msg
    with pytest.raises(ValueError, match=r"thresholds\.positon_C: unknown threshold"):
        validation.assert_agree(scene, plants="analytic,mujoco", positon_C=1.0)


@pytest.mark.parametrize(
    "name",
    [
        "paper_example1",
        "paper_example1_controlled",
        "paper_example2",
        "paper_example2_controlled",
    ],
)
def test_assert_agree_passes_on_the_paper_examples(name: str) -> None:
    plants = "analytic,mujoco" if name != "paper_example1_controlled" else None
    res = validation.assert_agree(name, plants=plants, t_end=0.05)
    assert res.passed
    # the items the plugin names before a run are exactly the checks the run makes
    scene = validation.resolve_scene(name)
    chosen = tuple(c.subject.value for c in res.checks if c.name == "completed")
    assert pytest_plugin.expected_labels(scene, chosen) == [c.label for c in res.checks]


def test_pair_checks_are_the_compared_differences():
    from validation.compare.differences import Difference
    from validation.testing.agree import PAIR_CHECKS

    assert PAIR_CHECKS == tuple(d.value for d in Difference)


def test_a_check_that_does_not_apply_is_skipped_not_passed(pytester: pytest.Pytester) -> None:
    """An uncontrolled scene has no control torque to compare: its control checks are reported as
    skipped, "not applicable", never as passes."""
    text = (SCENES_DIR / "paper_example1.toml").read_text()
    text, k = re.subn(r"(?m)^t_end = .*$", "t_end = 0.05", text)
    assert k == 1
    pytester.makefile(".toml", test_free=text)
    result = pytester.runpytest(*TWO, "-rA")
    counts = result.parseoutcomes()
    assert counts.get("failed", 0) == 0 and counts.get("errors", 0) == 0 and counts["passed"] > 0
    skipped = [line for line in result.outlines if line.startswith("SKIPPED")]
    assert skipped and all("not applicable" in line for line in skipped)
    assert any("control_torque" in line for line in skipped)
