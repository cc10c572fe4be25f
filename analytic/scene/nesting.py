"""Depth of a scene's lists and tables: refused beyond :data:`~analytic.scene.limits.MAX_SCENE_NESTING`,
in the text before the TOML parser recurses through it, and in a document given as dicts.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

from analytic.scene.limits import MAX_SCENE_NESTING

# TOML tokens that can hold a bracket which is not one: strings (multi-line ones first) and
# comments; then the brackets themselves and newlines.
_TOML_TOKENS = re.compile(
    r'"""(?:\\.|[^\\])*?"""(?:"{1,2})?'
    r"|'''[\s\S]*?'''(?:'{1,2})?"
    r'|"(?:\\.|[^"\\\n])*"'
    r"|'[^'\n]*'"
    r"|#[^\n]*"
    r"|[\[\]{}\n]"
)
_TOML_HEADER = re.compile(r"\s*\[\[?\s*([^\]]*?)\s*\]")


def check_text_nesting(text: str, given: str) -> None:
    """Refuse TOML text whose arrays and inline tables nest deeper than :data:`MAX_SCENE_NESTING`,
    before the parser (which recurses once per level) reads it; the message names the key (dotted,
    under the last table header) and the line. Strings and comments are skipped; the scan is
    linear in the text."""
    depth, line, line_start, table, key = 0, 1, 0, "", ""
    for tok in _TOML_TOKENS.finditer(text):
        c = tok.group()
        if c == "\n" or c[0] in "\"'#":
            if "\n" in c:
                line += c.count("\n")
                line_start = tok.start() + c.rindex("\n") + 1
            continue
        if c in "[{":
            if depth == 0:
                head = text[line_start : tok.start()]
                if not head.strip():  # a [table] header: its name is the table of what follows
                    m = _TOML_HEADER.match(text, line_start)
                    table, key = (m.group(1) if m else ""), ""
                elif "=" in head:
                    key = head.split("=", 1)[0].strip()
            depth += 1
            if depth > MAX_SCENE_NESTING:
                dotted = ".".join(x for x in (table, key) if x) or "scene"
                raise ValueError(
                    f"{dotted}: nested deeper than {MAX_SCENE_NESTING} levels of lists and tables "
                    f"(line {line} of {given!r})"
                )
        else:
            depth = max(depth - 1, 0)


def check_nesting(data: Any, source: str = "") -> None:
    """Refuse a document whose lists and tables nest deeper than :data:`MAX_SCENE_NESTING` below
    it (dotted keys build deep tables without brackets), naming the dotted path of the first value
    beyond the limit. Iterative, so a document of any depth (or one that holds itself) is walked
    without recursion."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        node, path, depth = stack.pop()
        if isinstance(node, Mapping):
            children = ((f"{path}.{k}" if path else str(k), v) for k, v in node.items())
        elif isinstance(node, list | tuple):
            children = ((f"{path}[{i}]", v) for i, v in enumerate(node))
        else:
            continue
        if depth > MAX_SCENE_NESTING:
            where = f" (in {source!r})" if source else ""
            raise ValueError(
                f"{path or 'scene'}: nested deeper than {MAX_SCENE_NESTING} levels of lists and "
                f"tables{where}"
            )
        stack.extend((v, p, depth + 1) for p, v in children)


__all__ = ["check_nesting", "check_text_nesting"]
