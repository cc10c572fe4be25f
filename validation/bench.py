"""Benchmarks: what the analytic engine costs, and the fast engine's speed goals as ratios
measured in this one process (numbers printed, never asserted; tests cover correctness).

``python -m validation.bench [--skip-long] [--json FILE]`` (also ``tumble bench``) prints

* the cost of one evaluation of the controlled dynamics (``M``, ``Q``, Udwadia-Kalaba with control)
  for n = 2, 5, 50 on the numpy reference path and on the compiled path, next to MuJoCo's
  ``mj_forward`` on the same body (median of repeats, µs);
* every goal of :mod:`validation.goals` with its ratio and whether it holds (the 60 s Example 1
  goal takes about a minute; ``--skip-long`` leaves it out); the Pinocchio plant's goal is skipped,
  with the reason printed, when ``pin`` is not installed;
* with ``--json``, the same numbers written atomically to FILE.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # small matrices: one BLAS thread (tests/conftest.py)

import argparse  # noqa: E402

import numpy as np  # noqa: E402

from analytic.model import TumblingModel  # noqa: E402
from analytic.scene import Scene  # noqa: E402
from validation.timing import chain_scene, time_call  # noqa: E402


def analytic_eval_cost(scene: Scene, compiled: bool = False) -> float:
    """Seconds per evaluation of the controlled dynamics on the numpy path or the compiled one."""
    q, qd = scene.initial.q0(), scene.initial.qdot0()
    if compiled:
        from analytic.fast import FastModel

        fm = FastModel(scene)
        q, qd = np.ascontiguousarray(q), np.ascontiguousarray(qd)
        fm.qddot(0.3, q, qd)
        return time_call(lambda: fm.qddot(0.3, q, qd))
    model = TumblingModel(scene)
    return time_call(lambda: model.acceleration(0.3, q, qd))


def mujoco_forward_cost(scene: Scene) -> float | None:
    """``mj_forward`` on the same body (None when the MuJoCo twin is not available)."""
    try:
        import mujoco

        from model_xml import build_spec
    except ImportError:
        return None
    m = build_spec(scene).compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return time_call(lambda: mujoco.mj_forward(m, d))


def evaluation_table(ns: tuple[int, ...] = (2, 5, 50)) -> list[dict[str, float]]:
    """µs per evaluation for chain scenes of n masses: numpy path, compiled path, mj_forward."""
    rows = []
    for n in ns:
        sc = chain_scene(n)
        mj = mujoco_forward_cost(sc)
        rows.append(
            {
                "n": n,
                "numpy_us": analytic_eval_cost(sc) * 1e6,
                "compiled_us": analytic_eval_cost(sc, compiled=True) * 1e6,
                "mj_forward_us": mj * 1e6 if mj else float("nan"),
            }
        )
    return rows


def run(skip_long: bool = False, json_path: str | None = None, out=print) -> bool:
    """Print the table and the goals; returns whether every goal measured holds."""
    from validation import goals

    out("one evaluation of the controlled dynamics (median, µs)")
    out(f"  {'n':>4} {'numpy':>10} {'compiled':>10} {'mj_forward':>11}")
    rows = evaluation_table()
    for r in rows:
        out(
            f"  {r['n']:>4} {r['numpy_us']:10.1f} {r['compiled_us']:10.2f} "
            f"{r['mj_forward_us']:11.2f}"
        )
    out("\nspeed goals, each a ratio measured in this process")
    measured = goals.measure(skip_long, progress=out)
    out("\nsummary")
    for g in measured:
        if g.skipped:
            out(f"  SKIPPED  {g.name}: {g.skipped}")
        else:
            out(f"  {g.verdict}  {g.name}: {g.value:.3g} (≤ {g.limit:g})")
    if json_path:
        import json

        from validation.atomic import write_text

        doc = {
            "evaluation_us": rows,
            "goals": [
                {
                    "name": g.name,
                    "ratio": None if g.skipped else g.value,
                    "limit": g.limit,
                    "holds": g.holds,
                    "verdict": g.verdict,
                    "skipped": g.skipped or None,
                    "extrapolated": g.extrapolated,
                    "detail": g.detail,
                    "data": g.data,
                }
                for g in measured
            ],
        }
        write_text(json_path, json.dumps(doc, indent=2, allow_nan=True) + "\n")
        out(f"written: {json_path}")
    return all(g.holds for g in measured if not g.skipped)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m validation.bench", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--skip-long", action="store_true", help="skip the 60 s Example 1 goal")
    ap.add_argument("--json", help="also write the numbers to this JSON file")
    args = ap.parse_args(argv)
    run(args.skip_long, args.json, out=lambda s: print(s, flush=True))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
