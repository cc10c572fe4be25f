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
from validation.compare.thresholds import thresholds_for

ROOT = Path(__file__).resolve().parents[2]
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


def _commands() -> list[str]:
    """Every ``tumble ...`` command the README shows (in code blocks and inline code), with
    optional parts (``[SCENE]``, ``[--quick]``) left out."""
    text = README.read_text(encoding="utf-8")
    found = re.findall(r"(?m)(?:^|&& |`)(tumble(?: [^`&#\n]*)?)", text)
    found = [cmd for cmd in found if cmd.strip() != "tumble"]
    out = []
    for cmd in found:
        cmd = re.sub(r"\s*\[[^\]]*\]", "", cmd).strip()
        if cmd not in out:
            out.append(cmd)
    return out


COMMANDS = _commands()


def test_readme_shows_the_commands():
    assert "tumble validate" in COMMANDS and len(COMMANDS) >= 8


@pytest.mark.parametrize("cmd", COMMANDS)
def test_every_command_shown_is_one_the_cli_takes(cmd):
    """Each command line the README shows parses as written (subcommand and options exist)."""
    import shlex

    from validation.cli import build_parser

    args = build_parser().parse_args(shlex.split(cmd)[1:])
    assert callable(args.func)


def test_every_link_leads_to_a_file():
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)#\s]+)\)", text)
    assert links
    missing = [link for link in links if not (ROOT / link).exists()]
    assert not missing, missing


def test_ci_runs_the_readme_test_command():
    """.ci/run installs and tests exactly as the README's second command says."""
    text = README.read_text(encoding="utf-8")
    line = next(x for x in text.splitlines() if 'pip install ".[test]"' in x)
    steps = [s.strip() for s in line.split("&&")]
    ci = (ROOT / ".ci" / "run").read_text()
    for step in steps[steps.index('pip install ".[test]"') :]:
        assert re.search(rf"(?m)^{re.escape(step)}$", ci), step
