"""The threshold record: backwards-compatible construction, the bound ``atol + rtol · scale`` and
which part decides it, and refusal of bad input naming the field."""

from __future__ import annotations

import math

import pytest

from analytic.threshold import Bound, BoundPart, Threshold, ThresholdSource


def test_a_threshold_built_as_before_has_no_relative_part():
    """Positional construction as the project's records were written (name, value, unit,
    reason): rtol 0, so the bound is the value whatever the scale."""
    th = Threshold("position_C", 1e-6, "m", "why")
    assert th.rtol == 0.0 and th.source is ThresholdSource.DEFAULT
    for scale in (0.0, 1.0, 1e6):
        b = th.bound(scale)
        assert b.value == 1e-6 and b.relative == 0.0 and b.decided_by is BoundPart.ABSOLUTE


def test_bound_is_atol_plus_rtol_times_scale():
    th = Threshold("rod_velocities", 1e-5, "m/s", "why", rtol=1e-7)
    b = th.bound(1000.0)
    # scipy's atol + rtol·|y| with atol 1e-5 m/s, rtol 1e-7, |y| = 1000 m/s: 1e-5 + 1e-4
    assert b.absolute == 1e-5 and b.relative == pytest.approx(1e-4, rel=1e-15)
    assert b.value == pytest.approx(1.1e-4, rel=1e-15) and b.scale == 1000.0
    assert b.decided_by is BoundPart.RELATIVE
    small = th.bound(10.0)  # 1e-6 relative part < 1e-5 absolute
    assert small.value == pytest.approx(1.1e-5, rel=1e-15)
    assert small.decided_by is BoundPart.ABSOLUTE


def test_the_absolute_part_decides_a_tie():
    """At the scale where the parts are equal the absolute part is named: the relative part
    decides only where it is the larger."""
    b = Bound(1e-6, 1e-6, 10.0)
    assert b.decided_by is BoundPart.ABSOLUTE and b.value == 2e-6
    assert Bound(1e-6, 1.0000001e-6, 10.0).decided_by is BoundPart.RELATIVE


def test_bound_parts_are_named_by_their_strings():
    assert BoundPart("absolute") is BoundPart.ABSOLUTE
    assert BoundPart("relative") is BoundPart.RELATIVE


@pytest.mark.parametrize("rtol", [-1e-7, math.nan, math.inf, "1e-7", True])
def test_a_bad_rtol_is_refused_naming_the_field(rtol):
    with pytest.raises(ValueError, match=r"thresholds\.position_C\.rtol: .*got"):
        Threshold("position_C", 1e-6, "m", "why", rtol=rtol)


def test_a_relative_threshold_cannot_also_have_an_rtol():
    """A relative threshold's value is already a fraction of its scale."""
    with pytest.raises(ValueError, match=r"thresholds\.rod_forces\.rtol: must be 0"):
        Threshold("rod_forces", 1e-6, "1", "why", relative=True, floor=1.0, rtol=1e-7)
    ok = Threshold("rod_forces", 1e-6, "1", "why", relative=True, floor=1.0)
    assert ok.rtol == 0.0


@pytest.mark.parametrize("scale", [-1.0, math.nan, math.inf])
def test_a_bad_scale_is_refused_naming_the_field(scale):
    th = Threshold("velocity_C", 1e-5, "m/s", "why", rtol=1e-7)
    with pytest.raises(ValueError, match=r"thresholds\.velocity_C\.scale: .*got"):
        th.bound(scale)


def test_the_existing_checks_still_refuse_bad_values():
    with pytest.raises(ValueError, match=r"thresholds\.x: must be a finite non-negative"):
        Threshold("x", -1.0, "m", "why", rtol=1e-7)
    with pytest.raises(ValueError, match=r"thresholds\.x\.floor"):
        Threshold("x", 1.0, "1", "why", relative=True)
