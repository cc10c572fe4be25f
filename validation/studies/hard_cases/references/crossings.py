"""Event instants: where a sampled signal changes sign (flips of a spin, masses passing through
each other), by linear interpolation between samples."""

from __future__ import annotations

import numpy as np


def zero_crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Instants, s, where ``x`` changes sign between samples (linear interpolation); ``t`` and
    ``x`` shape (N,) -> shape (k,)."""
    s = np.sign(x)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def mass_crossings(t: np.ndarray, p: np.ndarray) -> list[tuple[float, int]]:
    """Every instant two neighbouring masses pass through each other (``p_{i+1} - p_i`` changes
    sign), as ``(time s, i)`` (0-based: masses i and i + 1), sorted by time; ``p`` shape (N, n)."""
    gaps = np.diff(p, axis=1)
    out = [(float(tc), i) for i in range(gaps.shape[1]) for tc in zero_crossings(t, gaps[:, i])]
    return sorted(out)


def max_instant_difference(a: np.ndarray, b: np.ndarray) -> float:
    """``max |a_k - b_k|`` of two lists of instants, s; infinite when their numbers differ or
    both are empty (the events themselves disagree)."""
    if len(a) != len(b) or not len(a):
        return float("inf")
    return float(np.max(np.abs(a - b)))


__all__ = ["mass_crossings", "max_instant_difference", "zero_crossings"]
