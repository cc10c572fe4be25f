"""Rules across tables: an effect needs its data, data of an unlisted effect is ignored with one
warning, masses off the drawn rod get one warning.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import copy
import warnings

import pytest

from analytic.effects import Effect
from analytic.scene import load_scene, scene_from_dict
from tests.analytic.scene.test_loading import _raw
from validation.scenes import scene_path

# ------------------------------------------------------------------------------------------------
# Bad input caught at load, before any work, with the field named
# ------------------------------------------------------------------------------------------------


def test_missing_effect_constant_is_refused_also_when_switched_on_later():
    raw = _raw("paper_example1")
    del raw["springs"]["k_cubic"]
    raw["scene"]["effects"].remove("springs.cubic")
    sc = scene_from_dict(raw)  # not needed while the effect is off
    with pytest.raises(ValueError, match=r"^springs\.k_cubic: required by effect springs\.cubic$"):
        sc.with_effects(sc.effects | {Effect.SPRINGS_CUBIC})


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda raw: raw.update(external_torque={"constant": [1.0, 0.0, 0.0]}),
            "external_torque: given but effect 'external_torque' is not listed in scene.effects, "
            "so ignored",
        ),
        (
            lambda raw: raw["scene"]["effects"].remove("gravity"),
            "gravity: given but effect 'gravity' is not listed in scene.effects, so ignored",
        ),
        (
            lambda raw: (
                raw.update(external_torque={"amplitude": [0.0, 1.0, 0.0]}),
                raw["scene"]["effects"].remove("gravity"),
            ),
            "gravity, external_torque: given but effects 'gravity', 'external_torque' are not "
            "listed in scene.effects, so ignored",
        ),
    ],
)
def test_table_for_an_unlisted_effect_gives_one_warning(change, message):
    raw = _raw("paper_example1")
    change(raw)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene_from_dict(raw)
    assert [str(w.message) for w in caught] == [message]


# ------------------------------------------------------------------------------------------------
# Masses off the drawn rod
# ------------------------------------------------------------------------------------------------


def _one_warning(raw: dict) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene_from_dict(raw)
    return [str(w.message) for w in caught]


def test_masses_beyond_the_drawn_rod_get_one_warning_naming_them():
    """The rod's length is a picture (the masses slide on an unbounded line): a rest or initial
    position beyond it loads, with one line naming each field and value and the drawn rod."""
    raw = _raw("paper_example1")  # rod drawn from 0 to 16 m along a from O'
    assert _one_warning(copy.deepcopy(raw)) == []
    raw["masses"]["p_e"] = [4.0, 17.5]
    raw["initial"]["p"] = [-0.5, 11.0]
    (msg,) = _one_warning(raw)
    assert msg == (
        "masses.p_e[1] = 17.5 m, initial.p[0] = -0.5 m: lie beyond the drawn rod "
        "(body.shape.rod_start = 0 m, rod_length = 16 m: 0 m to 16 m from O'); the rod's length "
        "is a picture only, the masses slide on an unbounded line"
    )
    raw["initial"]["p"] = [5.0, 11.0]
    (msg,) = _one_warning(raw)
    assert msg.startswith("masses.p_e[1] = 17.5 m: lies beyond the drawn rod")
    # the same scene without a picture has no drawn rod to leave
    del raw["body"]["shape"]
    assert _one_warning(raw) == []


def test_no_builtin_scene_draws_a_mass_off_its_rod():
    from validation.scenes import builtin_names

    for name in builtin_names():
        with warnings.catch_warnings():
            warnings.filterwarnings("error", message=".*beyond the drawn rod")
            load_scene(scene_path(name))
