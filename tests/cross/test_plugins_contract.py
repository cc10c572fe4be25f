"""The plant contract as a plugin's author meets it (``docs/plugins.md``): the worked plugin of the
page, an engine of its own (``tests/support/plugin_newton``: Newton-Euler equations, not the
analytic plant's), installed from its own ``pyproject.toml`` and run by ``tumble validate``; its
deliberately wrong twin named the outlier; the page's code is the tested code; a plugin named in
the progress lines; ``--plants all`` leaving out a plugin that refuses the scene."""

from __future__ import annotations

import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mj_bridge.plants as plants_mod
from analytic.plant import AnalyticPlant
from analytic.scene import load_scene
from tests.support.plugins import install_project
from validation.preflight import LeftOut, plant_choice
from validation.runs.progress import StageProgress, plant_title

ROOT = Path(__file__).resolve().parents[2]
NEWTON = ROOT / "tests" / "support" / "plugin_newton"
MODULE = NEWTON / "tumble_plugin_newton.py"
DOC = ROOT / "docs" / "plugins.md"
TUMBLE = Path(sys.executable).parent / "tumble"
SCENE = "paper_example1_controlled"


def _newton():
    sys.path.insert(0, str(NEWTON))
    try:
        import tumble_plugin_newton
    finally:
        sys.path.remove(str(NEWTON))
    return tumble_plugin_newton


def _tumble(args, site: Path, cwd: Path) -> subprocess.CompletedProcess:
    """``tumble <args>`` in a subprocess that sees the plugin installed in ``site`` (and this
    checkout first, as the tests' own PYTHONPATH says)."""
    path = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([*path, str(site)]))
    return subprocess.run(
        [str(TUMBLE), *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=900
    )


def test_the_doc_shows_the_tested_plugin_verbatim():
    """The worked plugin in docs/plugins.md is the tested module, character for character, and
    its registration is the package's pyproject.toml table."""
    doc = DOC.read_text()
    blocks = re.findall(r"<!-- file: (\S+) -->\n```\w*\n(.*?)```\n", doc, flags=re.S)
    shown = dict(blocks)
    assert "tests/support/plugin_newton/tumble_plugin_newton.py" in shown
    for rel, text in shown.items():
        assert (ROOT / rel).read_text() == text, rel


def test_newton_plant_is_not_the_analytic_plant_and_agrees_with_it():
    """The worked plugin shares no integration with the analytic plant (its own state, its own
    equations, its own quadratures) and still lands on the analytic plant's motion: positions
    within 1e-9 m over 1 s of the controlled paper example (the two formulations differ by
    ~3e-11 m at rtol 1e-12), the momenta and energy balances on the same values; its slipped
    twin (Coriolis term dropped) is metres away."""
    mod = _newton()
    assert not issubclass(mod.NewtonEulerPlant, AnalyticPlant)
    sc = load_scene(SCENE)
    ref = AnalyticPlant().simulate(sc, t_end=1.0)
    tr = mod.NewtonEulerPlant().simulate(sc, t_end=1.0)
    assert tr.engine == "newton" and tr.status.value == "ok"
    np.testing.assert_array_equal(tr.t, sc.output.with_t_end(1.0).times())
    assert tr.info["formulation"] == "Newton-Euler"
    assert np.abs(tr.q[:, :3] - ref.q[:, :3]).max() < 1e-9
    assert np.abs(tr.q[:, 7:] - ref.q[:, 7:]).max() < 1e-9
    scale = np.abs(ref.invariants.energy).max()
    assert np.abs(tr.invariants.energy - ref.invariants.energy).max() < 1e-9 * scale
    wrong = mod.SlippedNewtonPlant().simulate(sc, t_end=1.0)
    assert np.abs(wrong.q[:, :3] - ref.q[:, :3]).max() > 1e-3


def test_newton_plant_tightens_down_to_the_public_floor():
    """``tightened`` divides the tolerances by TIGHTER_RTOL and stops at RTOL_FLOOR (public names
    of analytic.plant); ``check_scene`` refuses too many masses naming the field."""
    from analytic.plant import RTOL_FLOOR, TIGHTER_RTOL

    mod = _newton()
    pl = mod.NewtonEulerPlant()
    sc = load_scene(SCENE)
    tight = pl.tightened(sc, mod.NewtonSettings(rtol=1e-10, atol=1e-12))
    assert tight.rtol == pytest.approx(1e-10 / TIGHTER_RTOL) and tight.atol == pytest.approx(
        1e-12 / TIGHTER_RTOL
    )
    assert pl.tightened(sc, mod.NewtonSettings(rtol=RTOL_FLOOR)) is None
    with pytest.raises(ValueError, match="rtol"):
        mod.NewtonSettings(rtol=-1.0)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    return install_project(NEWTON, tmp_path_factory.mktemp("newton") / "site")


def test_tumble_validate_with_the_newton_plugin_passes(site, tmp_path):
    """``tumble validate --plants analytic,newton`` with the package installed -> exit 0, every
    check passes (positions within the default thresholds), the progress line names the plugin
    with its label."""
    out = tmp_path / "out"
    res = _tumble(
        ["validate", SCENE, "--t-end", "0.5", "--plants", "analytic,newton", "--out", str(out)],
        site,
        tmp_path,
    )
    assert res.returncode == 0, res.stderr
    assert f"tumble: validate {SCENE}: newton plant (Newton-Euler), 0 -> 0.5 s" in res.stderr
    doc = json.loads((out / "report.json").read_text())
    assert [p["engine"] for p in doc["plants"]] == ["analytic", "newton"]
    pair = [c for c in doc["checks"] if c["subject"] == "analytic vs newton"]
    assert pair and all(c["passed"] for c in pair)


def test_the_referee_names_the_slipped_newton_plant_the_outlier(site, tmp_path):
    """``tumble validate --plants analytic,newton,newton_slip`` -> exit 1; the referee names the
    slipped plant the outlier of the position of C while the analytic and Newton-Euler plants
    agree with each other."""
    out = tmp_path / "out"
    res = _tumble(
        ["validate", SCENE, "--t-end", "0.5", "--plants", "analytic,newton,newton_slip",
         "--out", str(out)],
        site,
        tmp_path,
    )
    assert res.returncode == 1, res.stderr
    doc = json.loads((out / "report.json").read_text())
    pair = [c for c in doc["checks"] if c["subject"] == "analytic vs newton"]
    assert pair and all(c["passed"] for c in pair)
    position = [v for v in doc["referee"] if v["quantity"] == "position_C"]
    assert position and position[0]["verdict"] == "outlier", position
    assert position[0]["outlier"] == "newton_slip", position
    assert sorted(position[0]["group"]) == ["analytic", "newton"], position


class _Picky(AnalyticPlant):
    """A plugin that refuses every scene (its ``check_scene`` raises ValueError)."""

    engine = "picky"
    label = "Picky engine"

    def check_scene(self, scene):
        super().check_scene(scene)
        raise ValueError(f"scene.name: the picky plant runs no scene (got {scene.name!r})")


@pytest.fixture
def with_picky(monkeypatch):
    """The registry with the built-ins and the plugin :class:`_Picky`."""
    known = {**plants_mod.PLANTS, "picky": _Picky}
    monkeypatch.setattr(plants_mod, "_load", lambda: (known, ()))
    monkeypatch.setattr(plants_mod.PinocchioPlant, "unavailable", classmethod(lambda cls: ""))


def test_progress_names_a_plugin_plant_with_its_label(with_picky):
    """A plugin's stage, not on a terminal -> ``picky plant (Picky engine), 0 -> 2 s`` (it was a
    bare ``picky``); a built-in stays ``mujoco plant``; a stage that is no plant stays bare."""
    buf = io.StringIO()
    p = StageProgress("validate x", 2.0, stream=buf)
    p("mujoco", 0.0)
    p("picky", 0.0)
    p("compare", 0.0)
    assert buf.getvalue().splitlines() == [
        "tumble: validate x: mujoco plant, 0 -> 2 s",
        "tumble: validate x: picky plant (Picky engine), 0 -> 2 s",
        "tumble: validate x: compare",
    ]
    assert plant_title("analytic") == "analytic plant" and plant_title("nothing") == ""


def test_plants_all_leaves_out_a_plugin_that_refuses_the_scene(with_picky):
    """``--plants all`` with a plugin refusing the scene -> the others are chosen, one warning
    names the plugin and its reason, the choice lists it as left out (the report's note)."""
    sc = load_scene(SCENE)
    with pytest.warns(UserWarning, match=r"^picky plant left out: scene\.name: ") as got:
        choice = plant_choice("all", sc)
    assert len([w for w in got if "picky" in str(w.message)]) == 1
    assert "picky" not in choice.plants and {"analytic", "mujoco"} <= set(choice.plants)
    assert choice.left_out == (
        LeftOut("picky", f"scene.name: the picky plant runs no scene (got {SCENE!r})"),
    )


def test_naming_a_plugin_that_refuses_the_scene_is_still_refused(with_picky):
    """``--plants analytic,picky`` (named, not ``all``) -> ValueError naming the field, before any
    run: a plant the user asked for is not silently dropped."""
    from validation.validate import validation_request

    with pytest.raises(ValueError, match=r"^scene\.name: the picky plant"):
        validation_request(SCENE, plants="analytic,picky")


def test_the_referee_note_names_the_plants_left_out(with_picky):
    """A request made with ``all`` carries the plants left out; the report's referee note (shown
    in report.md beside the verdicts) says which and why."""
    from validation.report.markdown import referee_lines
    from validation.validate import validation_request

    with pytest.warns(UserWarning):
        req = validation_request(SCENE, plants="all")
    assert [x.engine for x in req.left_out] == ["picky"]
    lines = referee_lines([], {"referee_note": "; ".join(str(x) for x in req.left_out)})
    assert any("picky plant left out: scene.name: the picky plant runs no scene" in ln for ln in lines)


def test_judge_plants_all_leaves_out_a_plugin_that_refuses_the_scene(with_picky):
    """``tumble judge --plants all`` resolves its referee plants as ``validate`` does: the plugin
    that refuses the scene is left out with one warning, the others stay (no ValueError)."""
    from validation.external import judge

    sc = load_scene(SCENE)
    with pytest.warns(UserWarning, match=r"^picky plant left out: scene\.name: "):
        chosen = judge._plants("all", sc)
    assert "picky" not in chosen and {"analytic", "mujoco"} <= set(chosen)
    with pytest.raises(ValueError, match=r"^plants: picky cannot run"):
        judge._plants("analytic,picky", sc)
