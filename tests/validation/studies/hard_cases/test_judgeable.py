"""A float32 plant's checks whose bounds are below its round-off are "not judgeable at float32":
never a PASS or a FAIL, in the table and in its JSON; a float64 plant's are judged as before."""

from __future__ import annotations

import dataclasses
import json
import types

import numpy as np
import pytest

from analytic.effects import Precision
from validation.compare.checks import Subject, judge
from validation.studies.hard_cases import judgeable, runner
from validation.studies.hard_cases.catalogue import Measure, Reference
from validation.studies.hard_cases.criterion import CheckSpec
from validation.studies.hard_cases.table import HardCaseRow, HardCaseTable, Verdict, jsonable
from validation.studies.roundoff import EPS


def _spec(what, against, bound="hard_x"):
    return CheckSpec(what=Measure(what), against=Reference(against), bound=bound, why="why")


def _traj(R_max=100.0, p_max=5.0):
    t = np.linspace(0.0, 2.0, 5)
    R = np.stack([np.linspace(0.0, R_max, 5), 0 * t, 0 * t], axis=1)
    return types.SimpleNamespace(t=t, R=R, p=np.full((5, 2), p_max))


@pytest.mark.parametrize(
    "what, against, scale",
    [
        ("position_C", "analytic", 100.0),
        ("rod_positions", "analytic", 5.0),
        ("com_path", "centre_of_mass", 100.0),
        ("positions", "mirror", 100.0),
        ("attitude", "analytic", 1.0),
        ("invariants", "balances", 1.0),
        ("flip_times", "analytic", 2.0),
    ],
)
def test_the_magnitude_of_each_kind_of_measure(what, against, scale):
    assert judgeable.magnitude(_spec(what, against), _traj(), 2.0) == pytest.approx(scale)


def test_a_check_until_a_time_takes_the_magnitude_up_to_then():
    spec = dataclasses.replace(_spec("position_C", "analytic"), until=1.0)
    assert judgeable.magnitude(spec, _traj(), 2.0) == pytest.approx(50.0)  # |R| at t = 1 s


def test_a_check_below_float32_round_off_is_not_judgeable_and_an_indicator_always_is():
    tr, f32 = _traj(), Precision.FLOAT32
    spec = _spec("position_C", "analytic")
    nj = judgeable.assess(spec, "mjx", "position_C", f32, "hard_x", 1e-7, 3e-9, tr, 2.0)
    assert nj is not None and nj.round_off == pytest.approx(EPS[f32] * 100.0)
    assert nj.to_dict()["verdict"] == "not judgeable at float32"
    assert judgeable.assess(spec, "mjx", "position_C", f32, "hard_x", 1e-4, 3e-9, tr, 2.0) is None
    f64 = Precision.FLOAT64
    assert judgeable.assess(spec, "mjx", "position_C", f64, "hard_x", 1e-12, 0.0, tr, 2.0) is None
    flips = _spec("flips", "run", bound="")
    assert judgeable.assess(flips, "mjx", "flips", f32, "", 0.0, 0.0, tr, 2.0) is None


def _row(unjudged_all: bool):
    subject = Subject.pair("analytic", "mjx")
    checks = [
        judge("completed", Subject.plant("mjx"), 2.0, 2.0, "s", "horizon"),
        judge("position_C", subject, 3e-9, 1e-7, "m", "why", bound="hard_x"),
        judge(
            "attitude",
            subject,
            1e-3 if not unjudged_all else 1e-9,
            1e-2,
            "rad",
            "w",
            bound="hard_y",
        ),
    ]
    tr = _traj()
    spec = _spec("position_C", "analytic")
    nj = judgeable.assess(
        spec, "mjx", checks[1].label, Precision.FLOAT32, "hard_x", 1e-7, 3e-9, tr, 2.0
    )
    checks[1] = dataclasses.replace(checks[1], applicable=False, reason=nj.reason)
    unjudged = [nj]
    if unjudged_all:
        spec2 = _spec("attitude", "analytic")
        nj2 = judgeable.assess(
            spec2, "mjx", checks[2].label, Precision.FLOAT32, "hard_y", 1e-8, 1e-9, tr, 2.0
        )
        checks[2] = dataclasses.replace(checks[2], applicable=False, reason=nj2.reason)
        unjudged.append(nj2)
    return HardCaseRow(
        case="c", criterion="crit", plants=("analytic", "mjx"), figures={"mjx": {}},
        checks=tuple(checks), verdict=Verdict.PASS, wall_time_s=1.0,
        not_judgeable=tuple(unjudged), precisions={"mjx": Precision.FLOAT32},
    )  # fmt: skip


def test_the_table_and_json_say_not_judgeable_never_pass_or_fail():
    only = _row(unjudged_all=True)
    assert only.plant_verdict("mjx") is Verdict.NOT_JUDGEABLE
    some = _row(unjudged_all=False)
    assert some.plant_verdict("mjx") is Verdict.PASS  # judged on the attitude, not the position
    table = HardCaseTable((only,), plants=("analytic", "mjx"))
    md = table.to_markdown()
    assert "**not judgeable at float32**" in md
    assert "- not judgeable at float32: analytic_vs_mjx.position_C = 3.000e-09 m" in md
    doc = json.loads(json.dumps(jsonable(table.to_dict())))
    mjx = doc["rows"][0]["plants"]["mjx"]
    assert mjx["verdict"] == "not judgeable" and mjx["precision"] == "float32"
    pos, att = "analytic_vs_mjx.position_C", "analytic_vs_mjx.attitude"
    assert mjx["not judgeable"] == [pos, att]
    by_label = {c["label"]: c for c in doc["rows"][0]["checks"]}
    assert by_label[pos]["verdict"] == "not judgeable at float32"
    assert by_label[pos]["judgeable"] is False and by_label["mjx.completed"]["judgeable"]
    assert doc["rows"][0]["not_judgeable"][0]["round_off"] == pytest.approx(
        EPS[Precision.FLOAT32] * 100
    )


def test_a_float32_plant_on_a_real_case(monkeypatch):
    """The runner on a fast case with the analytic plant taken as float32: its 1e-9 m and 1e-10
    bounds are below float32 round-off for a 100 m, O(1) case, so not judgeable; the case does
    not fail for it."""
    monkeypatch.setattr(runner, "plant_precision", lambda plant, scene: Precision.FLOAT32)
    row = runner.run_case("zero_gravity", ("analytic",))
    assert row.plant_verdict("analytic") is Verdict.NOT_JUDGEABLE
    assert {x.check for x in row.not_judgeable} == {
        "analytic.com_path_vs_centre_of_mass",
        "analytic.invariants",
    }
    assert row.verdict is Verdict.PASS and all(c.passed for c in row.checks)
