"""The referee: N plants, the outliers named with their distances; the plant protocol.

Planted outliers (a MuJoCo run at a coarse step, a plant whose body inertia is perturbed, among
three and among four plants) must be named for the quantity they spoil, while the faithful plants
are seen to agree. The rule itself is checked on planted distance tables of two to six plants, at
its boundaries, against the three-plant rule as first written, and its noise floor on a signal
that is zero in exact arithmetic.
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
from validation.compare.checks import Check, Comparison, Subject, compare_plants
from validation.compare.noise_floor import FloorPart
from validation.compare.referee import Clause, Outlier, VerdictKind, decide, referee, rule
from validation.compare.thresholds import (
    REFEREE_NOISE_FRACTION,
    REFEREE_ROUNDOFF_FORCE,
    REFEREE_SEPARATION,
    thresholds_for,
)

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
    assert v.group == ("analytic", "pinocchio")
    assert v.outliers == (Outlier("mujoco", 1.8e-8),)
    assert "MJ is the outlier, 1.8e-08 m from the others" in v.text
    # 9e-12 counts as the floor; the sentence says so, with the floor and where it comes from
    assert "agree below the noise floor 1e-09 m = 0.001 × threshold (9e-12 m)" in v.text


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
    assert v.kind is VerdictKind.AGREE and v.outlier == "" and v.outliers == ()
    assert v.group == ("analytic", "mujoco", "pinocchio")


def test_three_way_disagreement_is_said():
    v = rule("position_C", _checks({P_AM: 2e-6, P_AP: 5e-6, P_MP: 9e-6}))
    assert v.kind is VerdictKind.DISAGREE and "all three disagree" in v.text
    assert "noise floor 1e-09 m" in v.text


def test_a_value_that_could_not_be_computed_counts_as_the_worst():
    v = rule("position_C", _checks({P_AM: math.nan, P_AP: 1e-12, P_MP: math.nan}))
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "mujoco"
    assert v.outliers[0].distance == math.inf


def test_nothing_computed_names_no_plant():
    """Every distance infinite: no group has a finite spread, so no plant is named (the
    three-plant rule as first written named one by the pairs' order)."""
    v = rule("position_C", _checks({P_AM: math.nan, P_AP: math.nan, P_MP: math.nan}))
    assert v.kind is VerdictKind.DISAGREE and v.outlier == ""


def test_a_plant_at_distance_zero_is_no_outlier():
    """A floor of 0 (threshold 0, no round-off scale) and a at distance 0 from b and c: the
    three-plant rule as first written named b or c by the pairs' order; no plant is named."""
    d = {("a", "b"): 0.0, ("a", "c"): 0.0, ("b", "c"): 1e-9}
    r = decide("abc", d, {p: True for p in d}, 0.0)
    assert r.kind is VerdictKind.AGREE and r.outliers == ()


def test_rule_needs_every_pair():
    with pytest.raises(ValueError, match=r"^checks: the referee needs every pair"):
        rule("position_C", _checks({P_AM: 1.0, P_AP: 1.0}))
    with pytest.raises(ValueError, match=r"^distance: no value for the pair b vs c"):
        decide(("a", "b", "c"), {("a", "b"): 1.0, ("a", "c"): 1.0}, {}, 1e-9)
    with pytest.raises(ValueError, match=r"^plants: "):
        decide(("a",), {}, {}, 1e-9)


# ---------------------------------------------------------------------------------------------
# N plants: planted distance tables
# ---------------------------------------------------------------------------------------------

FLOOR = 1e-9  # the default threshold part of the floor of a 1e-6 m threshold
TH = 1e-6


def _table(plants: str, planted: dict[str, float], base: float) -> dict[tuple[str, str], float]:
    """Every pair of ``plants`` (one letter each) at ``base``, except the pairs ``planted``
    (``"ab": d``)."""
    out = {}
    for i, a in enumerate(plants):
        for b in plants[i + 1 :]:
            out[(a, b)] = planted.get(a + b, planted.get(b + a, base))
    return out


def _decide(plants: str, planted: dict[str, float], base: float = 2e-10):
    d = _table(plants, planted, base)
    return decide(tuple(plants), d, {p: v <= TH for p, v in d.items()}, FLOOR)


def _far(plant: str, others: str, d: float) -> dict[str, float]:
    """``plant`` at distance ``d`` from each of ``others``."""
    return {plant + o: d for o in others}


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_all_below_the_floor_agree(n):
    r = _decide("abcdef"[:n], {"ab": 0.9 * FLOOR})
    assert r.kind is VerdictKind.AGREE and r.clause is Clause.BELOW_FLOOR
    assert r.group == tuple("abcdef"[:n]) and r.outliers == ()


def test_two_plants_agree_or_disagree_but_name_no_outlier():
    assert _decide("ab", {"ab": 5e-7}).kind is VerdictKind.AGREE  # within the threshold
    r = _decide("ab", {"ab": 5e-6})
    assert r.kind is VerdictKind.DISAGREE and r.outliers == ()


@pytest.mark.parametrize("n", [4, 5, 6])
def test_one_outlier_among_n(n):
    plants = "abcdef"[:n]
    # the last plant 3e-8 .. 5e-8 from the others, who agree to 2e-10 (below the floor)
    planted = {
        plants[-1] + o: (3e-8, 4e-8, 5e-8, 3.5e-8, 4.5e-8)[i] for i, o in enumerate(plants[:-1])
    }
    r = _decide(plants, planted)
    assert r.kind is VerdictKind.OUTLIER and r.clause is Clause.SEPARATED
    assert r.group == tuple(plants[:-1])
    assert r.outliers == (Outlier(plants[-1], 3e-8),)  # its smallest distance to a member


def test_two_outliers_each_with_its_distance():
    """Five plants: a, b, c agree to 1e-10; d is 2e-7 and e is 4e-6 from them (and 3e-6 from
    each other): both outside the majority, the farther first."""
    planted = {**_far("d", "abc", 2e-7), **_far("e", "abc", 4e-6), "de": 3e-6}
    r = _decide("abcde", planted, base=1e-10)
    assert r.kind is VerdictKind.OUTLIER and r.group == ("a", "b", "c")
    assert r.outliers == (Outlier("e", 4e-6), Outlier("d", 2e-7))


def test_a_pair_of_twins_against_a_majority():
    """Five plants: d and e agree with each other to 1e-12 (twins: two runs of one slip), 1e-6
    from a, b, c, who agree to 3e-9: the twins are both outliers; the majority is the group."""
    planted = {**_far("d", "abc", 1e-6), **_far("e", "abc", 1.1e-6), "de": 1e-12}
    r = _decide("abcde", planted, base=3e-9)
    assert r.kind is VerdictKind.OUTLIER and r.group == ("a", "b", "c")
    assert {o.plant for o in r.outliers} == {"d", "e"}
    assert dict((o.plant, o.distance) for o in r.outliers) == {"d": 1e-6, "e": 1.1e-6}


def test_twins_against_twins_split():
    """Four plants, two pairs of twins 1e-7 apart: no group holds a majority."""
    r = _decide("abcd", {"ab": 1e-11, "cd": 2e-11}, base=1e-7)
    assert r.kind is VerdictKind.SPLIT and r.clause is Clause.NO_MAJORITY
    assert r.groups == (("a", "b"), ("c", "d")) and r.outliers == () and r.group == ()


def test_three_against_three_split():
    planted = {a + b: 5e-6 for a in "abc" for b in "def"}
    r = _decide("abcdef", planted, base=4e-10)
    assert r.kind is VerdictKind.SPLIT
    assert r.groups == (("a", "b", "c"), ("d", "e", "f"))


def test_twins_and_scattered_plants_split():
    """Four plants: only a and b confirm each other; c and d are far from them and from each
    other: a group, but not a majority, so the plants split (c and d alone)."""
    planted = {"ab": 1e-10, "cd": 7e-6, **_far("c", "ab", 3e-6), **_far("d", "ab", 5e-6)}
    r = _decide("abcd", planted)
    assert r.kind is VerdictKind.SPLIT and r.groups == (("a", "b"),)


def test_no_group_over_the_threshold_is_all_disagree():
    """Four plants at distances within a factor of 3 of each other, over the threshold."""
    planted = {"ab": 2e-6, "ac": 3e-6, "ad": 4e-6, "bc": 5e-6, "bd": 6e-6, "cd": 2.5e-6}
    r = _decide("abcd", planted)
    assert r.kind is VerdictKind.DISAGREE and r.clause is Clause.OVER_THRESHOLD


def test_no_group_within_the_threshold_agrees():
    planted = {"ab": 2e-8, "ac": 3e-8, "ad": 4e-8, "bc": 5e-8, "bd": 6e-8, "cd": 2.5e-8}
    r = _decide("abcd", planted)
    assert r.kind is VerdictKind.AGREE and r.clause is Clause.WITHIN_THRESHOLD


def test_the_tightest_majority_group_decides():
    """Five plants: a, b, c within 1e-10; d 1e-8 from them; e 1e-5 from all. {a, b, c} and
    {a, b, c, d} are both separated majorities (nested): the innermost is the group, so d is named
    beside e, as it is without e (a far plant does not hide a near one)."""
    planted = {**_far("d", "abc", 1e-8), **_far("e", "abcd", 1e-5)}
    r = _decide("abcde", planted, base=1e-10)
    assert r.kind is VerdictKind.OUTLIER and r.group == ("a", "b", "c")
    assert r.outliers == (Outlier("e", 1e-5), Outlier("d", 1e-8))
    without_e = _decide("abcd", _far("d", "abc", 1e-8), base=1e-10)
    assert without_e.group == ("a", "b", "c") and without_e.outliers == (Outlier("d", 1e-8),)


def test_n_plant_verdict_names_the_outlier_and_states_the_floor():
    subjects = ["p vs q", "p vs r", "p vs s", "q vs r", "q vs s", "r vs s"]  # any plant names
    values = dict(zip(subjects, [1e-10, 1e-10, 4e-7, 2e-10, 5e-7, 6e-7], strict=True))
    v = rule("position_C", _checks(values), {"s": "Engine S"})
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "s" and v.group == ("p", "q", "r")
    assert "Engine S is the outlier, 4e-07 m from the others" in v.text
    assert "noise floor 1e-09 m = 0.001 × threshold" in v.text
    doc = v.to_dict()
    assert doc["outliers"] == [{"plant": "s", "distance": 4e-7}]
    assert doc["group"] == ["p", "q", "r"] and doc["noise_floor_parts"]["decided_by"] == "threshold"


# ---------------------------------------------------------------------------------------------
# Three plants: the N-plant rule is the three-plant rule
# ---------------------------------------------------------------------------------------------


def _three_plant_rule(values: list[float], passed: list[bool], floor: float, k: float) -> str:
    """The three-plant rule as first written (d1 ≤ d2 ≤ d3), applied by hand to one row."""
    d1, d2, d3 = sorted(values)
    if d3 <= floor:
        return "agree"
    if d2 >= k * max(d1, floor):
        return "outlier"
    return "agree" if all(passed) else "all disagree"


def test_three_plants_n_rule_equals_the_three_plant_rule():
    """20 000 random distance triples (log-uniform over eight decades around the floor and the
    threshold, plus exact ties, exact multiples k·d1 and values at the floor): both rules give the
    same verdict and, for an outlier, the same plant."""
    rng = np.random.default_rng(11)
    k, th = REFEREE_SEPARATION, TH
    rows = [list(10.0 ** rng.uniform(-13, -4, 3)) for _ in range(20_000)]
    for _ in range(1_000):  # boundaries: ties, exact separations, the floor itself
        d1 = 10.0 ** rng.uniform(-12, -5)
        rows += [
            [d1, k * d1, k * d1],
            [d1, k * d1 * (1 - 1e-12), k * d1],
            [d1, d1, 10 * k * d1],
            [FLOOR, FLOOR, FLOOR],
            [d1 / 1e3, k * FLOOR, 2 * k * FLOOR],
            [d1 / 1e3, k * FLOOR * (1 - 1e-12), 2 * k * FLOOR],
        ]
    for vals in rows:
        vals = [float(x) for x in rng.permutation(vals)]
        d = dict(zip((("a", "b"), ("a", "c"), ("b", "c")), vals, strict=True))
        r = decide("abc", d, {p: x <= th for p, x in d.items()}, FLOOR)
        want = _three_plant_rule(vals, [x <= th for x in vals], FLOOR, k)
        assert r.kind.value == want, (vals, r)
        if want == "outlier":  # the plant outside the closest pair
            closest = min(d, key=d.get)
            assert [o.plant for o in r.outliers] == [x for x in "abc" if x not in closest]


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

    fraction = re.search(r"the larger of ([0-9.e+-]+) × the threshold", text)
    separation = re.search(r"d2 ≥ ([0-9.e+-]+) × max\(d1, noise floor\)", text)
    assert fraction and separation, text
    return float(fraction.group(1)), float(separation.group(1))


def test_every_verdict_is_derivable_from_the_printed_rule(tmp_path):
    """The report's table and its printed rule give back every verdict: rows drawn over every
    clause (all below the floor with large ratios, as measured for the attitude; outliers with the
    closest pair below or above the floor; three similar values inside and over the threshold)."""
    from validation.report.markdown import render_markdown

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
        threshold, floor, set_by = float(cells[4]), float(cells[5]), cells[6]
        assert set_by == "threshold"
        assert floor == pytest.approx(fraction * threshold, rel=1e-3)
        assert printed_vals == pytest.approx(vals, rel=1e-3)
        kind = cells[8].split(":")[0]
        want = _three_plant_rule(vals, [x <= threshold for x in vals], fraction * threshold, k)
        assert kind == want == v.kind.value
        if v.clause.value == "below noise floor":  # the sentence relies on the floor: it says so
            assert "below the noise floor" in v.text
        assert f"noise floor {floor:.2g} m = " in v.text  # every sentence states its floor


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
    assert f"below the noise floor {floor:.2g} rad = 0.001 × threshold" in v.text


# ---------------------------------------------------------------------------------------------
# Four real plants
# ---------------------------------------------------------------------------------------------


@needs_pin
def test_four_plants_name_the_perturbed_one_with_its_distance():
    """The analytic, MuJoCo, Pinocchio and Drake plants on the controlled Example 1 (0.5 s), the
    Drake plant given the body inertia off by 1e-4 (relative). The controller makes ω follow its
    requirement whatever the inertia (Eq. 84), so every state agrees; the torque it needs carries
    the error: τ is linear in J (J ω̇ + ω × J ω), so Drake's torque is off by O(1e-4) relative.
    Drake is the control torque's outlier, at its smallest pair value; the other three are the
    group."""
    pytest.importorskip("pydrake")
    from mj_bridge.drake_plugin import DrakePlant

    scene = paper_scene("paper_example1_controlled")
    body = dataclasses.replace(scene.body, inertia=scene.body.inertia * (1 + 1e-4))
    wrong = dataclasses.replace(scene, body=body)
    t_end = 0.5
    trs = [plant(e).simulate(scene, t_end=t_end) for e in ("analytic", "mujoco", "pinocchio")]
    trs.append(DrakePlant().simulate(wrong, t_end=t_end))
    cmp = compare_plants(trs, scene, t_end=t_end)
    verdicts = {v.quantity: v for v in referee(cmp, trajectories=trs)}
    v = verdicts["control_torque"]
    assert v.kind is VerdictKind.OUTLIER, v.text
    assert v.group == ("analytic", "mujoco", "pinocchio") and v.outlier == "drake"
    (o,) = v.outliers
    to_drake = [x for p, x in v.values.items() if "drake" in p]
    assert len(to_drake) == 3 and o.distance == min(to_drake)
    assert 1e-6 < o.distance < 1e-3  # over the threshold, at the perturbation's order
    assert f"drake is the outlier, {o.distance:.2g} from the others" in v.text
    spread = max(x for p, x in v.values.items() if "drake" not in p)
    assert o.distance >= REFEREE_SEPARATION * max(spread, v.floor)
    for q in ("position_C", "attitude", "angular_velocity"):  # the motion is the requirement's
        assert verdicts[q].kind is VerdictKind.AGREE and len(verdicts[q].group) == 4


@needs_pin
def test_round_off_of_a_real_zero_torque_is_not_an_outlier():
    """A rod through C (d = 0) with only the masses controlled under the identity weighting: the
    control torque is zero in exact arithmetic (MuJoCo and Pinocchio give ~1e-16 of the 2e7 N rod
    forces), but the analytic plant's solve leaves a residue of ~4e-12 of them (a variant of
    ``hard/rod_through_C`` with a light body, J ~ 110 kg·m², and heavy masses). Every distance is
    above the threshold part of the floor (1e-9), and the round-off part, REFEREE_ROUNDOFF_FORCE ε
    × the largest control force of the three plants, decides: all agree, said with the round-off."""
    import tomllib
    from pathlib import Path

    import validation
    from analytic.scene.loading import scene_from_dict

    src = Path(validation.__file__).parent / "scenes" / "hard" / "rod_through_C.toml"
    d = tomllib.loads(src.read_text())
    for key in ("thresholds", "hard_case"):
        d.pop(key)
    d["scene"]["effects"].append("control.masses")
    d["rod"]["axis"] = [-2 / 7, -6 / 7, 3 / 7]
    d["masses"]["mass"] = [30.0, 8.0e3, 5.0e4]
    d["body"].update(mass=8.0e4, inertia=[108.0, 114.0, 113.0])
    d["initial"].update(omega=[-14.0, 19.0, 15.6], p=[0.64, -0.04, -0.54])
    d["control"] = {
        "weighting": "identity",
        "masses": {
            "indices": [1, 2, 3],
            "l": [0.8, -1.0, 0.5],
            "lambda": [math.pi / 2, math.pi, math.pi / 4],
            "alpha": [2.0, 2.0, 2.0],
            "beta": [12.0, 12.0, 12.0],
        },
    }
    scene = scene_from_dict(d)
    trs = [plant(e).simulate(scene, t_end=0.5) for e in ("analytic", "mujoco", "pinocchio")]
    cmp = compare_plants(trs, scene, t_end=0.5)
    v = {v.quantity: v for v in referee(cmp, trajectories=trs)}["control_torque"]
    force = max(
        max(np.abs(tr.rod_forces).max(), np.linalg.norm(tr.torque, axis=1).max()) for tr in trs
    )
    assert min(v.values.values()) > REFEREE_NOISE_FRACTION * v.threshold
    assert v.floor == pytest.approx(REFEREE_ROUNDOFF_FORCE * np.finfo(float).eps * force)
    assert v.kind is VerdictKind.AGREE and v.floor_set_by is FloorPart.ROUND_OFF, v.text
    assert "round-off, 1e5 ε × largest control force" in v.text
