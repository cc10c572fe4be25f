"""The fault table in ``docs/verdicts.md`` and the fault-injection suite are the same list: every
test of ``tests/cross/test_fault_*.py`` is a row there (its docstring "fault -> what the tool does" is
the row), and every row names a test that exists."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "verdicts.md"


def _fault_tests() -> dict[str, str]:
    """test name -> its docstring, over every ``tests/cross/test_fault_*.py``."""
    out = {}
    for path in sorted((ROOT / "tests" / "cross").glob("test_fault_*.py")):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test_"):
                out[node.name] = ast.get_docstring(node) or ""
    return out


def test_every_fault_test_is_a_row_of_the_table_and_back():
    table = DOC.read_text().split("## The fault table", 1)[1]
    rows = set(re.findall(r"\| `(test_\w+)` \|", table))
    tests = _fault_tests()
    assert rows == set(tests), {
        "tests missing from docs/verdicts.md": sorted(set(tests) - rows),
        "rows naming no test": sorted(rows - set(tests)),
    }


def test_every_fault_test_says_fault_and_outcome():
    """Each docstring reads "<fault> -> <what the tool does>", so the table can be read alone."""
    bad = [name for name, doc in _fault_tests().items() if "->" not in doc]
    assert not bad, bad
