"""The plants' task (``plant_task``): the parent's report is told times only, a few times a
second; a watcher, when given, every state the plant passes; without one the plant is asked for
no state at all."""

from __future__ import annotations

import numpy as np

from analytic.progress import takes_state
from validation.runs.plant_runs import plant_task

STATES = 50


class _Plant:
    engine = "analytic"

    def __init__(self):
        self.progress = None

    def simulate(self, sc, settings, t_end, progress):
        self.progress = progress
        for k in range(1, STATES + 1):
            t = t_end * k / STATES
            if takes_state(progress):
                progress(t, np.full(7, t))
            else:
                progress(t)
        return "trajectory"


def test_the_watcher_gets_every_state_and_the_report_times_only():
    reported, watched = [], []
    pl = _Plant()
    tr, wall = plant_task(
        pl, None, None, 1.0, report=reported.append, watch=lambda t, q: watched.append((t, q))
    )
    assert tr == "trajectory" and wall >= 0
    assert [t for t, _ in watched] == [k / STATES for k in range(1, STATES + 1)]
    assert all(np.all(q == t) for t, q in watched)
    assert reported and reported[-1] == 1.0 and len(reported) < STATES  # throttled, the end kept
    assert all(isinstance(t, float) for t in reported)


def test_without_a_watcher_no_state_is_asked_for():
    reported = []
    pl = _Plant()
    plant_task(pl, None, None, 1.0, report=reported.append)
    assert not takes_state(pl.progress)
    assert reported[-1] == 1.0
