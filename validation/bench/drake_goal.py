"""The Drake plant's speed goal, for ``tumble bench`` (an entry of :data:`validation.bench.goals.GOALS`).

**Drake plant**: the controlled Example 1 over 20 s, DOP853 at rtol 1e-12 (atol 1e-13), on the Drake
plant (:class:`mj_bridge.drake_plugin.DrakePlant`) / on the analytic plant, both through the plant
protocol. At this tolerance the two are equally accurate (each is within ~1e-9 m of its own
rtol-2.5e-14 run: Drake 1.1e-9 m, analytic 2.6e-9 m, measured), and they agree to 1.7e-9 m; the
distance of their positions of C is recorded as the check that both ran the same motion. As for the
Pinocchio plant's goal, both step on scipy's loop (the analytic plant with ``stepper="scipy"``), so
the ratio compares the plants, not the loops; one run of the analytic plant on its default
(compiled) loop is printed beside it, with that ratio. Each plant runs once first (compilation,
cache loads), then the two alternate for ``rounds`` repeats; each round's ratio is of the CPU times
of the integrations (:class:`validation.bench.timing.CpuMeter`), the goal's value their median.
Holds when ≤ :data:`DRAKE_LIMIT`. Skipped, with the reason, when Drake is not installed. About 15 s.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable

import numpy as np

from mj_bridge.drake_plugin import DrakePlant, DrakeSettings
from mj_bridge.plants import AnalyticSettings, plant
from validation.bench.goal import Goal, run_share
from validation.bench.plant_rounds import plant_rounds
from validation.bench.verdicts import spread_of
from validation.scenes import resolve_scene

DRAKE_GOAL = "Drake plant: 20 s controlled Example 1 at rtol 1e-12, Drake CPU / analytic CPU"
DRAKE_LIMIT = 20.0
"""From the goal set when Drake was measured outside the project (19.5 with the springs as a
Python system); this plant, its per-evaluation work compiled, measured ~4.4 on scipy's loop (and
~33 against the analytic plant's compiled loop)."""


def goal_drake(
    t_end: float = 20.0,
    rounds: int = 5,
    scene_name: str = "paper_example1_controlled",
    progress: Callable[[str], None] = print,
) -> Goal:
    """The Drake plant's integration CPU time over the analytic plant's (see the module docstring).

    ``data`` holds every wall (``analytic_s``, ``drake_s``: integration; ``*_call_s``: the whole
    ``simulate`` call), the CPU times and per-round ratios, the order of the rounds, the evaluations,
    the two plants' largest distance in C (m) and the analytic plant's wall on its default loop.
    """
    why = DrakePlant.unavailable()
    if why:
        return Goal(DRAKE_GOAL, math.nan, DRAKE_LIMIT, skipped=f"drake is not installed: {why}")
    sc = resolve_scene(scene_name)
    runs = {  # the same (scipy's) loop on both sides: the ratio compares the plants
        "analytic": (plant("analytic"), AnalyticSettings("DOP853", 1e-12, 1e-13, stepper="scipy")),
        "drake": (DrakePlant(), DrakeSettings("DOP853", 1e-12, 1e-13)),
    }

    try:
        r = plant_rounds(sc, runs, t_end, rounds)
    except (RuntimeError, ValueError, ImportError) as exc:
        return Goal(DRAKE_GOAL, math.inf, DRAKE_LIMIT, f"a run failed: {exc}")
    first, default_loop, walls, calls, cpus, order = (
        r.first, r.default_loop, r.walls, r.calls, r.cpus, r.order
    )
    tr_a, tr_d = first["analytic"][0], first["drake"][0]
    dR = float(np.max(np.linalg.norm(tr_a.R - tr_d.R, axis=1)))
    med_cpu = {name: statistics.median(v) for name, v in cpus.items()}
    med_call = {name: statistics.median(v) for name, v in calls.items()}
    ratios = [d / a for d, a in zip(cpus["drake"], cpus["analytic"], strict=True)]
    spread = spread_of(ratios, run_share(cpus, walls))
    default_s = float(default_loop.info["wall_time_s"])
    versus_default = statistics.median(walls["drake"]) / default_s if default_s > 0 else math.inf
    progress(
        f"  {t_end:g} s, DOP853 rtol 1e-12: analytic {med_cpu['analytic']:.3f} s "
        f"(nfev {tr_a.info['nfev']}), Drake {med_cpu['drake']:.3f} s "
        f"(nfev {tr_d.info['nfev']}) of CPU time; {rounds} interleaved rounds"
    )
    return Goal(
        DRAKE_GOAL,
        spread.median,
        DRAKE_LIMIT,
        f"analytic {med_cpu['analytic']:.3f} s, Drake {med_cpu['drake']:.3f} s (CPU time of the "
        f"integration on scipy's loop, median of {rounds}); whole simulate call "
        f"{med_call['analytic']:.3f} s / {med_call['drake']:.3f} s; nfev {tr_a.info['nfev']} / "
        f"{tr_d.info['nfev']}; the two plants' C within {dR:.2g} m; against the analytic plant on "
        f"its default ({default_loop.info.get('stepper', '?')}) loop, {default_s:.3f} s (one run): "
        f"{versus_default:.1f}x",
        data={
            "t_end_s": t_end,
            "rounds": rounds,
            "analytic_s": walls["analytic"],
            "drake_s": walls["drake"],
            "analytic_call_s": calls["analytic"],
            "drake_call_s": calls["drake"],
            "analytic_cpu_s": cpus["analytic"],
            "drake_cpu_s": cpus["drake"],
            "ratios": ratios,
            "warm_s": {name: first[name][1] for name in runs},
            "order": order,
            "nfev": {"analytic": tr_a.info["nfev"], "drake": tr_d.info["nfev"]},
            "max_distance_C_m": dR,
            "analytic_default_loop_s": default_s,
            "drake_vs_default_loop": versus_default,
            "drake_version": tr_d.info.get("drake_version", ""),
        },
        spread=spread,
    )


__all__ = ["DRAKE_GOAL", "DRAKE_LIMIT", "goal_drake"]
