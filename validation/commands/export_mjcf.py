"""``tumble export-mjcf``: the MJCF text of a scene's MuJoCo twin (built with MjSpec, full
precision), to a file."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands.options import add_out, add_scene

NAME = "export-mjcf"
HELP = "write the MJCF of a scene's MuJoCo twin (full precision)"
DESCRIPTION = "Write the MuJoCo model generated from the scene (MjSpec) as MJCF text."
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scene(p)
    add_out(p, "output file (default: out/<scene slug>.xml)")


def run(args: argparse.Namespace) -> int:
    from model_xml import to_mjcf
    from validation.runs.atomic import write_text
    from validation.runs.outputs import default_out_file
    from validation.scenes import resolve_scene

    scene = resolve_scene(args.scene)
    out = Path(args.out) if args.out else default_out_file(scene.name, ".xml")
    if out.is_dir():
        raise ValueError(f"--out {out}: is a directory; give a file name")
    write_text(out, to_mjcf(scene))
    print(f"wrote {out}")
    return 0
