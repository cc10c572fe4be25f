"""``tumble scene-reference``: the scene format's reference, every key with its type, unit,
default and meaning, rendered from the loader's own declarations (markdown); with
``--json-schema``, the scene format's JSON Schema (draft-07) for editors, from the same
declarations."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from validation.commands.options import add_out

NAME = "scene-reference"
HELP = "print the scene format's reference (every key; docs/scene-format.md) or its JSON Schema"
DESCRIPTION = (
    "Render the reference of the scene format, every key with its type, unit, default and "
    "meaning, from the loader's own declarations (markdown, on stdout); with --json-schema, the "
    "scene format's JSON Schema (draft-07) that Taplo, Tombi and VS Code's Even Better TOML read "
    "(docs/scene-format.md, Editors)."
)
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_out(p, "write it to this file instead")
    p.add_argument(
        "--json-schema",
        action="store_true",
        help="the JSON Schema of a scene file instead of the markdown reference",
    )


def run(args: argparse.Namespace) -> int:
    from validation.runs.atomic import write_text

    if args.json_schema:
        from validation.report.scene_schema import render_json as render
    else:
        from validation.report.scene_reference import render

    if args.out:
        write_text(Path(args.out), render())
        print(f"wrote {args.out}")
    else:
        sys.stdout.write(render())
    return 0
