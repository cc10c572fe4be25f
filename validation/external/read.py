"""``read_trajectory``: another engine's run of a scene, from a CSV or Parquet trajectory file.

The file is read through :func:`analytic.safe_files.read_regular` (a regular file only, as a
scene file the user names: a symbolic link is followed to the file it names, a FIFO, device or
directory is refused without blocking; at most :func:`size_limit` bytes), parsed as numbers
and nothing else, and checked whole before anything is built from it: the header
(:func:`validation.external.columns.parse_header`), then the values
(:func:`validation.external.table.check_table`). Nothing in the file is evaluated or names a path.
Every refusal is one :class:`~validation.external.errors.TrajectoryFileError` line naming the file,
the data row (1-based, the header not counted; a CSV message adds the line number) and the column.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from analytic.safe_files import read_regular
from analytic.scene import Scene
from analytic.trajectory import Engine
from validation.external.columns import ColumnGroup, TrajectoryFormat, header, parse_header
from validation.external.csv_text import parse_csv
from validation.external.errors import TrajectoryFileError, Where
from validation.external.parquet_table import parse_parquet
from validation.external.record import ExternalTrajectory, external_trajectory
from validation.external.table import check_table

BYTES_PER_VALUE = 64
"""Bytes per value a file may spend on average (:func:`size_limit`): ``repr`` of a double is at
most 24 characters (``-1.2345678901234567e-308``) plus a comma; the rest is room for blanks."""

SUFFIXES = {".csv": TrajectoryFormat.CSV, ".parquet": TrajectoryFormat.PARQUET, ".pq": TrajectoryFormat.PARQUET}
"""File name suffixes (any case) and the format each names."""


def size_limit(scene: Scene) -> int:
    """The largest file read for ``scene``, bytes: every column for its n, one row per output
    sample and the header, at :data:`BYTES_PER_VALUE` each, plus 64 KiB."""
    rows = len(scene.output.times()) + 1
    return rows * len(header(scene.n)) * BYTES_PER_VALUE + (64 << 10)


def format_of(path: str | Path) -> TrajectoryFormat:
    """The format named by the file's suffix (``.csv``, ``.parquet`` or ``.pq``, any case).

    Raises:
        TrajectoryFileError: another suffix.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise TrajectoryFileError(
            f"trajectory file {str(path)!r}: unknown format (suffix {suffix or 'none'!r}); "
            "name it .csv or .parquet"
        )
    return SUFFIXES[suffix]


def _read_bytes(path: Path, where: Where, limit: int) -> bytes:
    try:
        return read_regular(path, limit, follow_links=True)
    except FileNotFoundError:
        raise TrajectoryFileError(f"{where.file}: no such file") from None
    except OSError as exc:  # a link, FIFO, device, directory; larger than the limit; permissions
        reason = exc.strerror or str(exc)
        raise TrajectoryFileError(f"{where.file}: {reason}") from None


def read_trajectory(
    path: str | Path,
    scene: Scene,
    *,
    engine: Engine | str,
    format: TrajectoryFormat | None = None,
) -> ExternalTrajectory:
    """Read and check a trajectory file of ``scene`` (``docs/trajectory-format.md``).

    Args:
        path: the file (read only; a regular file).
        scene: the scene it is a run of: its mass count n and its output grid
            (``scene.output.times()``; shorten the horizon with ``scene.output.with_t_end``).
        engine: the plant name the run goes by (``Trajectory.engine``): the file's run is none
            of the built-in plants; the caller names it (``tumble judge --label``).
        format: CSV or Parquet; default from the suffix (:func:`format_of`).

    Returns:
        the :class:`ExternalTrajectory`: the run in the paper's coordinates on the scene's grid,
        the optional column groups present, and the SHA-256 of the bytes read.

    Raises:
        TrajectoryFileError (a ValueError): one line naming the file and, where it applies, the
            data row and column: unreadable or not a regular file, too large, not CSV numbers or
            Parquet doubles, wrong column count, unknown, duplicate or missing column, a mass count
            other than the scene's, NaN or infinity, t not increasing or not the scene's grid,
            a quaternion with ``| |u| − 1 |`` beyond 1e-6.
    """
    path = Path(path)
    fmt = format_of(path) if format is None else TrajectoryFormat(format)
    limit = size_limit(scene)
    if fmt is TrajectoryFormat.CSV:
        where = Where(str(path), header_lines=1)
        data = _read_bytes(path, where, limit)
        names, values = parse_csv(data, where)
    else:
        where = Where(str(path))
        data = _read_bytes(path, where, limit)
        max_rows = len(scene.output.times())
        names, values = parse_parquet(data, where, max_rows, len(header(scene.n)))
    layout = parse_header(names, scene.n, f"{where.file}, header")
    check_table(names, values, layout, scene, where)
    groups = {
        g: values[:, layout.columns(g, scene.n)]
        for g in ColumnGroup
        if g.required or g in layout.present
    }
    digest = hashlib.sha256(data).hexdigest()
    return external_trajectory(scene, str(engine), groups, fmt, str(path), sha256=digest)


__all__ = ["BYTES_PER_VALUE", "SUFFIXES", "format_of", "read_trajectory", "size_limit"]
