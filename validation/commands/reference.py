"""``tumble reference``: a reference pack (the scene, a tight reference trajectory with its error
estimate, and a README with the controller and the thresholds) for testing an engine in any
language; ``tumble judge --reference`` judges a run against it."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands.options import add_out, add_scene, add_t_end

NAME = "reference"
HELP = (
    "write a reference pack: the scene, a tight reference trajectory, README with the controller "
    "and thresholds"
)
DESCRIPTION = (
    "Write what an engineer needs to test an engine in any language: OUT/scene.toml, "
    "OUT/reference.csv (the analytic plant at DOP853 rtol 1e-13, every column incl. the "
    "controller's outputs tau and F), OUT/reference.json (its error estimated by "
    "self-convergence against rtol 1e-14, beside every threshold) and OUT/README.md (the problem, "
    "the controller's equations with the paper's numbers, the error definitions and acceptance "
    "thresholds). Judge a run against it with tumble judge SCENE --trajectory FILE --reference OUT."
)
CHOOSES_PLANTS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scene(p)
    add_t_end(
        p,
        "the pack's horizon, s: in (0, the scene's t_end], on its output grid (a pack judges any "
        "horizon up to its own)",
        metavar="T",
    )
    add_out(p, "output directory (default: out/reference_<scene slug>)")


def run(args: argparse.Namespace) -> int:
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
