"""The ``[hard_case]`` format: every bad entry is refused naming its field, and a plant's own bound
overrides the general one."""

from __future__ import annotations

import copy
import tomllib

import pytest

from analytic import scene_from_dict
from validation.studies import hard_cases as hc
from validation.studies.hard_cases.criterion import parse_criterion


def _data(name: str) -> dict:
    return tomllib.loads((hc.HARD_DIR / f"{name}.toml").read_text(encoding="utf-8"))


def _criterion(data: dict):
    return parse_criterion(scene_from_dict(data))


def _check(data: dict, i: int = 0) -> dict:
    return data["hard_case"]["check"][i]


BAD_CRITERIA = [
    ("no table", lambda d: d.pop("hard_case"), r"^hard_case: missing required table"),
    ("unknown key", lambda d: d["hard_case"].update(fsat=True), r"^hard_case\.fsat: unknown key"),
    (
        "fast",
        lambda d: d["hard_case"].update(fast="yes"),
        r"^hard_case\.fast: must be true or false",
    ),
    ("criterion", lambda d: d["hard_case"].update(criterion=""), r"^hard_case\.criterion: must be"),
    (
        "what",
        lambda d: _check(d).update(what="__import__('os')"),
        r"^hard_case\.check\[0\]\.what: unknown value",
    ),
    (
        "against",
        lambda d: _check(d).update(against="oracle"),
        r"^hard_case\.check\[0\]\.against: unknown",
    ),
    (
        "pair",
        lambda d: _check(d).update(what="tracking", against="euler"),
        r"^hard_case\.check\[0\]\.what: 'tracking' is not measured against 'euler'",
    ),
    (
        "implicit",
        lambda d: _check(d).update(what="completed", against="run"),
        r"^hard_case\.check\[0\]\.what: 'completed' is not measured against 'run'",
    ),
    (
        "no bound",
        lambda d: _check(d).pop("bound"),
        r"^hard_case\.check\[0\]\.bound: must name a hard_",
    ),
    (
        "unknown bound",
        lambda d: _check(d).update(bound="hard_nope"),
        r"^hard_case\.check\[0\]\.bound: no number 'hard_nope' in \[thresholds\]",
    ),
    (
        "until",
        lambda d: _check(d).update(until=1.0),
        r"^hard_case\.check\[0\]\.until: only for checks against",
    ),
    ("why", lambda d: _check(d).pop("why"), r"^hard_case\.check\[0\]\.why: must be a non-empty"),
    (
        "unused bound",
        lambda d: d["thresholds"].update(hard_unused=1.0),
        r"^thresholds\.hard_unused: no \[\[hard_case\.check\]\] uses this bound",
    ),
    (
        "sentence bound",
        lambda d: d["thresholds"].update(hard_criterion="a sentence"),
        r"^thresholds\.hard_criterion: a bound must be a number",
    ),
    (
        "duplicate",
        lambda d: d["hard_case"]["check"].append(dict(_check(d))),
        r"^hard_case\.check\[4\]: the same figure as hard_case\.check\[0\]",
    ),
    (
        "not applicable",
        lambda d: d["hard_case"].update(not_applicable={"bullet": "no"}),
        r"^hard_case\.not_applicable\.bullet: unknown plant",
    ),
    (
        "unused parameters",
        lambda d: d["hard_case"].update(mirror={"scene": "paper_example1"}),
        r"^hard_case\.mirror: no check is made against 'mirror'",
    ),
]


@pytest.mark.parametrize(
    ("what", "corrupt", "message"), BAD_CRITERIA, ids=[b[0] for b in BAD_CRITERIA]
)
def test_bad_criterion_is_refused_naming_the_field(what, corrupt, message):
    data = copy.deepcopy(_data("rigid_body_alone"))
    _criterion(data)  # the file itself reads
    corrupt(data)
    with pytest.raises(ValueError, match=message):
        _criterion(data)


def test_indicator_takes_no_bound():
    data = copy.deepcopy(_data("pass_through"))
    _check(data).update(bound="hard_invariant_rel")
    with pytest.raises(
        ValueError, match=r"^hard_case\.check\[0\]\.bound: 'crossings' is an indicator"
    ):
        _criterion(data)


@pytest.mark.parametrize(
    ("case", "table", "value", "message"),
    [
        (
            "negative_w",
            "mirror",
            {"scene": "../../etc/passwd"},
            r"^hard_case\.mirror\.scene: must be a built-in",
        ),
        (
            "negative_w",
            "mirror",
            {"scene": "hard/long_horizon"},
            r"^hard_case\.mirror\.scene: must be a built-in",
        ),
        (
            "stiff_springs",
            "solvers",
            {"methods": ["Radau"], "rtol": 1e-8},
            r"^hard_case\.solvers\.atol: must be a finite",
        ),
        (
            "stiff_springs",
            "solvers",
            {"methods": ["Euler"], "rtol": 1e-8, "atol": 1e-10},
            r"^hard_case\.solvers\.methods\[0\]: unknown value",
        ),
        (
            "conflicting_requirements",
            "pinv_law",
            {"duplicate_mass": 3, "conflict_axis": 3, "conflict": 0.5},
            r"^hard_case\.pinv_law\.duplicate_mass: must be a tracked mass",
        ),
        (
            "conflicting_requirements",
            "pinv_law",
            {"duplicate_mass": 1, "conflict_axis": 4, "conflict": 0.5},
            r"^hard_case\.pinv_law\.conflict_axis: must be a tracked",
        ),
        (
            "conflicting_requirements",
            "pinv_law",
            {"duplicate_mass": 1, "conflict_axis": 3, "conflict": -1},
            r"^hard_case\.pinv_law\.conflict: must be positive",
        ),
    ],
)
def test_bad_reference_parameters_are_refused(case, table, value, message):
    data = copy.deepcopy(_data(case))
    data["hard_case"][table] = value
    with pytest.raises(ValueError, match=message):
        _criterion(data)


def test_missing_reference_parameters_are_refused():
    data = copy.deepcopy(_data("negative_w"))
    del data["hard_case"]["mirror"]
    with pytest.raises(ValueError, match=r"^hard_case\.mirror: missing required table"):
        _criterion(data)


def test_plant_specific_bound_overrides_the_general_one():
    """``hard_<plant>_<x>`` is that plant's alone; every other plant gets ``hard_<x>``."""
    c = hc.cases()["rigid_body_alone"].criterion
    spec = next(s for s in c.checks if s.bound == "hard_reference_rel")
    assert c.bound_for(spec, "mujoco") == ("hard_mujoco_reference_rel", 1e-8)
    assert c.bound_for(spec, "analytic") == ("hard_reference_rel", 1e-9)
    assert c.bound_for(spec, "pinocchio") == ("hard_reference_rel", 1e-9)
