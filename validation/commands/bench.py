"""``tumble bench``: the fast engine's speed goals as ratios measured in this process, printed
(and with ``--out`` written); exits 0 whether or not a goal holds. Its options are those of
``python -m validation.bench.command``, defined there once."""

from __future__ import annotations

import argparse

NAME = "bench"
HELP = "the fast engine's speed goals as ratios measured in this process"
DESCRIPTION = (
    "Time one controlled-dynamics evaluation (numpy path, compiled path, mj_forward) and print "
    "each speed goal of the fast engine as a ratio with whether it holds: evaluation vs "
    "mj_forward (n = 2, 5), the controller inside MuJoCo's RK4 vs the bare step, n = 1000 vs "
    "n = 10, and the 60 s controlled Example 1 vs MuJoCo RK4 at the same accuracy. With "
    "--batched, only the batched plants' (mjx, mjwarp) scenes per second against batch size, as "
    "a multiple of the MuJoCo C plant's loop, on the device JAX or Warp finds (a GPU when they "
    "see one). Numbers only: exits 0 whether or not a goal holds."
)
CHOOSES_PLANTS = False


def add_arguments(p: argparse.ArgumentParser) -> None:
    from validation.bench.command import add_arguments as add_bench_arguments

    add_bench_arguments(p)  # the options of python -m validation.bench.command, one definition


def run(args: argparse.Namespace) -> int:
    from validation.bench.command import run as run_bench
    from validation.bench.command import write_bench

    def say(s: str) -> None:
        print(s, flush=True)

    from validation.bench.command import batched_options, measure_batched

    try:
        batched = batched_options(args)
    except argparse.ArgumentTypeError as exc:
        raise ValueError(str(exc)) from None
    if batched is not None:
        if args.out:
            write_bench(args.out, out=say, batched=batched)
        else:
            measure_batched(out=say, **batched)
        return 0
    if args.out:
        write_bench(args.out, args.skip_long, out=say)
    else:
        run_bench(args.skip_long, None, out=say)
    return 0
