"""The difference quantities of two plants: the attitude angle against independent references."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from validation.compare.differences import attitude_angle


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product, w first, batched over leading axes."""
    a0, av = a[..., :1], a[..., 1:]
    b0, bv = b[..., :1], b[..., 1:]
    w = a0 * b0 - np.sum(av * bv, axis=-1, keepdims=True)
    v = a0 * bv + b0 * av + np.cross(av, bv)
    return np.concatenate([w, v], axis=-1)


def test_attitude_angle_q_and_minus_q_agree():
    rng = np.random.default_rng(1)
    u = rng.normal(size=(50, 4))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    # exact on any machine: x·(-y) = -(x·y) in IEEE arithmetic, so the vector part cancels to 0
    assert np.all(attitude_angle(u, -u) == 0.0)
    assert np.all(attitude_angle(u, u) == 0.0)


@pytest.mark.parametrize("theta", [1e-9, 1e-4, 0.3, 1.0, 2.5, math.pi - 1e-6])
def test_attitude_angle_of_a_known_rotation(theta):
    rng = np.random.default_rng(2)
    u = rng.normal(size=(20, 4))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    n = rng.normal(size=(20, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    dq = np.concatenate([np.full((20, 1), math.cos(theta / 2)), math.sin(theta / 2) * n], axis=1)
    # body-fixed (right) and space-fixed (left) perturbations are both rotations by theta
    np.testing.assert_allclose(attitude_angle(u, quat_mul(u, dq)), theta, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(attitude_angle(u, quat_mul(dq, u)), theta, rtol=1e-9, atol=1e-15)
    # and a sign flip of the perturbed quaternion does not matter
    np.testing.assert_allclose(attitude_angle(u, -quat_mul(u, dq)), theta, rtol=1e-9, atol=1e-15)


def test_attitude_angle_matches_scipy_and_ignores_scale():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(30, 4))
    b = rng.normal(size=(30, 4))
    ra = Rotation.from_quat(a, scalar_first=True)
    rb = Rotation.from_quat(b, scalar_first=True)
    expected = (ra.inv() * rb).magnitude()
    np.testing.assert_allclose(attitude_angle(a, b), expected, atol=1e-12)
    np.testing.assert_allclose(attitude_angle(3.0 * a, 0.5 * b), expected, atol=1e-12)


def test_attitude_angle_rejects_bad_shapes():
    with pytest.raises(ValueError, match="u_b"):
        attitude_angle(np.zeros((3, 4)), np.zeros((3, 3)))
