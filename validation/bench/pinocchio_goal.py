"""The Pinocchio plant's speed goal (:func:`goal_pinocchio`).

The controlled Example 1 over 20 s, DOP853 at rtol 1e-12 (atol 1e-13), on the Pinocchio plant / on
the analytic plant, both through the plant protocol (``plant(name).simulate``). Each plant runs
once first (compilation, cache loads), then the two alternate for ``rounds`` repeats
(:func:`validation.bench.plant_rounds.plant_rounds`); the ratio is the median of the rounds' ratios
of the integrations' CPU time (each plant's ``info["wall_time_s"]`` times the share of a CPU the
thread had during it; the walls and the whole ``simulate`` call are printed too). Both plants step
on scipy's loop (the analytic plant with ``stepper="scipy"``), so the ratio compares the plants, not
the loops; one run of the analytic plant on its default (compiled) loop is printed beside it. Holds
when ≤ :data:`PINOCCHIO_LIMIT`. Skipped, with the reason printed, when Pinocchio (``pin``) is not
installed.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable

import numpy as np

from mj_bridge.plants import AnalyticSettings, PinocchioPlant, PinocchioSettings, plant
from validation.bench.goal import Goal, run_share
from validation.bench.plant_rounds import plant_rounds
from validation.bench.verdicts import spread_of
from validation.scenes import resolve_scene

PINOCCHIO_GOAL = (
    "Pinocchio plant: 20 s controlled Example 1 at rtol 1e-12, Pinocchio / analytic integration "
    "CPU time"
)
PINOCCHIO_LIMIT = 3.0


def goal_pinocchio(
    t_end: float = 20.0,
    rounds: int = 7,
    scene_name: str = "paper_example1_controlled",
    progress: Callable[[str], None] = print,
) -> Goal:
    """The goal (module docstring): the Pinocchio plant's integration CPU time over the
    analytic plant's.

    ``data`` holds every CPU time (``analytic_cpu_s``, ``pinocchio_cpu_s``) and their per-round
    ratios (``ratios``), every wall (``analytic_s``, ``pinocchio_s``: integration; ``*_call_s``: the whole
    ``simulate`` call), their medians, the order of the rounds and the two plants' agreement (max
    distance between their positions of C, m) as a check that both ran the same motion.
    """

    why = PinocchioPlant.unavailable()
    if why:
        return Goal(
            PINOCCHIO_GOAL, math.nan, PINOCCHIO_LIMIT, skipped=f"pin is not installed: {why}"
        )
    sc = resolve_scene(scene_name)
    runs = {  # the same (scipy's) loop on both sides: the ratio compares the plants
        "analytic": (plant("analytic"), AnalyticSettings("DOP853", 1e-12, 1e-13, stepper="scipy")),
        "pinocchio": (plant("pinocchio"), PinocchioSettings("DOP853", 1e-12, 1e-13)),
    }

    try:
        r = plant_rounds(sc, runs, t_end, rounds)
    except (RuntimeError, ValueError) as exc:
        return Goal(PINOCCHIO_GOAL, math.inf, PINOCCHIO_LIMIT, f"a run failed: {exc}")
    first, default_loop, walls, calls, cpus, order = (
        r.first,
        r.default_loop,
        r.walls,
        r.calls,
        r.cpus,
        r.order,
    )
    tr_a, tr_p = first["analytic"][0], first["pinocchio"][0]
    dR = float(np.max(np.linalg.norm(tr_a.R - tr_p.R, axis=1)))
    med = {name: statistics.median(v) for name, v in walls.items()}
    med_cpu = {name: statistics.median(v) for name, v in cpus.items()}
    med_call = {name: statistics.median(v) for name, v in calls.items()}
    ratios = [p / a for p, a in zip(cpus["pinocchio"], cpus["analytic"], strict=True)]
    spread = spread_of(ratios, run_share(cpus, walls))
    progress(
        f"  {t_end:g} s, DOP853 rtol 1e-12: analytic {med_cpu['analytic']:.3f} s "
        f"(nfev {tr_a.info['nfev']}), Pinocchio {med_cpu['pinocchio']:.3f} s "
        f"(nfev {tr_p.info['nfev']}) of CPU time; {rounds} interleaved rounds"
    )
    return Goal(
        PINOCCHIO_GOAL,
        spread.median,
        PINOCCHIO_LIMIT,
        f"analytic {med_cpu['analytic']:.3f} s, Pinocchio {med_cpu['pinocchio']:.3f} s (CPU time "
        f"of the integration, median of {rounds}; wall {med['analytic']:.3f} s / "
        f"{med['pinocchio']:.3f} s); whole simulate call {med_call['analytic']:.3f} s / "
        f"{med_call['pinocchio']:.3f} s ({med_call['pinocchio'] / med_call['analytic']:.2f}x); "
        f"nfev {tr_a.info['nfev']} / {tr_p.info['nfev']}; the two plants' C within {dR:.2g} m; "
        f"the analytic plant on its default ({default_loop.info.get('stepper', '?')}) loop "
        f"{default_loop.info['wall_time_s']:.3f} s (one run)",
        data={
            "t_end_s": t_end,
            "rounds": rounds,
            "analytic_s": walls["analytic"],
            "pinocchio_s": walls["pinocchio"],
            "analytic_call_s": calls["analytic"],
            "pinocchio_call_s": calls["pinocchio"],
            "analytic_median_s": med["analytic"],
            "pinocchio_median_s": med["pinocchio"],
            "analytic_cpu_s": cpus["analytic"],
            "pinocchio_cpu_s": cpus["pinocchio"],
            "ratios": ratios,
            "warm_s": {name: first[name][1] for name in runs},
            "order": order,
            "nfev": {"analytic": tr_a.info["nfev"], "pinocchio": tr_p.info["nfev"]},
            "max_distance_C_m": dR,
            "analytic_default_loop_s": float(default_loop.info["wall_time_s"]),
        },
        spread=spread,
    )


__all__ = ["PINOCCHIO_GOAL", "PINOCCHIO_LIMIT", "goal_pinocchio"]
