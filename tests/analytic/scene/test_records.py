"""The records' own rules: the output grid and what output settings can hold.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import scene as S
from analytic.scene import OutputSettings


@pytest.mark.parametrize(
    ("t_end", "rate", "expected"),
    [
        (0.004, 100.0, [0.0, 0.004]),  # shorter than one output interval
        (0.016, 100.0, [0.0, 0.01, 0.016]),  # t_end appended after the grid
        (0.3, 10.0, [0.0, 0.1, 0.2, 0.3]),  # 0.3 x 10 = 3.0000000000000004 is on the grid
        (20.0, 100.0, np.arange(2001) / 100.0),
    ],
)
def test_output_grid_has_t0_and_ends_at_t_end(t_end, rate, expected):
    t = OutputSettings(t_end=t_end, rate=rate).times()
    np.testing.assert_allclose(t, expected, rtol=0, atol=1e-15)
    assert t[0] == 0.0 and t[-1] == t_end


def test_output_settings_refuse_what_cannot_be_held():
    with pytest.raises(ValueError, match=r"^output\.rate: too large: 20 s at 1e\+12 Hz"):
        OutputSettings(rate=1e12)
    with pytest.raises(ValueError, match=r"^t_end: too large"):
        OutputSettings().with_t_end(1e300)
    for bad in (-1.0, 0.0, math.nan, math.inf, "1", True):
        with pytest.raises(ValueError, match=r"^t_end: must be"):
            OutputSettings().with_t_end(bad)
    assert S.MAX_OUTPUT_SAMPLES * 8 * 100 <= 1 << 30  # 100 doubles a sample: about 1 GB at most
