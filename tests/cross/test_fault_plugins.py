"""Faults of plant plugins as the plant set meets them: a plugin installed beside the built-ins
that refuses the scene, under ``--plants all``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import mj_bridge.plants as plants_mod
from analytic.plant import AnalyticPlant
from tests.support.plugins import install_project

TUMBLE = Path(sys.executable).parent / "tumble"

PICKY = '''
"""A plant plugin that refuses every scene: its check_scene raises ValueError."""
from analytic.plant import AnalyticPlant


class PickyPlant(AnalyticPlant):
    engine = "picky"
    label = "Picky"

    def check_scene(self, scene):
        super().check_scene(scene)
        raise ValueError(f"scene.name: the picky plant runs no scene (got {scene.name!r})")
'''


def _picky_site(root: Path) -> Path:
    """The picky plugin installed as a distribution from its own pyproject.toml."""
    project = root / "project"
    project.mkdir(parents=True)
    (project / "tumble_picky.py").write_text(PICKY)
    (project / "pyproject.toml").write_text(
        textwrap.dedent(
            """
            [project]
            name = "tumble-picky"
            version = "0.1.0"

            [project.entry-points."tumbling_testbed.plants"]
            picky = "tumble_picky:PickyPlant"

            [tool.setuptools]
            py-modules = ["tumble_picky"]
            """
        )
    )
    return install_project(project, root / "site")


class _Picky(AnalyticPlant):
    engine = "picky"
    label = "Picky"

    def check_scene(self, scene):
        super().check_scene(scene)
        raise ValueError(f"scene.name: the picky plant runs no scene (got {scene.name!r})")


def test_run_validation_all_with_a_plugin_refusing_the_scene_notes_it(monkeypatch, tmp_path):
    """`run_validation(plants="all")` with a registered plugin refusing the scene -> the other
    plants run and pass, one warning, and report.json's and report.md's referee note name the
    plant left out and its reason."""
    from validation.validate import run_validation

    known = {**plants_mod.PLANTS, "picky": _Picky}
    monkeypatch.setattr(plants_mod, "_load", lambda: (known, ()))
    monkeypatch.setattr(plants_mod.PinocchioPlant, "unavailable", classmethod(lambda cls: "no"))
    with pytest.warns(UserWarning, match=r"^picky plant left out: scene\.name: "):
        res = run_validation(
            "paper_example1_controlled", tmp_path / "out", t_end=0.05, plants="all",
            figure_formats="svg",
        )
    assert res.passed
    doc = json.loads((tmp_path / "out" / "report.json").read_text())
    assert [p["engine"] for p in doc["plants"]] == ["analytic", "mujoco"]
    note = doc["run"]["referee_note"]
    assert note.startswith("picky plant left out: scene.name: the picky plant runs no scene"), note
    assert "picky plant left out" in (tmp_path / "out" / "report.md").read_text()


@pytest.mark.slow
def test_plants_all_with_a_plugin_refusing_the_scene_runs_the_others(tmp_path):
    """`--plants all` with an installed plugin whose check_scene refuses the scene -> that plant
    left out with one warning line naming it and why, the others run (not exit 2), and the
    report's referee note says which plant was left out and why."""
    site = _picky_site(tmp_path)
    path = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([*path, str(site)]))
    out = tmp_path / "out"
    res = subprocess.run(
        [str(TUMBLE), "validate", "paper_example1_controlled", "--t-end", "0.1", "--plants", "all",
         "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=900,
    )
    assert res.returncode == 0, res.stderr
    warned = [line for line in res.stderr.splitlines() if "picky" in line and "warning" in line]
    assert warned == [
        "tumble: warning: picky plant left out: scene.name: the picky plant runs no scene "
        "(got 'paper_example1_controlled')"
    ], res.stderr
    doc = json.loads((out / "report.json").read_text())
    engines = [p["engine"] for p in doc["plants"]]
    assert "picky" not in engines and {"analytic", "mujoco"} <= set(engines)
    assert "picky plant left out: scene.name: the picky plant runs no scene" in (
        doc["run"]["referee_note"]
    )
    assert "picky plant left out" in (out / "report.md").read_text()
