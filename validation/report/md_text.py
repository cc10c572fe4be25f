"""Text as ``report.md`` writes it: any string made literal Markdown on one line
(:func:`md_literal`, for every string a scene or an error message brings into the report), numbers
in the report's one format (:func:`fmt_number`), and JSON for the report's fenced block
(:func:`fenced_json`, :func:`jsonable`)."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np


def jsonable(x: Any) -> Any:
    """``x`` as JSON can hold it: mappings and sequences of JSON values, a non-finite float as its
    text (JSON has no inf or nan), anything else as its ``str``."""
    if isinstance(x, Mapping):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        return jsonable(x.item())
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)  # JSON has no inf/nan
    if isinstance(x, str | int | float | bool) or x is None:
        return x
    return str(x)


_MD_ESCAPES = str.maketrans(
    {
        "&": "&amp;",
        "<": "&lt;",
        ">": "&gt;",
        "\\": "\\\\",
        "`": "\\`",
        "*": "\\*",
        "[": "\\[",
        "]": "\\]",
        "|": "\\|",
        "\n": " ",
        "\r": " ",
        "\t": " ",
        "\v": " ",
        "\f": " ",
        "\x85": " ",
        "\u2028": " ",
        "\u2029": " ",
    }
)
_MD_LINE_START = ("#", "-", "+", "=", ">", "~")


def md_literal(text: Any) -> str:
    """``text`` as literal Markdown on one line, safe in a table cell or after a list marker: HTML
    special characters as entities (no tag or comment can open), the characters that make code,
    emphasis, links or table cells backslash-escaped, every line break a space, and a leading
    block marker (``#`` heading, ``-`` list, ``>`` quote ...) escaped. For every string a scene
    or an error message brings into ``report.md``."""
    out = str(text).translate(_MD_ESCAPES)
    if out.startswith(_MD_LINE_START):
        return "\\" + out
    return re.sub(r"^(\d+)([.)])", r"\1\\\2", out)  # "1." would start a numbered list


def md_cell(text: Any) -> str:
    """A Markdown table cell's text (:func:`md_literal`: a literal ``|`` would end the cell)."""
    return md_literal(text)


def fenced_json(meta: Mapping[str, Any]) -> str:
    """``meta`` as indented JSON for a fenced code block: a backtick (which could close the fence)
    is written as its JSON escape ``\\u0060``, so the block ends where the report ends it."""
    return json.dumps(jsonable(meta), indent=2).replace("`", "\\u0060")


def fmt_number(x: float) -> str:
    """A number as the report's tables give it: ``1.234e-05``, ``0``, ``–`` (none or NaN), ``∞``."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.3e}" if x != 0 else "0"


__all__ = ["fenced_json", "fmt_number", "jsonable", "md_cell", "md_literal"]
