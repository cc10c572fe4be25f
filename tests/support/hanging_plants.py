"""Plants that hang (test only), for the fuzzer's hard time limit: each runs under Pinocchio's
name and never finishes within a test's limit."""

from __future__ import annotations

import os
import time
from pathlib import Path

from analytic.plant import AnalyticPlant
from analytic.trajectory import Engine

SLEEP_S = 60.0
"""How long a hanging plant's run would take, s: far past any test's time limit."""

STALL_T = 0.0625
"""Where the stalling plant stalls, s (a binary fraction: it comes back exactly)."""


class SleepyPlant(AnalyticPlant):
    """A plant that hangs: its run writes its process id into ``pid_dir``, then sleeps SLEEP_S s
    without ever reporting progress."""

    engine = Engine.PINOCCHIO
    label = "sleepy"

    def __init__(self, pid_dir):
        super().__init__()
        self.pid_dir = str(pid_dir)

    def _simulate(self, scene, settings, t_end, progress):
        Path(self.pid_dir, f"{os.getpid()}.pid").write_text("")
        time.sleep(SLEEP_S)
        return super()._simulate(scene, settings, t_end, progress)


class StallingPlant(AnalyticPlant):
    """A plant that reaches t = STALL_T s and stalls there: it reports that progress, then
    sleeps SLEEP_S s, as an adaptive integrator grinding at a singularity does."""

    engine = Engine.PINOCCHIO
    label = "stalling"

    def _simulate(self, scene, settings, t_end, progress):
        progress(STALL_T)
        time.sleep(SLEEP_S)
        return super()._simulate(scene, settings, t_end, progress)
