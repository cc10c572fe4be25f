"""A directory's whole contents as a value, for the fault tests' "left untouched" assertions."""

from __future__ import annotations

import os
from pathlib import Path


def tree(d: Path) -> dict[str, bytes | str]:
    """Every entry under ``d``, by relative path: a file's bytes, a link as ``-> target``, a
    directory as ``dir``, a FIFO as ``fifo`` (never opened)."""
    out: dict[str, bytes | str] = {}
    for p in sorted(d.rglob("*")):
        rel = str(p.relative_to(d))
        if p.is_symlink():
            out[rel] = f"-> {os.readlink(p)}"
        elif p.is_dir():
            out[rel] = "dir"
        elif p.is_fifo():
            out[rel] = "fifo"
        else:
            out[rel] = p.read_bytes()
    return out
