"""Parquet bytes of a trajectory table, through pyarrow (imported when first needed).

The file holds the same columns as the CSV form (:mod:`validation.external.columns`), each a
``double`` (integer and float32 columns are read too, as float64); a null is refused like a NaN.
The row and column counts, the columns' types and the uncompressed sizes the column chunks declare
are read from the file's metadata and refused before any data is decompressed
(:func:`check_metadata`), so a small file cannot expand to more rows than the scene's grid, nor
to a large binary column.
"""

from __future__ import annotations

import os
import struct
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


FOOTER_LIMIT = 16 << 20
"""Largest Parquet footer (the file's metadata) read, bytes."""

DECODED_BYTES_PER_VALUE = 32
"""Bytes per value a column chunk may declare uncompressed (:func:`check_metadata`): 8 for a
double, the rest room for a dictionary page and the definition levels."""

DECODED_BYTES_PER_CHUNK = 4 << 10
"""Bytes per column chunk a file may declare uncompressed beyond its values (page headers,
statistics): a valid file of one-row row groups declares about 100."""

_NUMERIC_PHYSICAL = frozenset({"DOUBLE", "FLOAT", "INT32", "INT64"})


def footer_metadata(fd: int, size: int, where: Where) -> Any | None:
    """The Parquet metadata of the open file ``fd`` of ``size`` bytes, read from its footer
    alone (at most :data:`FOOTER_LIMIT` bytes); None when there is no readable footer."""
    pa, pq = _pyarrow(where.file)
    if size < 12:
        return None
    tail = os.pread(fd, 8, size - 8)
    if len(tail) != 8 or tail[4:] != b"PAR1":
        return None
    length = struct.unpack("<I", tail[:4])[0]
    if length + 12 > size or length > FOOTER_LIMIT:
        return None
    footer = os.pread(fd, length, size - 8 - length)
    try:
        return pq.read_metadata(pa.BufferReader(b"PAR1" + footer + tail))
    except (pa.ArrowException, OSError, ValueError):
        return None


def rows_text(rows: int, max_rows: int) -> str:
    """``"3000 rows, more than the scene's output grid has (3 samples)"``."""
    return f"{rows} rows, more than the scene's output grid has ({max_rows} samples)"


def check_metadata(
    meta: Any, schema: Any, arrow_schema: Any, where: Where, max_rows: int, max_columns: int
) -> None:
    """Refuse, from the footer alone and before any data is decompressed: more columns than a
    file of the scene can have, more rows than its grid, a column that is not a flat number
    (binary, string, nested: physical type other than DOUBLE, FLOAT, INT32, INT64), and column
    chunks that declare more uncompressed bytes than their values need
    (:data:`DECODED_BYTES_PER_VALUE` a value, :data:`DECODED_BYTES_PER_CHUNK` a chunk)."""
    if meta.num_columns > max_columns:
        raise TrajectoryFileError(
            f"{where.file}: {meta.num_columns} columns, more than the {max_columns} a file for "
            "this scene can have"
        )
    if meta.num_rows > max_rows:
        raise TrajectoryFileError(f"{where.file}: {rows_text(meta.num_rows, max_rows)}")
    pa, _ = _pyarrow(where.file)
    for field in arrow_schema:
        if not (pa.types.is_floating(field.type) or pa.types.is_integer(field.type)):
            raise TrajectoryFileError(
                f"{where.file}, column {field.name!r}: of type {field.type}, not numbers (double "
                "expected); refused before reading its data"
            )
    for c in range(meta.num_columns):
        col = schema.column(c)
        if col.physical_type not in _NUMERIC_PHYSICAL or col.max_repetition_level:
            raise TrajectoryFileError(
                f"{where.file}, column {col.path!r}: of Parquet type {col.physical_type}, not "
                "numbers (double expected); refused before reading its data"
            )
    chunks = meta.num_row_groups * meta.num_columns
    allowed = meta.num_rows * meta.num_columns * DECODED_BYTES_PER_VALUE
    allowed += chunks * DECODED_BYTES_PER_CHUNK
    declared = sum(
        max(meta.row_group(g).column(c).total_uncompressed_size, 0)
        for g in range(meta.num_row_groups)
        for c in range(meta.num_columns)
    )
    if declared > allowed:
        raise TrajectoryFileError(
            f"{where.file}: its {meta.num_rows:,} rows × {meta.num_columns} columns declare "
            f"{declared:,} bytes uncompressed, more than the {allowed:,} numbers need; refused "
            "before decompressing"
        )


def parse_parquet(
    data: bytes, where: Where, max_rows: int, max_columns: int
) -> tuple[list[str], np.ndarray]:
    """``(column names, values (N, C) float64)`` of Parquet bytes.

    Args:
        data: the whole file.
        where: how messages name the file.
        max_rows, max_columns: refused beyond these, from the metadata, before reading data
            (:func:`check_metadata`, with the column types and the declared sizes).

    Raises:
        TrajectoryFileError: not a Parquet file, too many rows or columns, a column that is not
            numeric, declared sizes beyond what the numbers need, a null value (row and column
            named), data that does not match the metadata.
    """
    pa, pq = _pyarrow(where.file)
    try:
        pf = pq.ParquetFile(pa.BufferReader(data))
        meta = pf.metadata
        schema = pf.schema
        arrow_schema = pf.schema_arrow
    except (pa.ArrowException, OSError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise TrajectoryFileError(f"{where.file}: not a readable Parquet file ({first})") from None
    check_metadata(meta, schema, arrow_schema, where, max_rows, max_columns)
    try:
        table = pf.read()
    except (pa.ArrowException, OSError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise TrajectoryFileError(f"{where.file}: not a readable Parquet file ({first})") from None
    if table.num_rows != meta.num_rows:
        raise TrajectoryFileError(
            f"{where.file}: {table.num_rows:,} rows read, the metadata says {meta.num_rows:,}"
        )
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


__all__ = ["check_metadata", "footer_metadata", "format_parquet", "parse_parquet", "rows_text"]
