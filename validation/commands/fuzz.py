"""``tumble fuzz``: differential fuzzing, seeded random scenes run on every chosen plant and
judged, each new disagreement shrunk to a minimal scene file; resumable. Exits 1 when a new
disagreement was found that tightened settings do not explain (``docs/fuzzing.md``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands import EXIT_FAILED
from validation.commands.options import (
    add_dashboard,
    add_out,
    add_plants,
    add_time_limit,
    add_workers,
    positive_float,
    positive_int,
)

NAME = "fuzz"
HELP = "differential fuzzing: random scenes on every plant, disagreements shrunk"
DESCRIPTION = (
    "Draw seeded random scenes across the whole scene format, run each on every chosen plant "
    "under the same controller, judge it with the comparison's checks and the referee, and "
    "shrink every new disagreement to a minimal scene file (OUT/counterexamples/*.toml); write "
    "OUT/campaign.md, campaign.html, campaign.json, campaign.png. Run again with the same --out to resume. "
    "Exits 1 when a new (not known) disagreement was found that tightened settings do not "
    "explain (docs/fuzzing.md)."
)
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--budget", type=positive_int, help="scenes to judge (default 40)")
    g.add_argument("--minutes", type=positive_float, help="judge scenes for this long")
    p.add_argument("--seed", type=int, default=0, help="the campaign's seed (default 0)")
    add_plants(p, "comma-separated plant names (default: every installed one)")
    p.add_argument(
        "--horizon", type=positive_float, default=0.5, help="each scene's horizon, s (default 0.5)"
    )
    add_out(
        p,
        "output directory: new, empty, or a campaign's to resume, proven by its manifest.json "
        "(default: out/fuzz_seed<seed>)",
    )
    add_time_limit(
        p,
        "wall-time limit of one plant's run; a run over it is stopped and counted as a timeout "
        "(default 30)",
    )
    add_workers(p)
    add_dashboard(p)


def run(args: argparse.Namespace) -> int:
    from validation.studies.fuzz.campaign import fuzz

    plants = (
        None if args.plants is None else [x.strip() for x in args.plants.split(",") if x.strip()]
    )
    out = Path(args.out) if args.out else Path("out") / f"fuzz_seed{args.seed}"

    res = fuzz(
        out,
        budget=args.budget,
        minutes=args.minutes,
        seed=args.seed,
        plants=plants,
        horizon=args.horizon,
        scheduler=args.scheduler,
        dask_workers=args.dask_workers,
        dashboard=args.dashboard,
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
