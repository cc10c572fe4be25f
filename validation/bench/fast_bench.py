"""Benchmark of the fast engine (numbers printed, never asserted).

``python -m validation.bench.fast_bench`` prints, for ``validation.bench.timing.chain_scene(n)`` (controlled:
ω and every mass tracked, Gauss weighting) with n = 2, 5, 10, 50, 1000, the median cost of one
evaluation of the controlled dynamics in µs of thread CPU time
(:func:`validation.bench.timing.time_call`): the numpy path (``TumblingModel.acceleration``), the fast path
(``FastModel.qddot``, the integrator's right-hand side, and ``FastModel.qddot_and_forces``, which also
returns the control outputs) and MuJoCo's ``mj_forward`` on the twin built by
``model_xml.build_spec(scene).compile()`` (columns shown as n/a when the twin is not importable), the
ratio fast / mj_forward, the ratio of the fast cost at n = 1000 to n = 10 (goal ≤ 150), and the JIT
time of the first call (compile, or load from numba's cache) measured separately.

It times the analytic engine's fast path against MuJoCo, so it lives in ``validation`` (the layer
that may import both), not beside the kernel in ``analytic``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from analytic import fast
from analytic.model import TumblingModel
from analytic.runtime import jit
from validation.bench.timing import chain_scene, time_call
from validation.runs import interrupts

NS = (2, 5, 10, 50, 1000)


def _mujoco(scene):
    """A callable running mj_forward on the twin, or None when unavailable."""
    try:  # deferred: the twin is optional here (see below)
        import mujoco

        from model_xml import build_spec

        m = build_spec(scene).compile()
    except Exception as exc:  # the twin is optional here (ImportError, or a builder in progress)
        interrupts.raise_if_interrupt(exc)  # an import a signal cut is the signal
        return None
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return lambda: mujoco.mj_forward(m, d)


def main(argv: list[str] | None = None) -> int:
    argparse.ArgumentParser(
        prog="python -m validation.bench.fast_bench",
        description="One evaluation of the controlled dynamics for n = 2 ... 1000 masses: the numpy "
        "path, the compiled path and MuJoCo's mj_forward (median µs of thread CPU time; printed, "
        "never asserted).",
    ).parse_args(argv)

    print(f"numba available: {fast.available()}; cache: {jit.cache_dir_note()}")
    sc2 = chain_scene(2)
    fm2 = fast.FastModel(sc2)
    q, qd = sc2.initial.q0(), sc2.initial.qdot0()
    t0 = time.perf_counter()
    fm2.qddot(0.3, q, qd)
    print(f"first call (JIT compile or cache load): {time.perf_counter() - t0:.3f} s")

    print("one evaluation of the controlled dynamics (median thread CPU time, µs)")
    hdr = f"{'n':>5} {'numpy':>10} {'fast qddot':>11} {'fast full':>10} {'mj_forward':>11}"
    print(hdr + f" {'fast/mj':>8} {'numpy/fast':>11}")
    fast_cost = {}
    for n in NS:
        sc = chain_scene(n)
        model = TumblingModel(sc)
        fm = fast.FastModel(sc, model)
        q = np.ascontiguousarray(sc.initial.q0())
        qd = np.ascontiguousarray(sc.initial.qdot0())
        fm.qddot(0.3, q, qd)
        c_np = time_call(lambda m=model, q=q, qd=qd: m.acceleration(0.3, q, qd), repeats=5)
        c_fq = time_call(lambda f=fm, q=q, qd=qd: f.qddot(0.3, q, qd), repeats=9)
        c_ff = time_call(lambda f=fm, q=q, qd=qd: f.qddot_and_forces(0.3, q, qd), repeats=9)
        fast_cost[n] = c_fq
        mj = _mujoco(sc)
        c_mj = time_call(mj, repeats=9) if mj else None
        mj_s = f"{c_mj * 1e6:11.2f}" if c_mj else f"{'n/a':>11}"
        r_s = f"{c_fq / c_mj:8.2f}" if c_mj else f"{'n/a':>8}"
        print(
            f"{n:>5} {c_np * 1e6:10.1f} {c_fq * 1e6:11.2f} {c_ff * 1e6:10.2f} {mj_s} {r_s}"
            f" {c_np / c_fq:11.0f}"
        )
    ratio = fast_cost[1000] / fast_cost[10]
    print(
        f"fast cost n=1000 / n=10: {ratio:.1f} (goal <= 150: {'holds' if ratio <= 150 else 'fails'})"
    )
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
