"""``read_trajectory``: another engine's run of a scene, from a CSV or Parquet trajectory file.

The file is opened through :func:`analytic.runtime.safe_files.open_regular` (a regular file only, as a
scene file the user names: a symbolic link is followed to the file it names, a FIFO, device or
directory is refused without blocking) and read whole, at most :func:`size_limit` bytes (a larger
file is refused naming its row count, its lines counted or its Parquet footer read, and the
limit), parsed as numbers and nothing else, and checked whole before anything is built from it: the header
(:func:`validation.external.columns.parse_header`), then the values
(:func:`validation.external.table.check_table`). Nothing in the file is evaluated or names a path.
Every refusal is one :class:`~validation.external.errors.TrajectoryFileError` line naming the file,
the data row (1-based, the header not counted; a CSV message adds the line number) and the column.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from analytic.runtime.safe_files import open_regular
from analytic.scene import Scene
from analytic.trajectory import Engine
from validation.external.columns import ColumnGroup, TrajectoryFormat, header, parse_header
from validation.external.csv_text import parse_csv
from validation.external.errors import TrajectoryFileError, Where
from validation.external.horizon import shortened
from validation.external.parquet_table import footer_metadata, parse_parquet
from validation.external.record import ExternalTrajectory, external_trajectory
from validation.external.table import GRID_TOL, check_table, grid_text

BYTES_PER_VALUE = 64
"""Bytes per value a CSV file may spend on average (:func:`size_limit`): ``repr`` of a double is
at most 24 characters (``-1.2345678901234567e-308``) plus a comma; the rest is room for blanks."""

PARQUET_BYTES_PER_VALUE = 1024
"""Bytes per value a Parquet file may spend on average (:func:`size_limit`): a valid file of
one-row row groups spends about 210 on each value's column chunk (its metadata, statistics and
page headers); what a Parquet file holds is bounded by its metadata's rows × columns and declared
sizes before anything is decompressed (:func:`validation.external.parquet_table.check_metadata`),
so this bound only keeps the bytes read in memory finite."""

SCAN_LIMIT = 1 << 30
"""Largest part of a CSV file too large to read whose lines are counted for the message."""

SUFFIXES = {".csv": TrajectoryFormat.CSV, ".parquet": TrajectoryFormat.PARQUET, ".pq": TrajectoryFormat.PARQUET}
"""File name suffixes (any case) and the format each names."""


def size_limit(scene: Scene, format: TrajectoryFormat = TrajectoryFormat.CSV) -> int:
    """The largest file read for ``scene``, bytes: every column for its n, one row per output
    sample and the header, at :data:`BYTES_PER_VALUE` each (Parquet:
    :data:`PARQUET_BYTES_PER_VALUE`), plus 64 KiB."""
    rows = len(scene.output.times()) + 1
    per_value = BYTES_PER_VALUE if format is TrajectoryFormat.CSV else PARQUET_BYTES_PER_VALUE
    return rows * len(header(scene.n)) * per_value + (64 << 10)


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


def _csv_rows(fd: int, size: int) -> tuple[int, bool]:
    """``(data rows, whole)``: the lines after the header in the first :data:`SCAN_LIMIT` bytes
    of the open file (blank lines at its end not counted), and whether that was the whole file."""
    newlines, offset = 0, 0
    while offset < min(size, SCAN_LIMIT):
        chunk = os.pread(fd, 1 << 20, offset)
        if not chunk:
            break
        newlines += chunk.count(b"\n")
        offset += len(chunk)
    whole = offset >= size
    if not whole:
        return max(newlines - 1, 0), False
    tail = os.pread(fd, min(size, 4 << 20), max(size - (4 << 20), 0))
    blank_end = tail[len(tail.rstrip(b" \t\r\n")) :]
    lines = newlines - blank_end.count(b"\n") + (1 if tail.strip() else 0)
    return max(lines - 1, 0), True


def _too_large(
    fd: int, size: int, limit: int, fmt: TrajectoryFormat, scene: Scene, where: Where
) -> str:
    """Why a file of ``size`` bytes, beyond ``limit``, is refused: its row count (CSV: its lines
    counted; Parquet: its footer's) against the scene's grid, and the byte limit."""
    grid = len(scene.output.times())
    per_value = BYTES_PER_VALUE if fmt is TrajectoryFormat.CSV else PARQUET_BYTES_PER_VALUE
    larger = (
        f"larger than {limit:,} bytes (the most a {fmt.value} file of the scene's {grid} samples "
        f"× {len(header(scene.n))} columns may take, {per_value} bytes a value)"
    )
    if fmt is TrajectoryFormat.CSV:
        rows, whole = _csv_rows(fd, size)
        counted = f"{rows} data rows" if whole else f"more than {rows} data rows"
        if not whole:
            counted += f" in its first {SCAN_LIMIT:,} bytes"
    else:
        meta = footer_metadata(fd, size, where)
        if meta is None:
            return f"{larger}, and no readable Parquet footer"
        rows, counted = meta.num_rows, f"{meta.num_rows} rows"
    if rows > grid:
        return f"{counted}, more than {grid_text(scene)}; {larger}"
    return f"{larger}, with {counted} in its {size:,} bytes"


def _read_bytes(path: Path, where: Where, scene: Scene, fmt: TrajectoryFormat) -> bytes:
    """The file's bytes, at most :func:`size_limit`; a larger file is refused naming its rows."""
    limit = size_limit(scene, fmt)
    try:
        with open_regular(path, follow_links=True) as fd:
            size = os.fstat(fd).st_size
            if size > limit:
                raise TrajectoryFileError(
                    f"{where.file}: {_too_large(fd, size, limit, fmt, scene, where)}"
                )
            chunks, total = [], 0
            while chunk := os.read(fd, 1 << 20):
                chunks.append(chunk)
                total += len(chunk)
                if total > limit:
                    raise TrajectoryFileError(
                        f"{where.file}: grew beyond {limit:,} bytes while it was read"
                    )
    except FileNotFoundError:
        raise TrajectoryFileError(f"{where.file}: no such file") from None
    except OSError as exc:  # a FIFO, device, directory; permissions
        reason = exc.strerror or str(exc)
        raise TrajectoryFileError(f"{where.file}: {reason}") from None
    return b"".join(chunks)


def read_trajectory(
    path: str | Path,
    scene: Scene,
    *,
    engine: Engine | str,
    format: TrajectoryFormat | None = None,
    up_to_file_end: bool = False,
    judged: Scene | None = None,
) -> ExternalTrajectory:
    """Read and check a trajectory file of ``scene`` (``docs/trajectory-format.md``).

    Args:
        path: the file (read only; a regular file).
        scene: the scene it is a run of: its mass count n and its output grid
            (``scene.output.times()``; shorten the horizon with ``scene.output.with_t_end``).
        engine: the plant name the run goes by (``Trajectory.engine``): the file's run is none
            of the built-in plants; the caller names it (``tumble judge --label``).
        format: CSV or Parquet; default from the suffix (:func:`format_of`).
        up_to_file_end: a file that stops on the grid before its end (at least two rows) is
            read up to its last row; the record's grid is then the scene's up to that row.
            Otherwise a short file is refused, the message naming the options that judge it.
        judged: a scene whose grid is ``scene``'s up to an earlier t_end (a reference pack's
            longer run judged over a shorter horizon): the record holds the rows up to that
            t_end only (the whole file is checked).

    Returns:
        the :class:`ExternalTrajectory`: the run in the paper's coordinates on the scene's grid
        (or the part of it the file or ``judged`` covers), the optional column groups present,
        and the SHA-256 of the bytes read.

    Raises:
        TrajectoryFileError (a ValueError): one line naming the file and, where it applies, the
            data row and column: unreadable or not a regular file, too large (naming its rows and
            the limit), not CSV numbers or Parquet doubles, wrong column count, unknown, duplicate
            or missing column, a mass count other than the scene's, NaN or infinity, t not
            increasing or not the scene's grid, a quaternion with ``| |u| − 1 |`` beyond 1e-6.
    """
    path = Path(path)
    fmt = format_of(path) if format is None else TrajectoryFormat(format)
    if fmt is TrajectoryFormat.CSV:
        where = Where(str(path), header_lines=1)
        data = _read_bytes(path, where, scene, fmt)
        names, values = parse_csv(data, where)
    else:
        where = Where(str(path))
        data = _read_bytes(path, where, scene, fmt)
        max_rows = len(scene.output.times())
        names, values = parse_parquet(data, where, max_rows, len(header(scene.n)))
    layout = parse_header(names, scene.n, f"{where.file}, header")
    check_table(names, values, layout, scene, where, up_to_file_end=up_to_file_end, hint=True)
    grid = scene.output.times()
    if judged is not None:
        on = judged
    elif values.shape[0] < len(grid):  # up_to_file_end: the grid up to the file's last row
        on = shortened(scene, float(grid[values.shape[0] - 1]))
    else:
        on = scene
    rows = len(on.output.times())
    if rows > values.shape[0] or not np.allclose(
        on.output.times(), grid[:rows], rtol=0.0, atol=GRID_TOL / scene.output.rate
    ):
        raise TrajectoryFileError(
            f"{where.file}: its grid does not hold {grid_text(on)} (the horizon judged)"
        )
    groups = {
        g: values[:rows, layout.columns(g, scene.n)]
        for g in ColumnGroup
        if g.required or g in layout.present
    }
    digest = hashlib.sha256(data).hexdigest()
    return external_trajectory(on, str(engine), groups, fmt, str(path), sha256=digest)


__all__ = [
    "BYTES_PER_VALUE",
    "PARQUET_BYTES_PER_VALUE",
    "SUFFIXES",
    "format_of",
    "read_trajectory",
    "size_limit",
]
