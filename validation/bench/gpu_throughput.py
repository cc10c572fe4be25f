"""``python -m validation.bench.gpu_throughput``: the batched plants' throughput where they are
meant to run, on a GPU (``docs/performance.md``, Batched runs: on a GPU).

The measurement of ``tumble bench --batched`` (:mod:`validation.bench.batch_throughput`: scenes of
one structure, one ``simulate_batch`` call per batch size on each batched plant, the MuJoCo C
plant's loop over the same scenes), with defaults for a GPU: batch sizes
:data:`GPU_BATCH_SIZES` (up to 4096 worlds) and a horizon of :data:`GPU_HORIZON_S`. It prints the
device JAX and Warp use (a GPU when they see one: neither plant chooses the CPU unless told), and
per plant and batch size the seconds of the call, scenes per second (whole call; the engine's
stepping alone) and their multiple of the C loop's; then one summary line per plant. A machine
where neither library sees a GPU gets a warning line first, and the measurement runs on its CPU
(there, keep the sizes and the horizon small: ``--sizes 1,16 --horizon 0.01``).

Options: ``--sizes N,N,...``, ``--horizon SECONDS``, ``--plants mjx,mjwarp`` (default: every
batched plant installed), ``--out DIR`` (``DIR/bench.json``, as ``tumble bench --out``).
Exits 0 whether or not a goal holds; 2 on a bad option.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

GPU_BATCH_SIZES = (1, 16, 256, 1024, 4096)
"""Batch sizes on a GPU: one world, a few, and the thousands a GPU is meant for."""
GPU_HORIZON_S = 0.1
"""Each scene's horizon on a GPU, s: 400 steps at the scenes' 2.5e-4 s, long enough that the
stepping outweighs a call's start (on a CPU: ``--horizon 0.01``)."""

GPU_WORDS = ("cuda", "gpu", "rocm", "metal")
"""Words in a device's name that mean a GPU."""


def sees_gpu(devices: dict[str, str]) -> bool:
    """Whether any library's default device (:func:`validation.bench.batch_throughput.
    accelerator_devices`) is a GPU."""
    return any(any(w in d.lower() for w in GPU_WORDS) for d in devices.values())


def main(argv: list[str] | None = None) -> int:
    from validation.bench.command import batch_sizes, bench_document, positive_seconds

    ap = argparse.ArgumentParser(
        prog="python -m validation.bench.gpu_throughput", description=__doc__.split("\n")[0]
    )
    ap.add_argument("--sizes", type=batch_sizes, default=GPU_BATCH_SIZES, metavar="N,N,...")
    ap.add_argument("--horizon", type=positive_seconds, default=GPU_HORIZON_S, metavar="SECONDS")
    ap.add_argument("--plants", default="", metavar="NAMES", help="default: every batched plant")
    ap.add_argument("--out", metavar="DIR", help="also write DIR/bench.json")
    args = ap.parse_args(argv)

    from mj_bridge.plants import parse_plants, plant
    from validation.bench import batch_throughput as bt
    from validation.bench.command import load_average, summary_line

    def say(s: str) -> None:
        print(s, flush=True)

    try:
        chosen = [plant(n) for n in parse_plants(args.plants)] if args.plants else None
    except ValueError as exc:
        ap.error(str(exc))
    if chosen is not None:
        not_batched = [p.engine for p in chosen if not p.batched]
        if not_batched:
            ap.error(f"--plants: not batched plants: {', '.join(not_batched)}")
    devices = bt.accelerator_devices()
    if not sees_gpu(devices):
        found = "; ".join(f"{k} {v}" for k, v in devices.items()) or "neither JAX nor Warp"
        say(f"warning: no GPU seen ({found}): measuring on the CPU")
    load_before = load_average()
    say(f"load average {load_before:.2f} on {os.cpu_count()} CPUs")
    measured = bt.goal_batched_throughput(
        chosen, sizes=args.sizes, horizon=args.horizon, progress=say, devices=devices
    )
    say("\nsummary")
    for g in measured:
        say("  " + summary_line(g))
    if args.out:
        from validation.report.provenance import FileKind, dumps, provenance
        from validation.runs.atomic import write_text
        from validation.runs.outputs import output_run

        machine = {
            "cpus": os.cpu_count(),
            "load_average_1min": {"before": load_before, "after": load_average()},
        }
        doc = bench_document([], list(measured), provenance(FileKind.BENCH), machine)
        with output_run(Path(args.out), "bench") as orun:
            write_text(orun.path / "bench.json", dumps(doc))
        say(f"written: {orun.final('bench.json')}")
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
