"""The closed-form error dynamics (Eqs. 78, 84) against independent closed forms and scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from validation.compare.tracking_laws import mass_error_reference, omega_error_reference


def test_omega_reference_is_exponential_decay():
    t = np.linspace(0.0, 5.0, 51)
    e0 = np.array([11.0, 9.0, 14.5])
    ref = omega_error_reference(t, e0, 0.6 * np.eye(3))
    np.testing.assert_allclose(ref, np.exp(-0.6 * t)[:, None] * e0, rtol=1e-12)


def test_mass_reference_is_the_damped_oscillator():
    t = np.linspace(0.0, 4.0, 41)
    alpha, beta = np.array([2.0]), np.array([12.0])
    e0, ed0 = np.array([0.3]), np.array([-0.4])
    wd = math.sqrt(beta[0] - alpha[0] ** 2 / 4)
    closed = np.exp(-alpha[0] * t / 2) * (
        e0[0] * np.cos(wd * t) + (ed0[0] + alpha[0] * e0[0] / 2) / wd * np.sin(wd * t)
    )
    np.testing.assert_allclose(
        mass_error_reference(t, e0, ed0, alpha, beta)[:, 0], closed, atol=1e-13
    )


def test_mass_reference_critically_damped_over_a_long_uniform_grid():
    """Critical damping, α² = 4β: e(t) = (e0 + (ė0 + α e0 / 2) t) exp(-α t / 2); 10⁴ uniform samples
    (the one-step propagator's rounding grows with the sample count)."""
    t = np.linspace(0.0, 20.0, 10_001)
    alpha, beta = np.array([3.0]), np.array([2.25])
    e0, ed0 = np.array([0.3]), np.array([-0.4])
    closed = (e0[0] + (ed0[0] + alpha[0] * e0[0] / 2) * t) * np.exp(-alpha[0] * t / 2)
    np.testing.assert_allclose(
        mass_error_reference(t, e0, ed0, alpha, beta)[:, 0], closed, atol=1e-13
    )


@pytest.mark.parametrize("grid", ["uniform", "uneven"])
def test_omega_reference_with_a_coupled_gain_matches_one_exponential_per_time(grid):
    """A non-symmetric, non-diagonal gain P: each sample equals its own expm(-P t) e0 (scipy),
    on a uniform grid (one-step propagator) and on an uneven one (batched exponentials)."""
    from scipy.linalg import expm

    rng = np.random.default_rng(7)
    gain = np.diag([0.4, 0.9, 1.7]) + 0.3 * rng.standard_normal((3, 3))
    assert np.all(np.linalg.eigvals(gain).real > 0)
    t = np.linspace(0.5, 12.5, 2_001)
    if grid == "uneven":
        t = np.sort(rng.uniform(0.5, 12.5, 400))
    e0 = np.array([11.0, -9.0, 14.5])
    want = np.stack([expm(-gain * (ti - t[0])) @ e0 for ti in t])
    np.testing.assert_allclose(omega_error_reference(t, e0, gain), want, rtol=0, atol=1e-12)
