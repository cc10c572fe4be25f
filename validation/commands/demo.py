"""``tumble demo``: the narrated teaching demo (a recording and its markdown)."""

from __future__ import annotations

import argparse
from pathlib import Path

from validation.commands.options import add_out, add_viewer

NAME = "demo"
HELP = "write a narrated teaching demo (.rrd + markdown)"
DESCRIPTION = (
    "Write a teaching demo: Example 1 uncontrolled and controlled, Example 2 with masses 1, 2, 4 "
    "controlled, and an effect switched off, narrated with equations; each step on the analytic "
    "plant with the MuJoCo twin as a ghost."
)
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_out(p, "output directory (default: out/demo)")
    add_viewer(p)


def run(args: argparse.Namespace) -> int:
    from validation.studies.demo import write_demo

    out = Path(args.out) if args.out else Path("out") / "demo"
    res = write_demo(out)
    print(f"wrote {res.markdown}; open the recording with: rerun {res.rrd}")
    return 0
