"""The pointwise comparison's arithmetic and its sentences: a relative difference per state, a
bound raised only by a state's measured rounding, and a finding that blames the right engine."""

from __future__ import annotations

import numpy as np

from validation.compare.pointwise import (
    Case,
    CaseDifferences,
    PointwiseFinding,
    relative_difference,
    state_bounds,
)
from validation.compare.thresholds import (
    POINTWISE_AGREEMENT,
    POINTWISE_FLOOR,
    POINTWISE_MARGIN,
    pointwise_threshold,
)

EPS32 = float(np.finfo(np.float32).eps)
EPS64 = float(np.finfo(np.float64).eps)
STATES = ("the initial state", "random state 1 (t = 1 s)")


def test_relative_difference_is_per_state_over_the_reference_scale():
    b = np.array([[1.0, -4.0, 2.0], [0.0, 0.0, 0.0]])
    a = b + np.array([[0.0, 0.4, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(relative_difference(a, b), [0.1, 0.0])
    a[1, 0] = np.nan
    assert relative_difference(a, b)[1] == np.inf
    rest = relative_difference(np.array([[POINTWISE_FLOOR]]), np.zeros((1, 1)))
    assert rest[0] == 1.0  # a state at rest divides by the floor


def test_a_bound_is_the_precisions_least_unless_the_state_rounds_worse():
    least32 = pointwise_threshold("float32").value
    d = np.array([0.0, 10 * EPS64, 1e5 * EPS64, 10 * POINTWISE_AGREEMENT])
    got = state_bounds("float32", d)
    assert got[0] == got[1] == least32  # the references agree to rounding: the least bound
    assert got[2] == POINTWISE_MARGIN * 1e5 * EPS32  # an ill-conditioned state raises it
    assert got[3] == least32  # references that disagree measure no rounding


def _diffs(vs_mujoco, vs_analytic, refs, case=Case.UNCONTROLLED):
    return CaseDifferences(case, STATES, vs_mujoco, vs_analytic, refs, (1e-12, 1e-12))


def test_the_initial_state_is_named_when_it_differs_else_the_worst():
    assert _diffs((2e-12, 1e-9), (2e-12, 1e-9), (0.0, 0.0)).worst() == 0
    assert _diffs((1e-13, 1e-9), (1e-13, 1e-9), (0.0, 0.0)).worst() == 1
    assert not _diffs((1e-13, 1e-13), (1e-13, 1e-13), (0.0, 0.0)).over


def test_a_finding_blames_the_engine_that_departs():
    plant = PointwiseFinding.of(
        "mjx", "float64", _diffs((3e-2, 3e-2), (3e-2, 3e-2), (1e-16, 1e-16))
    )
    text = plant.text()
    assert text.startswith("mjx: q̈ differs from MuJoCo C by 3.0e-02 relative at the initial state")
    assert "the models differ, not the integration" in text and "2 of 2 states" in text
    caused = PointwiseFinding(**{**plant.__dict__, "cause_text": "the difference is in x"})
    assert caused.text().endswith("; the difference is in x")

    mujoco = PointwiseFinding.of("mjx", "float64", _diffs((1e-16, 0.0), (0.5, 0.0), (0.5, 0.0)))
    assert "as MuJoCo C's does" in mujoco.text() and "not mjx's" in mujoco.text()

    both = PointwiseFinding.of("mjx", "float64", _diffs((0.2, 0.0), (0.5, 0.0), (0.4, 0.0)))
    assert "MuJoCo C and the analytic model differ by 4.0e-01" in both.text()
    assert PointwiseFinding.of("mjx", "float64", _diffs((0.0, 0.0), (0.0, 0.0), (0.0, 0.0))) is None
