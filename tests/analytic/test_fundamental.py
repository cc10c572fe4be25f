"""The fundamental-equation solver (``analytic.fundamental.solve``) against independent references.

What ``solve`` computes (module docstring of ``analytic.fundamental``): the modeling constraint
``a_mᵀq̈ = b_m`` is ideal (its reaction is a free multiple of ``a_m``); the control force
``Q_c`` acts on that norm-constrained system, ``M q̈ = Q + Q_c + λ a_m``, and is the one that
minimises ``Q_cᵀ N Q_c`` subject to ``A_c q̈ = b_c`` (least squares in the constraint rows when they
cannot all be met). The returned ``QC`` is the total ``M q̈ - Q = Q_c + λ a_m``. For ``N = M⁻¹``
this is Gauss's principle and equals the paper's Eq. (89) with ``A = [a_mᵀ; A_c]``; for other N it
differs from Eq. (B10) applied to the stacked A in that the norm reaction is not charged in the
cost (checked: the two differ by O(10%) for N = M⁻²).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import null_space

from analytic.effects import Weighting
from analytic.fundamental import solve
from analytic.kinematics import H as H_of
from analytic.model import TumblingModel
from analytic.scene import load_scene, scene_from_dict

try:
    from tests.support.scene_strategies import (
        FORCE_EFFECTS,
        random_scene_dict,
        random_state,
        rel_err,
    )
except ImportError:  # tests/ made a package
    from tests.support.scene_strategies import (
        FORCE_EFFECTS,
        random_scene_dict,
        random_state,
        rel_err,
    )

RTOL = 1e-10
SCENES = Path(__file__).resolve().parents[2] / "analytic" / "scenes"
WEIGHTINGS = (Weighting.M_INV, Weighting.M_INV2, Weighting.IDENTITY)


def controlled_scene_dict(
    rng,
    n,
    *,
    omega_components=(1, 2, 3),
    mass_indices=None,
    weighting="M^-1",
    effects=FORCE_EFFECTS,
    **kw,
) -> dict:
    """A random scene with angular-velocity tracking and (n > 0) mass tracking (1-based indices)."""
    data = random_scene_dict(rng, n, effects, **kw)
    eff = list(data["scene"]["effects"])
    ctrl: dict = {"weighting": weighting}
    if omega_components:
        eff.append("control.omega")
        ctrl["omega"] = {
            "components": list(omega_components),
            "b": rng.normal(size=3).tolist(),
            "sigma": rng.uniform(0, 3, 3).tolist(),
            "gamma": float(rng.uniform(0.2, 2.0)),
        }
    if n and mass_indices is None:
        mass_indices = list(range(1, n + 1))
    if mass_indices:
        k = len(mass_indices)
        eff.append("control.masses")
        ctrl["masses"] = {
            "indices": list(mass_indices),
            "l": rng.normal(size=k).tolist(),
            "lambda": rng.uniform(0.5, 3, k).tolist(),
            "alpha": rng.uniform(1, 3, k).tolist(),
            "beta": rng.uniform(5, 15, k).tolist(),
        }
    data["scene"]["effects"] = eff
    data["control"] = ctrl
    return data


def system(rng, n, **kw):
    """(model, M, Q, a_m, b_m, A_c, b_c) at a random state of a random controlled scene."""
    model = TumblingModel(scene_from_dict(controlled_scene_dict(rng, n, **kw)))
    q, qd = random_state(rng, n)
    t = float(rng.uniform(0, 5))
    M = model.mass_matrix(q)
    Q = model.generalized_force(t, q, qd)
    a_m, b_m = model.modeling_constraint(q, qd)
    A_c, b_c = model.control_constraints(t, q, qd)
    return model, M, Q, a_m, b_m, A_c, b_c


def eq89(M, Q, a_m, b_m, A_c, b_c):
    """The paper's printed Eq. (89) with plain inverses: A = [a_mᵀ; A_c]."""
    A = np.vstack([a_m, A_c])
    b = np.r_[b_m, b_c]
    Minv = np.linalg.inv(M)
    QC = A.T @ np.linalg.pinv(A @ Minv @ A.T) @ (b - A @ Minv @ Q)
    return Minv @ (Q + QC), QC


def kkt(M, Q, a_m, b_m, A_c, b_c, W):
    """Independent KKT solve of: min Q_cᵀ N Q_c over (q̈, Q_c, λ) subject to
    M q̈ - Q_c - λ a_m = Q, a_mᵀ q̈ = b_m, A_c q̈ = b_c, with ``W = N⁻¹`` given (stationarity in
    Q_c, ``2 N Q_c = ν1``, is written ``2 Q_c = W ν1`` so that no inverse of M is formed).
    Returns (q̈, Q_c + λ a_m, Q_c)."""
    nq, k = M.shape[0], A_c.shape[0]
    Z = np.zeros
    # unknowns: q̈ (nq), Q_c (nq), λ (1), ν1 (nq), ν2 (1), ν3 (k)
    rows = [
        np.hstack([Z((nq, nq)), Z((nq, nq)), Z((nq, 1)), M.T, a_m[:, None], A_c.T]),
        np.hstack([Z((nq, nq)), 2 * np.eye(nq), Z((nq, 1)), -W, Z((nq, 1)), Z((nq, k))]),
        np.hstack([Z((1, 2 * nq + 1)), -a_m[None], Z((1, 1 + k))]),
        np.hstack([M, -np.eye(nq), -a_m[:, None], Z((nq, nq + 1 + k))]),
        np.hstack([a_m[None], Z((1, 2 * nq + 2 + k))]),
        np.hstack([A_c, Z((k, 2 * nq + 2 + k))]),
    ]
    K = np.vstack(rows)
    rhs = np.r_[Z(nq), Z(nq), 0.0, Q, b_m, b_c]
    x = np.linalg.solve(K, rhs)
    qdd, Qc, lam = x[:nq], x[nq : 2 * nq], x[2 * nq]
    return qdd, Qc + lam * a_m, Qc


def inverse_weight(M, w: Weighting) -> np.ndarray:
    """``W = N⁻¹`` for the weightings of Appendix B: M (Gauss), M², I."""
    return {Weighting.M_INV: M, Weighting.M_INV2: M @ M, Weighting.IDENTITY: np.eye(len(M))}[w]


# ------------------------------------------------------------------------------------------------
# (a) Gauss weighting = the paper's Eq. (89)
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, 2, 4])
@pytest.mark.parametrize("seed", range(4))
def test_gauss_matches_printed_eq89(n, seed):
    rng = np.random.default_rng(10 * n + seed)
    _, M, Q, a_m, b_m, A_c, b_c = system(rng, n)
    sol = solve(M, Q, a_m, b_m, A_c, b_c, Weighting.M_INV)
    qdd_ref, QC_ref = eq89(M, Q, a_m, b_m, A_c, b_c)
    assert rel_err(sol.qddot, qdd_ref) < RTOL
    assert rel_err(sol.constraint_force, QC_ref) < RTOL
    assert rel_err(M @ sol.qddot - Q, QC_ref) < RTOL
    assert sol.rank == A_c.shape[0] and np.linalg.norm(sol.residual) < 1e-10 * np.linalg.norm(b_c)


@pytest.mark.parametrize("seed", range(4))
def test_gauss_matches_eq89_for_random_dense_constraints(seed):
    """Not only the paper's A: random dense control rows (with R columns) and no control at all."""
    rng = np.random.default_rng(500 + seed)
    n = 3
    _, M, Q, a_m, b_m, _, _ = system(rng, n)
    for k in (0, 1, 4):
        A_c, b_c = rng.normal(size=(k, n + 7)), rng.normal(size=k)
        sol = solve(M, Q, a_m, b_m, A_c, b_c, Weighting.M_INV)
        qdd_ref, QC_ref = eq89(M, Q, a_m, b_m, A_c, b_c)
        assert rel_err(sol.qddot, qdd_ref) < RTOL
        assert rel_err(sol.constraint_force, QC_ref) < RTOL


# ------------------------------------------------------------------------------------------------
# (b) the control minimises Q_cᵀ N Q_c (KKT of the equality-constrained QP)
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("w", WEIGHTINGS, ids=lambda w: w.name)
@pytest.mark.parametrize("n", [1, 3])
@pytest.mark.parametrize("seed", range(3))
def test_control_minimises_weighted_cost_kkt(w, n, seed):
    rng = np.random.default_rng(100 * n + seed)
    _, M, Q, a_m, b_m, A_c, b_c = system(rng, n)
    for A, b in ((A_c, b_c), (rng.normal(size=(3, n + 7)), rng.normal(size=3))):
        sol = solve(M, Q, a_m, b_m, A, b, w)
        qdd_ref, QC_ref, Qc_ref = kkt(M, Q, a_m, b_m, A, b, inverse_weight(M, w))
        assert rel_err(sol.qddot, qdd_ref) < RTOL
        assert rel_err(sol.constraint_force, QC_ref) < RTOL
        # The solver's motion is feasible and no feasible control is cheaper: random feasible
        # perturbations of the optimal Q_c (keeping A_c q̈ = b_c on the norm-constrained system)
        # only raise the cost.
        N = np.linalg.inv(inverse_weight(M, w))
        nq = n + 7
        # q̈ = a + K Q_c; feasible δQ_c satisfy A K δQ_c = 0, i.e. δq̈ ∈ null([a_mᵀ; A]),
        # δQ_c = M δq̈ + δλ a_m
        D = null_space(np.vstack([a_m, A]))
        for _ in range(5):
            dqdd = D @ rng.normal(size=D.shape[1])
            dQc = M @ dqdd + rng.normal() * a_m
            dQc *= 1e-3 * np.linalg.norm(Qc_ref) / np.linalg.norm(dQc)
            assert (Qc_ref + dQc) @ N @ (Qc_ref + dQc) > Qc_ref @ N @ Qc_ref
        assert nq == len(sol.qddot)


# ------------------------------------------------------------------------------------------------
# (c) singular M: a rigid body alone (n = 0)
# ------------------------------------------------------------------------------------------------


def qmul(p, r):
    return np.r_[p[0] * r[0] - p[1:] @ r[1:], p[0] * r[1:] + r[0] * p[1:] + np.cross(p[1:], r[1:])]


@pytest.mark.parametrize("w", WEIGHTINGS, ids=lambda w: w.name)
@pytest.mark.parametrize("components", [(), (2,), (1, 3), (1, 2, 3)])
@pytest.mark.parametrize("seed", range(3))
def test_rigid_body_singular_M_euler(w, components, seed):
    """n = 0 (M [0, u] = 0): the acceleration meets the norm constraint (Eq. 58), the ω requirement
    (Eq. 84), and Euler's equations ``J ω̇ + ω × Jω = τ_given + τ`` with the returned torque τ
    (ω̇ = d/dt of ω = 2 vec(conj(u) ⊗ u̇), computed from ü by the quaternion product); the centre of
    mass obeys ``m R̈ = m g + F_C``. With Gauss's N the torque acts only on the controlled axes."""
    rng = np.random.default_rng(1000 * seed + len(components))
    data = controlled_scene_dict(
        rng,
        0,
        omega_components=components,
        weighting=w.value,
        effects=("gravity", "external_torque"),
    )
    model = TumblingModel(scene_from_dict(data))
    q, qd = random_state(rng, 0, unit_u=True, tangent=True)
    t = float(rng.uniform(0, 5))
    qdd, ctrl = model.acceleration(t, q, qd)
    u, ud, udd = q[3:7], qd[3:7], qdd[3:7]
    conj = u * np.r_[1, -1, -1, -1]
    omega = 2 * qmul(conj, ud)[1:]
    omega_dot = 2 * (qmul(ud * np.r_[1, -1, -1, -1], ud) + qmul(conj, udd))[1:]
    J = np.diag(data["body"]["inertia"])
    et = data["external_torque"]
    tau_g = np.array(et["constant"]) + np.array(et["amplitude"]) * np.cos(et["frequency"] * t)
    scale = np.linalg.norm(J @ omega_dot) + np.linalg.norm(np.cross(omega, J @ omega)) + 1.0

    # norm constraint: d²/dt²(|u|²-1) + δ1 d/dt(|u|²-1) + δ2(|u|²-1) = 0 with δ from the scene
    d1, d2 = model.scene.stabilization.delta1, model.scene.stabilization.delta2
    phi_dd = 2 * (ud @ ud + u @ udd)
    assert abs(phi_dd + d1 * 2 * (u @ ud) + d2 * (u @ u - 1)) < 1e-12 * (1 + np.abs(udd).max())
    # ω requirement: ω̇_c = ω̄̇_c - γ (ω_c - ω̄_c), ω̄ = b cos(σ t)
    c = [i - 1 for i in components]
    if c:
        om = data["control"]["omega"]
        b, s, g = np.array(om["b"]), np.array(om["sigma"]), om["gamma"]
        wbar, wbar_dot = b * np.cos(s * t), -b * s * np.sin(s * t)
        target = wbar_dot[c] - g * (omega[c] - wbar[c])
        assert np.allclose(omega_dot[c], target, rtol=0, atol=1e-11 * scale)
    # Euler
    lhs = J @ omega_dot + np.cross(omega, J @ omega)
    assert np.linalg.norm(lhs - tau_g - ctrl.torque) < 1e-11 * scale
    if w is Weighting.M_INV:
        free = [i for i in range(3) if i not in c]
        assert np.allclose(ctrl.torque[free], 0, atol=1e-12 * scale)
        assert np.linalg.norm(ctrl.force_at_C) <= 1e-13 * np.linalg.norm(ctrl.QC)
    if not c:
        assert np.linalg.norm(ctrl.torque) < 1e-12 * scale
    m_BR = data["body"]["mass"]
    g_vec = np.array(data["gravity"]["vector"])
    assert np.allclose(m_BR * qdd[:3], m_BR * g_vec + ctrl.force_at_C, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("seed", range(3))
def test_singular_M_gauss_matches_bordered_system(seed):
    """Singular M (n = 0, and masses all at C): Gauss's solution is the unique (q̈, ν) of the
    bordered system ``M q̈ - Aᵀν = Q, A q̈ = b`` (ideal constraints; nonsingular because
    ``[M; A]`` has full column rank). Also off the unit sphere, with u̇ not tangent."""
    rng = np.random.default_rng(77 + seed)
    for n, kw in ((0, {}), (2, {"d": np.zeros(3)})):
        data = controlled_scene_dict(rng, n, omega_components=(1, 3), **kw)
        model = TumblingModel(scene_from_dict(data))
        q, qd = random_state(rng, n)
        if n:
            q[7:] = 0.0  # every mass at C (d = 0)
        M = model.mass_matrix(q)
        assert np.linalg.matrix_rank(M) == n + 6
        Q = model.generalized_force(0.3, q, qd)
        a_m, b_m = model.modeling_constraint(q, qd)
        A_c, b_c = model.control_constraints(0.3, q, qd)
        A, b = np.vstack([a_m, A_c]), np.r_[b_m, b_c]
        k = A.shape[0]
        Bord = np.block([[M, -A.T], [A, np.zeros((k, k))]])
        x = np.linalg.solve(Bord, np.r_[Q, b])
        sol = solve(M, Q, a_m, b_m, A_c, b_c, Weighting.M_INV)
        assert rel_err(sol.qddot, x[: n + 7]) < RTOL
        assert rel_err(sol.constraint_force, A.T @ x[n + 7 :]) < RTOL


# ------------------------------------------------------------------------------------------------
# (d) rank-deficient control rows
# ------------------------------------------------------------------------------------------------


def ls_residual(a_m, b_m, A, b):
    """Least-squares compromise, independent of M: the control can give any q̈ on the hyperplane
    a_mᵀq̈ = b_m (the constrained compliance has range a_m^⊥), so the unattainable part of A q̈ = b
    is the residual of min |A q̈ - b| over that hyperplane."""
    q0 = a_m * b_m / (a_m @ a_m)
    Na = null_space(a_m[None])
    z = np.linalg.lstsq(A @ Na, b - A @ q0, rcond=None)[0]
    return A @ (q0 + Na @ z) - b


@pytest.mark.parametrize("w", WEIGHTINGS, ids=lambda w: w.name)
@pytest.mark.parametrize("n", [0, 2, 3])
def test_duplicated_consistent_requirement_same_motion(w, n):
    rng = np.random.default_rng(300 + n)
    _, M, Q, a_m, b_m, A_c, b_c = system(rng, n, weighting=w.value)
    ref = solve(M, Q, a_m, b_m, A_c, b_c, w)
    k = A_c.shape[0]
    for extra_A, extra_b in (
        (A_c[[0]], b_c[[0]]),  # exact duplicate
        (A_c[[k - 1]] * 3.0, b_c[[k - 1]] * 3.0),  # scaled duplicate
        (A_c[[0]] - 2.0 * A_c[[1]], b_c[[0]] - 2.0 * b_c[[1]]),  # linear combination
    ):
        sol = solve(M, Q, a_m, b_m, np.vstack([A_c, extra_A]), np.r_[b_c, extra_b], w)
        assert sol.rank == k
        assert rel_err(sol.qddot, ref.qddot) < RTOL
        assert rel_err(sol.constraint_force, ref.constraint_force) < RTOL
        assert np.linalg.norm(sol.residual) < 1e-10 * np.linalg.norm(b_c)


@pytest.mark.parametrize("w", WEIGHTINGS, ids=lambda w: w.name)
@pytest.mark.parametrize("n", [0, 2, 3])
def test_conflicting_duplicates_least_squares_compromise(w, n):
    rng = np.random.default_rng(400 + n)
    _, M, Q, a_m, b_m, A_c, b_c = system(rng, n, weighting=w.value)
    k = A_c.shape[0]
    j = k - 1
    delta = 0.7 * (1 + abs(b_c[j]))
    A2, b2 = np.vstack([A_c, A_c[[j]]]), np.r_[b_c, b_c[j] + delta]
    sol = solve(M, Q, a_m, b_m, A2, b2, w)
    assert sol.rank == k
    # the compromise: both copies meet halfway, every other requirement is met exactly
    expected = np.zeros(k + 1)
    expected[j], expected[k] = delta / 2, -delta / 2
    assert np.allclose(sol.residual, expected, rtol=0, atol=1e-9 * delta)
    assert np.allclose(sol.residual, ls_residual(a_m, b_m, A2, b2), rtol=0, atol=1e-9 * delta)
    assert np.allclose(A2 @ sol.qddot - b2, sol.residual, rtol=0, atol=1e-9 * delta)
    # the quaternion constraint is never traded against the control
    assert abs(a_m @ sol.qddot - b_m) < 1e-12 * (abs(b_m) + np.linalg.norm(sol.qddot))
    # same motion as asking for the mean once
    b_mean = b_c.copy()
    b_mean[j] += delta / 2
    ref = solve(M, Q, a_m, b_m, A_c, b_mean, w)
    assert rel_err(sol.qddot, ref.qddot) < RTOL


@pytest.mark.parametrize("w", WEIGHTINGS, ids=lambda w: w.name)
def test_conflicting_random_rows_residual_is_least_squares(w):
    """More requirements than the norm-constrained system can meet (k > nq - 1): the residual is
    the least-squares residual over the constraint hyperplane, and a_mᵀq̈ = b_m still holds."""
    rng = np.random.default_rng(9)
    n = 1
    _, M, Q, a_m, b_m, _, _ = system(rng, n)
    A, b = rng.normal(size=(n + 9, n + 7)), rng.normal(size=n + 9)
    sol = solve(M, Q, a_m, b_m, A, b, w)
    assert sol.rank == n + 6
    ref = ls_residual(a_m, b_m, A, b)
    assert np.linalg.norm(sol.residual - ref) < 1e-9 * np.linalg.norm(b)
    assert abs(a_m @ sol.qddot - b_m) < 1e-12 * (abs(b_m) + np.linalg.norm(sol.qddot))


# ------------------------------------------------------------------------------------------------
# (e) Gauss: no force at C, no rod force on untracked masses
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_gauss_no_force_at_C_nor_on_untracked_masses(seed):
    """With N = M⁻¹ the control force lies in the row space of [a_mᵀ; A_c], which has no R columns
    and no columns of untracked masses: Q^C_R = 0 and F_i = 0 for them (to round-off)."""
    rng = np.random.default_rng(600 + seed)
    n = 5
    tracked = sorted(rng.choice(np.arange(1, n + 1), size=2, replace=False).tolist())
    data = controlled_scene_dict(rng, n, omega_components=(1, 2, 3), mass_indices=tracked)
    model = TumblingModel(scene_from_dict(data))
    q, qd = random_state(rng, n)
    _, ctrl = model.acceleration(1.3, q, qd)
    scale = np.linalg.norm(ctrl.QC)
    untracked = [i for i in range(n) if i + 1 not in tracked]
    assert np.linalg.norm(ctrl.force_at_C) <= 1e-13 * scale
    assert np.linalg.norm(ctrl.rod_forces[untracked]) <= 1e-13 * scale
    assert np.linalg.norm(ctrl.rod_forces[[i - 1 for i in tracked]]) > 1e-6 * scale
    # torque = ¼ H Q^C_u is the body torque whose virtual work matches Q^C_u off the u direction
    u = q[3:7]
    QCu = ctrl.QC[3:7]
    assert np.allclose(
        H_of(u).T @ ctrl.torque / (u @ u), QCu - u * (u @ QCu) / (u @ u), atol=1e-12 * scale
    )


def test_gauss_example2_subset_zero_force_at_C_and_on_masses_3_5():
    """Paper Example 2 controlled (masses 1, 2, 4 tracked): no force at C, no rod force on 3, 5."""
    scene = load_scene(SCENES / "paper_example2_controlled.toml")
    model = TumblingModel(scene)
    q, qd = scene.initial.q0(), scene.initial.qdot0()
    for t in (0.0, 0.37):
        _, ctrl = model.acceleration(t, q, qd)
        scale = np.linalg.norm(ctrl.QC)
        assert np.linalg.norm(ctrl.force_at_C) <= 1e-13 * scale
        assert np.linalg.norm(ctrl.rod_forces[[2, 4]]) <= 1e-13 * scale
