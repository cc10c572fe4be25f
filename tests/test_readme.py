"""The README's snippets do what they say: every ```python block runs as written, every ```toml
block is a scene that loads.

Each python block runs in its own interpreter, in an empty temporary directory (so a snippet can
rely only on the package, not on files of the checkout), with this checkout first on the path.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from analytic.scene import scene_from_dict
from validation.thresholds import thresholds_for

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
SNIPPET_TIMEOUT_S = 600
"""Generous: a first run on a fresh machine compiles the numba kernels (~15 s; tests/conftest.py)."""


def _blocks(lang: str) -> list[tuple[int, str]]:
    """``(line number, text)`` of each fenced block of ``lang`` in the README."""
    text = README.read_text(encoding="utf-8")
    return [
        (text.count("\n", 0, m.start()) + 1, m.group(1))
        for m in re.finditer(rf"^```{lang}\n(.*?)^```", text, flags=re.S | re.M)
    ]


PYTHON = _blocks("python")
TOML = _blocks("toml")


def test_readme_has_snippets_of_both_kinds():
    assert PYTHON and TOML


@pytest.mark.parametrize(("line", "code"), PYTHON, ids=[f"README.md:{n}" for n, _ in PYTHON])
def test_python_snippet_runs_as_written(line, code, tmp_path):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    proc = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=SNIPPET_TIMEOUT_S,
    )
    assert proc.returncode == 0, f"README.md:{line}: the snippet fails:\n{proc.stderr[-3000:]}"


@pytest.mark.parametrize(("line", "text"), TOML, ids=[f"README.md:{n}" for n, _ in TOML])
def test_toml_snippet_is_a_scene(line, text):
    scene = scene_from_dict(tomllib.loads(text), source=f"README.md:{line}")
    thresholds_for(scene)  # and its [thresholds], if any, are known names
