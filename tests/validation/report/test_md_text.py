"""The report's Markdown text: a string made literal on one line, numbers in one format, the
fenced JSON block that no backtick can close."""

from __future__ import annotations

import json
import math

import numpy as np

from validation.report.md_text import fenced_json, fmt_number, jsonable, md_cell, md_literal


def test_a_string_becomes_one_literal_line():
    assert md_literal("# a\nb | `c` <d>") == "\\# a b \\| \\`c\\` &lt;d&gt;"
    assert md_literal("2) second") == "2\\) second"
    assert md_cell("x|y") == "x\\|y"


def test_numbers_have_one_format():
    assert [fmt_number(x) for x in (0.0, 1.5e-7, math.nan, math.inf, None)] == [
        "0",
        "1.500e-07",
        "–",
        "∞",
        "–",
    ]


def test_the_json_block_holds_what_json_cannot():
    meta = {"a": np.float64(1.5), "b": (1, np.int64(2)), "c": math.inf, "d": "`"}
    assert jsonable(meta) == {"a": 1.5, "b": [1, 2], "c": "inf", "d": "`"}
    text = fenced_json(meta)
    assert "`" not in text and json.loads(text)["d"] == "`"
