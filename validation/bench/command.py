"""Benchmarks: what the analytic engine costs, and the fast engine's speed goals as ratios
measured in this one process (numbers printed, never asserted; tests cover correctness).

``python -m validation.bench.command [--skip-long] [--out DIR]`` is ``tumble bench``: the same options, the
same output. It prints

* the cost of one evaluation of the controlled dynamics (``M``, ``Q``, Udwadia-Kalaba with control)
  for n = 2, 5, 50 on the numpy reference path and on the compiled path, next to MuJoCo's
  ``mj_forward`` on the same body (median thread CPU time of repeats, µs);
* every goal of :mod:`validation.bench.goals` with its ratio, the spread of its per-round ratios,
  the share of a CPU the process had, and its verdict: HOLDS, FAILS, or TOO_BUSY when the rounds
  disagree too much for a verdict (:mod:`validation.bench.verdicts`); the 60 s Example 1 goal,
  the longest (``docs/performance.md``), is left out by ``--skip-long``; the Pinocchio plant's
  goal is skipped, with the reason printed, when ``pin`` is not installed;
* the load average before and after, and, when any goal was TOO_BUSY, one line saying the machine
  was too busy for a verdict on it;
* with ``--out DIR``, the same numbers in ``DIR/bench.json`` (with ``DIR/manifest.json``, one run
  of :func:`validation.runs.outputs.output_run`, like every other command's ``--out``); the file carries
  the provenance block of :mod:`validation.report.provenance` and follows
  ``validation/report/schemas/bench.schema.json`` (``docs/json-output.md``).

``--json FILE`` (this module's former option, a file rather than a directory) still writes FILE,
with a deprecation warning: use ``--out DIR``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from validation.bench.verdicts import SPREAD_BOUND, Verdict
from validation.runs import interrupts

# deferred, in every function below: `tumble`'s parser imports this module for the options of
# `tumble bench` on every command, so it imports neither numpy nor the engines nor the goals,
# which take seconds to import (docs/performance.md, Import costs)
if TYPE_CHECKING:
    from analytic.scene import Scene
    from validation.bench.goal import Goal


def analytic_eval_cost(scene: Scene, compiled: bool = False) -> float:
    """Seconds per evaluation of the controlled dynamics on the numpy path or the compiled one."""
    import numpy as np

    from analytic.model import TumblingModel
    from validation.bench.timing import time_call

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
    except ImportError as exc:
        interrupts.raise_if_interrupt(exc)  # an import a signal cut is the signal
        return None
    from validation.bench.timing import time_call

    m = build_spec(scene).compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return time_call(lambda: mujoco.mj_forward(m, d))


def evaluation_table(ns: tuple[int, ...] = (2, 5, 50)) -> list[dict[str, float]]:
    """µs per evaluation for chain scenes of n masses: numpy path, compiled path, mj_forward."""
    from validation.bench.timing import chain_scene

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
    """Print the table and the goals, and write them to ``json_path`` when given; returns whether
    every goal measured holds."""
    holds, doc = measure_and_print(skip_long, out)
    if json_path:
        from validation.report.provenance import dumps
        from validation.runs.atomic import write_text

        write_text(json_path, dumps(doc))
        out(f"written: {json_path}")
    return holds


def measure_and_print(skip_long: bool = False, out=print) -> tuple[bool, dict[str, Any]]:
    """Measure, print as it goes; returns (every goal measured holds, the ``bench.json`` document)."""
    from validation.bench import goals
    from validation.report.provenance import FileKind, provenance

    load_before = load_average()
    out(
        f"one evaluation of the controlled dynamics (median thread CPU time, µs); load average "
        f"{load_before:.2f} on {os.cpu_count()} CPUs"
    )
    out(f"  {'n':>4} {'numpy':>10} {'compiled':>10} {'mj_forward':>11}")
    rows = evaluation_table()
    for r in rows:
        out(
            f"  {r['n']:>4} {r['numpy_us']:10.1f} {r['compiled_us']:10.2f} "
            f"{r['mj_forward_us']:11.2f}"
        )
    out("\nspeed goals, each a ratio measured in this process")
    measured = goals.measure(skip_long, progress=out)
    load_after = load_average()
    out("\nsummary")
    for g in measured:
        out("  " + summary_line(g))
    busy = [g for g in measured if g.verdict is Verdict.TOO_BUSY]
    if busy:
        out(
            f"the machine was too busy for a verdict on {len(busy)} goal(s) (load average "
            f"{load_before:.2f} before, {load_after:.2f} after, on {os.cpu_count()} CPUs): their "
            f"rounds spread wider than {SPREAD_BOUND:g} of the limit or across it; run "
            "`tumble bench` again on a quieter machine"
        )
    holds = all(g.holds for g in measured if not g.skipped)
    machine = {
        "cpus": os.cpu_count(),
        "load_average_1min": {"before": load_before, "after": load_after},
    }
    return holds, bench_document(rows, measured, provenance(FileKind.BENCH), machine)


def measure_batched(
    sizes: tuple[int, ...] | None = None, horizon: float | None = None, out=print
) -> tuple[bool, dict[str, Any]]:
    """``--batched``: only the batched plants' throughput (:mod:`validation.bench.batch_throughput`,
    its default sizes and horizon unless given), printed as it goes; returns (every goal measured
    holds, the ``bench.json`` document, with no evaluation table)."""
    from validation.bench import batch_throughput as bt
    from validation.report.provenance import FileKind, provenance

    load_before = load_average()
    out(
        f"batched throughput, wall clock of whole calls; load average {load_before:.2f} on "
        f"{os.cpu_count()} CPUs"
    )
    measured = list(
        bt.goal_batched_throughput(
            sizes=sizes or bt.BATCH_SIZES,
            horizon=bt.HORIZON_S if horizon is None else horizon,
            progress=out,
        )
    )
    load_after = load_average()
    out("\nsummary")
    for g in measured:
        out("  " + summary_line(g))
    machine = {
        "cpus": os.cpu_count(),
        "load_average_1min": {"before": load_before, "after": load_after},
    }
    holds = all(g.holds for g in measured if not g.skipped)
    return holds, bench_document([], measured, provenance(FileKind.BENCH), machine)


def load_average() -> float:
    """The machine's 1-minute load average (NaN where the platform has none)."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return math.nan


def summary_line(g: Goal) -> str:
    """``"HOLDS  name: 0.574 (≤ 1; interquartile 0.571-0.576 over 21 rounds, ...)"``."""
    if g.skipped:
        return f"{g.verdict}  {g.name}: {g.skipped}"
    spread = f"; {g.spread.text()}" if g.spread else ""
    return f"{g.verdict}  {g.name}: {g.value:.3g} (≤ {g.limit:g}{spread})"


def bench_document(
    rows: list[dict[str, float]],
    measured: list[Goal],
    block: dict[str, Any],
    machine: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The content of ``bench.json``: the provenance block, the machine's load, the bound of the
    verdicts, the evaluation table and the goals (schema
    ``validation/report/schemas/bench.schema.json``; a NaN, e.g. no MuJoCo, is written as null)."""
    return {
        "provenance": block,
        "machine": machine or {"cpus": os.cpu_count(), "load_average_1min": None},
        "spread_bound": SPREAD_BOUND,
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
                "spread": None if g.spread is None else dataclasses.asdict(g.spread),
                "detail": g.detail,
                "data": g.data,
            }
            for g in measured
        ],
    }


def write_bench(
    out_dir: str | Path, skip_long: bool = False, out=print, batched: dict[str, Any] | None = None
) -> Path:
    """Measure, print, and write ``out_dir/bench.json`` as one output run (with
    ``manifest.json``); returns the final path of ``bench.json``. ``batched``: the keyword
    arguments of :func:`measure_batched`, which then measures instead (``--batched``)."""
    from validation.report.provenance import dumps
    from validation.runs.atomic import write_text
    from validation.runs.outputs import output_run

    with output_run(Path(out_dir), "bench") as orun:
        if batched is None:
            _, doc = measure_and_print(skip_long, out)
        else:
            _, doc = measure_batched(out=out, **batched)
        write_text(orun.path / "bench.json", dumps(doc))
    final = orun.final("bench.json")
    out(f"written: {final}")
    return final


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``tumble bench`` and ``python -m validation.bench.command`` (one definition)."""
    ap.add_argument(
        "--out", metavar="DIR", help="also write DIR/bench.json (with DIR/manifest.json)"
    )
    ap.add_argument("--skip-long", action="store_true", help="skip the 60 s Example 1 goal")
    ap.add_argument(
        "--batched",
        action="store_true",
        help="only the batched plants' throughput: scenes per second against batch size, as a "
        "multiple of the MuJoCo C plant's loop, on the device JAX or Warp finds",
    )
    ap.add_argument(
        "--batch-sizes",
        metavar="N,N,...",
        type=batch_sizes,
        default=None,
        help="with --batched: the batch sizes (default 1,16,256)",
    )
    ap.add_argument(
        "--batch-horizon",
        metavar="SECONDS",
        type=positive_seconds,
        default=None,
        help="with --batched: each scene's horizon, s (default 0.01: 40 steps at 2.5e-4 s)",
    )


def batch_sizes(text: str) -> tuple[int, ...]:
    """``--batch-sizes``: whole numbers ≥ 1, comma-separated (argparse's type)."""
    try:
        sizes = tuple(int(x) for x in text.split(",") if x.strip())
    except ValueError:
        sizes = ()
    if not sizes or min(sizes) < 1:
        raise argparse.ArgumentTypeError(
            f"must be whole numbers ≥ 1, comma-separated (got {text!r})"
        )
    return sizes


def positive_seconds(text: str) -> float:
    """``--batch-horizon``: a positive finite number of seconds (argparse's type)."""
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds (got {text!r})")
    return v


def batched_options(args: argparse.Namespace) -> dict[str, Any] | None:
    """The keyword arguments of :func:`measure_batched` from ``--batched`` and its options (None
    without ``--batched``); ``--batch-sizes`` or ``--batch-horizon`` alone: an ``ArgumentTypeError``
    naming the option."""
    if not getattr(args, "batched", False):
        for flag in ("batch_sizes", "batch_horizon"):
            if getattr(args, flag, None) is not None:
                raise argparse.ArgumentTypeError(f"--{flag.replace('_', '-')}: needs --batched")
        return None
    return {"sizes": args.batch_sizes, "horizon": args.batch_horizon}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m validation.bench.command", description=__doc__.split("\n")[0]
    )
    add_arguments(ap)
    ap.add_argument(
        "--json", metavar="FILE", help="deprecated: use --out DIR (writes DIR/bench.json)"
    )
    args = ap.parse_args(argv)

    def say(s: str) -> None:
        print(s, flush=True)

    if args.json and args.out:
        ap.error("--json is the deprecated form of --out: give one of them")
    try:
        batched = batched_options(args)
    except argparse.ArgumentTypeError as exc:
        ap.error(str(exc))
    if batched is not None:
        if args.json:
            ap.error("--batched: write its numbers with --out DIR")
        if args.out:
            write_bench(args.out, out=say, batched=batched)
        else:
            measure_batched(out=say, **batched)
        return 0
    if args.json:
        print(
            "python -m validation.bench.command: warning: --json FILE is deprecated; use --out DIR "
            "(writes DIR/bench.json with a manifest, as `tumble bench --out DIR`)",
            file=sys.stderr,
        )
        run(args.skip_long, args.json, out=say)
    elif args.out:
        write_bench(args.out, args.skip_long, out=say)
    else:
        run(args.skip_long, None, out=say)
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
