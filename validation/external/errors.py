"""The one error of a bad trajectory file, and how its messages name a file, a row and a column.

Rows are counted as a person reading the file counts them: **data rows from 1**, the header not
counted, so data row 1 is the first sample (t = 0). A CSV message adds the file's line number
(data row k is line k + 1, after the header line), which is the row number a spreadsheet shows.
"""

from __future__ import annotations

from dataclasses import dataclass


class TrajectoryFileError(ValueError):
    """A trajectory file (or a trajectory to be written) that breaks the format; ``str()`` is one
    line naming the file and, where it applies, the data row and the column."""


@dataclass(frozen=True)
class Where:
    """How messages name a file and its rows.

    Attributes:
        label: the file as given (its name), quoted in every message.
        header_lines: lines before the first data row (1 for a CSV file, 0 for Parquet, which has
            no text lines to count).
        noun: what the messages call it (the writer checks a trajectory before writing it).
    """

    label: str
    header_lines: int = 0
    noun: str = "trajectory file"

    @property
    def file(self) -> str:
        return f"{self.noun} {self.label!r}"

    def row(self, k: int) -> str:
        """``"data row 3 (line 4)"`` for the 0-based data row index ``k = 2`` of a CSV file."""
        text = f"data row {k + 1}"
        return f"{text} (line {k + 1 + self.header_lines})" if self.header_lines else text

    def at(self, k: int, column: str) -> str:
        """``"trajectory file 'x.csv', data row 3 (line 4), column 'u_w'"``."""
        return f"{self.file}, {self.row(k)}, column {column!r}"


__all__ = ["TrajectoryFileError", "Where"]
