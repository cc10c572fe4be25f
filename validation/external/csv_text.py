"""CSV text of a trajectory table: parsing numbers and nothing else, and writing them exactly.

The text is UTF-8 (a leading byte-order mark is skipped), one header line of comma-separated
names, then one line per sample of comma-separated decimal numbers; blanks around a field are
ignored, lines may end in CRLF, trailing empty lines are ignored. A field is a number written as
``[+-]digits[.digits][e[+-]digits]``; nothing else is accepted (no quotes, no thousands separators
or underscores, no empty fields, no expressions), and ``nan``/``inf`` are refused by name. The
writer prints each float with ``repr`` (the shortest text that reads back to the same double), so
a written table reads back bit for bit.
"""

from __future__ import annotations

import io
import re
from collections.abc import Sequence

import numpy as np

from validation.external.errors import TrajectoryFileError, Where

_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")
_NON_FINITE = {"nan", "inf", "infinity"}
_ONLY_NUMBER_CHARS = re.compile(r"[^0-9eE+\-.,\s]")
_BLANK_LINE = re.compile(r"\n[ \t\r]*\n")


def _show(text: str) -> str:
    return repr(text if len(text) <= 24 else text[:21] + "...")


def _lines(data: bytes, where: Where) -> list[str]:
    """The file's lines (UTF-8, BOM and trailing empty lines dropped, CR of CRLF removed)."""
    if data.startswith(b"PAR1"):
        raise TrajectoryFileError(f"{where.file}: a Parquet file, not CSV text (name it .parquet)")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise TrajectoryFileError(
            f"{where.file}: not UTF-8 text (byte {exc.start}); a CSV file of numbers is expected"
        ) from None
    text = text.removeprefix("\ufeff")
    lines = text.split("\n")
    lines = [line.removesuffix("\r") for line in lines]
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise TrajectoryFileError(f"{where.file}: empty (a header line and data rows expected)")
    return lines


def _field(text: str, k: int, name: str, where: Where) -> float:
    """One field's number; refuses anything else naming the row and column."""
    s = text.strip()
    if _NUMBER.match(s):
        return float(s)
    if s.lower().lstrip("+-") in _NON_FINITE:
        what = "NaN" if "nan" in s.lower() else f"infinite ({s})"
        raise TrajectoryFileError(f"{where.at(k, name)}: {what}; every value must be finite")
    if not s:
        raise TrajectoryFileError(f"{where.at(k, name)}: empty value")
    raise TrajectoryFileError(f"{where.at(k, name)}: not a number: {_show(s)}")


def _parse_rows(rows: Sequence[str], names: Sequence[str], where: Where) -> np.ndarray:
    """Field by field, naming the first bad row and column (the slow path, and the reference)."""
    out = np.empty((len(rows), len(names)))
    for k, line in enumerate(rows):
        fields = line.split(",")
        if not line.strip():
            raise TrajectoryFileError(f"{where.file}, {where.row(k)}: empty line")
        if len(fields) != len(names):
            raise TrajectoryFileError(
                f"{where.file}, {where.row(k)}: {len(fields)} values, but the header has "
                f"{len(names)} columns"
            )
        for c, text in enumerate(fields):
            out[k, c] = _field(text, k, names[c], where)
    return out


def _parse_fast(body: str, n_rows: int, n_cols: int) -> np.ndarray | None:
    """numpy's C parser on a body of plain numbers only; None where it might differ from
    :func:`_parse_rows` (other characters, blank lines, a ragged or malformed row)."""
    if _ONLY_NUMBER_CHARS.search(body) or _BLANK_LINE.search("\n" + body + "\n"):
        return None
    try:
        values = np.loadtxt(io.StringIO(body), delimiter=",", dtype=np.float64, comments=None, ndmin=2)
    except ValueError:
        return None
    return values if values.shape == (n_rows, n_cols) else None


def parse_csv(data: bytes, where: Where) -> tuple[list[str], np.ndarray]:
    """``(header names, values (N, C))`` of CSV bytes.

    Raises:
        TrajectoryFileError: not UTF-8, empty, a row with another number of values than the
            header, a field that is not a number (NaN and infinities named as such).
    """
    lines = _lines(data, where)
    names = [name.strip() for name in lines[0].split(",")]
    if len(names) == 1 and any(sep in lines[0] for sep in ";\t"):
        raise TrajectoryFileError(
            f"{where.file}, header: one column {_show(names[0])}; columns are separated by commas"
        )
    rows = lines[1:]
    if not rows:
        return names, np.empty((0, len(names)))
    fast = _parse_fast("\n".join(rows), len(rows), len(names))
    return names, fast if fast is not None else _parse_rows(rows, names, where)


def format_csv(names: Sequence[str], values: np.ndarray) -> bytes:
    """CSV bytes of a table: the header line, then one line per row, each float as ``repr``."""
    lines = [",".join(names)]
    lines += [",".join(map(repr, row)) for row in np.asarray(values, dtype=np.float64).tolist()]
    return ("\n".join(lines) + "\n").encode("utf-8")


__all__ = ["format_csv", "parse_csv"]
