"""``tumble simulate``: one scene on the analytic model; ``trajectory.npz``, ``summary.json`` and a
printed summary (tracking errors at the end, invariant drifts). Exits 1 when the run failed."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from validation.commands import EXIT_FAILED
from validation.commands.options import add_out, add_scene, positive_float

NAME = "simulate"
HELP = "run a scene on the analytic model; write trajectory.npz and print a summary"
DESCRIPTION = (
    "Integrate a scene with the paper's analytic model (scipy solver from the scene, "
    "overridable), write OUT/trajectory.npz and OUT/summary.json, and print the tracking errors "
    "at the end and the invariant drifts."
)
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    from analytic.effects import Backend, SolverMethod, Stepper

    add_scene(p)
    add_out(p, "output directory (default: out/simulate_<scene slug>)")
    p.add_argument("--method", choices=[m.value for m in SolverMethod], help="scipy solver")
    p.add_argument("--rtol", type=positive_float, help="relative tolerance")
    p.add_argument("--atol", type=positive_float, help="absolute tolerance")
    p.add_argument("--t-end", type=positive_float, help="horizon in seconds")
    p.add_argument(
        "--backend",
        choices=[b.value for b in Backend],
        default=Backend.AUTO.value,
        help="right-hand side: the compiled kernel (auto/numba) or the numpy reference",
    )
    p.add_argument(
        "--stepper",
        choices=[s.value for s in Stepper],
        default=Stepper.AUTO.value,
        help="integration loop: compiled (CyRK; DOP853, RK45, RK23; auto where it applies) or the "
        "scipy reference",
    )


def run(args: argparse.Namespace) -> int:
    # deferred: after main's signal handlers (validation.cli's docstring): numpy, MuJoCo, numba
    from analytic.simulate import simulate
    from analytic.trajectory import RunStatus
    from validation.compare.summary import drift_figures, summary_table
    from validation.runs.atomic import write_bytes, write_text
    from validation.runs.outputs import default_out_dir, output_run
    from validation.runs.progress import Progress
    from validation.scenes import resolve_scene

    scene = resolve_scene(args.scene)
    t_end = args.t_end or scene.output.t_end
    out = Path(args.out) if args.out else default_out_dir("simulate_", scene.name)
    with output_run(out, "simulate") as run:
        prog = Progress(f"simulate {scene.name}", t_end)
        try:
            tr = simulate(
                scene,
                method=args.method,
                rtol=args.rtol,
                atol=args.atol,
                t_end=args.t_end,
                progress=prog,
                backend=args.backend,
                stepper=args.stepper,
            )
        finally:
            prog.close()
        write_bytes(run.path / "trajectory.npz", tr.npz_bytes())
        summary = {
            "run_id": run.run_id,
            "scene": scene.name,
            "engine": tr.engine,
            "status": tr.status.value,
            "message": tr.message,
            "info": tr.info,
            "drift": drift_figures(tr),
            "final_tracking_error": {
                "e_omega": tr.tracking.e_omega[-1].tolist() if tr.tracking.e_omega.size else [],
                "e_p": tr.tracking.e_p[-1].tolist() if tr.tracking.e_p.size else [],
            },
        }
        write_text(run.path / "summary.json", json.dumps(summary, indent=2, default=str))
        if tr.status is RunStatus.INTERRUPTED:
            raise KeyboardInterrupt  # the partial trajectory is kept, marked interrupted
        if tr.status is not RunStatus.OK:
            run.mark_failed(tr.message)
    print(summary_table(tr))
    print(f"wrote {run.final('trajectory.npz')} and {run.final('summary.json')}")
    return 0 if tr.status is RunStatus.OK else EXIT_FAILED
