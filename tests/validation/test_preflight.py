"""A plant whose pointwise check refuses the scene is a check_scene refusal: named, it refuses the
run; of a set, it is left out with one warning."""

from __future__ import annotations

import warnings

import pytest

from analytic.scene import load_scene
from validation.preflight import LeftOut, PlantChoice, without_refusals

SCENE = load_scene("paper_example1")
REFUSED = (("mjx", "opt.enableflags: energy is not supported"),)


def test_a_named_plant_that_refuses_refuses_the_run():
    named = PlantChoice(("analytic", "mjx"), named=True)
    with pytest.raises(ValueError) as err:
        without_refusals(named, REFUSED, SCENE)
    assert str(err.value) == "mjx: opt.enableflags: energy is not supported"


def test_a_set_leaves_it_out_with_one_warning():
    choice = PlantChoice(("analytic", "mujoco", "mjx"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = without_refusals(choice, REFUSED, SCENE)
    assert got.plants == ("analytic", "mujoco")
    assert got.left_out == (LeftOut("mjx", REFUSED[0][1]),)
    assert [str(w.message) for w in caught] == [f"mjx plant left out: {REFUSED[0][1]}"]
    assert without_refusals(choice, (), SCENE) is choice
    with pytest.raises(ValueError, match="fewer than two"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        without_refusals(PlantChoice(("analytic", "mjx")), REFUSED, SCENE)
