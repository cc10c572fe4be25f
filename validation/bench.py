"""Benchmarks: what the analytic engine costs (numbers printed, never asserted).

``python -m validation.bench`` prints

* the cost of one evaluation of the controlled dynamics (``M``, ``Q``, Udwadia-Kalaba with control)
  for n = 2, 5, 50 (median of repeats, µs), and next to it MuJoCo's ``mj_forward`` on the same body
  when the MuJoCo twin is available, as a ratio measured in this process;
* the wall time of the 60 s controlled Example 1 at rtol 1e-12 (DOP853).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # small matrices: one BLAS thread (tests/conftest.py)

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from analytic.model import TumblingModel  # noqa: E402
from analytic.scene import Scene, load_scene, scene_from_dict  # noqa: E402
from analytic.simulate import simulate  # noqa: E402
from validation.scenes import scene_path  # noqa: E402


def chain_scene(n: int, seed: int = 0) -> Scene:
    """A controlled scene with n masses on a generic rod (not through C), all masses tracked."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    p_e = np.linspace(-0.4 * n, 0.4 * n, n) if n > 1 else np.zeros(n)
    data = {
        "scene": {
            "name": f"bench_chain_{n}",
            "effects": [
                "gravity",
                "springs.linear",
                "springs.cubic",
                "mass_inertia",
                "control.omega",
                "control.masses",
            ],
        },
        "body": {"mass": 1e4, "inertia": [3e4, 4e4, 5e4]},
        "rod": {"axis": a.tolist(), "offset": [0.3, -0.2, 0.1]},
        "masses": {
            "mass": (1e3 * (1 + rng.random(n))).tolist(),
            "p_e": p_e.tolist(),
            "ring_radius": [0.2] * n,
        },
        "springs": {"k_linear": [1e5] * (n + 1), "k_cubic": [1e3] * (n + 1)},
        "initial": {
            "Rdot": [1, 2, 3],
            "omega": [0.3, -0.2, 0.5],
            "p": (p_e + 0.1).tolist(),
            "attitude": {"axis": [1, 1, 1], "angle_deg": 30},
        },
        "control": {
            "omega": {"b": [1, 0.5, -0.5], "sigma": [0, 1, 2], "gamma": 0.5},
            "masses": {"l": [0.2] * n, "lambda": [1.0] * n, "alpha": [2.0] * n, "beta": [12.0] * n},
        },
    }
    return scene_from_dict(data)


def time_call(fn, repeats: int = 7, number: int | None = None) -> float:
    """Median seconds per call of ``fn()`` over ``repeats`` batches of ``number`` calls."""
    if number is None:
        t0 = time.perf_counter()
        fn()
        one = max(time.perf_counter() - t0, 1e-7)
        number = max(1, int(0.05 / one))
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        runs.append((time.perf_counter() - t0) / number)
    return statistics.median(runs)


def analytic_eval_cost(scene: Scene) -> float:
    model = TumblingModel(scene)
    q, qd = scene.initial.q0(), scene.initial.qdot0()
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m validation.bench", description=__doc__)
    ap.add_argument("--skip-long", action="store_true", help="skip the 60 s Example 1 run")
    args = ap.parse_args(argv)
    print("one evaluation of the controlled dynamics (median)")
    print(f"  {'n':>4} {'analytic µs':>12} {'mj_forward µs':>14} {'ratio':>8}")
    for n in (2, 5, 50):
        sc = chain_scene(n)
        a = analytic_eval_cost(sc)
        mj = mujoco_forward_cost(sc)
        mj_s = f"{mj * 1e6:14.1f}" if mj else f"{'n/a':>14}"
        ratio = f"{a / mj:8.1f}" if mj else f"{'n/a':>8}"
        print(f"  {n:>4} {a * 1e6:12.1f} {mj_s} {ratio}")
    ex1 = load_scene(scene_path("paper_example1_controlled"))
    a = analytic_eval_cost(ex1)
    mj = mujoco_forward_cost(ex1)
    print(
        f"  paper_example1_controlled: analytic {a * 1e6:.1f} µs"
        + (f", mj_forward {mj * 1e6:.1f} µs, ratio {a / mj:.1f}" if mj else "")
    )
    if not args.skip_long:
        tr = simulate(ex1, t_end=60.0)
        print(
            "60 s controlled Example 1, DOP853 rtol 1e-12 atol 1e-13: "
            f"{tr.info['wall_time_s']:.2f} s wall, {tr.info['nfev']} evaluations, "
            f"{tr.info['nsteps']} steps, status {tr.status.value}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
