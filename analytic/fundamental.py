"""The fundamental equation of constrained motion (Udwadia-Kalaba), Eqs. (48), (74), (89), (B10).

Given the unconstrained system ``M q̈ = Q`` (Eq. 50), the modeling constraint ``a_mᵀ q̈ = b_m``
(Eqs. 56-59, one row) and control constraints ``A_c q̈ = b_c`` (Eqs. 80, 85, Remark 4), return the
constrained acceleration and the generalized constraint/control force ``Q^C = M q̈ - Q``.

Two properties are required here that the paper's printed form does not have:

* **M may be singular along u.** A rigid body alone (n = 0, or every mass at C) has
  ``M u = 0`` along the quaternion direction. Following Udwadia & Phohomsiri (Proc. R. Soc. A 462,
  2006) / Udwadia & Schutte (2010), the modeling constraint is added to the mass matrix:
  ``M_α = M + α a_m a_mᵀ``, ``Q_α = Q + α a_m b_m``. Because ``a_mᵀ q̈ = b_m`` always holds, this adds
  zero to the equations of motion, and ``M_α`` is positive definite whenever ``[M; a_mᵀ]`` has full
  column rank (the condition for the motion to be unique at all).
* **A may be rank deficient** (redundant or conflicting requirements). The control constraints are
  imposed on the system that already obeys the modeling constraint (its constrained compliance
  ``K = M_α⁻¹ - y yᵀ/s``, ``y = M_α⁻¹ a_m``, ``s = a_mᵀ y``, is independent of α), and the
  Moore-Penrose inverse gives the least-squares compromise; the part of ``A_c q̈ = b_c`` that cannot be
  met is returned as ``residual``. The quaternion constraint is never traded against the control.

For the cost ``J = Q_cᵀ N Q_c`` (Appendix B) with ``W = N⁻¹``, the control force on the
norm-constrained system is ``Q_c = W Z (Zᵀ W Z)⁺ r`` with ``Z = K A_cᵀ`` and ``r = b_c - A_c a``
(Eq. B10 restricted to the control rows); for ``N = M⁻¹`` (Gauss, ``W = M``) ``Zᵀ M Z = A_c K A_cᵀ``
and this is Eq. (89). Only ``W`` is ever needed, so no weighting requires inverting M.

The formulas are written once, in :func:`solve_array`, for any array namespace (numpy, jax.numpy)
and leading batch dimensions, with the factorisation of ``M_α`` and the rank decision passed in:
:func:`solve` (the numpy reference, one system) uses scipy's Cholesky and :func:`pinv_psd`; the
array path's defaults are an LU solve and :func:`pinv_psd_masked` (fixed shapes, ``jax.jit``-able).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from analytic.array_ops import matvec, vecdot, vecmat
from analytic.effects import Weighting

# Relative eigenvalue cut-off of the Moore-Penrose inverse of the (symmetric PSD) constraint Gram
# matrix: eigenvalues below PINV_RCOND x the largest are treated as zero (rank deficiency). Round-off
# in the Gram matrix is ~1e-16 x cond(M); 1e-10 separates a truly redundant requirement from a merely
# ill-conditioned one for mass ratios up to ~1e6 (the hard-case range).
PINV_RCOND = 1e-10


@dataclass(frozen=True)
class FundamentalSolution:
    """Result of one evaluation of the fundamental equation.

    Attributes:
        qddot: constrained acceleration, shape (nq,).
        constraint_force: the total generalized constraint force ``M q̈ - Q``: the paper's ``Q^C``
            of Eq. (89), the control force plus the reaction of the quaternion-norm constraint along
            ``a_m = [0, u, 0]`` (docs/errata.md C4), shape (nq,).
        control_force: the applied control force alone, without that reaction, shape (nq,); it
            differs from ``constraint_force`` only along ``a_m``, which ``H(u) u = 0`` removes from
            the torque (``τ = ¼ H Q^C_u``), so either gives the same τ, rod forces and force at C.
        lambda_m: multiplier of the modeling constraint alone (uncontrolled part), scalar.
        residual: ``A_c q̈ - b_c``, the unattainable part of the control requirements, shape (k,).
        rank: numerical rank of the control Gram matrix (k when every requirement is independent).
    """

    qddot: np.ndarray
    constraint_force: np.ndarray
    control_force: np.ndarray
    lambda_m: float
    residual: np.ndarray
    rank: int


def pinv_psd(G: np.ndarray, rcond: float = PINV_RCOND) -> tuple[np.ndarray, int]:
    """Moore-Penrose inverse of a symmetric positive semidefinite Gram matrix, and its rank.

    The rows of ``A_c`` carry different units (rad/s² for ω rows, m/s² for mass rows) and masses
    may span many decades, so the rank is decided on the Jacobi-scaled matrix ``D G D``
    (``D = diag(G)^-1/2``, unit diagonal), which is invariant to the rows' units. At full rank the
    inverse is computed from the scaled matrix too (``G⁻¹ = D (D G D)⁻¹ D``, better conditioned);
    at rank r < k it is the Moore-Penrose inverse of G from its r largest eigenpairs.

    One matrix (k, k), numpy, the rank decided by a Python branch; :func:`pinv_psd_masked` is the
    same inverse for any array namespace and leading batch dimensions.
    """
    dg = np.diag(G).copy()
    dg[dg <= 0] = 1.0
    D = 1.0 / np.sqrt(dg)
    DD = np.outer(D, D)
    w, V = np.linalg.eigh(G * DD)
    wmax = float(np.max(np.abs(w))) if w.size else 0.0
    keep = w > rcond * wmax
    rank = int(np.count_nonzero(keep))
    if rank == G.shape[0]:
        return ((V / w) @ V.T) * DD, rank
    w, V = np.linalg.eigh(G)
    top = np.argsort(w)[::-1][:rank]
    return (V[:, top] / w[top]) @ V[:, top].T, rank


def pinv_psd_masked(xp, G, rcond: float = PINV_RCOND):
    """:func:`pinv_psd` with the rank decision made by masking (fixed shapes, no branch on
    values: ``jax.jit``-able): both inverses are computed, the Jacobi-scaled one (full rank) and
    the Moore-Penrose one of the unscaled G from its r largest eigenpairs, and the rank selects.

    Args:
        xp: the array namespace (numpy or jax.numpy).
        G: symmetric PSD, shape (..., k, k), k >= 1.

    Returns:
        ``(G⁺ (..., k, k), rank (...) integer array)``.

    The cut-off is :data:`PINV_RCOND` whatever the dtype: in float32 the eigenvalues carry a
    round-off of ~1e-7 of the largest, so a requirement set redundant in exact arithmetic is
    then seen as full rank (the model's own rows never are: ``analytic.fast``'s docstring).
    """
    k = G.shape[-1]
    dg = xp.diagonal(G, axis1=-2, axis2=-1)
    dg = xp.where(dg <= 0, 1.0, dg)
    D = 1.0 / xp.sqrt(dg)
    DD = D[..., :, None] * D[..., None, :]
    w, V = xp.linalg.eigh(G * DD)
    wmax = xp.max(xp.abs(w), axis=-1)
    keep = w > rcond * wmax[..., None]
    rank = xp.sum(keep, axis=-1)
    w_safe = xp.where(keep, w, 1.0)
    full = ((V / w_safe[..., None, :]) @ V.mT) * DD
    w2, V2 = xp.linalg.eigh(G)  # ascending: the r largest are the last r
    top = xp.arange(k) >= (k - rank)[..., None]
    w2inv = xp.where(top, 1.0 / xp.where(top, w2, 1.0), 0.0)
    low = (V2 * w2inv[..., None, :]) @ V2.mT
    return xp.where((rank == k)[..., None, None], full, low), rank


class ArraySolution(NamedTuple):
    """:class:`FundamentalSolution`'s fields as arrays with leading batch dimensions (...):
    ``qddot``, ``constraint_force``, ``control_force`` (..., nq), ``lambda_m`` (...),
    ``residual`` (..., k), ``rank`` (...) (integers; 0 when k = 0). A tuple: a JAX pytree."""

    qddot: Any
    constraint_force: Any
    control_force: Any
    lambda_m: Any
    residual: Any
    rank: Any


def lu_factor(xp):
    """The array path's factorisation of ``M_α``: a closure solving ``M_α X = B`` by
    ``xp.linalg.solve`` (LU with partial pivoting, batched), ``B`` of shape (..., nq, m)."""

    def factor(Ma):
        return lambda B: xp.linalg.solve(Ma, B)

    return factor


def cholesky_factor(Ma: np.ndarray):
    """The numpy reference's factorisation of one ``M_α`` (nq, nq): scipy's Cholesky, which raises
    ``numpy.linalg.LinAlgError`` when ``M_α`` is not positive definite (the motion not unique)."""
    from scipy.linalg import cho_factor, cho_solve  # here: 0.4 s of import, off the start-up

    c = cho_factor(Ma, lower=False, check_finite=False)
    return lambda B: cho_solve(c, B, check_finite=False)


def solve_array(
    xp,
    M,
    Q,
    a_m,
    b_m,
    A_c,
    b_c,
    weighting: Weighting = Weighting.M_INV,
    *,
    factor=None,
    pinv=None,
) -> ArraySolution:
    """The fundamental equation for any array namespace and leading batch dimensions: the one
    form of the formulas (:func:`solve` is this with numpy, scipy's Cholesky and
    :func:`pinv_psd`).

    Args:
        xp: numpy or jax.numpy.
        M: (..., nq, nq); Q, a_m: (..., nq); b_m: (...); A_c: (..., k, nq); b_c: (..., k).
        weighting: the cost matrix N of Appendix B (a Python branch: static).
        factor: ``factor(M_α)`` returns a function solving ``M_α X = B`` for B (..., nq, m);
            default :func:`lu_factor` (jit-able).
        pinv: ``pinv(G)`` returns ``(G⁺, rank)``; default :func:`pinv_psd_masked` (jit-able).

    Returns:
        :class:`ArraySolution`.
    """
    if factor is None:
        factor = lu_factor(xp)
    if pinv is None:

        def pinv(G):
            return pinv_psd_masked(xp, G)

    nq = Q.shape[-1]
    k = A_c.shape[-2]
    # Udwadia-Phohomsiri: M_α = M + α a_m a_mᵀ, Q_α = Q + α a_m b_m (adds zero to the motion)
    alpha = xp.diagonal(M, axis1=-2, axis2=-1).sum(axis=-1) / nq
    Ma = M + alpha[..., None, None] * (a_m[..., :, None] * a_m[..., None, :])
    Qa = Q + (alpha * b_m)[..., None] * a_m
    batch = Ma.shape[:-2]
    solve_Ma = factor(Ma)
    A_cT = A_c.mT
    if A_cT.shape != (*batch, nq, k):
        A_cT = xp.broadcast_to(A_cT, (*batch, nq, k))
    X = solve_Ma(xp.concatenate([Qa[..., None], a_m[..., None], A_cT], axis=-1))
    a0, y, Y = X[..., 0], X[..., 1], X[..., 2:]
    s = vecdot(a_m, y)
    lambda_m = (b_m - vecdot(a_m, a0)) / s
    acc = a0 + lambda_m[..., None] * y  # Eq. (60): the uncontrolled, norm-constrained acceleration
    if k == 0:
        zeros = xp.zeros_like(acc)
        return ArraySolution(
            acc, lambda_m[..., None] * a_m, zeros, lambda_m, zeros[..., :0], xp.zeros(batch, int)
        )

    Ay = matvec(A_c, y)
    Z = Y - y[..., :, None] * (Ay / s[..., None])[..., None, :]  # K A_cᵀ, shape (..., nq, k)
    r = b_c - matvec(A_c, acc)
    if weighting is Weighting.M_INV:
        G = A_c @ Z  # A_c K A_cᵀ = Zᵀ M Z
        Ginv, rank = pinv(0.5 * (G + G.mT))
        mu = matvec(Ginv, r)
        qddot = acc + matvec(Z, mu)
        Q_ctl = vecmat(mu, A_c)  # A_cᵀμ; M K Q_ctl differs only along a_m
    else:
        WZ = M @ (M @ Z) if weighting is Weighting.M_INV2 else Z  # W = N⁻¹: M² or I
        G = Z.mT @ WZ
        Ginv, rank = pinv(0.5 * (G + G.mT))
        Q_ctl = matvec(WZ, matvec(Ginv, r))
        v = solve_Ma(Q_ctl[..., None])[..., 0]
        qddot = acc + v - y * (vecdot(a_m, v) / s)[..., None]  # q̈ = a + K Q_ctl
    # Q^C = M q̈ - Q = a_m λ_m + (I - a_m yᵀ/s) Q_ctl, assembled without cancellation.
    Q_C = Q_ctl + a_m * (lambda_m - vecdot(y, Q_ctl) / s)[..., None]
    residual = matvec(A_c, qddot) - b_c
    return ArraySolution(qddot, Q_C, Q_ctl, lambda_m, residual, rank)


def solve(
    M: np.ndarray,
    Q: np.ndarray,
    a_m: np.ndarray,
    b_m: float,
    A_c: np.ndarray,
    b_c: np.ndarray,
    weighting: Weighting = Weighting.M_INV,
) -> FundamentalSolution:
    """Constrained acceleration for ``M q̈ = Q`` under ``a_mᵀ q̈ = b_m`` and ``A_c q̈ = b_c``: the
    numpy reference, :func:`solve_array` with scipy's Cholesky of ``M_α`` and :func:`pinv_psd`.

    Args:
        M: mass matrix, shape (nq, nq), symmetric PSD with ``[M; a_mᵀ]`` of full column rank.
        Q: generalized force, shape (nq,).
        a_m: modeling-constraint row, shape (nq,).
        b_m: its right-hand side.
        A_c: control rows, shape (k, nq), k >= 0.
        b_c: their right-hand sides, shape (k,).
        weighting: the cost matrix N of Appendix B.

    Raises:
        numpy.linalg.LinAlgError: when ``[M; a_mᵀ]`` is rank deficient (the motion is not unique).
    """
    sol = solve_array(
        np,
        M,
        Q,
        a_m,
        np.float64(b_m),
        A_c,
        b_c,
        weighting,
        factor=cholesky_factor,
        pinv=pinv_psd,
    )
    return FundamentalSolution(
        sol.qddot,
        sol.constraint_force,
        sol.control_force,
        float(sol.lambda_m),
        sol.residual,
        int(sol.rank),
    )
