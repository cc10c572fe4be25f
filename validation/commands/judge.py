"""``tumble judge``: another engine's trajectory file of a scene judged beside the built-in plants
(or against a reference pack), with validate's checks, referee, report and recording. Exits 0
when every judged check passes, 1 when one fails, 2 for bad input."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands.options import (
    add_figure_format,
    add_out,
    add_plants,
    add_scene,
    add_t_end,
    add_viewer,
)
from validation.commands.outcome import print_outcome

NAME = "judge"
HELP = "judge another engine's trajectory file of a scene beside the built-in plants"
DESCRIPTION = (
    "Read FILE, another engine's run of the scene on its output grid "
    "(docs/trajectory-format.md), run the built-in plants beside it as referees (or, with "
    "--reference, take a reference pack's trajectory instead), and compare every pair with the "
    "same checks, referee, report, figures and recording as validate, the file being one more "
    "plant. A check needing columns the file lacks is 'not judged'. Exits 0 when every judged "
    "check passes, 1 when one fails, 2 for bad input (a bad file: its row and column)."
)
CHOOSES_PLANTS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scene(p)
    p.add_argument(
        "--trajectory", required=True, metavar="FILE", help="the trajectory file (.csv, .parquet)"
    )
    p.add_argument(
        "--label",
        help="the file's plant name in the report (default: from the file name; lower-case "
        "letters, digits and _, not a plant's name)",
    )
    add_plants(
        p,
        "comma-separated built-in plants to run beside the file (default: every installed one "
        "that can run the scene)",
    )
    p.add_argument(
        "--reference",
        metavar="DIR",
        help="a reference pack (tumble reference): judge against its trajectory, running no plant",
    )
    add_t_end(
        p,
        "judge the scene as if its t_end were T, s: in (0, the scene's t_end], on its output "
        "grid; the file then holds the grid up to T",
        metavar="T",
    )
    p.add_argument(
        "--up-to-file-end",
        action="store_true",
        help="a file that stops on the grid before the end is judged up to its last row (the "
        "report states the horizon judged); without it such a file is refused",
    )
    add_out(p, "output directory (default: out/judge_<scene slug>)")
    add_figure_format(p, "comma-separated figure formats: png, svg, pdf (default: png)")
    add_viewer(p)


def run(args: argparse.Namespace) -> int:
    from validation.external.judge import judge_request, run_judge
    from validation.runs.outputs import default_out_dir
    from validation.runs.progress import StageProgress, Status
    from validation.runs.warmup import warming

    request = judge_request(  # the scene, the file, the label, the plants, the pack: checked once
        args.scene,
        args.trajectory,
        label=args.label,
        plants=args.plants,
        reference=args.reference,
        t_end=args.t_end,
        up_to_file_end=args.up_to_file_end,
        figure_formats=args.figure_format,
    )
    scene = request.validation.scene
    horizon = request.horizon
    over = f", {horizon.sentence}" if horizon is not None and not horizon.whole else ""
    out = Path(args.out) if args.out else default_out_dir("judge_", scene.name)
    res = None
    with warming(scene, request.validation.plants, Status()):
        progress = StageProgress(
            f"judge {request.label} on {scene.name}",
            request.validation.horizon,
            stages=len(request.validation.plants) or None,
        )
        try:
            res = run_judge(request, out, progress=progress)
        finally:
            progress.close(walls=res.wall_times if res is not None else None, stopped=res is None)
    return print_outcome(
        res,
        f"{request.label} on {scene.name}{over}",
        "not judged or not applicable",
        not_judged=True,
    )
