"""The input boundary of a validation (``validation/validate/request.py``): every input is
checked once per boundary (``tumble validate``, :func:`validation.run_validation`,
:func:`validation.assert_agree`),
into a frozen :class:`~validation.validate.ValidationRequest` the run trusts, and a scene is
resolved by one function (:func:`validation.scenes.resolve_scene`).

No plant runs here: the run itself is stopped where it would begin (``_validate_into``).
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import sys
from pathlib import Path

import pytest

import mj_bridge.plants as plants_mod
import validation.compare.thresholds as thresholds_mod
import validation.preflight as preflight_mod
import validation.scenes as scenes_mod
import validation.validate as validate_mod
from analytic.scene import load_scene
from analytic.scene.dump import scene_to_toml
from analytic.trajectory import Engine
from validation.cli import EXIT_USAGE, main
from validation.scenes import DEFAULT_SCENE, HARD_DIR, resolve_scene
from validation.testing.agree import assert_agree
from validation.validate import ValidationRequest, run_validation, validation_request

COUNTED = {
    "resolve_scene": scenes_mod,
    "thresholds_for": thresholds_mod,
    "plant_choice": preflight_mod,
    "check_validation_inputs": preflight_mod,
    "parse_plants": plants_mod,
}
"""The input checks whose entries are counted, and the module that defines each."""


class _Stop(ValueError):
    """Raised where the run would begin: a ValueError, so the output directory is left alone."""


@pytest.fixture
def entries(monkeypatch) -> collections.Counter:
    """How often each check of :data:`COUNTED` is entered, wherever it is called from (every
    module holding the function is given the counting one); the run stops where it would begin."""
    counts: collections.Counter = collections.Counter()
    for name, home in COUNTED.items():
        real = getattr(home, name)

        def counting(*args, _real=real, _name=name, **kwargs):
            counts[_name] += 1
            return _real(*args, **kwargs)

        counting = functools.wraps(real)(counting)
        for module in list(sys.modules.values()):
            if getattr(module, "__name__", "").startswith(("validation", "mj_bridge")) and (
                getattr(module, name, None) is real
            ):
                monkeypatch.setattr(module, name, counting)

    def stop(*args, **kwargs):
        raise _Stop("stopped where the plants would start")

    monkeypatch.setattr(validate_mod, "_validate_into", stop)
    return counts


ONCE = {name: 1 for name in COUNTED}


def test_tumble_validate_checks_each_input_once(entries, tmp_path, capsys):
    rc = main(["validate", "--plants", "analytic,mujoco", "--out", str(tmp_path / "v")])
    assert rc == EXIT_USAGE and "stopped where the plants would start" in capsys.readouterr().err
    assert dict(entries) == ONCE


def test_run_validation_checks_each_input_once(entries, tmp_path):
    with pytest.raises(_Stop):
        run_validation(DEFAULT_SCENE, tmp_path / "v", plants="analytic,mujoco")
    assert dict(entries) == ONCE


def test_assert_agree_checks_each_input_once_with_its_overrides(entries, tmp_path):
    with pytest.raises(_Stop):
        assert_agree(DEFAULT_SCENE, plants="analytic,mujoco", out_dir=tmp_path, position_C=1e-3)
    assert dict(entries) == ONCE


def test_a_request_is_frozen_and_holds_what_the_run_needs():
    req = validation_request(
        DEFAULT_SCENE, plants="mujoco,analytic", t_end=0.5, figure_formats="svg,png"
    )
    assert isinstance(req, ValidationRequest)
    assert req.plants == (Engine.ANALYTIC, Engine.MUJOCO)  # report order, whatever was given
    assert req.horizon == 0.5 and req.scene.name == DEFAULT_SCENE
    assert [f.value for f in req.figure_formats] == ["svg", "png"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        req.horizon = 1.0  # type: ignore[misc]


def test_threshold_overrides_are_laid_over_the_scene_and_checked():
    req = validation_request(DEFAULT_SCENE, plants="analytic,mujoco", thresholds={"energy": 0.5})
    assert req.thresholds["energy"].value == 0.5
    assert req.scene.extra["thresholds"]["energy"] == 0.5  # the scene as it runs says so too
    with pytest.raises(ValueError, match=r"thresholds\.energie: unknown threshold"):
        validation_request(DEFAULT_SCENE, plants="analytic,mujoco", thresholds={"energie": 0.5})


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"plants": "analytic"}, "plants"),
        ({"t_end": -1.0}, "t_end"),
        ({"figure_formats": "gif"}, "figure_format"),
        ({"dt": 0.0}, "dt"),
    ],
)
def test_bad_input_is_refused_naming_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        validation_request(DEFAULT_SCENE, **({"plants": "analytic,mujoco"} | kwargs))


def test_every_boundary_resolves_a_scene_the_same_way(tmp_path):
    """A built-in name, a hard case by ``hard/<name>``, a path (str or Path) and a Scene: the
    same resolver for the command line, the Python API and the request."""
    hard = HARD_DIR / "zero_gravity.toml"
    hard_text = scene_to_toml(load_scene(hard))
    for given in ("hard/zero_gravity", "hard/zero_gravity.toml", str(hard), hard):
        by_request = validation_request(given, plants="analytic,mujoco").scene
        assert scene_to_toml(by_request) == scene_to_toml(resolve_scene(given)) == hard_text
    sc = resolve_scene(None)
    assert sc.name == DEFAULT_SCENE and resolve_scene(sc) is sc
    with pytest.raises(ValueError, match=r"^scene: no file and no built-in scene named 'nope'"):
        validation_request("nope", plants="analytic,mujoco")
    assert not Path("nope").exists()
