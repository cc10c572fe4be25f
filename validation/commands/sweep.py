"""``tumble sweep``: what accuracy costs in time, a work-precision study of one scene over the
engines' solvers and settings, on this machine's processes or a Dask cluster."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands.options import (
    add_dashboard,
    add_out,
    add_scene,
    add_t_end,
    add_viewer,
    add_workers,
)

NAME = "sweep"
HELP = "what accuracy costs in time: work-precision study over both engines"
DESCRIPTION = (
    "Compute a reference solution, run the analytic engine over scipy solvers and tolerances and "
    "MuJoCo over integrators and timesteps, and write OUT/sweep.csv, sweep.json, sweep.md, "
    "sweep.html (the cheapest setting per accuracy level marked), work_precision.png and "
    "sweep.rrd; also the cost of each effect and the effect of the quaternion stabilisation "
    "(delta1, delta2)."
)
CHOOSES_PLANTS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scene(p)
    add_out(p, "output directory (default: out/sweep_<scene slug>)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="a small grid over a 0.5 s horizon (~10 s on an idle 2-core machine)",
    )
    add_t_end(p, "horizon in seconds (default 20)")
    add_workers(p)
    add_dashboard(p)
    add_viewer(p)


def run(args: argparse.Namespace) -> int:
    from validation.runs.outputs import default_out_dir
    from validation.scenes import resolve_scene
    from validation.studies.sweep import run_sweep

    scene = resolve_scene(args.scene)
    out = Path(args.out) if args.out else default_out_dir("sweep_", scene.name)
    # progress: the series counted and each stage's line logged (validation.runs.progress)
    if args.scheduler is None and args.dask_workers is None and not args.dashboard:
        res = run_sweep(scene, out, quick=args.quick, t_end=args.t_end)
    else:  # a Dask cluster's executor (validation.studies.sweep.running.executor_for)
        from validation.studies.sweep.running import executor_for

        cluster = executor_for(None, args.scheduler, args.dask_workers, dashboard=args.dashboard)
        with cluster as (ex, _width):
            res = run_sweep(scene, out, quick=args.quick, t_end=args.t_end, executor=ex)
    print(f"sweep of {scene.name}: {len(res.runs)} runs in {res.wall_time_s:.1f} s")
    by_id = {r["run_id"]: r for r in res.runs}
    print("  cheapest setting reaching each accuracy level:")
    for engine, levels in res.cheapest.items():
        for lvl, rid in levels.items():
            r = by_id.get(rid)
            pick = f"{r['method']} {r['setting_name']} {r['setting']:g}" if r else "none reaches it"
            print(f"    {engine:<9} error <= {float(lvl):.0e}: {pick}")
    print(f"table: {res.out_dir / 'sweep.md'}  figure: {res.out_dir / 'work_precision.png'}")
    return 0
