"""The ``tumble`` command line.

Errors are one line on stderr (``tumble: error: ...``) and a non-zero exit status, never a
traceback. Outputs are written atomically.
"""

from __future__ import annotations

import os

# Small dense matrices only: one BLAS thread (see tests/conftest.py for the measurement).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

from analytic.effects import Backend, MjIntegrator, SolverMethod  # noqa: E402
from analytic.trajectory import RunStatus  # noqa: E402
from validation.progress import Progress  # noqa: E402
from validation.scenes import DEFAULT_SIMULATE_SCENE, builtin_names, resolve_scene  # noqa: E402

EXIT_FAILED = 1  # a run or a check failed
EXIT_USAGE = 2  # bad input (scene, arguments)


def _positive_float(s: str) -> float:
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {s!r}") from None
    if not v > 0 or v != v or v == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number: {s!r}")
    return v


def _add_scene_arg(p: argparse.ArgumentParser, default: str) -> None:
    p.add_argument(
        "scene",
        nargs="?",
        default=None,
        help=f"scene file (TOML) or built-in scene name (default: {default}); "
        f"built-in: {', '.join(builtin_names())}",
    )


def cmd_simulate(args: argparse.Namespace) -> int:
    from analytic.simulate import simulate
    from validation.summary import drift_figures, summary_table

    scene = resolve_scene(args.scene, DEFAULT_SIMULATE_SCENE)
    t_end = args.t_end or scene.output.t_end
    out = Path(args.out or Path("out") / scene.name)
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
        )
    finally:
        prog.close()
    path = tr.save_npz(out / "trajectory.npz")
    summary = {
        "scene": scene.name,
        "engine": tr.engine.value,
        "status": tr.status.value,
        "message": tr.message,
        "info": tr.info,
        "drift": drift_figures(tr),
        "final_tracking_error": {
            "e_omega": tr.tracking.e_omega[-1].tolist() if tr.tracking.e_omega.size else [],
            "e_p": tr.tracking.e_p[-1].tolist() if tr.tracking.e_p.size else [],
        },
    }
    from validation.atomic import write_text

    write_text(out / "summary.json", json.dumps(summary, indent=2, default=str))
    print(summary_table(tr))
    print(f"wrote {path} and {out / 'summary.json'}")
    return 0 if tr.status is RunStatus.OK else EXIT_FAILED


def cmd_validate(args: argparse.Namespace) -> int:
    from validation.scenes import DEFAULT_VALIDATE_SCENE
    from validation.validate import run_validation

    scene = resolve_scene(args.scene, DEFAULT_VALIDATE_SCENE)
    out = Path(args.out or Path("out") / f"validate_{scene.name}")
    t_end = args.t_end or scene.output.t_end
    prog = Progress(f"validate {scene.name}", t_end)

    def progress(stage: str, t: float) -> None:
        prog.label = f"validate {scene.name} [{stage}]"
        prog(t)

    try:
        res = run_validation(
            scene, out, integrator=args.integrator, dt=args.dt, t_end=args.t_end, progress=progress
        )
    finally:
        prog.close()
    n_fail = sum(1 for c in res.checks if not c.passed)
    verdict = "PASS" if res.passed else "FAIL"
    print(f"{verdict}: {len(res.checks) - n_fail}/{len(res.checks)} checks passed for {scene.name}")
    for c in res.checks:
        if not c.passed:
            print(f"  failed: {c.label}: {c.value:.3e} > {c.threshold:.3e} {c.unit}")
    print(f"report: {Path(res.out_dir) / 'report.md'}  recording: {Path(res.out_dir) / 'run.rrd'}")
    return 0 if res.passed else EXIT_FAILED


def cmd_export_mjcf(args: argparse.Namespace) -> int:
    from model_xml import to_mjcf
    from validation.atomic import write_text

    scene = resolve_scene(args.scene, DEFAULT_SIMULATE_SCENE)
    out = Path(args.out or f"{scene.name}.xml")
    write_text(out, to_mjcf(scene))
    print(f"wrote {out}")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    from validation.validate import write_demo

    out = Path(args.out or Path("out") / "demo")
    res = write_demo(out)
    print(f"wrote {res.markdown}; open the recording with: rerun {res.rrd}")
    return 0


def cmd_hard_cases(args: argparse.Namespace) -> int:
    from validation.hard_cases import run_hard_cases

    out = Path(args.out or Path("out") / "hard_cases")

    def progress(case: str, i: int, total: int) -> None:
        if sys.stderr.isatty():
            print(f"hard case {i + 1}/{total}: {case}", file=sys.stderr)

    table = run_hard_cases(out, names=args.case or None, fast_only=args.fast, progress=progress)
    for r in table.rows:
        print(f"  {'PASS' if r.passed else 'FAIL'}  {r.case}")
    n_pass = sum(1 for r in table.rows if r.passed)
    verdict = "PASS" if table.passed else "FAIL"
    print(f"{verdict}: {n_pass}/{len(table.rows)} hard cases; table in {out / 'hard_cases.md'}")
    return 0 if table.passed else EXIT_FAILED


def cmd_sweep(args: argparse.Namespace) -> int:
    from validation.sweep import run_sweep

    scene = resolve_scene(args.scene, DEFAULT_SIMULATE_SCENE)
    out = Path(args.out or Path("out") / f"sweep_{scene.name}")

    def progress(line: str) -> None:
        if sys.stderr.isatty():
            print(line, file=sys.stderr)

    res = run_sweep(scene, out, quick=args.quick, progress=progress)
    print(f"sweep of {scene.name}: {len(res.runs)} runs in {res.wall_time_s:.1f} s")
    by_id = {r["run_id"]: r for r in res.runs}
    print("  cheapest setting reaching each accuracy level:")
    for engine, levels in res.cheapest.items():
        for lvl, rid in levels.items():
            r = by_id.get(rid)
            pick = f"{r['method']} {r['setting_name']} {r['setting']:g}" if r else "none reaches it"
            print(f"    {engine:<9} error <= {float(lvl):.0e}: {pick}")
    print(f"table: {out / 'sweep.md'}  figure: {out / 'work_precision.png'}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from validation.bench import run

    out = Path(args.out) if args.out else None
    run(
        args.skip_long, str(out / "bench.json") if out else None, out=lambda s: print(s, flush=True)
    )
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tumble",
        description="Cross-validation testbed for tumbling multibody dynamics: the Koganti-Udwadia "
        "analytic model and a MuJoCo twin under one closed-form controller.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser(
        "simulate",
        help="run a scene on the analytic model; write trajectory.npz and print a summary",
        description="Integrate a scene with the paper's analytic model (scipy solver from the "
        "scene, overridable), write OUT/trajectory.npz and OUT/summary.json, and print the "
        "tracking errors at the end and the invariant drifts.",
    )
    _add_scene_arg(p, DEFAULT_SIMULATE_SCENE)
    p.add_argument("--out", help="output directory (default: out/<scene name>)")
    p.add_argument("--method", choices=[m.value for m in SolverMethod], help="scipy solver")
    p.add_argument("--rtol", type=_positive_float, help="relative tolerance")
    p.add_argument("--atol", type=_positive_float, help="absolute tolerance")
    p.add_argument("--t-end", type=_positive_float, help="horizon in seconds")
    p.add_argument(
        "--backend",
        choices=[b.value for b in Backend],
        default=Backend.AUTO.value,
        help="right-hand side: the compiled kernel (auto/numba) or the numpy reference",
    )
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser(
        "validate",
        help="run a scene on the analytic plant and on MuJoCo under one controller; compare",
        description="Run the scene on the analytic model and on its MuJoCo twin, both driven by "
        "the same analytic controller, compare trajectories, invariants and control forces, and "
        "write OUT/report.md, OUT/report.json, figures and OUT/run.rrd. Exits 1 when a check "
        "fails.",
    )
    from validation.scenes import DEFAULT_VALIDATE_SCENE

    _add_scene_arg(p, DEFAULT_VALIDATE_SCENE)
    p.add_argument("--out", help="output directory (default: out/validate_<scene name>)")
    p.add_argument(
        "--integrator",
        choices=[i.value for i in MjIntegrator],
        help="MuJoCo integrator (default: the scene's)",
    )
    p.add_argument("--dt", type=_positive_float, help="MuJoCo timestep in seconds")
    p.add_argument("--t-end", type=_positive_float, help="horizon in seconds")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser(
        "export-mjcf",
        help="write the MJCF of a scene's MuJoCo twin (full precision)",
        description="Write the MuJoCo model generated from the scene (MjSpec) as MJCF text.",
    )
    _add_scene_arg(p, DEFAULT_SIMULATE_SCENE)
    p.add_argument("--out", help="output file (default: <scene name>.xml)")
    p.set_defaults(func=cmd_export_mjcf)

    p = sub.add_parser(
        "demo",
        help="write a narrated teaching demo (.rrd + markdown)",
        description="Write a teaching demo: Example 1 uncontrolled and controlled, Example 2 "
        "with masses 1, 2, 4 controlled, and an effect switched off, narrated with equations; "
        "each step on the analytic plant with the MuJoCo twin as a ghost.",
    )
    p.add_argument("--out", help="output directory (default: out/demo)")
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser(
        "hard-cases",
        help="run the hard-case stability suite and write its table",
        description="Run the hard cases (validation/scenes/hard/*.toml: a rigid body alone, stiff "
        "springs, extreme mass ratios, fast spin, long horizons, many masses, off-manifold and "
        "conflicting requirements ...) on both engines against their stated criteria; write "
        "OUT/hard_cases.md and OUT/hard_cases.json. Exits 1 when a case fails.",
    )
    p.add_argument("--out", help="output directory (default: out/hard_cases)")
    p.add_argument("--fast", action="store_true", help="only the fast subset")
    p.add_argument("--case", action="append", help="run only this case (repeatable)")
    p.set_defaults(func=cmd_hard_cases)

    p = sub.add_parser(
        "sweep",
        help="what accuracy costs in time: work-precision study over both engines",
        description="Compute a reference solution, run the analytic engine over scipy solvers and "
        "tolerances and MuJoCo over integrators and timesteps, and write OUT/sweep.csv, "
        "sweep.json, sweep.md (the cheapest setting per accuracy level marked), "
        "work_precision.png and sweep.rrd; also the cost of each effect and the effect of the "
        "quaternion stabilisation (delta1, delta2).",
    )
    _add_scene_arg(p, DEFAULT_SIMULATE_SCENE)
    p.add_argument("--out", help="output directory (default: out/sweep_<scene name>)")
    p.add_argument("--quick", action="store_true", help="a small grid (minutes, not tens)")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser(
        "bench",
        help="the fast engine's speed goals as ratios measured in this process",
        description="Time one controlled-dynamics evaluation (numpy path, compiled path, "
        "mj_forward) and print each speed goal of the fast engine as a ratio with whether it "
        "holds: evaluation vs mj_forward (n = 2, 5), the controller inside MuJoCo's RK4 vs the "
        "bare step, n = 1000 vs n = 10, and the 60 s controlled Example 1 vs MuJoCo RK4 at the "
        "same accuracy. Numbers only: exits 0 whether or not a goal holds.",
    )
    p.add_argument("--out", help="also write OUT/bench.json")
    p.add_argument("--skip-long", action="store_true", help="skip the 60 s Example 1 goal")
    p.set_defaults(func=cmd_bench)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            return args.func(args)
    except ValueError as exc:
        print(f"tumble: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except OSError as exc:
        print(
            f"tumble: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
            file=sys.stderr,
        )
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("tumble: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
