"""``tumble hard-cases``: the hard-case stability suite on every chosen plant, each case against
the criterion its file states; its table written. Exits 1 when a case fails."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands import EXIT_FAILED
from validation.commands.options import add_out, add_plants

NAME = "hard-cases"
HELP = "run the hard-case stability suite and write its table"
DESCRIPTION = (
    "Run the hard cases (validation/scenes/hard/*.toml: a rigid body alone, stiff springs, "
    "extreme mass ratios, fast spin, long horizons, many masses, off-manifold and conflicting "
    "requirements ...) on every installed plant against the criterion each file states in its "
    "[hard_case] table (docs/hard_cases.md); write OUT/hard_cases.md, OUT/hard_cases.html and "
    "OUT/hard_cases.json. "
    "Exits 1 when a case fails."
)
CHOOSES_PLANTS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_out(p, "output directory (default: out/hard_cases)")
    p.add_argument("--fast", action="store_true", help="only the fast subset")
    p.add_argument("--case", action="append", help="run only this case (repeatable)")
    add_plants(
        p,
        "comma-separated plants, plugins included, or 'all' (default: every installed default "
        "plant, analytic,mujoco,pinocchio)",
    )


def run(args: argparse.Namespace) -> int:
    from validation.studies.hard_cases import run_hard_cases

    out = Path(args.out) if args.out else Path("out") / "hard_cases"
    plants = None
    if args.plants is not None:
        from mj_bridge.plants import parse_plants

        plants = list(parse_plants(args.plants))

    from validation.runs.progress import ItemsProgress

    progress, done = ItemsProgress("hard cases", "cases"), None
    try:
        table = run_hard_cases(
            out, names=args.case or None, fast_only=args.fast, progress=progress, plants=plants
        )
        done = len(table.rows)
    finally:
        progress.close(done)
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
