"""The three batched products the array form of the model uses, written with ``@`` so that every
array library this project supports runs them: numpy from 2.0 (``np.matvec`` and ``np.vecmat``
arrived in 2.2, later than the lowest numpy that the lowest supported numba installs) and
jax.numpy.

Each works on stacks: leading dimensions broadcast as in ``@``; the last one or two are the
vector's and the matrix's.
"""

from __future__ import annotations


def matvec(A, x):
    """``A x`` over the last two axes of A (..., m, k) and the last axis of x (..., k) -> (..., m)."""
    return (A @ x[..., None])[..., 0]


def vecmat(x, A):
    """``xᵀ A``: x (..., m), A (..., m, k) -> (..., k)."""
    return (x[..., None, :] @ A)[..., 0, :]


def vecdot(x, y):
    """``xᵀ y`` over the last axis (real arrays): (..., k), (..., k) -> (...)."""
    return (x * y).sum(axis=-1)
