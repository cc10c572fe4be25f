"""``write_trajectory``: a plant's :class:`Trajectory` as a trajectory file (CSV or Parquet).

The columns are :data:`validation.external.columns.COLUMNS` for the scene's n: t, R, u and p from
``q`` (Eq. 44), ``v = Ṙ``, ``ω = H(u) u̇`` (body axes, Eq. 12), ``ṗ``, the control torque ``τ``
(body axes), the rod forces ``F`` and the plant's quadratures (work, impulses). Every value is written at full precision (CSV: ``repr``,
the shortest text that reads back to the same double; Parquet: doubles), so
:func:`validation.external.read.read_trajectory` gives back t, R, u, p, v, ω, ṗ, τ and F exactly.
The table is checked as the reader checks a file (:func:`validation.external.table.check_table`)
before anything is written, so what is written can be read; the file is written atomically
(:func:`validation.runs.atomic.write_bytes`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from analytic.effects import Effect
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from validation.external.columns import ColumnGroup, TrajectoryFormat, header, parse_header
from validation.external.csv_text import format_csv
from validation.external.errors import TrajectoryFileError, Where
from validation.external.parquet_table import format_parquet
from validation.external.read import format_of
from validation.external.table import check_table
from validation.runs.atomic import write_bytes


def _quadratures(trajectory: Trajectory, scene: Scene) -> np.ndarray:
    """``[W, I_L, I_P]`` per sample, shape (N, 7) (:mod:`analytic.assemble`), from the invariants:
    ``I_P = P_expected − P(0) − m_T g t`` undoes how :func:`analytic.invariants.compute_invariants`
    builds ``P_expected`` (to round-off)."""
    inv = trajectory.invariants
    impulse = inv.linear_momentum_expected - inv.linear_momentum[0]
    if scene.has(Effect.GRAVITY):
        m_T = float(scene.body.mass) + float(np.sum(scene.masses.mass))
        impulse = impulse - m_T * np.outer(trajectory.t - trajectory.t[0], scene.gravity)
    return np.concatenate([inv.work[:, None], inv.angular_impulse, impulse], axis=1)


def _group_values(trajectory: Trajectory, group: ColumnGroup, scene: Scene) -> np.ndarray:
    """The trajectory's samples of one column group, shape (N, k), in the group's column order."""
    tr = trajectory
    if group is ColumnGroup.WORK:
        return _quadratures(tr, scene)
    values = {
        ColumnGroup.TIME: tr.t[:, None],
        ColumnGroup.POSITION: tr.R,
        ColumnGroup.ATTITUDE: tr.u,
        ColumnGroup.ROD_POSITIONS: tr.p,
        ColumnGroup.VELOCITY: tr.qdot[:, :3],
        ColumnGroup.ANGULAR_VELOCITY: tr.omega,
        ColumnGroup.ROD_VELOCITIES: tr.qdot[:, 7:],
        ColumnGroup.TORQUE: tr.torque,
        ColumnGroup.ROD_FORCES: tr.rod_forces,
    }
    return np.asarray(values[group], dtype=np.float64)


def trajectory_table(
    trajectory: Trajectory, scene: Scene, groups: frozenset[ColumnGroup] | None = None
) -> tuple[tuple[str, ...], np.ndarray]:
    """``(header names, values (N, C))`` of a trajectory of ``scene``: the required groups and
    ``groups`` (default every optional group), in the order of
    :data:`~validation.external.columns.COLUMNS`."""
    names = header(trajectory.n, groups)
    chosen = [g for g in ColumnGroup if g.required or groups is None or g in groups]
    values = np.concatenate([_group_values(trajectory, g, scene) for g in chosen], axis=1)
    return names, values


def write_trajectory(
    path: str | Path,
    scene: Scene,
    trajectory: Trajectory,
    *,
    format: TrajectoryFormat | None = None,
    groups: frozenset[ColumnGroup] | None = None,
) -> Path:
    """Write ``trajectory`` (a run of ``scene``) as a trajectory file; returns the path.

    Args:
        path: the file to write (atomically; its directory is created).
        scene: the scene the trajectory is a run of (checked: its n and its output grid).
        trajectory: the run, complete on the scene's grid.
        format: CSV or Parquet; default from the suffix (``.csv``, ``.parquet``, ``.pq``).
        groups: the optional column groups to write (default all).

    Raises:
        TrajectoryFileError: the trajectory is not one the reader would accept (another n, not
            the scene's grid, a NaN, a non-unit quaternion), naming the row and column.
        OutputError: the file could not be written (the target is unchanged).
    """
    path = Path(path)
    fmt = format_of(path) if format is None else TrajectoryFormat(format)
    lines = 1 if fmt is TrajectoryFormat.CSV else 0
    where = Where(str(path), header_lines=lines, noun="trajectory to write to")
    if trajectory.n != scene.n:
        raise TrajectoryFileError(
            f"{where.file}: the trajectory has n = {trajectory.n} masses, the scene "
            f"{scene.name!r} n = {scene.n}"
        )
    names, values = trajectory_table(trajectory, scene, groups)
    check_table(names, values, parse_header(names, scene.n, where.file), scene, where)
    if fmt is TrajectoryFormat.CSV:
        data = format_csv(names, values)
    else:
        data = format_parquet(names, values, str(path))
    return write_bytes(path, data)


__all__ = ["trajectory_table", "write_trajectory"]
