"""Per-step cost of MuJoCo RK4 on the paper scenes, with and without the controller in the callback.

Run: ``python -m validation.bench.mujoco_steps [--steps N] [--repeats R]``. Prints medians over R repeats of N
steps (µs of thread CPU time per step: what another process's time on the core costs is not
counted, :mod:`validation.bench.timing`) and the ratio to MuJoCo's own step for:

* ``mujoco``: ``mj_step`` alone (no Python callback; controlled scenes with ctrl = 0);
* ``empty cb``: a Python ``mjcb_control`` that does nothing (the price of calling Python 4x a step);
* ``analytic``: the analytic controller (numpy ``TumblingModel``) at every RK4 stage;
* ``analytic_fast``: the same controller from the analytic side's compiled kernel, through a
  Python callback;
* ``native``: the compiled kernel as a native ``mjcb_control`` (:mod:`mj_bridge.native`, the twin's
  default), with the work and impulse accumulation of a real run;
* ``mujoco UK``: Udwadia–Kalaba from MuJoCo's own matrices at every stage.
"""

from __future__ import annotations

import argparse
import statistics
import time

import mujoco

from analytic.scene import load_scene
from mj_bridge.callbacks import installed
from mj_bridge.twin import ControllerSource, Twin
from model_xml.regenerate import PAPER_SCENES, scene_path


def _per_step_us(tw: Twin, callback, steps: int, repeats: int) -> float:
    scene = tw.scene
    samples = []
    for _ in range(repeats):
        tw.set_state(0.0, scene.initial.q0(), scene.initial.qdot0())
        tw.d.ctrl[:] = 0.0
        with installed(control=callback, act_bias=None):
            mujoco.mj_step(tw.m, tw.d)  # warm-up (numba compile, caches)
            t0 = time.thread_time_ns()
            mujoco.mj_step(tw.m, tw.d, nstep=steps)
            samples.append((time.thread_time_ns() - t0) / steps * 1e-3)
    return statistics.median(samples)


def _native_per_step_us(tw: Twin, steps: int, repeats: int) -> float:
    scene = tw.scene
    samples = []
    for _ in range(repeats):
        tw.set_state(0.0, scene.initial.q0(), scene.initial.qdot0())
        tw.d.ctrl[:] = 0.0
        with tw.callbacks():
            tw.step(1)  # warm-up
            t0 = time.thread_time_ns()
            tw.step(steps)
            samples.append((time.thread_time_ns() - t0) / steps * 1e-3)
    return statistics.median(samples)


def run(steps: int = 400, repeats: int = 5) -> list[dict]:
    """Measure every scene; returns one row per scene with µs per step for each variant."""
    rows = []
    for name in PAPER_SCENES:
        scene = load_scene(scene_path(name))
        row = {"scene": name, "n": scene.n}
        base = Twin(scene, integrator="RK4")
        row["mujoco"] = _per_step_us(base, None, steps, repeats)
        row["empty cb"] = _per_step_us(base, lambda m, d: None, steps, repeats)
        if scene.controlled:
            for src in ControllerSource:
                tw = Twin(scene, integrator="RK4", controller=src)
                label = "mujoco UK" if src is ControllerSource.MUJOCO else src.value
                row[label] = _per_step_us(tw, tw.control_callback, steps, repeats)
                if src is ControllerSource.ANALYTIC_FAST and tw.native:
                    row["native"] = _native_per_step_us(tw, steps, repeats)
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m validation.bench.mujoco_steps", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--steps", type=int, default=400, help="steps per repeat")
    ap.add_argument("--repeats", type=int, default=5, help="repeats (median taken)")
    args = ap.parse_args(argv)
    if args.steps < 1 or args.repeats < 1:
        raise ValueError(f"--steps/--repeats: must be positive (got {args.steps}, {args.repeats})")
    rows = run(args.steps, args.repeats)
    cols = ["mujoco", "empty cb", "analytic", "analytic_fast", "native", "mujoco UK"]
    print(
        f"MuJoCo {mujoco.__version__}, RK4, µs of thread CPU time per step (median of "
        f"{args.repeats} x {args.steps})"
    )
    print(f"{'scene':28s} {'n':>2s} " + " ".join(f"{c:>14s}" for c in cols))
    for r in rows:
        cells = []
        for c in cols:
            if c in r:
                ratio = r[c] / r["mujoco"]
                cells.append(f"{r[c]:8.1f} ({ratio:4.1f}x)" if c != "mujoco" else f"{r[c]:14.1f}")
            else:
                cells.append(f"{'-':>14s}")
        print(f"{r['scene']:28s} {r['n']:2d} " + " ".join(cells))
    print("goal: a ratio <= 2.0x, i.e. the controller adds no more than one MuJoCo step")
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
