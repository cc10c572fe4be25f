"""``python -m validation.studies.fuzz.bench [ROUNDS] [--campaign] [--runaway]``: the fuzzer's
throughput goals, each measured in this one process and printed (never asserted).

1. **Scene-validations per core-minute** (:mod:`validation.studies.fuzz.throughput`), always.
2. **A campaign's wall against its plants' compute** and 3. **two Dask workers against one**
   (:mod:`validation.studies.fuzz.campaign_goals`, campaigns timed task by task by
   :mod:`validation.studies.fuzz.campaign_timing`): they take minutes, so they run only with
   ``--campaign``.
4. The runaway campaign's goals (:mod:`validation.studies.fuzz.runaway_goal`), with ``--runaway``.

Beside them, what the hard time limit costs per plant run, where this process can fork
(:mod:`validation.studies.fuzz.limit_overhead`).
"""

from __future__ import annotations

from validation.bench.verdicts import Verdict
from validation.runs import workers
from validation.studies.fuzz.campaign_goals import (
    OTHERS_BOUND_CPUS,
    campaign_verdict,
    goal_campaign_wall,
    goal_dask_scaling,
)
from validation.studies.fuzz.campaign_timing import default_plants
from validation.studies.fuzz.limit_overhead import served_overhead
from validation.studies.fuzz.throughput import GOAL_PER_CORE_MINUTE, HORIZON_S, SCENE, measure


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m validation.studies.fuzz.bench",
        description="The fuzzer's throughput goals, as ratios measured in this process "
        "(docs/fuzzing.md, Throughput).",
    )
    parser.add_argument(
        "rounds", nargs="?", type=int, default=5, help="timed validations (default 5)"
    )
    parser.add_argument(
        "--campaign",
        action="store_true",
        help="also the two campaign goals (wall against the plants' compute on a process pool of "
        "two; two Dask workers against one): about 8 minutes",
    )
    parser.add_argument(
        "--runaway",
        action="store_true",
        help="also the runaway campaign's goals (seed 7, 40 violent scenes over 2 s: no model "
        "finding, no run over its time limit, its wall, every counterexample reproduced by its "
        "command; validation.studies.fuzz.runaway_goal): about 4 minutes",
    )
    args = parser.parse_args(argv)
    if args.rounds < 1:
        parser.error(f"rounds: must be a whole number ≥ 1 (got {args.rounds})")
    campaign = args.campaign
    t = measure(args.rounds)
    print(
        f"one validation of {SCENE} over {HORIZON_S:g} s, three plants: CPU {t.cpu_s:.3f} s "
        f"(plants {t.plants_s:.3f} s wall), {t.per_core_minute:.0f} per core-minute "
        f"(goal ≥ {GOAL_PER_CORE_MINUTE:g}: {'holds' if t.per_core_minute >= GOAL_PER_CORE_MINUTE else 'fails'})"
    )
    if workers.can_fork() and workers.can_serve():
        for name in default_plants():
            print("hard time limit per run, " + served_overhead(name).text())
    if campaign:
        for goal in (goal_campaign_wall, goal_dask_scaling):
            g = goal()
            others = g.data.get("others_cpus")
            if campaign_verdict(g, others) is Verdict.TOO_BUSY:
                print(
                    f"{g.name}: ratio {g.value:.3g} (goal ≤ {g.limit:.3g}): the machine was too "
                    f"busy for a verdict (other processes used {others:.2f} CPUs, more than "
                    f"{OTHERS_BOUND_CPUS:g}). {g.detail}"
                )
            else:
                print(g.line())
    if args.runaway:
        from validation.studies.fuzz.runaway_goal import runaway_campaign

        for line in runaway_campaign().lines():
            print(line)
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
