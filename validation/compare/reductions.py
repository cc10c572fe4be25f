"""The reductions every compared quantity goes through: a vector per sample to one scalar per
sample, and a run's samples to one largest magnitude.

The contract: :func:`norm` is the Euclidean norm of each row (``|x|`` of a 1-D array),
:func:`maxabs` the largest ``|x|`` of each row (zeros without columns), :func:`largest` the largest
finite magnitude over a run (0 when there is none); each a pure function of its array. A change to
how a vector quantity becomes a scalar series costs this module only.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def norm(x: np.ndarray) -> np.ndarray:
    """The Euclidean norm of each row, shape (N, k) -> (N,); ``|x|`` for a 1-D array."""
    return np.linalg.norm(x, axis=1) if x.ndim == 2 else np.abs(x)


def maxabs(x: np.ndarray) -> np.ndarray:
    """Max over columns of |x|, shape (N, k) -> (N,); zeros when k = 0."""
    if x.shape[1] == 0:
        return np.zeros(x.shape[0])
    return np.max(np.abs(x), axis=1)


def largest(x: Any, rows: bool) -> float:
    """The largest finite magnitude of ``x`` (shape (N, k), or (N,)): of each row's Euclidean norm
    when ``rows`` (a vector per sample), else of every entry; 0 when there is none."""
    a = np.asarray(x, float)
    if a.size == 0:
        return 0.0
    m = np.linalg.norm(a, axis=1) if rows and a.ndim == 2 else np.abs(a)
    m = m[np.isfinite(m)]
    return float(m.max()) if m.size else 0.0


def largest_row_norm(x: np.ndarray) -> float:
    """The largest per-sample magnitude of ``x``: the row norm of a vector series (k > 1), the
    largest ``|x|`` of a row otherwise; 0 without samples (non-finite values are kept)."""
    if x.size == 0:
        return 0.0
    v = norm(x) if x.ndim == 2 and x.shape[1] > 1 else np.abs(x).reshape(x.shape[0], -1).max(axis=1)
    return float(np.max(v)) if v.size else 0.0


__all__ = ["largest", "largest_row_norm", "maxabs", "norm"]
