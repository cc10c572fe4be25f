"""Every speed goal of ``tumble bench``, in the order they are measured and printed (:data:`GOALS`).

A goal is a ratio measured in this one process, with whether it holds; numbers are printed, never
asserted (tests cover correctness, not speed). ``python -m validation.bench.command [--skip-long]``
(or ``tumble bench``) runs :func:`measure`. Each goal is one module, its docstring stating what it
measures and its limit:

1. evaluation vs ``mj_forward`` (n = 2, 5), 2. the controller inside MuJoCo's RK4 vs the bare step,
   4. n = 1000 vs n = 10: :mod:`validation.bench.evaluation_goals`;
3. the 60 s controlled Example 1 vs MuJoCo RK4 at the same accuracy:
   :mod:`validation.bench.example1_goal` (long);
5. the Pinocchio plant vs the analytic plant: :mod:`validation.bench.pinocchio_goal`;
6. the compiled loop vs the evaluations it makes: :mod:`validation.bench.compiled_stepping_goal`;
7. ``tumble validate`` warm vs the plants' compute, and cold vs warm:
   :mod:`validation.bench.whole_command_goal` (long);
8. the Drake plant vs the analytic plant: :mod:`validation.bench.drake_goal` (long);
9. each batched plant's time per scene in one call of 256 vs the C plant's loop, with its scenes
   per second against batch size: :mod:`validation.bench.batch_throughput` (long; ``tumble bench
   --batched`` alone).

A new goal is a module returning a :class:`validation.bench.goal.Goal` and one entry of
:data:`GOALS`.

How a goal is timed and judged. The in-process goals (1, 2, 4) time both sides of their ratio in
alternating ~5 ms batches (:func:`validation.bench.timing.interleaved`), by the thread's CPU time,
not the wall clock: the time the scheduler gives to another process is not the code's cost
(:mod:`validation.bench.timing`). The plant-level goals (5, 6, 8) and goal 3 time whole runs (5, 6
and 8 alternating) and count the CPU time of each integration as its wall times the share of a CPU
the thread had during it (:class:`validation.bench.timing.CpuMeter`). Each round gives one ratio: a
goal's value is their median, its spread their interquartile range
(:class:`validation.bench.verdicts.Spread`), printed with the share of a CPU the thread had. The
verdict (:func:`validation.bench.verdicts.decide`) is HOLDS or FAILS when the rounds agree, and
TOO_BUSY ("the machine was too busy for a verdict") when the spread is wider than
:data:`validation.bench.verdicts.SPREAD_BOUND` of the limit or straddles it. Goal 3 is a search of
single runs (no spread: its verdict is its value's); the ``tumble validate`` goals time new
processes (a pool of workers: their CPU time is not their wait), by wall, their pairs giving the
spread. One BLAS thread throughout.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from analytic import fast
from validation.bench.compiled_stepping_goal import goal_compiled_stepping
from validation.bench.evaluation_goals import goal_controller_in_rk4, goal_evaluation, goal_scaling
from validation.bench.example1_goal import goal_example1_60s
from validation.bench.goal import Goal
from validation.bench.pinocchio_goal import goal_pinocchio
from validation.bench.whole_command_goal import goal_whole_command

Progress = Callable[[str], None]
"""Where a goal prints what it does as it goes (``print``, or a test's list)."""


@dataclass(frozen=True)
class GoalEntry:
    """One entry of :data:`GOALS`.

    Attributes:
        measure: measures the goal (or goals: a tuple, printed in order), given the progress
            printer.
        long: left out by ``--skip-long`` (minutes of runs, or new processes).
    """

    measure: Callable[[Progress], Goal | tuple[Goal, ...]]
    long: bool = False


def _drake(progress: Progress) -> Goal:
    """The Drake plant's goal; skipped, with the reason, where Drake is not installed."""
    # deferred: the Drake plugin's modules load only when its goal runs (about 15 s, long goals only)
    from validation.bench.drake_goal import goal_drake

    return goal_drake(progress=progress)


def _batched(progress: Progress) -> tuple[Goal, ...]:
    """Every batched plant's throughput goal; skipped, with the reason, where none is installed."""
    # deferred: it lists the plants (their plugins' modules) only when its goal runs
    from validation.bench.batch_throughput import goal_batched_throughput

    return goal_batched_throughput(progress=progress)


GOALS: tuple[GoalEntry, ...] = (
    GoalEntry(lambda progress: goal_evaluation(2)),
    GoalEntry(lambda progress: goal_evaluation(5)),
    GoalEntry(lambda progress: goal_controller_in_rk4("paper_example1_controlled")),
    GoalEntry(lambda progress: goal_controller_in_rk4("paper_example2_controlled")),
    GoalEntry(lambda progress: goal_scaling()),
    GoalEntry(lambda progress: goal_compiled_stepping(progress=progress)),
    GoalEntry(lambda progress: goal_pinocchio(progress=progress)),
    GoalEntry(lambda progress: goal_example1_60s(progress=progress), long=True),
    GoalEntry(lambda progress: goal_whole_command(progress=progress), long=True),
    GoalEntry(_drake, long=True),
    GoalEntry(_batched, long=True),
)
"""Every goal, in the order ``tumble bench`` measures and prints them."""


def measure(
    skip_long: bool = False,
    progress: Progress = print,
    goals: tuple[GoalEntry, ...] = GOALS,
) -> list[Goal]:
    """Measure every goal of ``goals`` in order (the long ones unless ``skip_long``), printing each
    goal's line to ``progress`` as soon as it is measured; the goals measured."""
    if not fast.available():
        progress("numba is not installed: the analytic side runs on numpy")
    out: list[Goal] = []
    for entry in goals:
        if entry.long and skip_long:
            continue
        got = entry.measure(progress)
        for g in got if isinstance(got, tuple) else (got,):
            out.append(g)
            progress(g.line())
    return out


__all__ = ["GOALS", "Goal", "GoalEntry", "measure"]
