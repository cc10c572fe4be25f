"""The registry of speed goals: every goal once, in order, the long ones left out by
``--skip-long``, each goal's line printed as soon as it is measured (planted goals: the timing
itself is ``tumble bench``'s, never a test's)."""

from __future__ import annotations

from validation.bench import goals
from validation.bench.goal import Goal


def test_measure_runs_each_entry_in_order_and_prints_its_lines():
    ran: list[str] = []

    def one(name: str):
        def measure(progress):
            ran.append(name)
            progress(f"measuring {name}")
            return Goal(name, 0.5, 1.0)

        return measure

    entries = (
        goals.GoalEntry(one("a")),
        goals.GoalEntry(lambda progress: (Goal("b1", 2.0, 1.0), Goal("b2", 0.1, 1.0)), long=True),
        goals.GoalEntry(one("c")),
    )
    lines: list[str] = []
    got = goals.measure(False, lines.append, entries)
    assert [g.name for g in got] == ["a", "b1", "b2", "c"] and ran == ["a", "c"]
    body = [x for x in lines if not x.startswith("numba")]
    assert body == ["measuring a", got[0].line(), got[1].line(), got[2].line(), "measuring c",
                    got[3].line()]  # fmt: skip
    short = goals.measure(True, lambda _s: None, entries)
    assert [g.name for g in short] == ["a", "c"]


def test_every_goal_is_registered_once_and_the_long_ones_are_marked():
    """Seven short entries (evaluation n = 2, 5; the controller in RK4 on two scenes; scaling;
    compiled stepping; Pinocchio) then the long ones (60 s Example 1, the whole command, Drake,
    the batched plants' throughput)."""
    assert len(goals.GOALS) == len(set(map(id, goals.GOALS))) == 11
    assert [e.long for e in goals.GOALS] == [False] * 7 + [True] * 4
