"""The checks on a trajectory table's numbers, the same for a file read and a trajectory written.

A table is the file's header (names) and its samples as one float array, shape (N, C), one row
per data row, columns in file order. :func:`check_table` refuses, in this order, the first
non-finite value, a time that does not increase, a time off the scene's output grid, a row count
other than the grid's (a file that stops on the grid early is accepted when the caller asks,
``up_to_file_end``), and a quaternion that is not unit; every message names the data row and the column
(:class:`~validation.external.errors.Where`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from analytic.scene import Scene
from validation.external.columns import ColumnGroup, HeaderLayout
from validation.external.errors import TrajectoryFileError, Where

QUAT_NORM_TOL = 1e-6
"""Largest ``| |u| − 1 |`` a row's quaternion may have. The file's u is kept as written (an
engine's norm drift is what the ``quat_norm`` check judges, at 1e-9), so this bound only refuses
what is not a unit quaternion at all: a column in the wrong place, angles instead of a quaternion,
a quaternion printed with fewer than about seven significant digits (rounding four components to
seven digits moves the norm by up to ~1e-7)."""

GRID_TOL = 1e-6
"""Largest ``|t_k − t̂_k|`` of a row's time from the scene's output grid ``t̂``, in sample
intervals (1/rate). The file's samples are judged as the grid's samples, so a time off the grid
by ``ε/rate`` shifts the state by up to ``ε·Ω/rate`` for a motion at rate Ω: at the paper's 100 Hz
and Ω ≤ 10 rad/s (or 10 m/s per m), 1e-6 intervals are ≤ 1e-7 rad or m, a decade below the
comparison's 1e-6 agreement thresholds. It admits a time column written with 17 significant
digits, computed as k/rate or summed as t += 1/rate over up to 1e5 samples (round-off ≤ N²·1.1e-16
intervals); it refuses a time printed with too few digits (e.g. six decimals of a 0.001 s grid)."""


def grid_text(scene: Scene) -> str:
    """The scene's output grid in words: first, step, last and count."""
    t = scene.output.times()
    return (
        f"the scene's output grid (first 0 s, step 1/rate = {1.0 / scene.output.rate!r} s, "
        f"last t_end = {float(t[-1])!r} s, {len(t)} samples)"
    )


def _first_bad_cell(bad: np.ndarray) -> tuple[int, int]:
    """``(row, column)`` of the first True of a (N, C) mask in file order (row by row)."""
    flat = int(np.argmax(bad.reshape(-1)))
    return divmod(flat, bad.shape[1])


def check_finite(values: np.ndarray, names: Sequence[str], where: Where) -> None:
    """Refuse the first NaN or infinite value (file order)."""
    bad = ~np.isfinite(values)
    if bad.any():
        k, c = _first_bad_cell(bad)
        x = float(values[k, c])
        what = "NaN" if x != x else f"infinite ({x!r})"
        raise TrajectoryFileError(f"{where.at(k, names[c])}: {what}; every value must be finite")


def check_time(
    t: np.ndarray, scene: Scene, where: Where, *, up_to_file_end: bool = False, hint: bool = False
) -> None:
    """Refuse a time that does not increase, then a time off the scene's grid (each value within
    :data:`GRID_TOL` intervals of its grid point), then a row count other than the grid's, naming
    the expected grid.

    Args:
        t: the time column.
        scene: the scene whose output grid the column must be.
        where: how messages name the file and rows.
        up_to_file_end: a file that stops on the grid before its end is accepted (at least two
            rows): it is judged up to its last row (``tumble judge --up-to-file-end``).
        hint: a file that stops on the grid early is refused with the options that judge it
            over the horizon it covers (the reader of ``tumble judge``; not the writer).
    """
    dt = np.diff(t)
    if (dt <= 0).any():
        k = int(np.argmax(dt <= 0)) + 1
        raise TrajectoryFileError(
            f"{where.at(k, 't')}: {float(t[k])!r} s is not after the previous row's "
            f"{float(t[k - 1])!r} s (t must increase)"
        )
    grid = scene.output.times()
    common = min(len(t), len(grid))
    step = 1.0 / scene.output.rate
    off = np.abs(t[:common] - grid[:common]) > GRID_TOL * step
    if off.any():
        k = int(np.argmax(off))
        raise TrajectoryFileError(
            f"{where.at(k, 't')}: {float(t[k])!r} s, expected {float(grid[k])!r} s "
            f"(± {GRID_TOL:g} sample intervals) on {grid_text(scene)}"
        )
    if len(t) == len(grid):
        return
    count = f"{where.file}, column 't': {len(t)} data rows, not {grid_text(scene)}"
    if len(t) > len(grid):
        raise TrajectoryFileError(count)
    last = float(grid[len(t) - 1])
    if len(t) < 2:
        raise TrajectoryFileError(
            f"{count}: one data row (t = 0) covers no horizon to judge"
            if up_to_file_end or hint
            else count
        )
    if up_to_file_end:
        return
    if hint:
        raise TrajectoryFileError(
            f"{count}; it stops on the grid at t = {last!r} s: to judge it over the 0-{last:g} s "
            f"it covers, give --t-end {last:g} or --up-to-file-end ([judge] t_end or "
            "up_to_file_end = true)"
        )
    raise TrajectoryFileError(count)


def check_quaternions(u: np.ndarray, where: Where) -> None:
    """Refuse the first row whose ``| |u| − 1 |`` exceeds :data:`QUAT_NORM_TOL`."""
    err = np.abs(np.linalg.norm(u, axis=1) - 1.0)
    bad = err > QUAT_NORM_TOL
    if bad.any():
        k = int(np.argmax(bad))
        raise TrajectoryFileError(
            f"{where.file}, {where.row(k)}, columns 'u_w' … 'u_z': |u| − 1 = "
            f"{float(np.linalg.norm(u[k]) - 1.0):.3g}, beyond {QUAT_NORM_TOL:g} (not a unit "
            "quaternion: w first, body → inertial; docs/trajectory-format.md)"
        )


def check_table(
    names: Sequence[str],
    values: np.ndarray,
    layout: HeaderLayout,
    scene: Scene,
    where: Where,
    *,
    up_to_file_end: bool = False,
    hint: bool = False,
) -> None:
    """Every check of this module, in the order of the module docstring.

    Args:
        names: header names in file order, C of them.
        values: the samples, shape (N, C), file order.
        layout: where each group is (:func:`validation.external.columns.parse_header`).
        scene: the scene whose grid and mass count the file must have.
        where: how messages name the file and rows.
        up_to_file_end, hint: as :func:`check_time`.
    """
    if values.shape[0] == 0:
        raise TrajectoryFileError(f"{where.file}: no data rows, expected {grid_text(scene)}")
    check_finite(values, names, where)
    check_time(
        values[:, layout.index["t"]], scene, where, up_to_file_end=up_to_file_end, hint=hint
    )
    check_quaternions(values[:, layout.columns(ColumnGroup.ATTITUDE, scene.n)], where)


__all__ = [
    "GRID_TOL",
    "QUAT_NORM_TOL",
    "check_finite",
    "check_quaternions",
    "check_table",
    "check_time",
    "grid_text",
]
