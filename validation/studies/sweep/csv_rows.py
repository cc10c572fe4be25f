"""``sweep.csv``: one line per setting, the columns of :data:`validation.studies.sweep.rows.COLUMNS`.

Floats are written as their shortest exact ``repr`` (so they read back bit for bit), None as an
empty cell, booleans as ``true`` / ``false``; :func:`read_csv` restores the types.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from analytic.runtime.safe_files import read_regular
from validation.studies.sweep.rows import BOOL_COLUMNS, COLUMNS, FLOAT_COLUMNS, INT_COLUMNS

MAX_CSV_BYTES = 64 << 20
"""Largest ``sweep.csv`` read back (bytes): a sweep writes a few kB; far above any real one."""


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)  # shortest repr that round-trips exactly
    return str(v)


def to_csv(runs: Sequence[Mapping[str, Any]]) -> str:
    """The text of ``sweep.csv``."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in runs:
        w.writerow([_cell(r[c]) for c in COLUMNS])
    return buf.getvalue()


def read_csv(path: str | Path) -> list[dict[str, Any]]:
    """Rows of ``sweep.csv`` with their types restored (empty cells -> None); the file is read
    as a regular file of at most :data:`MAX_CSV_BYTES` (:func:`analytic.runtime.safe_files.read_regular`:
    a FIFO or device there is an ``OSError``, never a wait)."""
    rows = []
    text = read_regular(path, MAX_CSV_BYTES).decode("utf-8")
    with io.StringIO(text, newline="") as f:
        for raw in csv.DictReader(f):
            row: dict[str, Any] = {}
            for k, v in raw.items():
                if v == "" and k != "note":
                    row[k] = None
                elif k in FLOAT_COLUMNS:
                    row[k] = float(v)
                elif k in INT_COLUMNS:
                    row[k] = int(v)
                elif k in BOOL_COLUMNS:
                    row[k] = v == "true"
                else:
                    row[k] = v
            rows.append(row)
    return rows


__all__ = ["read_csv", "to_csv"]
