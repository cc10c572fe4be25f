"""``tumble scene-reference``: the scene format's reference, every key with its type, unit,
default and meaning, rendered from the loader's own declarations (markdown)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from validation.commands.options import add_out

NAME = "scene-reference"
HELP = "print the scene format's reference (every key; docs/scene-format.md)"
DESCRIPTION = (
    "Render the reference of the scene format, every key with its type, unit, default and "
    "meaning, from the loader's own declarations (markdown, on stdout)."
)
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_out(p, "write it to this file instead")


def run(args: argparse.Namespace) -> int:
    from validation.report.scene_reference import render
    from validation.runs.atomic import write_text

    if args.out:
        write_text(Path(args.out), render())
        print(f"wrote {args.out}")
    else:
        sys.stdout.write(render())
    return 0
