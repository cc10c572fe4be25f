"""Parquet bytes of a trajectory table, through pyarrow (imported when first needed).

The file holds the same columns as the CSV form (:mod:`validation.external.columns`), each a
``double`` (integer and float32 columns are read too, as float64); a null is refused like a NaN.
The row and column counts are read from the file's metadata and refused before any data is
decompressed, so a small file cannot expand to more rows than the scene's grid.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from validation.external.errors import TrajectoryFileError, Where


def _pyarrow(where: str) -> tuple[Any, Any]:
    """``(pyarrow, pyarrow.parquet)``, or one line saying that Parquet needs pyarrow."""
    try:  # deferred: pyarrow is optional here (it comes with rerun-sdk) and only Parquet needs it
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise TrajectoryFileError(
            f"{where}: reading or writing Parquet needs pyarrow, which is not installed "
            "(it comes with rerun-sdk; `pip install pyarrow`), or use CSV"
        ) from None
    return pa, pq


def parse_parquet(
    data: bytes, where: Where, max_rows: int, max_columns: int
) -> tuple[list[str], np.ndarray]:
    """``(column names, values (N, C) float64)`` of Parquet bytes.

    Args:
        data: the whole file.
        where: how messages name the file.
        max_rows, max_columns: refused beyond these, from the metadata, before reading data.

    Raises:
        TrajectoryFileError: not a Parquet file, too many rows or columns, a column that is not
            numeric, a null value (row and column named).
    """
    pa, pq = _pyarrow(where.file)
    try:
        pf = pq.ParquetFile(pa.BufferReader(data))
        meta = pf.metadata
    except (pa.ArrowException, OSError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise TrajectoryFileError(f"{where.file}: not a readable Parquet file ({first})") from None
    if meta.num_columns > max_columns:
        raise TrajectoryFileError(
            f"{where.file}: {meta.num_columns} columns, more than the {max_columns} a file for "
            "this scene can have"
        )
    if meta.num_rows > max_rows:
        raise TrajectoryFileError(
            f"{where.file}: {meta.num_rows} rows, more than the scene's output grid has "
            f"({max_rows})"
        )
    try:
        table = pf.read()
    except (pa.ArrowException, OSError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise TrajectoryFileError(f"{where.file}: not a readable Parquet file ({first})") from None
    names = [str(name) for name in table.column_names]
    values = np.empty((table.num_rows, len(names)))
    for c, name in enumerate(names):
        col = table.column(c)
        kind = col.type
        if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
            raise TrajectoryFileError(
                f"{where.file}, column {name!r}: of type {kind}, not numbers (double expected)"
            )
        if col.null_count:
            k = int(np.argmax(np.asarray(col.is_null().to_numpy(zero_copy_only=False))))
            raise TrajectoryFileError(f"{where.at(k, name)}: missing value (null)")
        values[:, c] = col.to_numpy().astype(np.float64, copy=False)
    return names, values


def format_parquet(names: Sequence[str], values: np.ndarray, label: str) -> bytes:
    """Parquet bytes of a table: one ``double`` column per name, in order."""
    pa, pq = _pyarrow(f"trajectory file {label!r}")
    values = np.asarray(values, dtype=np.float64)
    table = pa.table({name: values[:, c] for c, name in enumerate(names)})
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


__all__ = ["format_parquet", "parse_parquet"]
