"""The comparison's thresholds: which have a relative part and why its number holds, the scene's
``[thresholds]`` table setting ``rtol``, and bad tables refused naming the field and value."""

from __future__ import annotations

import math
import tomllib

import pytest

from analytic.scene import builtin_scene_path, scene_from_dict
from validation.compare.differences import MAGNITUDES, Difference
from validation.compare.thresholds import (
    DEFAULTS,
    REFEREE_NOISE_FRACTION,
    REFEREE_ROUNDOFF_STATE,
    SCALED,
    STATE_RTOL,
    thresholds_for,
)

EPS = 2.220446049250313e-16  # float64 machine epsilon


def _scene(thresholds: dict | None = None):
    """paper_example1 as a scene read from TOML, with a ``[thresholds]`` table when given."""
    data = tomllib.loads(builtin_scene_path("paper_example1").read_text(encoding="utf-8"))
    if thresholds is not None:
        data["thresholds"] = thresholds
    return scene_from_dict(data, "test")


def test_the_relative_part_belongs_to_the_states_and_the_tracking_laws():
    """The states' differences that grow with the motion and the tracking laws have an rtol; the
    attitude (a unit quaternion's angle), the quaternion norm and the relative thresholds none."""
    assert SCALED <= set(DEFAULTS)
    for name, th in DEFAULTS.items():
        assert (th.rtol > 0) == (name in SCALED), name
        if th.rtol:
            assert not th.relative and th.rtol == STATE_RTOL
    assert "attitude" not in SCALED and DEFAULTS["attitude"].rtol == 0.0
    # every difference with a magnitude of its own has a scale to multiply, and only those
    differences = {d.value for d in Difference}
    assert set(MAGNITUDES) == SCALED & differences


def test_state_rtol_sits_between_the_integrators_error_and_a_modelling_difference():
    """Independent of the code's numbers: RK4 at dt = 2.5e-4 s loses about (ω h)^4 of the state
    per second, at most 15 rad/s · 2.5e-4 s; over a 20 s run that is ~4e-9 (and DOP853 at rtol
    1e-10, ~1e-9). A modelling slip shows at 1e-3 of the motion. The rtol sits more than a decade
    above the worst integration estimate and at least three decades below a modelling slip."""
    rk4_20s = (15 * 2.5e-4) ** 4 * 20
    integration = max(1e-9, rk4_20s)
    assert 3e-9 < integration < 5e-9
    assert STATE_RTOL >= 10 * integration
    assert STATE_RTOL <= 1e-3 / 1e3


def test_the_absolute_parts_still_decide_at_the_scales_they_were_set_for():
    """At 10 m (m/s, rad/s), the paper's bodies and rates, the relative part is at most the
    absolute one: the old bounds are unchanged where they were set."""
    for name in SCALED:
        th = DEFAULTS[name]
        assert th.bound(10.0).relative <= th.value, name


def test_the_referee_round_off_part_never_exceeds_a_thousandth_of_the_relative_part():
    """The referee's floor is a fraction of the absolute part; the states' round-off part
    (1e3 ε × scale) stays below a thousandth of the check's relative part at every scale, so the
    relative part, left out of the floor, would never have been under it either."""
    assert REFEREE_ROUNDOFF_STATE * EPS < REFEREE_NOISE_FRACTION * STATE_RTOL


def test_a_scene_table_sets_rtol_and_value():
    th = thresholds_for(
        _scene(
            {
                "position_C": {"value": 2e-6, "rtol": 1e-8, "reason": "tighter"},
                "rod_velocities": 3e-5,
            }
        )
    )
    assert th["position_C"].value == 2e-6 and th["position_C"].rtol == 1e-8
    assert th["position_C"].source == "scene" and "tighter" in th["position_C"].reason
    assert "default 1e-06 + 1e-07 × scale" in th["position_C"].reason
    # a number is the whole bound, as before bounds had a relative part: no rtol
    assert th["rod_velocities"].value == 3e-5 and th["rod_velocities"].rtol == 0.0
    assert th["velocity_C"] == DEFAULTS["velocity_C"]
    b = th["position_C"].bound(1000.0)
    assert b.value == pytest.approx(2e-6 + 1e-5, rel=1e-15) and b.decided_by == "relative"


def test_a_scene_may_switch_the_relative_part_off():
    th = thresholds_for(_scene({"velocity_C": {"value": 1e-5, "rtol": 0}}))
    assert th["velocity_C"].rtol == 0.0 and th["velocity_C"].bound(1e6).value == 1e-5


def test_an_override_without_rtol_is_the_whole_bound_as_before():
    """Scene files and code written before bounds had a relative part keep their meaning: a
    value given alone (a number or a table without rtol) bounds the difference at every scale."""
    th = thresholds_for(
        _scene({"position_C": 1e-15, "velocity_C": {"value": 1e-9, "reason": "tight"}})
    )
    assert th["position_C"].rtol == 0.0 and th["position_C"].bound(1e4).value == 1e-15
    assert th["velocity_C"].rtol == 0.0 and th["velocity_C"].bound(1e4).value == 1e-9


def test_the_loader_keeps_rtol_in_the_scene():
    sc = _scene({"angular_velocity": {"value": 1e-5, "rtol": 1e-9}})
    assert sc.extra["thresholds"]["angular_velocity"] == {"value": 1e-5, "rtol": 1e-9}


@pytest.mark.parametrize(
    ("table", "field"),
    [
        ({"position_C": {"value": 1e-6, "rtol": -1e-7}}, "thresholds.position_C.rtol"),
        ({"position_C": {"value": 1e-6, "rtol": math.inf}}, "thresholds.position_C.rtol"),
        ({"position_C": {"value": 1e-6, "rtol": "small"}}, "thresholds.position_C.rtol"),
        ({"position_C": {"value": 1e-6, "rtl": 1e-7}}, "thresholds.position_C.rtl"),
    ],
)
def test_the_loader_refuses_a_bad_rtol_naming_the_field(table, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        _scene(table)


@pytest.mark.parametrize(
    ("table", "field", "value"),
    [
        ({"position_C": {"value": 1e-6, "rtol": -1e-7}}, "thresholds.position_C.rtol", "-1e-07"),
        ({"position_C": {"value": 1e-6, "rtol": math.nan}}, "thresholds.position_C.rtol", "nan"),
        ({"position_C": {"value": 1e-6, "rtol": True}}, "thresholds.position_C.rtol", "True"),
        ({"attitude": {"value": 1e-6, "rtol": 1e-7}}, "thresholds.attitude.rtol", "1e-07"),
        (
            {"control_torque": {"value": 1e-6, "rtol": 1e-7}},
            "thresholds.control_torque.rtol",
            "1e-07",
        ),
        ({"quat_norm": {"value": 1e-9, "rtol": 1e-3}}, "thresholds.quat_norm.rtol", "0.001"),
        ({"position_C": {"rtol": 1e-7}}, "thresholds.position_C.value", "missing"),
        ({"position_C": {"value": 1e-6, "atol": 1e-7}}, "thresholds.position_C.atol", "unknown"),
    ],
)
def test_thresholds_for_refuses_bad_input_naming_field_and_value(table, field, value):
    """The comparison's own check of a table (an override given in code, not read by the loader)."""
    with pytest.raises(ValueError, match=field.replace(".", r"\.")) as err:
        thresholds_for(overrides=table)
    assert value in str(err.value)


def test_an_rtol_of_zero_is_accepted_for_any_name():
    """Zero is no relative part: allowed for the names without one, changing nothing."""
    th = thresholds_for(overrides={"attitude": {"value": 1e-6, "rtol": 0.0}})
    assert th["attitude"].rtol == 0.0 and th["attitude"].value == 1e-6
