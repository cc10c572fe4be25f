"""The fast engine's speed goals, each measured as a ratio in this one process, with whether it
holds. Numbers are printed, never asserted (tests cover correctness, not speed).

``python -m validation.bench.command [--skip-long]`` (or ``tumble bench``) prints these:

1. **evaluation**: one evaluation of the analytic controlled dynamics (``M``, ``Q``, Udwadia–Kalaba
   with control; ``FastModel.qddot``, the integrator's right-hand side) / MuJoCo's ``mj_forward``
   on the same body (``model_xml.build_spec(scene).compile()``), for
   ``validation.bench.timing.chain_scene`` n = 2 and n = 5. Holds when ≤ 1.
2. **controller in RK4**: the extra cost per RK4 step of the analytic controller running in
   ``mjcb_control`` (four stages; the twin's default: the compiled stage as a native callback,
   :mod:`mj_bridge.native`, with work and impulses accumulated as in a run) / the bare ``mj_step``
   (RK4, no callback, ctrl = 0), on the controlled paper scenes. Holds when ≤ 1 ("costs no more than
   the MuJoCo step it sits in"). The same controller through the Python callback is printed too.
3. **60 s Example 1**: the controlled Example 1 over 60 s, analytic DOP853 at rtol 1e-12 (atol 1e-13):
   its error against a reference (DOP853 at rtol 2.5e-14) in the sweep's error measure
   (:func:`validation.studies.sweep.errors_against`); then MuJoCo RK4 with dt halving from 1e-3 s until its
   error is at most the analytic one. Ratio = analytic CPU time / RK4 CPU time at exactly that
   accuracy (each run's integration, :class:`~validation.bench.timing.CpuMeter`): the dt is
   interpolated between the last two runs by RK4's observed order and the time linearly in the
   step count (the first run found as accurate is also printed). If none is
   reached within the time cap, the RK4 cost at the needed dt is extrapolated from its observed
   order and the ratio is marked as extrapolated. Holds when ≤ 1.
4. **n scaling**: cost of one fast evaluation at n = 1000 / at n = 10. Holds when ≤ 150.
5. **Pinocchio plant**: the controlled Example 1 over 20 s, DOP853 at rtol 1e-12 (atol 1e-13), on
   the Pinocchio plant / on the analytic plant, both through the plant protocol
   (``plant(name).simulate``). Each plant runs once first (compilation, cache loads), then the two
   alternate for ``rounds`` repeats; the ratio is the median of the rounds' ratios of the
   integrations' CPU time (each plant's ``info["wall_time_s"]`` times the share of a CPU the thread
   had during it; the walls and the whole ``simulate`` call are printed too). Both
   plants step on scipy's loop (the analytic plant with ``stepper="scipy"``), so the ratio compares
   the plants, not the loops; one run of the analytic plant on its default (compiled) loop is
   printed beside it. Holds when ≤ 3. Skipped, with the reason printed, when Pinocchio (``pin``) is
   not installed; it takes a few seconds, so ``--skip-long`` keeps it.
6. **compiled stepping**: the controlled Example 1 over 60 s, DOP853 at rtol 1e-12 (atol 1e-13), on
   the analytic plant's compiled loop (:mod:`analytic.compiled_stepping`): its CPU time
   (``info["wall_time_s"]`` times the CPU share) / (its evaluations ``nfev`` x the thread CPU time of
   one evaluation of the compiled
   right-hand side, :func:`analytic.fast_rhs.rhs_into` called from a compiled loop, ``nfev`` times,
   on 64 states of the run in turn). Runs and timing loops alternate for ``rounds`` repeats
   (the median of the rounds' ratios). The same ratio for scipy's loop (the before) is printed beside it. Holds when ≤ 1.5
   (:data:`COMPILED_STEPPING_LIMIT`). Skipped, with the reason, when the compiled loop is
   unavailable (CyRK or numba missing). About 10 to 20 s.

How a goal is timed and judged. The in-process goals (1, 2, 4) time both sides of their ratio
in alternating ~5 ms batches (:func:`validation.bench.timing.interleaved`), by the thread's CPU time,
not the wall clock: the time the scheduler gives to another process is not the code's cost, and
where it lands follows the alternation, so wall-clock medians made one side look slower at random
on a busy machine (:mod:`validation.bench.timing` has the measurements). The plant-level goals (5,
6) and goal 3 time whole runs (5 and 6 alternating) and count the CPU time of each integration as
its wall times the share of a CPU the thread had during it
(:class:`validation.bench.timing.CpuMeter`). Each round
gives one ratio: a goal's value is their median, its spread their interquartile range
(:class:`validation.bench.verdicts.Spread`), printed with the share of a CPU the thread had. The
verdict (:func:`validation.bench.verdicts.decide`) is HOLDS or FAILS when the rounds agree, and
TOO_BUSY ("the machine was too busy for a verdict") when the spread is wider than
:data:`validation.bench.verdicts.SPREAD_BOUND` of the limit or straddles it. Goal 3 is a search of single
runs (no spread: its verdict is its value's); the ``tumble validate`` goals time new processes (a
pool of workers: their CPU time is not their wait), by wall, their three pairs giving the spread.
One BLAS thread throughout.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

import analytic
import mj_bridge
from analytic import compiled_stepping, fast
from analytic.simulate import simulate
from mj_bridge.callbacks import installed
from mj_bridge.plants import AnalyticSettings, PinocchioPlant, PinocchioSettings, plant
from mj_bridge.registry import BUILTIN, plugin_names
from mj_bridge.twin import Twin
from model_xml import build_spec
from validation.bench.timing import (
    CpuMeter,
    chain_scene,
    interleaved,
    median_per_call,
    median_share,
)
from validation.bench.verdicts import Spread, Verdict, decide, spread_of
from validation.scenes import resolve_scene
from validation.studies.sweep import errors_against, ref_samples, reference_run


@dataclass(frozen=True)
class Goal:
    """One goal: ``value`` compared with ``limit`` (holds when value ≤ limit and, when measured
    in rounds, the rounds agree: :func:`validation.bench.verdicts.decide`)."""

    name: str
    value: float
    limit: float
    detail: str = ""
    extrapolated: bool = False
    data: dict[str, Any] = field(default_factory=dict)
    skipped: str = ""
    """Why the goal was not measured ("" when it was); a skipped goal neither holds nor fails."""
    spread: Spread | None = None
    """The per-round ratios' spread (None: measured once)."""

    @property
    def verdict(self) -> Verdict:
        """HOLDS, FAILS, TOO_BUSY or SKIPPED."""
        if self.skipped:
            return Verdict.SKIPPED
        return decide(self.value, self.limit, self.spread)

    @property
    def holds(self) -> bool:
        return self.verdict is Verdict.HOLDS

    def line(self) -> str:
        if self.skipped:
            return f"{self.name}: skipped ({self.skipped})"
        verdict = {
            Verdict.HOLDS: "holds",
            Verdict.FAILS: "fails",
            Verdict.TOO_BUSY: "the machine was too busy for a verdict (the rounds disagree)",
        }[self.verdict]
        if self.extrapolated:
            verdict += " (extrapolated)"
        spread = f"; {self.spread.text()}" if self.spread else ""
        return (
            f"{self.name}: ratio {self.value:.3g} (goal ≤ {self.limit:g}{spread}): {verdict}. "
            f"{self.detail}"
        )


def _ratios(num: list, den: list, minus_one: bool = False) -> list[float]:
    """Per-round ratios of two functions' batches (thread CPU per call); ``minus_one``: the added
    cost ``num / den - 1``."""
    return [a.per_call_s / b.per_call_s - (1.0 if minus_one else 0.0) for a, b in zip(num, den, strict=True)]


def _share(cpus: dict[str, list[float]], walls: dict[str, list[float]]) -> float | None:
    """Median share of a CPU over whole runs (CPU time / wall of each), None without runs."""
    shares = [c / w for k in cpus for c, w in zip(cpus[k], walls[k], strict=True) if w > 0]
    return statistics.median(shares) if shares else None


def _chain(n: int):

    sc = chain_scene(n)
    fm = fast.FastModel(sc)
    q = np.ascontiguousarray(sc.initial.q0())
    qd = np.ascontiguousarray(sc.initial.qdot0())
    m = build_spec(sc).compile()
    d = mujoco.MjData(m)
    return sc, (lambda: fm.qddot(0.3, q, qd)), (lambda: mujoco.mj_forward(m, d))


def goal_evaluation(n: int, rounds: int = 21) -> Goal:
    """Goal 1 (module docstring) for the chain scene of ``n`` masses. ``data``: the median thread
    CPU time per call of each side, µs, and the per-round ratios."""
    _, fa, fm = _chain(n)
    s = interleaved({"analytic": fa, "mj_forward": fm}, rounds)
    ratios = _ratios(s["analytic"], s["mj_forward"])
    spread = spread_of(ratios, median_share(s))
    c = {k: median_per_call(v) for k, v in s.items()}
    return Goal(
        f"evaluation n={n}: analytic controlled dynamics / mj_forward",
        spread.median,
        1.0,
        f"analytic {c['analytic'] * 1e6:.2f} µs, mj_forward {c['mj_forward'] * 1e6:.2f} µs "
        "(thread CPU time per call, medians)",
        data={**{k: v * 1e6 for k, v in c.items()}, "ratios": ratios},
        spread=spread,
    )


def goal_controller_in_rk4(scene_name: str, steps: int = 200, rounds: int = 21) -> Goal:
    """Goal 2 (module docstring) on a controlled paper scene. ``data``: thread CPU time per step of
    each variant, µs (medians), the per-round added costs (``ratios``) and whether the native
    callback ran."""

    sc = resolve_scene(scene_name)
    tw = Twin(sc, integrator="RK4")
    tw_py = Twin(sc, integrator="RK4", native_callback=False)
    q0, qd0 = sc.initial.q0(), sc.initial.qdot0()

    def bare() -> None:
        tw.set_state(0.0, q0, qd0)
        tw.d.ctrl[:] = 0.0
        mujoco.mj_step(tw.m, tw.d, nstep=steps)

    def controlled(twin: Twin) -> Callable[[], None]:
        def run() -> None:  # as mj_bridge.simulate runs it: work and impulses accumulated
            twin.set_state(0.0, q0, qd0)
            twin.d.ctrl[:] = 0.0
            with twin.callbacks():
                twin.step(steps)

        return run

    def bare_nocb() -> None:
        with installed(control=None, act_bias=None):
            bare()

    def empty_cb() -> None:
        with installed(control=lambda m, d: None, act_bias=None):
            bare()

    fns = {"bare": bare_nocb, "empty": empty_cb, "controlled": controlled(tw)}
    fns["python_cb"] = controlled(tw_py)
    s = interleaved(fns, rounds)
    ratios = _ratios(s["controlled"], s["bare"], minus_one=True)
    spread = spread_of(ratios, median_share(s))
    c = {k: median_per_call(v) for k, v in s.items()}
    step = c["bare"] / steps
    ctl = c["controlled"] / steps
    empty = c["empty"] / steps
    py = c["python_cb"] / steps
    how = "native mjcb_control" if tw.native else "Python mjcb_control (native unavailable)"
    return Goal(
        f"controller in RK4 ({scene_name}): added cost per step / bare mj_step",
        spread.median,
        1.0,
        f"bare RK4 step {step * 1e6:.1f} µs, with the analytic controller ({how}) "
        f"{ctl * 1e6:.1f} µs ({ctl / step:.2f}x); through a Python callback {py * 1e6:.1f} µs "
        f"({py / step:.2f}x), of which calling an empty Python callback 4x a step costs "
        f"{(empty - step) * 1e6:.1f} µs (thread CPU time, medians)",
        data={
            "bare_us": step * 1e6,
            "controlled_us": ctl * 1e6,
            "python_cb_us": py * 1e6,
            "empty_cb_us": empty * 1e6,
            "native": tw.native,
            "ratios": ratios,
        },
        spread=spread,
    )


def goal_example1_60s(
    t_end: float = 60.0, cap_s: float = 120.0, progress: Callable[[str], None] = print
) -> Goal:

    sc = resolve_scene("paper_example1_controlled")
    progress(f"  reference (DOP853 rtol 2.5e-14, {t_end:g} s) ...")
    ref = ref_samples(reference_run(sc, t_end))
    meter = CpuMeter()
    with meter:
        tr_a = analytic.simulate(
            sc, method="DOP853", rtol=1e-12, atol=1e-13, t_end=t_end, progress=meter
        ).raise_if_interrupted()
    e_a = errors_against(tr_a, ref)["error"]
    w_a = meter.cpu_of(float(tr_a.info["wall_time_s"]))  # CPU time: see the module docstring
    progress(
        f"  analytic rtol 1e-12: error {e_a:.3g}, {w_a:.2f} s (wall {tr_a.info['wall_time_s']:.2f} s)"
    )
    interval = 1.0 / sc.output.rate
    pts: list[tuple[float, float, float]] = []  # (dt, error, CPU time)
    k = round(interval / 1e-3)
    while True:
        dt = interval / k
        meter = CpuMeter()
        with meter:
            tr = mj_bridge.simulate(
                sc, integrator="RK4", dt=dt, t_end=t_end, progress=meter
            ).raise_if_interrupted()
        e = errors_against(tr, ref)["error"] if tr.status.value == "ok" else math.inf
        w = meter.cpu_of(float(tr.info["wall_time_s"]))
        pts.append((dt, e, w))
        progress(f"  RK4 dt {dt:.4g}: error {e:.3g}, {w:.2f} s (wall {tr.info['wall_time_s']:.2f} s)")
        if e <= e_a:
            value, detail = w_a / w, ""
            if len(pts) >= 2 and math.isfinite(pts[-2][1]) and pts[-2][1] > e_a:
                # the run found is more accurate than needed: interpolate the dt that just reaches
                # e_a by the observed order, and its CPU time linearly in the step count (1/dt)
                (dt1, e1, w1), (dt2, e2, w2) = pts[-2], pts[-1]
                order = math.log(e1 / e2) / math.log(dt1 / dt2)
                dt_need = dt2 * (e_a / e2) ** (1.0 / order)
                w_need = w1 + (w2 - w1) * (1 / dt_need - 1 / dt1) / (1 / dt2 - 1 / dt1)
                value = w_a / w_need  # the conservative ratio: MuJoCo at exactly that accuracy
                detail = (
                    f"; interpolated by RK4's observed order {order:.2f}: dt {dt_need:.3g} s "
                    f"reaches {e_a:.2e} in about {w_need:.2f} s (the ratio uses this)"
                )
            return Goal(
                "60 s controlled Example 1: analytic rtol 1e-12 / MuJoCo RK4 CPU time at the same"
                " accuracy",
                value,
                1.0,
                f"analytic {w_a:.2f} s (error {e_a:.2e}); RK4 dt {dt:.4g} s {w:.2f} s "
                f"(error {e:.2e}){detail}",
                data={"analytic": (e_a, w_a), "rk4": pts},
            )
        if 2 * w > cap_s or not math.isfinite(e):
            break
        k *= 2
    # Extrapolate from the last two finite points: error ∝ dt^p, CPU time ∝ 1/dt.
    fin = [p for p in pts if math.isfinite(p[1]) and p[1] > 0]
    if len(fin) < 2:
        return Goal("60 s controlled Example 1", math.inf, 1.0, "RK4 runs failed", data={})
    (dt1, e1, _), (dt2, e2, w2) = fin[-2], fin[-1]
    order = math.log(e1 / e2) / math.log(dt1 / dt2)
    dt_need = dt2 * (e_a / e2) ** (1.0 / order) if order > 0 else 0.0
    w_need = w2 * dt2 / dt_need if dt_need > 0 else math.inf
    return Goal(
        "60 s controlled Example 1: analytic rtol 1e-12 / MuJoCo RK4 CPU time at the same accuracy",
        w_a / w_need,
        1.0,
        f"analytic {w_a:.2f} s (error {e_a:.2e}); RK4 did not reach it within the {cap_s:g} s cap: "
        f"observed order {order:.2f} predicts dt {dt_need:.3g} s at {w_need:.3g} s",
        extrapolated=True,
        data={"analytic": (e_a, w_a), "rk4": pts},
    )


def goal_scaling(rounds: int = 21) -> Goal:
    """Goal 4 (module docstring). ``data``: thread CPU time per call at each n, µs (medians), and
    the per-round ratios."""

    fns = {}
    for n in (10, 1000):
        sc = chain_scene(n)
        fm = fast.FastModel(sc)
        q = np.ascontiguousarray(sc.initial.q0())
        qd = np.ascontiguousarray(sc.initial.qdot0())
        fns[n] = lambda fm=fm, q=q, qd=qd: fm.qddot(0.3, q, qd)
    s = interleaved(fns, rounds)
    ratios = _ratios(s[1000], s[10])
    spread = spread_of(ratios, median_share(s))
    c = {k: median_per_call(v) for k, v in s.items()}
    return Goal(
        "scaling: fast evaluation cost n=1000 / n=10",
        spread.median,
        150.0,
        f"n=10 {c[10] * 1e6:.2f} µs, n=1000 {c[1000] * 1e6:.2f} µs (thread CPU time per call, "
        "medians)",
        data={"n10_us": c[10] * 1e6, "n1000_us": c[1000] * 1e6, "ratios": ratios},
        spread=spread,
    )


PINOCCHIO_GOAL = (
    "Pinocchio plant: 20 s controlled Example 1 at rtol 1e-12, Pinocchio / analytic integration "
    "CPU time"
)
PINOCCHIO_LIMIT = 3.0



@dataclass(frozen=True)
class PlantRounds:
    """Two plants' 20 s runs timed in alternating rounds (:func:`plant_rounds`).

    Attributes:
        first: name -> ``(trajectory, wall, call, cpu)`` of the warm-up run (compilation and
            cache loads), s.
        default_loop: the analytic plant's run on its default loop at the same tolerances.
        walls, calls, cpus: name -> per-round integration wall, whole ``simulate`` call and
            integration CPU time, s.
        order: who went first in each round.
    """

    first: dict[str, tuple[Any, float, float, float]]
    default_loop: Any
    walls: dict[str, list[float]]
    calls: dict[str, list[float]]
    cpus: dict[str, list[float]]
    order: list[list[str]]


def plant_rounds(sc, runs: dict[str, tuple[Any, Any]], t_end: float, rounds: int) -> PlantRounds:
    """Each of ``runs`` (name -> ``(plant, settings)``) once to warm up, then ``rounds`` rounds
    alternating who goes first, each run's integration CPU time measured by a :class:`CpuMeter`;
    ``RuntimeError`` naming the plant whose run did not finish."""

    def once(name: str):
        pl, settings = runs[name]
        meter = CpuMeter()
        t0 = time.perf_counter()
        with meter:
            tr = pl.simulate(sc, settings, t_end=t_end, progress=meter).raise_if_interrupted()
        call = time.perf_counter() - t0
        if tr.status.value != "ok":
            raise RuntimeError(f"{name} plant: {tr.message}")
        wall = float(tr.info["wall_time_s"])
        return tr, wall, call, meter.cpu_of(wall)

    first = {name: once(name) for name in runs}
    default_loop = plant("analytic").simulate(
        sc, AnalyticSettings("DOP853", 1e-12, 1e-13), t_end=t_end
    )
    walls: dict[str, list[float]] = {name: [] for name in runs}
    calls: dict[str, list[float]] = {name: [] for name in runs}
    cpus: dict[str, list[float]] = {name: [] for name in runs}
    order = []
    for k in range(rounds):
        names = list(runs) if k % 2 == 0 else list(reversed(runs))  # alternate who goes first
        order.append(names)
        for name in names:
            _, wall, call, cpu = once(name)
            walls[name].append(wall)
            calls[name].append(call)
            cpus[name].append(cpu)
    return PlantRounds(first, default_loop, walls, calls, cpus, order)


def goal_pinocchio(
    t_end: float = 20.0,
    rounds: int = 7,
    scene_name: str = "paper_example1_controlled",
    progress: Callable[[str], None] = print,
) -> Goal:
    """Goal 5 (see the module docstring): the Pinocchio plant's integration CPU time over the
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
        r.first, r.default_loop, r.walls, r.calls, r.cpus, r.order
    )
    tr_a, tr_p = first["analytic"][0], first["pinocchio"][0]
    dR = float(np.max(np.linalg.norm(tr_a.R - tr_p.R, axis=1)))
    med = {name: statistics.median(v) for name, v in walls.items()}
    med_cpu = {name: statistics.median(v) for name, v in cpus.items()}
    med_call = {name: statistics.median(v) for name, v in calls.items()}
    ratios = [p / a for p, a in zip(cpus["pinocchio"], cpus["analytic"], strict=True)]
    spread = spread_of(ratios, _share(cpus, walls))
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


COMPILED_STEPPING_GOAL = (
    "compiled stepping: 60 s controlled Example 1 at rtol 1e-12, CPU time / (nfev x one compiled "
    "right-hand side evaluation)"
)
COMPILED_STEPPING_LIMIT = 1.5
"""The loop may add at most half the cost of the evaluations it makes. The evaluations are the
work (~2 µs each); a DOP853 step adds a few hundred flops of stage combinations, error norms and
interpolation to its 12-16 evaluations (~30 µs), a few percent. scipy's loop, stepping from Python,
costs ~6 (quiet machine) to ~16 (loaded) times its evaluations; 1.5 leaves room for the calls into
the C++ loop (one per second simulated), the copies of the samples and timing noise on a shared
machine."""


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
    """Goal 6 (see the module docstring): the compiled loop's CPU time over the cost of the
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
    ratios = [w / (nfev * e) for w, e in zip(cpus["compiled"], rhs[: len(cpus["compiled"])], strict=True)]
    spread = spread_of(ratios, _share(cpus, walls))
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


WHOLE_COMMAND_LIMIT = 1.5
"""``tumble validate`` warm: total wall ≤ 1.5 × the plants' compute. What is not the plants
(imports, the comparison, figures, the recording, the files) may cost half as much again."""

COLD_WARM_LIMIT = 3.0
"""``tumble validate`` cold (an empty numba cache) / warm: a first run may take three times a later
one (it compiles every kernel once, with numba's documented API only, announced with its measured
estimate; ``tumble warmup`` pays it ahead, e.g. when a Docker image is built)."""


def _plant_names() -> tuple[str, ...]:
    """Every plant name of this installation (the stages of a run that are plants)."""

    return BUILTIN + plugin_names()


def _validate_once(out: str, env: dict[str, str]) -> tuple[float, dict[str, float]]:
    """Wall of one ``python -m validation validate`` (default scene, every installed plant) in a
    new process, s, and its ``report.json`` stage walls."""

    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "validation", "validate", "--out", out],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(
            f"tumble validate exited {proc.returncode}: {proc.stderr.strip()[-300:]}"
        )
    doc = json.loads((Path(out) / "report.json").read_text(encoding="utf-8"))
    return wall, {k: float(v) for k, v in doc["run"]["wall_times_s"].items()}


FIRST_RUN_PAIRS = 3
"""Cold/warm pairs timed for the first-run goal, each in its own empty numba cache; the goal is
their median ratio."""


def goal_whole_command(progress: Callable[[str], None] = print) -> tuple[Goal, Goal]:
    """The command a user waits for: ``tumble validate`` on the default scene in a new process.

    :data:`FIRST_RUN_PAIRS` pairs, each a cold run (numba's cache pointed at an empty directory,
    ``NUMBA_CACHE_DIR``; the user's own cache is not touched) followed at once by a warm run in
    the same, now filled, directory. A pair is timed back to back because the machine's speed
    drifts (on a shared 2-core VM, warm runs of the same code ranged 3.6-6.3 s within an hour):
    a cold run and a warm one from different minutes would measure the drift. Returns the goal
    "warm wall / plants' compute" (the plants' stage walls in ``report.json``), the median over the
    warm runs, and the goal "cold wall / warm wall", the median of the pairs' ratios; each with the
    spread of its per-pair ratios. Timed by wall: the run is several processes (a pool of workers)
    whose waiting for each other is part of what the user waits for."""

    progress(
        f"timing tumble validate in new processes: {FIRST_RUN_PAIRS} x (cold in an empty numba "
        "cache, then warm)"
    )
    pairs = []
    for i in range(FIRST_RUN_PAIRS):
        with tempfile.TemporaryDirectory(prefix="tumble-bench-") as tmp:
            env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, "numba"))
            cold, _ = _validate_once(os.path.join(tmp, "cold"), env)
            warm = _validate_once(os.path.join(tmp, "warm"), env)
        pairs.append((cold, warm))
        progress(f"  pair {i + 1}: cold {cold:.1f} s, warm {warm[0]:.1f} s")
    def plants_of(stages: dict[str, float]) -> float:
        return sum(v for k, v in stages.items() if k in _plant_names())

    whole_ratios = [w / plants_of(stages) for _, (w, stages) in pairs]
    whole_spread = spread_of(whole_ratios)
    wall, stages = sorted((w for _, w in pairs), key=lambda w: w[0])[len(pairs) // 2]
    plants = plants_of(stages)
    rest = {k: round(v, 2) for k, v in stages.items() if k not in _plant_names()}
    whole = Goal(
        "tumble validate warm: total wall / plants' compute",
        whole_spread.median,
        WHOLE_COMMAND_LIMIT,
        f"median warm run {wall:.2f} s / {plants:.2f} s (other stages, s: {rest})",
        data={"wall_s": wall, "plants_s": plants, "stages_s": stages, "ratios": whole_ratios},
        spread=whole_spread,
    )
    ratios = [cold / warm[0] for cold, warm in pairs]
    cold, (warm, _) = pairs[ratios.index(statistics.median_low(ratios))]
    first = Goal(
        "tumble validate: cold (empty numba cache) / warm wall, median of pairs",
        statistics.median(ratios),
        COLD_WARM_LIMIT,
        f"{cold:.1f} s / {warm:.1f} s (pairs: "
        + ", ".join(f"{c:.1f}/{w[0]:.1f}" for c, w in pairs)
        + ")",
        data={"pairs_s": [[c, w[0]] for c, w in pairs], "ratios": ratios},
        spread=spread_of(ratios),
    )
    return whole, first


def measure(skip_long: bool = False, progress: Callable[[str], None] = print) -> list[Goal]:

    if not fast.available():
        progress("numba is not installed: the analytic side runs on numpy")
    goals = [goal_evaluation(2), goal_evaluation(5)]
    for g in goals:
        progress(g.line())
    for name in ("paper_example1_controlled", "paper_example2_controlled"):
        goals.append(goal_controller_in_rk4(name))
        progress(goals[-1].line())
    goals.append(goal_scaling())
    progress(goals[-1].line())
    goals.append(goal_compiled_stepping(progress=progress))
    progress(goals[-1].line())
    goals.append(goal_pinocchio(progress=progress))
    progress(goals[-1].line())
    if not skip_long:
        goals.append(goal_example1_60s(progress=progress))
        progress(goals[-1].line())
        for g in goal_whole_command(progress=progress):
            goals.append(g)
            progress(g.line())
    return goals
