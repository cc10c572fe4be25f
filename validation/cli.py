"""The ``tumble`` command line.

Errors are one line on stderr (``tumble: error: ...``) and a non-zero exit status, never a
traceback: 2 for bad input (found before any work), 1 for a failed run or check or a result that
could not be written, 130 after Ctrl-C and 143 after SIGTERM (the partial results are kept, marked
interrupted). Every output directory is one run, whole (:mod:`validation.runs.outputs`); default output
paths are built from a sanitised slug of the scene's name, always under ``out/``.

Only the standard library is imported before ``main`` has installed its signal handlers, so a
Ctrl-C during start-up (numpy, MuJoCo, numba loading) is one line too; an interrupt that lands
inside compiled code's Python callback is kept and raised at the next progress report, and one
that cuts an import (a C extension's initialisation then fails as ``ImportError``) or causes any
other exception ends the command as interrupted too, every command alike
(:mod:`validation.runs.interrupts`). ``--plants`` is refused when it names no plant.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import warnings
from pathlib import Path
from typing import NoReturn

from validation.runs import interrupts

EXIT_FAILED = 1  # a run or a check failed, or its results could not be written
EXIT_USAGE = 2  # bad input (scene, arguments), found before any work
EXIT_SIGINT = 130  # 128 + SIGINT, the shell's convention
EXIT_SIGTERM = 143  # 128 + SIGTERM


def _positive_float(s: str) -> float:
    """A positive finite number given on the command line; ``ArgumentTypeError`` quoting it."""
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number (got {s!r})") from None
    if not v > 0 or v != v or v == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number (got {s!r})")
    return v


def _plant_names(s: str) -> str:
    """A ``--plants`` value: comma-separated names, at least one (``''`` or ``','`` would
    otherwise read as "not given" and run the default plants); ``ArgumentTypeError`` quoting it.
    The names themselves are checked by the command (:func:`mj_bridge.plants.parse_plants`)."""
    if not any(x.strip() for x in s.split(",")):
        raise argparse.ArgumentTypeError(f"give at least one plant name (got {s!r})")
    return s


class _OneLineParser(argparse.ArgumentParser):
    """An argument parser whose refusals are one line, as every other bad input's: ``tumble
    validate: error: --dt: must be a positive finite number (got '0')``, exit 2 (no usage block;
    ``--help`` is unchanged). Sub-commands' parsers are of this class too (argparse makes them of
    their parent's)."""

    def error(self, message: str) -> NoReturn:
        text = message.splitlines()[0] if message else "bad arguments"
        if text.startswith("argument "):  # "argument --dt: ..." -> "--dt: ..."
            text = text[len("argument ") :]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {text}\n")


def _add_scene_arg(p: argparse.ArgumentParser, default: str, builtin: list[str]) -> None:
    p.add_argument(
        "scene",
        nargs="?",
        default=None,
        help=f"scene file (TOML) or built-in scene name (default: {default}); "
        f"built-in: {', '.join(builtin)}",
    )


def cmd_simulate(args: argparse.Namespace) -> int:
    # deferred: after main's signal handlers (module docstring): numpy, MuJoCo, numba
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


def cmd_validate(args: argparse.Namespace) -> int:
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
        progress = StageProgress(f"validate {scene.name}", request.horizon)
        try:
            res = run_request(request, out, progress=progress)
        finally:
            progress.close(walls=res.wall_times if res is not None else None, stopped=res is None)
    return _print_outcome(res, scene.name, "not applicable")


def _print_outcome(res, subject: str, idle_words: str, not_judged: bool = False) -> int:
    """The closing lines of ``tumble validate`` and ``tumble judge``: the verdict with its count
    (``idle_words`` names the checks left out), a failed run, each failed check, the reasons a
    file was not judged (``not_judged``), every referee ruling other than agree, and the report
    and recording written; returns the exit status."""
    from validation.compare.referee import VerdictKind
    from validation.compare.summary import check_sentence

    counted = [c for c in res.checks if c.applicable]
    n_fail = sum(1 for c in counted if not c.passed)
    idle = len(res.checks) - len(counted)
    verdict = "PASS" if res.passed else "FAIL"
    na = f" ({idle} {idle_words})" if idle else ""
    print(f"{verdict}: {len(counted) - n_fail}/{len(counted)} checks passed{na} for {subject}")
    if res.failure:
        print(f"  run failed: {res.failure}")
    for c in res.checks:
        if not c.passed:
            print(f"  failed: {check_sentence(c, reason=False)}")
    if not_judged:
        for why in sorted({c.reason for c in res.checks if c.reason.startswith("not judged")}):
            print(f"  {why}")
    for v in res.verdicts:
        if v.kind is not VerdictKind.AGREE:
            print(f"  referee: {v.text}")
    named = [f"{what}: {res.files[name]}" for what, name in _CLOSING_FILES if name in res.files]
    print("  ".join(named))
    return 0 if res.passed else EXIT_FAILED


_CLOSING_FILES = (("report", "report.md"), ("recording", "run.rrd"))
"""The files ``tumble validate``'s closing line names, each only when the run wrote it."""


def cmd_judge(args: argparse.Namespace) -> int:
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
        progress = StageProgress(f"judge {request.label} on {scene.name}", request.validation.horizon)
        try:
            res = run_judge(request, out, progress=progress)
        finally:
            progress.close(walls=res.wall_times if res is not None else None, stopped=res is None)
    return _print_outcome(
        res, f"{request.label} on {scene.name}{over}", "not judged or not applicable", not_judged=True
    )


def cmd_reference(args: argparse.Namespace) -> int:
    from validation.external.reference_pack import ACCURACY_MARGIN, write_pack
    from validation.runs.outputs import default_out_dir
    from validation.scenes import resolve_scene

    scene = resolve_scene(args.scene)
    if args.t_end is not None:
        from validation.external.horizon import horizon_on_grid, shortened

        scene = shortened(scene, horizon_on_grid(scene, args.t_end, "--t-end"))
    out = Path(args.out) if args.out else default_out_dir("reference_", scene.name)
    pack = write_pack(scene, out)
    worst = max(
        (a for a in pack.accuracy if a.estimate == a.estimate),
        key=lambda a: a.estimate / a.threshold,
        default=None,
    )
    if worst is not None:
        print(
            f"reference error estimate: at most {worst.estimate / worst.threshold:.1e} × its "
            f"threshold ({worst.quantity}); the pack needs {ACCURACY_MARGIN:g}"
        )
    if not pack.accurate_enough:
        bad = ", ".join(a.quantity for a in pack.accuracy if not a.ok)
        print(f"  not accurate enough for: {bad} (said in README.md and reference.json)")
    print(f"wrote the reference pack {pack.out_dir} ({', '.join(pack.files)})")
    return 0


def cmd_export_mjcf(args: argparse.Namespace) -> int:
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


def cmd_demo(args: argparse.Namespace) -> int:
    from validation.studies.demo import write_demo

    out = Path(args.out) if args.out else Path("out") / "demo"
    res = write_demo(out)
    print(f"wrote {res.markdown}; open the recording with: rerun {res.rrd}")
    return 0


def cmd_hard_cases(args: argparse.Namespace) -> int:
    from validation.studies.hard_cases import run_hard_cases

    out = Path(args.out) if args.out else Path("out") / "hard_cases"
    plants = None
    if args.plants is not None:
        from mj_bridge.plants import parse_plants

        plants = list(parse_plants(args.plants))

    def progress(case: str, i: int, total: int) -> None:
        if sys.stderr.isatty():
            print(f"hard case {i + 1}/{total}: {case}", file=sys.stderr)

    table = run_hard_cases(
        out, names=args.case or None, fast_only=args.fast, progress=progress, plants=plants
    )
    for r in table.rows:
        per_plant = ", ".join(f"{e} {r.plant_verdict(e)}" for e in table.plants)
        print(f"  {'PASS' if r.passed else 'FAIL'}  {r.case}  ({per_plant})")
    for e, why in table.not_installed.items():
        print(f"  {e}: not run ({why})")
    n_pass = sum(1 for r in table.rows if r.passed)
    verdict = "PASS" if table.passed else "FAIL"
    print(
        f"{verdict}: {n_pass}/{len(table.rows)} hard cases on {', '.join(table.plants)}; "
        f"table in {out / 'hard_cases.md'}"
    )
    return 0 if table.passed else EXIT_FAILED


def cmd_sweep(args: argparse.Namespace) -> int:
    from validation.runs.outputs import default_out_dir
    from validation.scenes import resolve_scene
    from validation.studies.sweep import run_sweep

    scene = resolve_scene(args.scene)
    out = Path(args.out) if args.out else default_out_dir("sweep_", scene.name)

    def progress(line: str) -> None:
        if sys.stderr.isatty():
            print(line, file=sys.stderr)

    if args.scheduler is None and args.dask_workers is None:
        res = run_sweep(scene, out, quick=args.quick, progress=progress, t_end=args.t_end)
    else:  # a Dask cluster's executor (validation.studies.sweep.running.executor_for)
        from validation.studies.sweep.running import executor_for

        with executor_for(None, args.scheduler, args.dask_workers) as (ex, _width):
            res = run_sweep(
                scene, out, quick=args.quick, progress=progress, t_end=args.t_end, executor=ex
            )
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


def cmd_fuzz(args: argparse.Namespace) -> int:
    from validation.studies.fuzz.campaign import fuzz

    plants = None if args.plants is None else [x.strip() for x in args.plants.split(",") if x.strip()]
    out = Path(args.out) if args.out else Path("out") / f"fuzz_seed{args.seed}"

    def progress(line: str) -> None:
        if sys.stderr.isatty():
            print(line, file=sys.stderr)

    res = fuzz(
        out,
        budget=args.budget,
        minutes=args.minutes,
        seed=args.seed,
        plants=plants,
        horizon=args.horizon,
        scheduler=args.scheduler,
        dask_workers=args.dask_workers,
        progress=progress,
        **({"time_limit_s": args.time_limit} if args.time_limit else {}),
    )
    new = sum(not e.known for e in res.counterexamples)
    against = sum(e.counts_against for e in res.counterexamples)
    print(
        f"fuzz seed {res.config.seed}: {len(res.scenes)} scenes in {res.wall_s:.1f} s, "
        f"{len(res.counterexamples)} minimal counterexamples ({new} new, {new - against} of them "
        f"numerical limits of the settings); report in {res.out_dir / 'campaign.md'}"
    )
    return EXIT_FAILED if against else 0


def _add_dask_args(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--scheduler", help="a Dask scheduler's address (tcp://host:8786)")
    g.add_argument(
        "--dask-workers",
        type=_positive_int,
        help="run on a local Dask cluster of N single-threaded worker processes",
    )


def _positive_int(s: str) -> int:
    try:
        v = int(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number (got {s!r})") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be ≥ 1 (got {s!r})")
    return v


def cmd_bench(args: argparse.Namespace) -> int:
    from validation.bench.command import run, write_bench

    def say(s: str) -> None:
        print(s, flush=True)

    if args.out:
        write_bench(args.out, args.skip_long, out=say)
    else:
        run(args.skip_long, None, out=say)
    return 0


def cmd_warmup(args: argparse.Namespace) -> int:
    from mj_bridge.plants import installed_plants
    from validation.runs.warmup import builtin_scenes, warm_up_command
    from validation.scenes import resolve_scene

    scenes = [resolve_scene(args.scene)] if args.scene else builtin_scenes()
    engines = list(installed_plants())
    return 0 if warm_up_command(scenes, engines, out=lambda s: print(s, flush=True)) else 1


def cmd_scene_reference(args: argparse.Namespace) -> int:
    from validation.report.scene_reference import render
    from validation.runs.atomic import write_text

    if args.out:
        write_text(Path(args.out), render())
        print(f"wrote {args.out}")
    else:
        sys.stdout.write(render())
    return 0


def _version() -> str:
    """The installed distribution's version ("unknown" when run from a bare checkout)."""
    from importlib import metadata  # deferred: ~15 ms (-X importtime), after main's handlers

    try:
        return metadata.version("tumbling-testbed")
    except metadata.PackageNotFoundError:
        return "unknown"


def build_parser() -> argparse.ArgumentParser:
    from analytic.effects import Backend, MjIntegrator, SolverMethod, Stepper
    from validation.scenes import DEFAULT_SCENE, builtin_names

    parser = _OneLineParser(
        prog="tumble",
        description="Cross-validation testbed for tumbling multibody dynamics: the Koganti-Udwadia "
        "analytic model and a MuJoCo twin under one closed-form controller.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser(
        "simulate",
        help="run a scene on the analytic model; write trajectory.npz and print a summary",
        description="Integrate a scene with the paper's analytic model (scipy solver from the "
        "scene, overridable), write OUT/trajectory.npz and OUT/summary.json, and print the "
        "tracking errors at the end and the invariant drifts.",
    )
    _add_scene_arg(p, DEFAULT_SCENE, builtin_names())
    p.add_argument("--out", help="output directory (default: out/simulate_<scene slug>)")
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
    p.add_argument(
        "--stepper",
        choices=[s.value for s in Stepper],
        default=Stepper.AUTO.value,
        help="integration loop: compiled (CyRK; DOP853, RK45, RK23; auto where it applies) or the "
        "scipy reference",
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
    _add_scene_arg(p, DEFAULT_SCENE, builtin_names())
    p.add_argument("--out", help="output directory (default: out/validate_<scene slug>)")
    p.add_argument(
        "--integrator",
        choices=[i.value for i in MjIntegrator],
        help="MuJoCo integrator (default: the scene's)",
    )
    p.add_argument("--dt", type=_positive_float, help="MuJoCo timestep in seconds")
    p.add_argument("--t-end", type=_positive_float, help="horizon in seconds")
    p.add_argument(
        "--plants",
        type=_plant_names,
        help="comma-separated plants to run: built-ins (analytic, mujoco, pinocchio) and "
        "installed plant plugins (drake; docs/plugins.md) by name, or 'all' for every installed "
        "one (default: every installed default plant, analytic,mujoco,pinocchio; with three or "
        "more the referee names an outlier)",
    )
    p.add_argument(
        "--figure-format",
        default="png",
        help="comma-separated figure formats: png, svg, pdf (default: png; e.g. png,svg for a paper)",
    )
    p.add_argument(
        "--time-limit",
        type=_positive_float,
        metavar="SECONDS",
        help="wall-time limit of each plant's run: a run over it is stopped and fails that plant, "
        "the others are compared (default: none for the built-in plants, 600 s for a plugin)",
    )
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser(
        "judge",
        help="judge another engine's trajectory file of a scene beside the built-in plants",
        description="Read FILE, another engine's run of the scene on its output grid "
        "(docs/trajectory-format.md), run the built-in plants beside it as referees (or, with "
        "--reference, take a reference pack's trajectory instead), and compare every pair with "
        "the same checks, referee, report, figures and recording as validate, the file being one "
        "more plant. A check needing columns the file lacks is 'not judged'. Exits 0 when every "
        "judged check passes, 1 when one fails, 2 for bad input (a bad file: its row and column).",
    )
    _add_scene_arg(p, DEFAULT_SCENE, builtin_names())
    p.add_argument(
        "--trajectory", required=True, metavar="FILE", help="the trajectory file (.csv, .parquet)"
    )
    p.add_argument(
        "--label",
        help="the file's plant name in the report (default: from the file name; lower-case "
        "letters, digits and _, not a plant's name)",
    )
    p.add_argument(
        "--plants",
        type=_plant_names,
        help="comma-separated built-in plants to run beside the file (default: every installed "
        "one that can run the scene)",
    )
    p.add_argument(
        "--reference",
        metavar="DIR",
        help="a reference pack (tumble reference): judge against its trajectory, running no plant",
    )
    p.add_argument(
        "--t-end",
        type=_positive_float,
        metavar="T",
        help="judge the scene as if its t_end were T, s: in (0, the scene's t_end], on its output "
        "grid; the file then holds the grid up to T",
    )
    p.add_argument(
        "--up-to-file-end",
        action="store_true",
        help="a file that stops on the grid before the end is judged up to its last row (the "
        "report states the horizon judged); without it such a file is refused",
    )
    p.add_argument("--out", help="output directory (default: out/judge_<scene slug>)")
    p.add_argument(
        "--figure-format",
        default="png",
        help="comma-separated figure formats: png, svg, pdf (default: png)",
    )
    p.set_defaults(func=cmd_judge)

    p = sub.add_parser(
        "reference",
        help="write a reference pack: the scene, a tight reference trajectory, README with the "
        "controller and thresholds",
        description="Write what an engineer needs to test an engine in any language: "
        "OUT/scene.toml, OUT/reference.csv (the analytic plant at DOP853 rtol 1e-13, every "
        "column incl. the controller's outputs tau and F), OUT/reference.json (its error "
        "estimated by self-convergence against rtol 1e-14, beside every threshold) and "
        "OUT/README.md (the problem, the controller's equations with the paper's numbers, the "
        "error definitions and acceptance thresholds). Judge a run against it with "
        "tumble judge SCENE --trajectory FILE --reference OUT.",
    )
    _add_scene_arg(p, DEFAULT_SCENE, builtin_names())
    p.add_argument(
        "--t-end",
        type=_positive_float,
        metavar="T",
        help="the pack's horizon, s: in (0, the scene's t_end], on its output grid (a pack "
        "judges any horizon up to its own)",
    )
    p.add_argument("--out", help="output directory (default: out/reference_<scene slug>)")
    p.set_defaults(func=cmd_reference)

    p = sub.add_parser(
        "export-mjcf",
        help="write the MJCF of a scene's MuJoCo twin (full precision)",
        description="Write the MuJoCo model generated from the scene (MjSpec) as MJCF text.",
    )
    _add_scene_arg(p, DEFAULT_SCENE, builtin_names())
    p.add_argument("--out", help="output file (default: out/<scene slug>.xml)")
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
        "conflicting requirements ...) on every installed plant against the criterion each file "
        "states in its [hard_case] table (docs/hard_cases.md); write OUT/hard_cases.md and "
        "OUT/hard_cases.json. Exits 1 when a case fails.",
    )
    p.add_argument("--out", help="output directory (default: out/hard_cases)")
    p.add_argument("--fast", action="store_true", help="only the fast subset")
    p.add_argument("--case", action="append", help="run only this case (repeatable)")
    p.add_argument(
        "--plants",
        type=_plant_names,
        help="comma-separated plants, plugins included, or 'all' (default: every installed "
        "default plant, analytic,mujoco,pinocchio)",
    )
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
    _add_scene_arg(p, DEFAULT_SCENE, builtin_names())
    p.add_argument("--out", help="output directory (default: out/sweep_<scene slug>)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="a small grid over a 0.5 s horizon (~10 s on an idle 2-core machine)",
    )
    p.add_argument("--t-end", type=_positive_float, help="horizon in seconds (default 20)")
    _add_dask_args(p)
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser(
        "fuzz",
        help="differential fuzzing: random scenes on every plant, disagreements shrunk",
        description="Draw seeded random scenes across the whole scene format, run each on every "
        "chosen plant under the same controller, judge it with the comparison's checks and the "
        "referee, and shrink every new disagreement to a minimal scene file "
        "(OUT/counterexamples/*.toml); write OUT/campaign.md, campaign.json, campaign.png. "
        "Run again with the same --out to resume. Exits 1 when a new (not known) disagreement "
        "was found that tightened settings do not explain (docs/fuzzing.md).",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument("--budget", type=_positive_int, help="scenes to judge (default 40)")
    g.add_argument("--minutes", type=_positive_float, help="judge scenes for this long")
    p.add_argument("--seed", type=int, default=0, help="the campaign's seed (default 0)")
    p.add_argument(
        "--plants",
        type=_plant_names,
        help="comma-separated plant names (default: every installed one)",
    )
    p.add_argument(
        "--horizon", type=_positive_float, default=0.5, help="each scene's horizon, s (default 0.5)"
    )
    p.add_argument(
        "--out",
        help="output directory: new, empty, or a campaign's to resume, proven by its manifest.json "
        "(default: out/fuzz_seed<seed>)",
    )
    p.add_argument(
        "--time-limit",
        type=_positive_float,
        metavar="SECONDS",
        help="wall-time limit of one plant's run; a run over it is stopped and counted as a "
        "timeout (default 30)",
    )
    _add_dask_args(p)
    p.set_defaults(func=cmd_fuzz)

    p = sub.add_parser(
        "bench",
        help="the fast engine's speed goals as ratios measured in this process",
        description="Time one controlled-dynamics evaluation (numpy path, compiled path, "
        "mj_forward) and print each speed goal of the fast engine as a ratio with whether it "
        "holds: evaluation vs mj_forward (n = 2, 5), the controller inside MuJoCo's RK4 vs the "
        "bare step, n = 1000 vs n = 10, and the 60 s controlled Example 1 vs MuJoCo RK4 at the "
        "same accuracy. Numbers only: exits 0 whether or not a goal holds.",
    )
    from validation.bench.command import add_arguments as add_bench_arguments

    add_bench_arguments(p)  # the options of python -m validation.bench.command, one definition
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser(
        "warmup",
        help="compile every numba kernel a scene needs (default: every built-in scene)",
        description="Compile (or load from numba's cache) every numba kernel the installed "
        "plants need for SCENE (default: every built-in scene), printing one line per kernel "
        "with its time, so that a Docker image or a CI job pays the one-time compile when it is "
        "built. Exits 1 when a kernel failed to compile.",
    )
    p.add_argument(
        "scene",
        nargs="?",
        default=None,
        help=f"scene file (TOML) or built-in scene name (default: all: {', '.join(builtin_names())})",
    )
    p.set_defaults(func=cmd_warmup)

    p = sub.add_parser(
        "scene-reference",
        help="print the scene format's reference (every key; docs/scene-format.md)",
        description="Render the reference of the scene format, every key with its type, unit, "
        "default and meaning, from the loader's own declarations (markdown, on stdout).",
    )
    p.add_argument("--out", help="write it to this file instead")
    p.set_defaults(func=cmd_scene_reference)
    return parser


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings as one line each (``tumble: warning: ...``), without the source line."""
    text = str(message).splitlines()[0] if str(message) else category.__name__
    print(f"tumble: warning: {text}", file=file or sys.stderr)


@contextlib.contextmanager
def user_warnings():
    """The warnings a ``tumble`` user sees: each once per place, one line each.

    ``ResourceWarning`` stays hidden, as in Python's own default: the one a user would meet is a
    Ctrl-C or SIGTERM landing inside an ``import``, which leaves that import's open ``.pyc`` file to
    the collector, a line about Python's internals before the one line that says what happened.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.simplefilter("ignore", ResourceWarning)
        warnings.showwarning = _one_line_warning
        yield


def _out_of_memory(exc: MemoryError) -> str:
    """One line for a ``MemoryError``: ``out of memory (...)`` (its own message may be empty)."""
    text = str(exc).splitlines()[0] if str(exc) else ""
    if text.startswith("out of memory"):
        return text
    return f"out of memory ({text})" if text else "out of memory"


def warn_skipped_plugins(file=None) -> None:
    """One line per plant plugin left out (``tumble: warning: plant plugin 'x' skipped: <why>``,
    :func:`mj_bridge.plants.plugin_errors`), before a command that runs plants; the others run."""
    from mj_bridge.plants import plugin_errors

    for err in plugin_errors():
        print(f"tumble: warning: {err}", file=file or sys.stderr)


_PLANT_COMMANDS = frozenset({"validate", "judge", "reference", "hard-cases", "sweep", "warmup"})
"""The commands that choose among the registered plants (their plugins are loaded, and the ones
left out named)."""


def main(argv: list[str] | None = None) -> int:
    """Run one ``tumble`` command; returns the exit status (see the module docstring).

    Every command runs under :func:`validation.runs.interrupts.handled`: a signal that arrives at
    any moment (an import of a C extension, a plant's run, a write) ends it with 130 / 143 and one
    line, whatever exception the code it landed in raised instead (:func:`_interrupted`)."""
    with interrupts.handled():
        try:
            with user_warnings():
                parser = build_parser()
                args = parser.parse_args(argv)
                if getattr(args, "command", None) in _PLANT_COMMANDS:
                    warn_skipped_plugins()
                status = args.func(args)
        except BaseException as exc:
            return _failed(exc)
        if interrupts.pending():  # swallowed by compiled code after the last progress report
            sigterm = interrupts.received_sigterm()
            print(
                f"tumble: {'terminated' if sigterm else 'interrupted'} as the run ended; "
                "its results are complete",
                file=sys.stderr,
            )
            return EXIT_SIGTERM if sigterm else EXIT_SIGINT
        if interrupts.received():  # caught and turned into a result by code that went on
            return _interrupted(interrupts.interrupt())
        return status


def _interrupted(exc: KeyboardInterrupt) -> int:
    """The one line and the status of a command a signal stopped."""
    sigterm = isinstance(exc, interrupts.Terminated) or interrupts.received_sigterm()
    print(
        f"tumble: {'terminated' if sigterm else 'interrupted'}; "
        "partial results (if any) are kept, marked interrupted",
        file=sys.stderr,
    )
    return EXIT_SIGTERM if sigterm else EXIT_SIGINT


def _failed(exc: BaseException) -> int:
    """The one line and the status of a command that raised ``exc``; an exception that is not
    one of a bad input, memory or a file is re-raised (a bug: its traceback is the report)."""
    from validation.runs.atomic import OutputError

    if isinstance(exc, OutputError):  # the run happened; its results could not be written
        print(f"tumble: error: {exc}", file=sys.stderr)
        return EXIT_FAILED
    ki = interrupts.interrupt_of(exc)  # also an ImportError of an import the signal cut
    if ki is not None:
        return _interrupted(ki)
    if isinstance(exc, ValueError):  # bad input (also OutputBusy: another run holds the directory)
        print(f"tumble: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if isinstance(exc, MemoryError):  # often without a message: one line saying what it is
        print(f"tumble: error: {_out_of_memory(exc)}", file=sys.stderr)
        return EXIT_FAILED
    if isinstance(exc, OSError):
        where = f": {exc.filename}" if exc.filename else ""
        print(f"tumble: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return EXIT_USAGE
    raise exc


def run(argv: list[str] | None = None) -> None:
    """The ``tumble`` program: :func:`main`, then the process ends at once with its status.

    Every file is written and closed by then and the output streams are flushed here; what is
    skipped is the interpreter's teardown of the loaded compiled kernels, about 0.3 s of nothing
    (measured on the default ``validate``). Code that calls ``tumble`` in-process uses
    :func:`main`, which returns the status instead.

    The program's process is the tool's own: its numerical environment (BLAS on one thread,
    ``NO_COLOR``) is set here, before numpy is imported
    (:func:`validation.runs.environment.set_process_env`), not on ``import validation``."""
    from validation.runs.environment import set_process_env

    set_process_env()
    status = main(argv)
    numba_cache = sys.modules.get("analytic.runtime.cache_check")
    if numba_cache is not None:  # what Python's teardown would do: the cache's manifest kept
        numba_cache.finish()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status)


if __name__ == "__main__":
    run()
