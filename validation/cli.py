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

from analytic.effects import SolverMethod  # noqa: E402
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
    p.set_defaults(func=cmd_simulate)
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
