"""The compiled-stepping goal (:func:`goal_compiled_stepping`).

The controlled Example 1 over 60 s, DOP853 at rtol 1e-12 (atol 1e-13), on the analytic plant's
compiled loop (:mod:`analytic.compiled_stepping`): its CPU time (``info["wall_time_s"]`` times the
CPU share) / (its evaluations ``nfev`` x the thread CPU time of one evaluation of the compiled
right-hand side, :func:`analytic.fast_rhs.rhs_into` called from a compiled loop, ``nfev`` times, on
64 states of the run in turn). Runs and timing loops alternate for ``rounds`` repeats (the median of
the rounds' ratios). The same ratio for scipy's loop is printed beside it. Holds when ≤
:data:`COMPILED_STEPPING_LIMIT`. Skipped, with the reason, when the compiled loop is unavailable
(CyRK or numba missing).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable

import numpy as np

from analytic import compiled_stepping, fast
from analytic.simulate import simulate
from validation.bench.goal import Goal, run_share
from validation.bench.timing import CpuMeter
from validation.bench.verdicts import spread_of
from validation.scenes import resolve_scene
from validation.studies.sweep import errors_against, ref_samples

COMPILED_STEPPING_GOAL = (
    "compiled stepping: 60 s controlled Example 1 at rtol 1e-12, CPU time / (nfev x one compiled "
    "right-hand side evaluation)"
)
COMPILED_STEPPING_LIMIT = 1.5
"""The loop may add at most half the cost of the evaluations it makes: the evaluations are the
work, and a DOP853 step adds only a few hundred flops of stage combinations, error norms and
interpolation to its 12-16 evaluations; the rest of the margin is for the calls into the C++ loop
(one per second simulated), the copies of the samples and timing noise on a shared machine
(measured costs: ``docs/performance.md``, Speed goals' margins)."""


def _rhs_timer(ip):
    """``loop(n, t, Y, fp, ip, work, out)``: ``n`` calls of the compiled right-hand side of the
    packed scene ``ip`` (:func:`analytic.fast_rhs.rhs_for`: the one the compiled loop embeds) from
    compiled code (no dispatch from Python per call), at the states ``(t[i], Y[i])`` in turn: what
    the compiled loop pays per evaluation."""
    # deferred: numba is optional (analytic.fast.available(); without it this goal is skipped)
    import numba

    from analytic.fast_rhs import rhs_for

    rhs_into = rhs_for(ip)

    @numba.njit(cache=False)
    def loop(n, t, Y, fp, ip, work, out):  # pragma: no cover - compiled
        s = 0.0
        m = t.size
        for i in range(n):
            rhs_into(t[i % m], Y[i % m], fp, ip, work, out)
            s += out[0]
        return s

    return loop


def goal_compiled_stepping(
    t_end: float = 60.0,
    rounds: int = 5,
    scipy_rounds: int = 3,
    scene_name: str = "paper_example1_controlled",
    progress: Callable[[str], None] = print,
) -> Goal:
    """The goal (module docstring): the compiled loop's CPU time over the cost of the
    evaluations it makes.

    ``data``: every wall and CPU time of the compiled loop and of scipy's (``compiled_s``,
    ``scipy_s``, ``compiled_cpu_s``, ``scipy_cpu_s``), the per-round ratios (``ratios``), the
    per-evaluation cost of each timing round (``rhs_us``), their medians, ``nfev`` and ``nsteps`` of
    both loops, scipy's ratio (``ratio_scipy``) and the two loops' largest difference in the sweep's
    error measure (``loops_differ``, :func:`validation.studies.sweep.errors_against`), a check that both
    ran the same motion.
    """

    why = compiled_stepping.unavailable()
    if why:
        return Goal(
            COMPILED_STEPPING_GOAL,
            math.nan,
            COMPILED_STEPPING_LIMIT,
            skipped=f"the compiled loop is unavailable: {why}",
        )
    sc = resolve_scene(scene_name)

    def run(stepper: str):
        meter = CpuMeter()
        with meter:
            tr = simulate(
                sc, method="DOP853", rtol=1e-12, atol=1e-13, t_end=t_end, stepper=stepper,
                progress=meter,
            ).raise_if_interrupted()  # fmt: skip
        if tr.status.value != "ok":
            raise RuntimeError(f"{stepper} loop: {tr.message}")
        wall = float(tr.info["wall_time_s"])
        return tr, wall, meter.cpu_of(wall)

    try:
        simulate(sc, t_end=1.0, stepper="compiled")  # warm: cfunc and kernel cache loads
        first = run("compiled")[0]
        nfev = int(first.info["nfev"])
        fm = fast.FastModel(sc)
        # the states of the run: 64 of its samples, evaluated in turn
        pick = np.linspace(0, len(first.t) - 1, 64).round().astype(int)
        ts = np.ascontiguousarray(first.t[pick])
        Y = np.ascontiguousarray(
            np.hstack([first.q[pick], first.qdot[pick], np.zeros((pick.size, 7))])
        )
        work = np.empty(2 * fm.nq + 3 + fm.k)
        out = np.empty(Y.shape[1])
        loop = _rhs_timer(fm.ip)
        loop(10, ts, Y, fm.fp, fm.ip, work, out)  # compile
        walls: dict[str, list[float]] = {"compiled": [], "scipy": []}
        cpus: dict[str, list[float]] = {"compiled": [], "scipy": []}
        rhs: list[float] = []
        tr_s = None
        for r in range(rounds):
            _, wall, cpu = run("compiled")
            walls["compiled"].append(wall)
            cpus["compiled"].append(cpu)
            t0 = time.thread_time_ns()
            loop(nfev, ts, Y, fm.fp, fm.ip, work, out)
            rhs.append((time.thread_time_ns() - t0) * 1e-9 / nfev)
            if r < scipy_rounds:
                tr_s, wall, cpu = run("scipy")
                walls["scipy"].append(wall)
                cpus["scipy"].append(cpu)
    except (RuntimeError, ValueError) as exc:
        return Goal(
            COMPILED_STEPPING_GOAL, math.inf, COMPILED_STEPPING_LIMIT, f"a run failed: {exc}"
        )
    med = {name: statistics.median(v) for name, v in cpus.items()}
    c = statistics.median(rhs)
    nfev_s = int(tr_s.info["nfev"])
    ratios = [
        w / (nfev * e) for w, e in zip(cpus["compiled"], rhs[: len(cpus["compiled"])], strict=True)
    ]
    spread = spread_of(ratios, run_share(cpus, walls))
    ratio_s = med["scipy"] / (nfev_s * c)
    differ = errors_against(first, ref_samples(tr_s))["error"]
    progress(
        f"  {t_end:g} s, DOP853 rtol 1e-12: compiled loop {med['compiled']:.3f} s (nfev {nfev}, "
        f"{first.info['nsteps']} steps), scipy's loop {med['scipy']:.3f} s (nfev {nfev_s}, "
        f"{tr_s.info['nsteps']} steps); one compiled evaluation {c * 1e6:.2f} µs"
    )
    return Goal(
        COMPILED_STEPPING_GOAL,
        spread.median,
        COMPILED_STEPPING_LIMIT,
        f"compiled loop {med['compiled']:.3f} s against {nfev} x {c * 1e6:.2f} µs = "
        f"{nfev * c:.3f} s of evaluations (CPU time, medians of {rounds}); scipy's loop "
        f"{med['scipy']:.3f} s against {nfev_s * c:.3f} s: ratio {ratio_s:.2f} (median of "
        f"{scipy_rounds}), {med['scipy'] / med['compiled']:.1f}x the compiled loop's; the two "
        "loops' samples "
        f"differ by {differ:.1e} (the sweep's error measure)",
        data={
            "t_end_s": t_end,
            "compiled_s": walls["compiled"],
            "scipy_s": walls["scipy"],
            "compiled_cpu_s": cpus["compiled"],
            "scipy_cpu_s": cpus["scipy"],
            "ratios": ratios,
            "rhs_us": [v * 1e6 for v in rhs],
            "compiled_cpu_median_s": med["compiled"],
            "scipy_cpu_median_s": med["scipy"],
            "rhs_median_us": c * 1e6,
            "nfev": {"compiled": nfev, "scipy": nfev_s},
            "nsteps": {"compiled": int(first.info["nsteps"]), "scipy": int(tr_s.info["nsteps"])},
            "ratio_scipy": ratio_s,
            "loops_differ": differ,
        },
        spread=spread,
    )


__all__ = ["COMPILED_STEPPING_GOAL", "COMPILED_STEPPING_LIMIT", "goal_compiled_stepping"]
