"""The round-off rule: a bound is judgeable at a precision only when it is at least eps times the
quantity's magnitude; a plant's precision is its settings'."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from analytic.effects import Precision
from validation.studies import roundoff


def test_eps_is_the_machine_epsilon_of_each_precision():
    assert roundoff.EPS[Precision.FLOAT32] == 2.0**-23
    assert roundoff.EPS[Precision.FLOAT32] == float(np.spacing(np.float32(1.0)))
    assert roundoff.EPS[Precision.FLOAT64] == float(np.spacing(1.0))


def test_a_bound_below_eps_times_the_magnitude_is_not_judgeable():
    eps = roundoff.EPS[Precision.FLOAT32]
    assert roundoff.judgeable(2 * eps * 100.0, 100.0, Precision.FLOAT32)
    assert not roundoff.judgeable(0.5 * eps * 100.0, 100.0, Precision.FLOAT32)
    assert roundoff.judgeable(1e-12, 100.0, Precision.FLOAT64)  # 100 x 2.2e-16 = 2.2e-14
    assert not roundoff.judgeable(1.0, float("nan"), Precision.FLOAT64)
    why = roundoff.not_judgeable_reason(1e-7, 105.0, "m", Precision.FLOAT32)
    assert why.startswith("not judgeable at float32") and "1.3e-05 m" in why


@dataclasses.dataclass(frozen=True)
class _Settings:
    precision: str = "float32"


def test_a_plants_precision_is_its_settings_else_float64():
    assert roundoff.precision_of(_Settings()) is Precision.FLOAT32
    assert roundoff.precision_of(object()) is Precision.FLOAT64
    with pytest.raises(ValueError, match="precision: unknown value 'float16'"):
        roundoff.precision_of(_Settings("float16"))
