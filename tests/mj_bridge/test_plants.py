"""The plant registry: built-ins, plant plugins (entry-point group ``tumbling_testbed.plants``), the
ones left out with one line each, and report order; a real plugin package installed from
``tests/support/plugin_example`` and run by ``tumble validate`` beside the built-ins."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import mj_bridge.plants as plants_mod
import mj_bridge.registry as registry
from analytic.plant import Plant
from mj_bridge.plants import (
    PLANTS,
    installed_plants,
    parse_plants,
    plant,
    plugin_errors,
    registered,
)
from tests.support.plugins import install_project
from validation.compare.subject import Subject, subject_order_key

EXAMPLE = Path(__file__).resolve().parents[1] / "support" / "plugin_example"
VENV_BIN = Path(sys.executable).parent

BROKEN_MODULE = "tpx_broken_plugins"
BROKEN = {  # entry point name -> (object it names, what its one line must say)
    "noimport": (f"{BROKEN_MODULE}_absent:Nothing", "cannot import"),
    "notaplant": (f"{BROKEN_MODULE}:NotAPlant", "is not a subclass of analytic.plant.Plant"),
    "mujoco": (f"{BROKEN_MODULE}:Impostor", "takes the built-in plant name 'mujoco'"),
    "misnamed": (f"{BROKEN_MODULE}:Misnamed", "not the entry point's name 'misnamed'"),
    "undescribed": (f"{BROKEN_MODULE}:Undescribed", "does not implement describe"),
    "Bad-Name": (f"{BROKEN_MODULE}:Misnamed", "is not a plant name"),
}


def _broken_distribution(root: Path) -> Path:
    """A directory holding a distribution (a real ``.dist-info`` with ``entry_points.txt``) that
    declares every plugin of :data:`BROKEN`, and the module they name."""
    root.mkdir(parents=True, exist_ok=True)
    (root / f"{BROKEN_MODULE}.py").write_text(
        textwrap.dedent(
            """
            from analytic.plant import AnalyticPlant, AnalyticSettings, Plant


            class NotAPlant:
                engine = "notaplant"


            class Impostor(AnalyticPlant):
                engine = "mujoco"


            class Misnamed(AnalyticPlant):
                engine = "something_else"


            class Undescribed(Plant):  # no describe
                engine = "undescribed"
                label = "Undescribed"
                settings_type = AnalyticSettings

                def default_settings(self, scene):
                    return AnalyticSettings()

                def _simulate(self, scene, settings, t_end, progress):
                    raise NotImplementedError
            """
        )
    )
    info = root / "tpx_broken_plugins-0.1.dist-info"
    info.mkdir(exist_ok=True)
    (info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: tpx-broken-plugins\nVersion: 0.1\n"
    )
    lines = ["[tumbling_testbed.plants]"] + [f"{k} = {v}" for k, (v, _) in BROKEN.items()]
    (info / "entry_points.txt").write_text("\n".join(lines) + "\n")
    return root


def _reload_registry() -> None:
    registry.entry_points.cache_clear()
    plants_mod._load.cache_clear()


@pytest.fixture
def broken_plugins(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(_broken_distribution(tmp_path / "broken")))
    _reload_registry()
    yield
    sys.modules.pop(BROKEN_MODULE, None)
    monkeypatch.undo()
    _reload_registry()


def test_builtins_come_first_and_drake_is_a_plugin_outside_the_defaults():
    assert list(PLANTS) == ["analytic", "mujoco", "pinocchio"]
    names = list(registered())
    assert names[:3] == ["analytic", "mujoco", "pinocchio"]
    for name, cls in registered().items():
        assert issubclass(cls, Plant) and cls.engine == name and type(cls.engine) is str
    assert "drake" in names  # the project's own entry point (pyproject.toml)
    assert "drake" not in installed_plants()
    assert installed_plants()[:2] == ("analytic", "mujoco")
    assert all(type(n) is str for n in installed_plants())


def test_parse_plants_orders_refuses_and_knows_all():
    assert parse_plants("drake, mujoco ,analytic") == ("analytic", "mujoco", "drake")
    with pytest.raises(ValueError, match=r"^plants: unknown plant 'bullet' \(known: analytic, "):
        parse_plants("analytic,bullet")
    with pytest.raises(ValueError, match=r"^plants: 'all' stands alone"):
        parse_plants("all,analytic")
    everything = parse_plants("all")
    assert everything[: len(installed_plants())] == installed_plants()
    assert set(everything) >= set(installed_plants())


def test_report_order_and_subjects_of_any_plant():
    """Built-ins in their order, then plugins by name, then any other label by name: a label
    sorting before a plugin's name alphabetically still comes after it."""
    assert registry.report_order(["zeta", "drake", "aaa", "mujoco", "analytic"]) == (
        "analytic",
        "mujoco",
        "drake",
        "aaa",
        "zeta",
    )
    assert Subject.pair("drake", "mujoco") == "mujoco vs drake"
    assert Subject.pair("aaa", "drake") == "drake vs aaa"
    assert Subject.pair("mujoco", "analytic") == Subject.BOTH
    s = Subject.pair("echo", "analytic")
    assert s.is_pair and s.plants == ("analytic", "echo") and s.slug == "analytic_vs_echo"
    assert s.value == "analytic vs echo" and type(s.value) is str
    assert json.dumps({"subject": s}) == '{"subject": "analytic vs echo"}'
    subjects = [Subject("mujoco vs drake"), Subject("drake"), Subject("analytic vs mujoco")]
    assert sorted(subjects, key=subject_order_key) == [
        "drake",
        "analytic vs mujoco",
        "mujoco vs drake",
    ]
    for bad in ("", " a", "a vs b vs c", "a vs "):
        with pytest.raises(ValueError, match="subject"):
            Subject(bad)
    with pytest.raises(ValueError, match="subject"):
        Subject.pair("analytic", "analytic")


def test_colours_beyond_the_built_ins_are_distinct_and_stable():
    from validation.recording.style import EXTRA_PLANT_COLORS, PLANT_COLOR, plant_color
    from validation.report.figures import plant_style

    builtin = {plant_color(n) for n in PLANTS}
    assert len(builtin) == 3
    extra = [plant_color(n) for n in ("drake", "some_label", "other_label")]
    assert plant_color("drake") == EXTRA_PLANT_COLORS[0][1]  # the first plugin by name
    assert not (set(extra) & (builtin | set(PLANT_COLOR.values())))
    assert plant_color("some_label") == plant_color("some_label")
    pair = plant_color("analytic vs drake")
    assert pair not in (plant_color("analytic"), plant_color("drake"))
    style = plant_style("drake")
    assert style["color"] == tuple(c / 255 for c in plant_color("drake"))
    assert plant_style("analytic vs drake")["marker"]


def test_broken_plugins_are_named_in_one_line_and_the_others_run(broken_plugins, capsys):
    errors = {e.name: e for e in plugin_errors()}
    assert set(errors) == set(BROKEN)
    for name, (_, says) in BROKEN.items():
        line = str(errors[name])
        assert "\n" not in line and says in line, line
        assert line.startswith(f"plant plugin {name!r} skipped: ")
    assert list(registered())[:3] == ["analytic", "mujoco", "pinocchio"]
    assert registered()["mujoco"] is PLANTS["mujoco"]  # a plugin cannot take a built-in's name
    assert "drake" in registered()
    assert installed_plants()[:2] == ("analytic", "mujoco")
    with pytest.raises(ValueError, match=r"^plants: plant plugin 'notaplant' skipped: "):
        plant("notaplant")
    with pytest.raises(ValueError, match="plant plugin 'noimport' skipped: cannot import"):
        parse_plants("analytic,noimport")

    from validation.cli import warn_skipped_plugins

    warn_skipped_plugins()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == len(BROKEN)
    assert all(line.startswith("tumble: warning: plant plugin '") for line in err)


def test_a_plugin_package_installed_from_tests_runs_in_tumble_validate(tmp_path):
    """The example package installed from its own pyproject.toml (:func:`tests.support.plugins.install_project`), then ``tumble validate --plants analytic,mujoco,echo`` in a subprocess that sees it and a
    distribution of broken plugins: the broken ones are named in one line each, the run passes,
    and the report holds the plugin as a plant, every pair compared."""
    site = install_project(EXAMPLE, tmp_path / "site")
    eps = list(site.glob("tumble_plugin_example-*.dist-info/entry_points.txt"))
    assert eps and "echo = tumble_plugin_example:EchoPlant" in eps[0].read_text()
    broken = _broken_distribution(tmp_path / "broken")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), str(broken)]))
    out = tmp_path / "out"
    res = subprocess.run(
        [
            str(VENV_BIN / "tumble"),
            "validate",
            "paper_example1_controlled",
            "--t-end",
            "0.5",
            "--plants",
            "analytic,mujoco,echo",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr
    warnings = [line for line in res.stderr.splitlines() if "plant plugin" in line]
    assert len(warnings) == len(BROKEN), res.stderr
    for name, (_, says) in BROKEN.items():
        mine = [
            w for w in warnings if w.startswith(f"tumble: warning: plant plugin {name!r} skipped: ")
        ]
        assert len(mine) == 1 and says in mine[0], (name, warnings)
    doc = json.loads((out / "report.json").read_text())
    assert [p["engine"] for p in doc["plants"]] == ["analytic", "mujoco", "echo"]
    pairs = {c["subject"] for c in doc["checks"] if " vs " in c["subject"]}
    assert pairs == {"analytic vs mujoco", "analytic vs echo", "mujoco vs echo"}
    echo = [c for c in doc["checks"] if c["subject"] == "echo"]
    assert echo and all(c["passed"] for c in echo)
    assert all(c["passed"] for c in doc["checks"] if c["subject"] == "analytic vs echo")
    assert "echo" in (out / "report.md").read_text()
    assert (out / "run.rrd").stat().st_size > 0


def test_a_plant_whose_check_scene_has_a_bug_stays_in_the_set_to_fail_alone(monkeypatch):
    """A plant set meets a plant whose ``check_scene`` raises something other than the
    ``ValueError`` of a refusal (a plugin's own bug): the set keeps it, so that the run fails that
    plant alone, naming what it raised, instead of the set's resolution raising it; a refusal still
    leaves the plant out."""
    from validation.scenes import resolve_scene

    real = plants_mod.plant

    class _Buggy:
        def check_scene(self, scene):
            raise RuntimeError("a plugin's own bug")

    class _Refusing:
        def check_scene(self, scene):
            raise ValueError("masses: cannot hold this scene")

    fakes = {"buggy": _Buggy(), "refusing": _Refusing()}
    monkeypatch.setattr(plants_mod, "plant", lambda name: fakes.get(name) or real(name))
    sc = resolve_scene("paper_example1")
    got = plants_mod.plants_for_scene(sc, ("analytic", "buggy", "refusing", "mujoco"))
    assert got == ("analytic", "buggy", "mujoco")


def _effect_scene(controlled: bool, claimed=frozenset()):
    """A short random scene with every effect on (two output samples; the control effects only
    when ``controlled``: tracked masses do not feel the springs), the masses off their rest
    positions."""
    import numpy as np

    from analytic.effects import CONTROL_EFFECTS, Effect
    from analytic.effects.registry import DECLARATIONS
    from analytic.scene import modified_scene
    from analytic.scene.random_scenes import random_scene

    forces = [  # every claimed effect that is not the control's or the given torque's
        d.effect.value
        for d in DECLARATIONS
        if d.effect in claimed
        and d.effect not in CONTROL_EFFECTS
        and d.effect is not Effect.EXTERNAL_TORQUE
    ]
    sc = random_scene(
        np.random.default_rng(11), 2, external_torque=True, controlled=controlled, effects=forces
    )
    stretched = [
        float(x) for x in np.asarray(sc.masses.p_e) + np.array([0.5, -0.3])
    ]  # every spring felt
    return modified_scene(
        sc, {"initial": {"p": stretched}, "output": {"t_end": 2.0 / sc.output.rate}}
    )


@pytest.mark.parametrize("name", [*PLANTS, "drake"])
def test_every_effect_a_plant_claims_changes_its_motion(name):
    """A plant claiming an effect it has no code for fails here: with the effect switched off the
    plant's motion must differ from the one with every effect on (each claimed effect at a time;
    the control effects on a controlled scene, the others on an uncontrolled one)."""
    import numpy as np

    from analytic.effects import CONTROL_EFFECTS

    cls = registered().get(name)
    if cls is None or cls.unavailable():
        pytest.skip(f"{name}: not installed")
    pl = cls()
    scenes = {c: _effect_scene(c, cls.effects) for c in (False, True)}
    full = {c: pl.simulate(sc) for c, sc in scenes.items()}
    for effect in sorted(cls.effects):
        c = effect in CONTROL_EFFECTS
        sc = scenes[c]
        assert effect in sc.effects
        off = pl.simulate(sc.with_effects(sc.effects - {effect}))
        same = np.array_equal(full[c].q, off.q) and np.array_equal(full[c].qddot, off.qddot)
        assert not same, f"{name}: switching {effect.value} off changes nothing"
