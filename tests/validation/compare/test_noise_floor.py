"""The referee's noise floor: its round-off scale is the largest control force across the plants,
its parts are the threshold's fraction (of the absolute part, not of the effective bound) and that
round-off, and a round-off residue on a signal zero in exact arithmetic names no outlier."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from validation.compare.checks import Check, Comparison, Group, Series, Subject
from validation.compare.noise_floor import (
    FloorPart,
    NoiseFloor,
    floor_rule_text,
    roundoff_scales,
    typical,
)
from validation.compare.referee import Clause, VerdictKind, referee, rule, rule_text
from validation.compare.thresholds import (
    DEFAULTS,
    REFEREE_NOISE_FRACTION,
    REFEREE_ROUNDOFF_FORCE,
    thresholds_for,
)

P_AM, P_AP, P_MP = Subject.BOTH, Subject.ANALYTIC_PINOCCHIO, Subject.MUJOCO_PINOCCHIO


def _zero_torque_comparison(force: float) -> Comparison:
    """Three plants on a signal zero in exact arithmetic (the torque of a rod through C with only
    the masses controlled): the analytic plant's round-off 5e-8 N·m from both others, which agree
    to 1e-12 N·m; the control forces of every plant reach ``force`` N. The relative check's scale
    is its floor 1 N·m (the reference torque is round-off)."""
    th = DEFAULTS["control_torque"]
    checks = tuple(
        Check("control_torque", s, v, th.value, "1", v <= th.value, "test", scale=1.0)
        for s, v in ((P_AM, 5e-8), (P_AP, 5e-8), (P_MP, 1e-12))
    )
    t = np.linspace(0.0, 1.0, 11)
    series = tuple(
        Series(
            f"{p}.rod_force_1",
            "rod force on mass 1",
            "N",
            Group.CONTROL,
            Subject(p),
            t,
            force * np.sin(3 * t),
        )
        for p in ("analytic", "mujoco", "pinocchio")
    )
    return Comparison("zero torque", t, series, checks, (), thresholds_for())


def test_round_off_on_a_zero_signal_is_not_an_outlier():
    """5e-8 N·m of round-off against control forces of 2.5e5 N: the round-off part of the floor
    (REFEREE_ROUNDOFF_FORCE ε × 2.5e5) is above 5e-8, so all agree, and the sentence says the
    round-off set the floor. Without the forces the threshold part alone (1e-9) would name the
    analytic plant."""
    (v,) = referee(_zero_torque_comparison(2.5e5))
    peak = 2.5e5 * np.abs(np.sin(3 * np.linspace(0.0, 1.0, 11))).max()  # the forces' largest |F|
    assert v.floor == pytest.approx(REFEREE_ROUNDOFF_FORCE * 2.220446049250313e-16 * peak)
    assert v.floor > 5e-8
    assert v.kind is VerdictKind.AGREE and v.clause is Clause.BELOW_FLOOR
    assert v.floor_set_by is FloorPart.ROUND_OFF
    assert "round-off, 1e5 ε × largest control force" in v.text

    small = referee(_zero_torque_comparison(1.0))[0]  # forces of 1 N: the threshold part rules
    assert small.floor_set_by is FloorPart.THRESHOLD and small.floor == pytest.approx(1e-9)
    assert small.kind is VerdictKind.OUTLIER and small.outlier == "analytic"


def test_round_off_scale_is_the_largest_force_across_plants():
    """The scale is the largest |F| of any plant over the run (independently: the sine's peak
    on the grid), and the floor's round-off part is REFEREE_ROUNDOFF_FORCE ε × scale / 1 N·m."""
    cmp = _zero_torque_comparison(2.5e5)
    peak = 2.5e5 * np.abs(np.sin(3 * np.linspace(0.0, 1.0, 11))).max()
    scale = roundoff_scales(cmp)["control_torque"]
    assert scale.value == pytest.approx(peak, rel=1e-15)
    floor = NoiseFloor.of(1e-6, scale, divisor=1.0)
    assert floor.roundoff_part == pytest.approx(
        REFEREE_ROUNDOFF_FORCE * 2.220446049250313e-16 * peak
    )
    assert floor.value == floor.roundoff_part and floor.threshold_part == pytest.approx(1e-9)


def test_the_rule_states_the_floor_in_its_own_words():
    assert floor_rule_text() in rule_text()


# ---------------------------------------------------------------------------------------------
# Scale-aware bounds: the floor is a fraction of the absolute part
# ---------------------------------------------------------------------------------------------


def _scaled_checks(values: dict[Subject, float], scale: float) -> dict[Subject, Check]:
    """velocity_C checks at a ``scale`` m/s motion: bound 1e-5 + 1e-7 × scale m/s."""
    th = DEFAULTS["velocity_C"]
    b = th.bound(scale)
    return {
        s: Check(
            "velocity_C",
            s,
            v,
            b.value,
            "m/s",
            v <= b.value,
            "test",
            absolute_part=b.absolute,
            relative_part=b.relative,
            magnitude=b.scale,
            decided_by=b.decided_by,
        )
        for s, v in values.items()
    }


def test_the_floor_is_a_fraction_of_the_absolute_part_not_of_the_effective_bound():
    """paper_example2's velocity of C: MuJoCo's RK4 2.2e-7 m/s from two DOP853 plants that agree
    to 3.5e-11 m/s, at |Ṙ| = 186 m/s. A thousandth of the effective bound (2.9e-5 m/s) would be
    2.9e-8 m/s, and 2.2e-7 is not ten times that: the outlier would go unnamed. The floor is a
    thousandth of the absolute part, 1e-8 m/s, and MuJoCo is named, as before the bound scaled."""
    checks = _scaled_checks({P_AM: 2.154e-7, P_AP: 3.46e-11, P_MP: 2.154e-7}, 186.0)
    first = next(iter(checks.values()))
    assert first.threshold == pytest.approx(1e-5 + 1.86e-5)
    v = rule("velocity_C", checks)
    assert v.floor == pytest.approx(REFEREE_NOISE_FRACTION * 1e-5)
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "mujoco"
    assert v.threshold == first.threshold  # the verdict shows the bound the checks used


def test_the_referee_of_a_comparison_takes_the_absolute_part():
    """Through :func:`referee`, on a comparison whose checks carry relative parts."""
    checks = _scaled_checks({P_AM: 2.154e-7, P_AP: 3.46e-11, P_MP: 2.154e-7}, 186.0)
    cmp = Comparison("s", np.zeros(1), (), tuple(checks.values()))
    (v,) = referee(cmp)
    assert v.quantity == "velocity_C" and v.noise.threshold_part == pytest.approx(1e-8)
    assert v.kind is VerdictKind.OUTLIER and v.outlier == "mujoco"


def test_a_plant_that_runs_away_does_not_raise_the_others_floor():
    """One plant's control forces grow a million times (it diverges): the round-off scale is a
    plant of the majority's largest force, not the runaway's, so the floor the two others are
    judged by stays theirs (the lower median of the plants' largest forces)."""
    cmp = _zero_torque_comparison(2.5e5)
    runaway = tuple(
        dataclasses.replace(s, values=s.values * 1e6) if s.subject.value == "analytic" else s
        for s in cmp.series
    )
    scale = roundoff_scales(dataclasses.replace(cmp, series=runaway))["control_torque"]
    assert scale.value == pytest.approx(roundoff_scales(cmp)["control_torque"].value, rel=1e-15)
    assert typical([3.0, 1.0, 2.0, 1e9]) == 2.0 and typical([5.0, 1e9]) == 5.0
