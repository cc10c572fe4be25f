"""The in-process speed goals: both sides of each ratio timed in this process in alternating
~5 ms batches by the thread's CPU time (:func:`validation.bench.timing.interleaved`).

* **evaluation** (:func:`goal_evaluation`): one evaluation of the analytic controlled dynamics
  (``M``, ``Q``, Udwadia–Kalaba with control; ``FastModel.qddot``, the integrator's right-hand
  side) / MuJoCo's ``mj_forward`` on the same body (``model_xml.build_spec(scene).compile()``),
  for ``validation.bench.timing.chain_scene`` n = 2 and n = 5. Holds when ≤ 1.
* **controller in RK4** (:func:`goal_controller_in_rk4`): the extra cost per RK4 step of the
  analytic controller running in ``mjcb_control`` (four stages; the twin's default: the compiled
  stage as a native callback, :mod:`mj_bridge.native`, with work and impulses accumulated as in a
  run) / the bare ``mj_step`` (RK4, no callback, ctrl = 0), on a controlled paper scene. Holds
  when ≤ 1 ("costs no more than the MuJoCo step it sits in"). The same controller through the
  Python callback is printed too.
* **n scaling** (:func:`goal_scaling`): cost of one fast evaluation at n = 1000 / at n = 10.
  Holds when ≤ 150.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

from analytic import fast
from mj_bridge.callbacks import installed
from mj_bridge.twin import Twin
from model_xml import build_spec
from validation.bench.goal import Goal, round_ratios
from validation.bench.timing import chain_scene, interleaved, median_per_call, median_share
from validation.bench.verdicts import spread_of
from validation.scenes import resolve_scene


def _chain(n: int):

    sc = chain_scene(n)
    fm = fast.FastModel(sc)
    q = np.ascontiguousarray(sc.initial.q0())
    qd = np.ascontiguousarray(sc.initial.qdot0())
    m = build_spec(sc).compile()
    d = mujoco.MjData(m)
    return sc, (lambda: fm.qddot(0.3, q, qd)), (lambda: mujoco.mj_forward(m, d))


def goal_evaluation(n: int, rounds: int = 21) -> Goal:
    """The evaluation goal (module docstring) for the chain scene of ``n`` masses. ``data``: the median thread
    CPU time per call of each side, µs, and the per-round ratios."""
    _, fa, fm = _chain(n)
    s = interleaved({"analytic": fa, "mj_forward": fm}, rounds)
    ratios = round_ratios(s["analytic"], s["mj_forward"])
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
    """The controller-in-RK4 goal (module docstring) on a controlled paper scene. ``data``: thread CPU time per step of
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
    ratios = round_ratios(s["controlled"], s["bare"], minus_one=True)
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


def goal_scaling(rounds: int = 21) -> Goal:
    """The n-scaling goal (module docstring). ``data``: thread CPU time per call at each n, µs (medians), and
    the per-round ratios."""

    fns = {}
    for n in (10, 1000):
        sc = chain_scene(n)
        fm = fast.FastModel(sc)
        q = np.ascontiguousarray(sc.initial.q0())
        qd = np.ascontiguousarray(sc.initial.qdot0())
        fns[n] = lambda fm=fm, q=q, qd=qd: fm.qddot(0.3, q, qd)
    s = interleaved(fns, rounds)
    ratios = round_ratios(s[1000], s[10])
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


__all__ = ["goal_controller_in_rk4", "goal_evaluation", "goal_scaling"]
