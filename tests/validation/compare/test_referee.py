"""The referee: three plants, one outlier named; the plant protocol; N-plant comparisons.

Planted outliers (a MuJoCo run at a coarse step, a plant whose body inertia is perturbed) must be
named for the quantity they spoil, while the two faithful plants are seen to agree. The rule itself
is checked on synthetic values at its boundaries.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.plant import AnalyticPlant, AnalyticSettings, Plant
from analytic.trajectory import Engine, RunStatus
from mj_bridge.plants import (
    PLANTS,
    MujocoPlant,
    MujocoRunSettings,
    PinocchioPlant,
    installed_plants,
    parse_plants,
    plant,
)
from tests.support.mj_scenes import paper_scene
from validation.compare.checks import Check, Subject, compare_plants
from validation.compare.referee import VerdictKind, referee, rule
from validation.compare.thresholds import REFEREE_NOISE_FRACTION, REFEREE_SEPARATION

HAVE_PIN = not PinocchioPlant.unavailable()
needs_pin = pytest.mark.skipif(not HAVE_PIN, reason="pin (Pinocchio) is not installed")

RK4_ORDER_BAND = (3.5, 4.5)
"""Observed order of MuJoCo's distance to the other two plants under dt halving: RK4 is 4th order;
±0.5 covers the pre-asymptotic terms at these steps (ω dt ≤ 0.03)."""


# ---------------------------------------------------------------------------------------------
# The rule on synthetic values
# ---------------------------------------------------------------------------------------------


def _checks(values: dict[Subject, float], threshold: float = 1e-6) -> dict[Subject, Check]:
    return {
        s: Check("position_C", s, v, threshold, "m", v <= threshold, "test")
        for s, v in values.items()
    }


P_AM, P_AP, P_MP = Subject.BOTH, Subject.ANALYTIC_PINOCCHIO, Subject.MUJOCO_PINOCCHIO


def test_outlier_is_the_plant_outside_the_closest_pair():
    v = rule("position_C", _checks({P_AM: 1.8e-8, P_AP: 9e-12, P_MP: 1.8e-8}), {"mujoco": "MJ"})
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "mujoco"
    assert "MJ is the outlier" in v.text
    assert "agree below the noise floor 1e-09 m (9e-12 m)" in v.text  # 9e-12 counts as the floor


def test_outlier_needs_the_separation():
    th = 1e-6
    d1 = 1e-8
    just = _checks({P_AM: d1, P_AP: REFEREE_SEPARATION * d1, P_MP: REFEREE_SEPARATION * d1}, th)
    assert rule("position_C", just).outlier == "pinocchio"
    short = _checks({P_AM: d1, P_AP: 0.9 * REFEREE_SEPARATION * d1, P_MP: 9 * d1}, th)
    assert rule("position_C", short).kind is VerdictKind.AGREE


def test_everything_below_the_noise_floor_agrees():
    th = 1e-6
    tiny = 0.9 * REFEREE_NOISE_FRACTION * th
    v = rule("position_C", _checks({P_AM: tiny, P_AP: tiny / 1e4, P_MP: tiny}, th))
    assert v.kind is VerdictKind.AGREE and v.outlier == ""


def test_three_way_disagreement_is_said():
    v = rule("position_C", _checks({P_AM: 2e-6, P_AP: 5e-6, P_MP: 9e-6}))
    assert v.kind is VerdictKind.DISAGREE and "all three disagree" in v.text


def test_a_value_that_could_not_be_computed_counts_as_the_worst():
    v = rule("position_C", _checks({P_AM: math.nan, P_AP: 1e-12, P_MP: math.nan}))
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "mujoco"


def test_rule_needs_three_pairs():
    with pytest.raises(ValueError, match="three pairs"):
        rule("position_C", _checks({P_AM: 1.0, P_AP: 1.0}))


# ---------------------------------------------------------------------------------------------
# The protocol
# ---------------------------------------------------------------------------------------------


def test_registry_and_protocol():
    assert list(PLANTS) == [Engine.ANALYTIC, Engine.MUJOCO, Engine.PINOCCHIO]
    for e, cls in PLANTS.items():
        assert issubclass(cls, Plant) and cls.engine == e
        assert dataclasses.is_dataclass(cls.settings_type)
    assert installed_plants()[:2] == (Engine.ANALYTIC, Engine.MUJOCO)
    assert parse_plants("mujoco, analytic") == (Engine.ANALYTIC, Engine.MUJOCO)
    with pytest.raises(ValueError, match=r"^plants: unknown plant 'bullet'"):
        plant("bullet")
    with pytest.raises(ValueError, match=r"^plants: give at least one"):
        parse_plants(" , ")


def test_settings_are_checked_naming_the_field():
    with pytest.raises(ValueError, match=r"^dt: "):
        MujocoRunSettings(dt=-1.0)
    with pytest.raises(ValueError, match=r"^integrator: "):
        MujocoRunSettings(integrator="leapfrog")
    with pytest.raises(ValueError, match=r"^rtol: "):
        AnalyticSettings(rtol=math.nan)
    with pytest.raises(ValueError, match=r"^settings: the analytic plant takes AnalyticSettings"):
        AnalyticPlant().simulate(paper_scene("paper_example1"), MujocoRunSettings(), t_end=0.01)
    with pytest.raises(ValueError, match=r"^t_end: "):
        MujocoPlant().simulate(paper_scene("paper_example1"), t_end=-1.0)


def test_a_plant_refuses_an_effect_it_lacks_before_running():
    class RigidOnly(AnalyticPlant):
        effects = frozenset({Effect.GRAVITY})

        def _simulate(self, *args, **kwargs):
            raise AssertionError("must not run")

    with pytest.raises(ValueError, match=r"^scene\.effects: the analytic plant cannot simulate "):
        RigidOnly().simulate(paper_scene("paper_example1"), t_end=0.01)


def test_every_plant_returns_paper_coordinates_on_one_grid():
    scene = paper_scene("paper_example2_controlled")
    runs = [plant(e).simulate(scene, t_end=0.05) for e in installed_plants()]
    for tr in runs:
        assert tr.status is RunStatus.OK
        np.testing.assert_allclose(tr.t, runs[0].t, rtol=0, atol=1e-12)
        assert tr.q.shape == (runs[0].t.size, 7 + scene.n)
        np.testing.assert_allclose(np.linalg.norm(tr.q[:, 3:7], axis=1), 1.0, atol=1e-10)


# ---------------------------------------------------------------------------------------------
# Planted outliers on real runs
# ---------------------------------------------------------------------------------------------


def _three(scene, t_end, **per_plant):
    out = []
    for e in (Engine.ANALYTIC, Engine.MUJOCO, Engine.PINOCCHIO):
        pl = plant(e)
        sc, settings = per_plant.get(e.value, (scene, None))
        out.append(pl.simulate(sc, settings, t_end=t_end))
    return out


@needs_pin
def test_coarse_mujoco_step_is_named_outlier_for_rod_positions():
    scene = paper_scene("paper_example2")
    coarse = MujocoRunSettings(scene.mujoco.integrator, 2.5e-3)
    trs = _three(scene, 1.0, mujoco=(scene, coarse))
    verdicts = {v.quantity: v for v in referee(compare_plants(trs, scene, t_end=1.0))}
    v = verdicts["rod_positions"]
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "mujoco", v.text
    assert v.values["analytic vs pinocchio"] < v.values["analytic vs mujoco"] / REFEREE_SEPARATION


@needs_pin
def test_perturbed_inertia_is_named_outlier_for_attitude():
    scene = paper_scene("paper_example1")
    body = dataclasses.replace(scene.body, inertia=scene.body.inertia * (1 + 1e-4))
    wrong = dataclasses.replace(scene, body=body)
    trs = _three(scene, 1.0, pinocchio=(wrong, None))
    verdicts = {v.quantity: v for v in referee(compare_plants(trs, scene, t_end=1.0))}
    v = verdicts["attitude"]
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "pinocchio", v.text


@needs_pin
def test_mujoco_distance_to_both_falls_at_rk4_order():
    """Example 2, 1 s: MuJoCo's distance to the analytic and the Pinocchio plant, dt and dt/2."""
    scene = paper_scene("paper_example2")
    ana = plant("analytic").simulate(scene, t_end=1.0)
    pin = plant("pinocchio").simulate(scene, t_end=1.0)
    dist = {}
    for dt in (2.5e-3, 1.25e-3):
        mj = plant("mujoco").simulate(
            scene, MujocoRunSettings(scene.mujoco.integrator, dt), t_end=1.0
        )
        cmp = compare_plants([ana, mj, pin], scene, t_end=1.0)
        dist[dt] = {
            other: cmp.check(label).value
            for other, label in (
                ("analytic", "rod_positions"),
                ("pinocchio", "mujoco_vs_pinocchio.rod_positions"),
            )
        }
    for other in ("analytic", "pinocchio"):
        order = math.log2(dist[2.5e-3][other] / dist[1.25e-3][other])
        assert RK4_ORDER_BAND[0] <= order <= RK4_ORDER_BAND[1], (other, order, dist)


def test_without_the_referee_the_report_says_how_to_install_it(tmp_path, monkeypatch):
    from validation.validate import run_validation

    monkeypatch.setattr(PinocchioPlant, "unavailable", classmethod(lambda cls: "planted: no pin"))
    res = run_validation("paper_example1_controlled", tmp_path / "v", t_end=0.05)
    doc = json.loads((tmp_path / "v" / "report.json").read_text())
    assert [p["engine"] for p in doc["plants"]] == ["analytic", "mujoco"]
    assert doc["referee"] == [] and "pip install" in doc["run"]["referee_note"]
    assert res.passed and res.verdicts == ()
    assert "No referee verdict" in (tmp_path / "v" / "report.md").read_text()


@needs_pin
def test_validate_with_three_plants_checks_every_pair(tmp_path):
    from validation.validate import run_validation

    res = run_validation("paper_example1_controlled", tmp_path / "v", t_end=0.05)
    pairs = {c.subject for c in res.checks if c.subject.is_pair}
    assert pairs == {P_AM, P_AP, P_MP}
    assert {c.subject for c in res.checks if c.name == "energy"} == {
        Subject.ANALYTIC,
        Subject.MUJOCO,
        Subject.PINOCCHIO,
    }
    assert res.passed and len(res.verdicts) == 8
    doc = json.loads((tmp_path / "v" / "report.json").read_text())
    assert set(doc["pairwise"]["position_C"]) == {s.value for s in pairs}
    assert len(doc["referee"]) == 8


# ---------------------------------------------------------------------------------------------
# Every verdict follows from the rule as the report prints it
# ---------------------------------------------------------------------------------------------


def _printed_rule(text: str) -> tuple[float, float]:
    """The noise fraction and the separation, read from the report's printed rule."""
    import re

    fraction = re.search(r"the noise floor, ([0-9.e+-]+) × the threshold", text)
    separation = re.search(r"d2 ≥ ([0-9.e+-]+) × max\(d1, noise floor\)", text)
    assert fraction and separation, text
    return float(fraction.group(1)), float(separation.group(1))


def _derive(values: list[float], passed: list[bool], floor: float, k: float) -> str:
    """The verdict of the printed rule, applied by hand to one row."""
    d1, d2, d3 = sorted(values)
    if d3 <= floor:
        return "agree"
    if d2 >= k * max(d1, floor):
        return "outlier"
    return "agree" if all(passed) else "all disagree"


def test_every_verdict_is_derivable_from_the_printed_rule(tmp_path):
    """The report's table and its printed rule give back every verdict: rows drawn over every
    clause (all below the floor with large ratios, as measured for the attitude; outliers with the
    closest pair below or above the floor; three similar values inside and over the threshold)."""
    from validation.compare.checks import Comparison
    from validation.compare.thresholds import thresholds_for
    from validation.report.report import render_markdown

    rng = np.random.default_rng(7)
    th = 1e-6
    rows = [
        [3.1e-11, 3.1e-11, 2.0e-12],  # 15x apart, below the floor (the measured attitude)
        [5e-12, 3e-8, 3.1e-8],  # outlier, closest pair below the floor
        [1e-8, 2e-7, 3e-7],  # outlier, closest pair above the floor
        [1e-7, 3e-7, 5e-7],  # no outlier, inside the threshold
        [2e-6, 5e-6, 9e-6],  # no outlier, over it
    ]
    rows += [list(10.0 ** rng.uniform(-13, -5, 3)) for _ in range(40)]
    verdicts = []
    for vals in rows:
        checks = _checks(dict(zip((P_AM, P_AP, P_MP), vals, strict=True)), th)
        verdicts.append(dataclasses.replace(rule("position_C", checks), quantity="position_C"))
    cmp = Comparison("s", np.zeros(1), (), (), (), thresholds_for())
    md = render_markdown(cmp, "PASSED", "", [], {}, verdicts)
    fraction, k = _printed_rule(md)
    section = md.split("## Referee", 1)[1].split("\n## ", 1)[0]
    table = [ln for ln in section.splitlines() if ln.startswith("| position_C |")]
    assert len(table) == len(rows)
    for line, vals, v in zip(table, rows, verdicts, strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        printed_vals = [float(c) for c in cells[1:4]]
        threshold, floor = float(cells[4]), float(cells[5])
        assert floor == pytest.approx(fraction * threshold, rel=1e-3)
        assert printed_vals == pytest.approx(vals, rel=1e-3)
        kind = cells[7].split(":")[0]
        assert kind == _derive(vals, [x <= threshold for x in vals], fraction * threshold, k)
        assert kind == v.kind.value
        if v.clause.value == "below noise floor":  # the sentence relies on the floor: it says so
            assert "below the noise floor" in v.text


def test_the_measured_attitude_row_says_it_relies_on_the_floor():
    """Attitude at Example 1's settings: analytic 3.1e-11 rad from both others, MuJoCo-Pinocchio
    2.0e-12 rad (15x apart): agreement by the noise floor, said in the sentence with its value."""
    th = 1e-6
    checks = {
        s: Check("attitude", s, v, th, "rad", True, "test")
        for s, v in {P_AM: 3.139e-11, P_AP: 3.134e-11, P_MP: 2.030e-12}.items()
    }
    v = rule("attitude", checks)
    assert v.kind is VerdictKind.AGREE
    floor = REFEREE_NOISE_FRACTION * th
    assert v.floor == pytest.approx(floor)
    assert f"below the noise floor {floor:.2g} rad" in v.text
