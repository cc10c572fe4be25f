"""Reading tables through the declarations: a misspelt or unknown name is named first, with the
closest declared one; a key given where it does not apply says when it does.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import pytest

from analytic.scene import scene_from_dict
from tests.analytic.scene.test_loading import _raw


def _rename(raw: dict, dotted: str, new: str) -> None:
    *head, last = dotted.split(".")
    node = raw
    for key in head:
        node = node[key]
    node[new] = node.pop(last)


TYPOS = [
    # (scene, dotted key to misspell, the misspelling, the message's start)
    ("paper_example1", "masses", "mass", "mass: unknown table (did you mean 'masses'?"),
    ("paper_example1_controlled", "control.masses.lambda", "lamda",
     "control.masses.lamda: unknown key (did you mean 'lambda'?"),
    ("paper_example1", "initial.attitude", "atitude",
     "initial.atitude: unknown table (did you mean 'attitude'?"),
    ("paper_example2", "springs.k_cubic", "k_cubik",
     "springs.k_cubik: unknown key (did you mean 'k_cubic'?"),
    ("paper_example1", "solver", "solvers", "solvers: unknown table (did you mean 'solver'?"),
    ("paper_example1", "body.shape.box_half_sizes", "box_halfsizes",
     "body.shape.box_halfsizes: unknown key (did you mean 'box_half_sizes'?"),
    ("paper_example1_controlled", "thresholds", "treshold",
     "treshold: unknown table (did you mean 'thresholds'?"),
]  # fmt: skip


@pytest.mark.parametrize(("name", "key", "typo", "message"), TYPOS)
def test_a_misspelt_table_or_key_is_named_first_with_the_closest_declared_name(
    name, key, typo, message
):
    """A misspelling is the error reported, whatever else it leaves missing or mis-sized: without
    [masses] the springs would have the wrong length, without lambda it would be missing."""
    raw = _raw(name)
    if key == "thresholds":
        raw["thresholds"] = {"position_C": 1e-6}
    _rename(raw, key, typo)
    with pytest.raises(ValueError) as exc:
        scene_from_dict(raw)
    assert str(exc.value).startswith(message), str(exc.value)


def test_an_unknown_name_without_a_close_one_lists_the_declared_ones():
    raw = _raw("paper_example1")
    raw["rod"]["zzz"] = 1.0
    with pytest.raises(
        ValueError, match=r"^rod\.zzz: unknown key \(known in \[rod\]: axis, offset\)"
    ):
        scene_from_dict(raw)


def test_a_key_given_where_it_does_not_apply_says_when_it_does():
    raw = _raw("paper_example2")  # a hollow cylinder: no box
    raw["body"]["shape"]["box_center"] = [0.0, 0.0, 0.0]
    with pytest.raises(
        ValueError, match=r'^body\.shape\.box_center: not used here: only with kind = "box_and_rod"'
    ):
        scene_from_dict(raw)
