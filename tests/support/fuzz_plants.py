"""Plants for the fuzzer's tests: wrong ones, a right one at coarse settings, and ones that hang.

They live in a module of their own, not in the test files: a campaign's plant runs may be made in
children of a fork server, which import the module a plant instance's class comes from to unpickle
it; a test module would bring pytest and every test's imports into each run."""

from __future__ import annotations

import dataclasses
import os
import time
from pathlib import Path

import numpy as np

from analytic.plant import AnalyticPlant
from analytic.trajectory import Engine

SHIFT_M = 1e-3
"""The shifted plant's error: C displaced by 1 mm (the position_C threshold is far below)."""


class ShiftedPlant(AnalyticPlant):
    """A wrong plant: the analytic plant's run with C displaced by SHIFT_M along x, under
    MuJoCo's name. Every scene shows it on ``position_C``, so the minimal scene must be the
    simplest one of the space."""

    engine = Engine.MUJOCO
    label = "shifted"

    def _simulate(self, scene, settings, t_end, progress):
        tr = super()._simulate(scene, settings, t_end, progress)
        q = np.array(tr.q)
        q[:, 0] += SHIFT_M
        return dataclasses.replace(tr, q=q, engine=Engine.MUJOCO)


class CoarsePlant(AnalyticPlant):
    """A right model at coarse default settings: the analytic plant at rtol 1e-5, under MuJoCo's
    name. Its disagreements are its settings', not its model's."""

    engine = Engine.MUJOCO
    label = "coarse"

    def default_settings(self, scene):
        return dataclasses.replace(super().default_settings(scene), rtol=1e-5, atol=1e-7)

    def _simulate(self, scene, settings, t_end, progress):
        tr = super()._simulate(scene, settings, t_end, progress)
        return dataclasses.replace(tr, engine=Engine.MUJOCO)


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
