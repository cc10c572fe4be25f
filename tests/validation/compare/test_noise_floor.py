"""The referee's noise floor: its round-off scale is the largest control force across the plants,
and its parts are the threshold's fraction and that round-off."""

from __future__ import annotations

import numpy as np
import pytest

from validation.compare.checks import Comparison, Group, Series, Subject
from validation.compare.noise_floor import NoiseFloor, floor_rule_text, roundoff_scales
from validation.compare.referee import rule_text
from validation.compare.thresholds import REFEREE_ROUNDOFF_FORCE, thresholds_for


def _zero_torque_comparison(force: float) -> Comparison:
    """Three plants whose control forces reach ``force`` N (a rod force ``force · sin 3t``)."""
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
    return Comparison("zero torque", t, series, (), (), thresholds_for())


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
