"""Reading one value of a scene: every number, vector, matrix, index list and choice passes through
one of these, so every error is a ``ValueError`` that starts with the dotted name of its field and
shows the value (``masses.mass[1]: must be positive (got -3.0)``).

Vectors and matrices come back as read-only float arrays; 1-based indices in the file come back
0-based. Axes and rotations given rounded are repaired within the bounds of
:mod:`analytic.scene.limits` and refused beyond them.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from analytic.scene.limits import (
    AXIS_NORMALISE_TOL,
    AXIS_REFUSE_TOL,
    ROTATION_EXACT_TOL,
    ROTATION_REFUSE_TOL,
)


def frozen(a: ArrayLike) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


class SceneText(str):
    """Text a scene file gives (its name, description, a threshold's reason), kept verbatim.

    A plain ``str`` in every respect; the JSON writers (``validation.report.provenance``) carry it as it
    is, where text the code writes itself may not be a placeholder such as ``"unknown"`` or
    ``"nan"``: a scene's description may well read "unknown"."""

    verbatim_text = True


def as_enum(kind: type, value: Any, name: str) -> Any:
    """``value`` as a member of the enum ``kind``, or ValueError naming ``name``, the value and
    the choices."""
    if isinstance(value, kind):
        return value
    try:
        return kind(value)
    except ValueError:
        allowed = ", ".join(repr(e.value) for e in kind)
        raise ValueError(f"{name}: unknown value {show(value)} (allowed: {allowed})") from None


def show(v: Any) -> str:
    """``repr(v)``, but an integer too long to read is shown by its number of digits."""
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 10**20:
        # (from its bit length: str() of an integer of more than 4300 digits raises)
        return f"an integer of about {int(abs(v).bit_length() * math.log10(2)) + 1} digits"
    try:
        r = repr(v)
    except ValueError:  # it holds an integer of more than 4300 digits
        return "a value holding an integer too long to show"
    if len(r) > _SHOW_MAX:  # a long list: its head and its length, so the message stays a line
        size = f"{len(v)} entries" if isinstance(v, list | tuple) else f"{len(r)} characters"
        return f"{r[: _SHOW_MAX // 2]}... ({size})"
    return r


_SHOW_MAX = 200  # characters of a bad value quoted in a message


def as_number(v: Any, name: str, *, positive=False, nonneg=False) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ValueError(f"{name}: must be a number (got {show(v)})")
    try:
        x = float(v)
    except OverflowError:  # an integer literal beyond the double range
        raise ValueError(f"{name}: must be finite (got {show(v)})") from None
    if not math.isfinite(x):
        raise ValueError(f"{name}: must be finite (got {show(v)})")
    if positive and not x > 0:
        raise ValueError(f"{name}: must be positive (got {show(v)})")
    if nonneg and not x >= 0:
        raise ValueError(f"{name}: must be non-negative (got {show(v)})")
    return x


def as_vector(v: Any, name: str, length: int | None = None, *, positive=False, nonneg=False):
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, list | tuple):
        raise ValueError(f"{name}: must be a list of numbers (got {show(v)})")
    if length is not None and len(v) != length:
        raise ValueError(f"{name}: must have {length} entries (got {len(v)}: {show(v)})")
    out = [as_number(x, f"{name}[{i}]", positive=positive, nonneg=nonneg) for i, x in enumerate(v)]
    return frozen(np.array(out, dtype=float).reshape(len(out)))


def as_matrix(v: Any, name: str, rows: int, cols: int) -> np.ndarray:
    if not isinstance(v, list | tuple) or len(v) != rows:
        raise ValueError(f"{name}: must be a {rows}x{cols} list of rows (got {show(v)})")
    return frozen(np.array([as_vector(r, f"{name}[{i}]", cols) for i, r in enumerate(v)]))


def unit_vector(v: np.ndarray, name: str) -> np.ndarray:
    """A unit vector given with its norm within :data:`AXIS_REFUSE_TOL` of 1: kept as given
    within :data:`AXIS_NORMALISE_TOL`, else normalised with one warning naming the norm (a printed
    axis is rounded: Example 1's a has |a| = 0.99997); refused further off."""
    nrm = float(np.linalg.norm(v))
    if nrm == 0.0:
        raise ValueError(f"{name}: must be a nonzero vector (got {v.tolist()!r})")
    if abs(nrm - 1.0) > AXIS_REFUSE_TOL:
        raise ValueError(
            f"{name}: must be a unit vector, norm within {AXIS_REFUSE_TOL:g} of 1 "
            f"(got norm {nrm!r} for {v.tolist()!r})"
        )
    if abs(nrm - 1.0) <= AXIS_NORMALISE_TOL:
        return frozen(v)
    warnings.warn(
        f"{name}: norm {nrm:.6g} normalised to 1 (got {v.tolist()!r})", UserWarning, stacklevel=5
    )
    return frozen(v / nrm)


def direction(v: np.ndarray, name: str) -> np.ndarray:
    """Any nonzero vector, scaled to unit length (rotation axes); kept as given when its norm is
    within :data:`AXIS_NORMALISE_TOL` of 1."""
    nrm = float(np.linalg.norm(v))
    if nrm == 0.0:
        raise ValueError(f"{name}: must be a nonzero vector (got {v.tolist()!r})")
    return frozen(v if abs(nrm - 1.0) <= AXIS_NORMALISE_TOL else v / nrm)


def nearest_rotation(m: np.ndarray, name: str) -> np.ndarray:
    """The rotation nearest ``m`` (polar decomposition); refuses a matrix far from one. A matrix
    orthonormal within :data:`ROTATION_EXACT_TOL` is kept as given."""
    if np.max(np.abs(m.T @ m - np.eye(3))) <= ROTATION_EXACT_TOL and np.linalg.det(m) > 0:
        return np.array(m, dtype=float)
    U, s, Vt = np.linalg.svd(m)
    if np.max(np.abs(s - 1.0)) > ROTATION_REFUSE_TOL or np.linalg.det(m) <= 0:
        raise ValueError(f"{name}: must be a rotation matrix (singular values {s.tolist()!r})")
    return U @ Vt


def indices(v: Any, name: str, upper: int) -> tuple[int, ...]:
    """1-based indices in the file, 0-based in the record; distinct and in range."""
    if not isinstance(v, list | tuple) or not v:
        raise ValueError(f"{name}: must be a non-empty list of 1-based indices (got {show(v)})")
    out = []
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, int) or not 1 <= x <= upper:
            raise ValueError(f"{name}[{i}]: must be an integer in 1..{upper} (got {show(x)})")
        out.append(x - 1)
    if len(set(out)) != len(out):
        raise ValueError(f"{name}: indices must be distinct (got {show(v)})")
    return tuple(out)


__all__ = [
    "SceneText",
    "as_enum",
    "as_matrix",
    "as_number",
    "as_vector",
    "direction",
    "frozen",
    "indices",
    "nearest_rotation",
    "show",
    "unit_vector",
]
