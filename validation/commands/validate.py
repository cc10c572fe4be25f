"""``tumble validate``: one scene on N plants under one controller, compared; the report, figures
and recording written. Exits 1 when a check fails."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands.options import (
    add_figure_format,
    add_out,
    add_plants,
    add_scene,
    add_t_end,
    add_time_limit,
    add_viewer,
    positive_float,
)
from validation.commands.outcome import print_outcome

NAME = "validate"
HELP = "run a scene on the analytic plant and on MuJoCo under one controller; compare"
DESCRIPTION = (
    "Run the scene on the analytic model and on its MuJoCo twin, both driven by the same "
    "analytic controller, compare trajectories, invariants and control forces, and write "
    "OUT/report.md, OUT/report.html, OUT/report.json, figures and OUT/run.rrd. Exits 1 when a "
    "check fails."
)
CHOOSES_PLANTS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    from analytic.effects import MjIntegrator

    add_scene(p)
    add_out(p, "output directory (default: out/validate_<scene slug>)")
    p.add_argument(
        "--integrator",
        choices=[i.value for i in MjIntegrator],
        help="MuJoCo integrator (default: the scene's)",
    )
    p.add_argument("--dt", type=positive_float, help="MuJoCo timestep in seconds")
    add_t_end(p, "horizon in seconds")
    add_plants(
        p,
        "comma-separated plants to run: built-ins (analytic, mujoco, pinocchio) and installed "
        "plant plugins (drake; docs/plugins.md) by name, or 'all' for every installed one "
        "(default: every installed default plant, analytic,mujoco,pinocchio; with three or more "
        "the referee names an outlier)",
    )
    add_figure_format(
        p,
        "comma-separated figure formats: png, svg, pdf (default: png; e.g. png,svg for a paper)",
    )
    add_time_limit(
        p,
        "wall-time limit of each plant's run: a run over it is stopped and fails that plant, "
        "the others are compared (default: none for the built-in plants, 600 s for a plugin)",
    )
    add_viewer(p)


def run(args: argparse.Namespace) -> int:
    from validation.runs.outputs import default_out_dir
    from validation.runs.progress import StageProgress, Status
    from validation.runs.warmup import warming
    from validation.scenes import resolve_scene
    from validation.validate import run_request, validation_request

    scene = resolve_scene(args.scene, check_thresholds=False)  # validation_request checks them
    out = Path(args.out) if args.out else default_out_dir("validate_", scene.name)
    request = validation_request(  # every input checked once, here: run_request trusts it
        scene,
        plants=args.plants,
        integrator=args.integrator,
        dt=args.dt,
        t_end=args.t_end,
        figure_formats=args.figure_format,
        time_limit=args.time_limit,
    )
    res = None
    # the analytic plant's last kernels may still compile while the plants start (warming)
    with warming(scene, request.plants, Status()):
        progress = StageProgress(
            f"validate {scene.name}", request.horizon, stages=len(request.plants) or None
        )
        try:
            res = run_request(request, out, progress=progress)
        finally:
            progress.close(walls=res.wall_times if res is not None else None, stopped=res is None)
    return print_outcome(res, scene.name, "not applicable")
