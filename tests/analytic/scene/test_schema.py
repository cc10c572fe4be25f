"""The key declarations: which data each effect reads, and which it cannot act without, are
declared on the keys themselves and drive the loader's rules."""

from __future__ import annotations

import copy
import tomllib
import warnings

import pytest

from analytic.effects import Effect
from analytic.scene import scene_from_dict
from analytic.scene.key import Key, Kind, Need
from analytic.scene.rules import EFFECT_DATA
from analytic.scene.schema import EFFECT_WARNING_ORDER, KEYS, effect_keys, key_spec
from validation.scenes import scene_path

# What each effect reads, from the paper and the scene format (docs/scene-format.md, "Effects"):
# gravity its vector (Eq. 46), the springs their constants (Eq. 38), the masses' own inertia one of
# the inertia keys (Remark 1), the control its requirement tables (Eqs. 75-76), the given torque
# its table (Remark 2).
READS = {
    Effect.GRAVITY: {"gravity"},
    Effect.SPRINGS_LINEAR: {"springs.k_linear"},
    Effect.SPRINGS_CUBIC: {"springs.k_cubic"},
    Effect.SPRINGS_DAMPING: {"springs.c_damping"},
    Effect.MASS_INERTIA: {
        "masses.ring_radius",
        "masses.inertia_axial",
        "masses.inertia_transverse",
        "masses.inertia_body",
    },
    Effect.CONTROL_OMEGA: {"control.omega"},
    Effect.CONTROL_MASSES: {"control.masses"},
    Effect.EXTERNAL_TORQUE: {"external_torque"},
}
# Those an effect cannot act without (gravity has a default vector; a mass without its own
# inertia is a point).
NEEDS = {
    "springs.k_linear",
    "springs.k_cubic",
    "springs.c_damping",
    "control.omega",
    "control.masses",
    "external_torque",
}


def test_every_effect_reads_the_data_the_format_gives_it():
    declared: dict[Effect, set[str]] = {}
    for dotted, effect in EFFECT_DATA:
        declared.setdefault(effect, set()).add(dotted)
    assert declared == READS
    assert {k.dotted for k in KEYS if k.effect_needs} == NEEDS
    assert set(EFFECT_WARNING_ORDER) == set(Effect)
    order = [EFFECT_WARNING_ORDER.index(k.effect) for k in effect_keys()]
    assert order == sorted(order)


def test_a_needed_key_says_so_in_its_when():
    for k in KEYS:
        if k.effect_needs:
            assert f"required by the effect {k.effect.value}" in k.when, k.dotted
    with pytest.raises(ValueError, match=r"^springs\.k_x: a key an effect needs says so"):
        Key("springs", "k_x", Kind.VECTOR_N1, "N/m", "x", Need.OPTIONAL,
            effect=Effect.SPRINGS_LINEAR, effect_needs=True)  # fmt: skip
    assert key_spec("springs", "k_linear").effect is Effect.SPRINGS_LINEAR


@pytest.mark.parametrize("dotted", sorted(NEEDS))
def test_listing_an_effect_without_the_data_it_needs_is_refused_naming_the_data(dotted):
    with open(scene_path("paper_example1_controlled"), "rb") as f:
        raw = tomllib.load(f)
    spec = key_spec(*dotted.rsplit(".", 1)) if "." in dotted else key_spec("", dotted)
    raw = copy.deepcopy(raw)
    raw["scene"]["effects"] = sorted({*raw["scene"]["effects"], spec.effect.value})
    node = raw
    *head, last = dotted.split(".")
    for part in head:
        node = node[part]
    node.pop(last, None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError) as exc:
            scene_from_dict(raw)
    assert str(exc.value).startswith(f"{dotted}: ")
