"""Quaternion identities of Eqs. (11)-(43) and the structure of M (Eq. 51).

Derivatives are checked with complex steps, ``∂f/∂u · v = Im f(u + i h v) / h``, which is exact (no
truncation, no cancellation) for the quadratic S and the linear H, L.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analytic.kinematics import H, L, S, S_batch, omega_of, tensor_along, udot_of
from analytic.model import TumblingModel

try:
    from tests.support.scene_strategies import random_scene, random_state, unit
except ImportError:  # tests/ made a package
    from tests.support.scene_strategies import random_scene, random_state, unit

H_STEP = 1e-30
SEEDS = range(20)


def cstep(f, u, v):
    """Directional derivative of f at u along v by complex step (exact for polynomials)."""
    return np.imag(f(u + 1j * H_STEP * np.asarray(v))) / H_STEP


def rand_u(rng, unit_u=False):
    u = rng.normal(size=4)
    return u / np.linalg.norm(u) if unit_u else u / np.linalg.norm(u) * rng.uniform(0.5, 1.5)


def qmul(p, r):
    """Hamilton product, w first."""
    return np.r_[p[0] * r[0] - p[1:] @ r[1:], p[0] * r[1:] + r[0] * p[1:] + np.cross(p[1:], r[1:])]


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


@pytest.mark.parametrize("seed", SEEDS)
def test_H_HT_is_4_norm2_identity(seed):
    rng = np.random.default_rng(seed)
    u = rand_u(rng)
    Hm = H(u)
    assert np.allclose(Hm @ Hm.T, 4 * (u @ u) * np.eye(3), rtol=0, atol=1e-14)
    assert np.allclose(Hm @ u, 0, atol=1e-15)  # ker H = span(u)
    uu = u / np.linalg.norm(u)
    assert np.allclose(H(uu) @ H(uu).T, 4 * np.eye(3), rtol=0, atol=1e-14)


@pytest.mark.parametrize("seed", SEEDS)
def test_Hdot_udot_vanishes(seed):
    """Ḣ u̇ = 0 (Eq. 16): Ḣ by complex step along u̇ equals H(u̇), and H(u̇)u̇ = 0."""
    rng = np.random.default_rng(seed)
    u, ud = rand_u(rng), rng.normal(size=4)
    Hdot = cstep(H, u, ud)
    assert np.allclose(Hdot, H(ud), rtol=0, atol=1e-14)
    assert np.allclose(Hdot @ ud, 0, atol=1e-14)


@pytest.mark.parametrize("seed", SEEDS)
def test_u_half_HT_orthogonal_det_one(seed):
    rng = np.random.default_rng(seed)
    u = rand_u(rng, unit_u=True)
    B = np.column_stack([u, 0.5 * H(u).T])
    assert np.allclose(B.T @ B, np.eye(4), rtol=0, atol=1e-14)
    assert abs(np.linalg.det(B) - 1.0) < 1e-14


@pytest.mark.parametrize("seed", SEEDS)
def test_dS_du_is_L(seed):
    """∂S_i/∂u = L_i (Eqs. 23-26) and Ṡ a = L_a u̇, Ṡ d = L_d u̇ (Eqs. 27, 29, 34), any u."""
    rng = np.random.default_rng(seed)
    u = rand_u(rng)
    for k in range(4):
        dS = cstep(S, u, np.eye(4)[k])
        for i in (1, 2, 3):
            assert np.allclose(dS[:, i - 1], L(i, u)[:, k], rtol=0, atol=1e-14)
    a, d, ud = unit(rng), rng.normal(size=3), rng.normal(size=4)
    for v in (a, d):
        Sdot_v = cstep(lambda x, v=v: S(x) @ v, u, ud)
        assert np.allclose(Sdot_v, tensor_along(v) @ u @ ud, rtol=0, atol=1e-13)
        # L_v is linear in u, so L̇_v = L_v(u̇) (used for Eq. 40)
        assert np.allclose(cstep(lambda x, v=v: tensor_along(v) @ x, u, ud), tensor_along(v) @ ud)


@pytest.mark.parametrize("seed", SEEDS)
def test_S_is_the_rotation_for_unit_u(seed):
    rng = np.random.default_rng(seed)
    u = rand_u(rng, unit_u=True)
    Sm = S(u)
    assert np.allclose(Sm.T @ Sm, np.eye(3), rtol=0, atol=1e-14)
    assert abs(np.linalg.det(Sm) - 1) < 1e-14
    ref = Rotation.from_quat(u, scalar_first=True).as_matrix()
    assert np.allclose(Sm, ref, rtol=0, atol=1e-14)
    # active body -> inertial: S v = vec(u ⊗ [0, v] ⊗ conj(u))
    v = rng.normal(size=3)
    uc = u * np.r_[1, -1, -1, -1]
    assert np.allclose(Sm @ v, qmul(qmul(u, np.r_[0, v]), uc)[1:], atol=1e-14)
    us = rng.normal(size=(5, 4))
    # exact: the same formula, each element rounded once in the same order (numpy's element-wise
    # operations never fuse or reorder), so the batch equals the loop on any machine
    assert np.allclose(S_batch(us), np.stack([S(x) for x in us]), rtol=0, atol=0)


@pytest.mark.parametrize("seed", SEEDS)
def test_omega_is_the_body_angular_velocity(seed):
    """For unit u and u̇ ⊥ u, Ṡ = S [ω]× with ω = H u̇ (body axes), and ω = 2 vec(conj(u) ⊗ u̇)."""
    rng = np.random.default_rng(seed)
    u = rand_u(rng, unit_u=True)
    ud = rng.normal(size=4)
    ud -= u * (u @ ud)
    w = omega_of(u, ud)
    assert np.allclose(w, H(u) @ ud, rtol=0, atol=1e-14)
    assert np.allclose(cstep(S, u, ud), S(u) @ skew(w), rtol=0, atol=1e-13)
    assert np.allclose(w, 2 * qmul(u * np.r_[1, -1, -1, -1], ud)[1:], rtol=0, atol=1e-14)


@pytest.mark.parametrize("seed", SEEDS)
def test_omega_of_and_udot_of_inverse_on_tangent_space(seed):
    rng = np.random.default_rng(seed)
    u, w, ud = rand_u(rng), rng.normal(size=3), rng.normal(size=4)
    ud_w = udot_of(u, w)
    assert abs(u @ ud_w) < 1e-14  # lands on the tangent space
    assert np.allclose(omega_of(u, ud_w), w, rtol=0, atol=1e-14)
    tangent = ud - u * (u @ ud) / (u @ u)
    assert np.allclose(udot_of(u, omega_of(u, ud)), tangent, rtol=0, atol=1e-14)
    uu = u / np.linalg.norm(u)
    assert np.allclose(udot_of(uu, w), 0.25 * H(uu).T @ w, rtol=0, atol=1e-15)
    # batched
    U, W = rng.normal(size=(6, 4)), rng.normal(size=(6, 3))
    assert np.allclose(omega_of(U, udot_of(U, W)), W, rtol=0, atol=1e-13)


# ------------------------------------------------------------------------------------------------
# Mass matrix
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, 2, 3, 5])
@pytest.mark.parametrize("seed", range(5))
def test_M_symmetric_positive_definite_with_a_mass_off_C(n, seed):
    """Generic states (u not unit, masses off C): M is symmetric positive definite."""
    rng = np.random.default_rng(100 * n + seed)
    model = TumblingModel(random_scene(rng, n))
    for _ in range(4):
        q, _ = random_state(rng, n)
        M = model.mass_matrix(q)
        assert np.linalg.norm(M - M.T) <= 1e-15 * np.linalg.norm(M)  # symmetric to round-off
        ev = np.linalg.eigvalsh(M)
        assert ev[0] > 1e-6 * ev[-1], ev


@pytest.mark.parametrize("seed", range(5))
def test_M_singular_along_u_for_rigid_body(seed):
    """n = 0: M [0, u] = 0 for any u (H u = 0), with exactly one zero eigenvalue."""
    rng = np.random.default_rng(seed)
    model = TumblingModel(random_scene(rng, 0))
    q, _ = random_state(rng, 0)
    M = model.mass_matrix(q)
    u_ext = np.r_[np.zeros(3), q[3:7]]
    assert np.linalg.norm(M @ u_ext) <= 1e-14 * np.linalg.norm(M)
    ev = np.linalg.eigvalsh(M)
    assert abs(ev[0]) < 1e-14 * ev[-1] and ev[1] > 1e-3 * ev[-1], ev


@pytest.mark.parametrize("seed", range(3))
def test_M_singular_along_u_when_every_mass_is_at_C(seed):
    """Masses present but all at C (p_i a + d = 0): same null direction as the rigid body."""
    rng = np.random.default_rng(50 + seed)
    a = unit(rng)
    c = float(rng.normal())
    n = 3
    model = TumblingModel(random_scene(rng, n, a=a, d=c * a))
    q, _ = random_state(rng, n)
    q[7:] = -c
    M = model.mass_matrix(q)
    u_ext = np.r_[np.zeros(3), q[3:7], np.zeros(n)]
    assert np.linalg.norm(M @ u_ext) <= 1e-14 * np.linalg.norm(M)
    ev = np.linalg.eigvalsh(M)
    assert abs(ev[0]) < 1e-14 * ev[-1] and ev[1] > 1e-6 * ev[-1], ev


def test_M_singular_with_masses_off_C_when_d_parallel_to_a_and_u_about_a():
    """Limit of "SPD whenever some mass is off C": with d ∥ a (e.g. Example 2, d = 0) and u a
    rotation about a, scaling u only stretches S along a (S(λu) a = (2λ²-1) a), which the p's can
    absorb: x = [0, u, -4(p + a·d)] is a null vector of M although every mass is off C.
    In general M is singular iff S c_i + c_i ∥ S a for every c_i = p_i a + d (L_c u = 2(S c + c)).
    The fundamental equation still has a unique solution there (``[M; a_mᵀ]`` has full rank)."""
    rng = np.random.default_rng(11)
    a = unit(rng)
    delta = 0.7
    n = 2
    model = TumblingModel(random_scene(rng, n, a=a, d=delta * a))
    theta = 1.1
    u = np.r_[np.cos(theta / 2), np.sin(theta / 2) * a]
    p = np.array([0.5, 2.0])  # masses at 1.2 a and 2.7 a from C: off C
    q = np.r_[np.zeros(3), u, p]
    M = model.mass_matrix(q)
    x = np.r_[np.zeros(3), u, -4.0 * (p + delta)]
    assert np.linalg.norm(M @ x) <= 1e-13 * np.linalg.norm(M) * np.linalg.norm(x)
    a_m = np.r_[np.zeros(3), u, np.zeros(n)]
    assert np.linalg.matrix_rank(np.vstack([M, a_m])) == n + 7
