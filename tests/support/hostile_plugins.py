"""Hostile plant plugins: each the analytic plant with one fault a plugin's own code can have
(an exit, a crash, a hang, a lie, garbage, a scene changed in place), to show that the fault fails
that plant alone (``tests/cross/test_fault_plants.py``).

:func:`install` writes a ``dist-info`` declaring every one of them as an entry point of the plant
group into a directory; that directory on ``PYTHONPATH`` shows them to ``importlib.metadata`` (as
``tests/support/plugins.py`` does for a project). Each is ``default = False``: run only when named.
"""

from __future__ import annotations

import ctypes
import dataclasses
import os
import signal
import time
from pathlib import Path

import numpy as np

from analytic.plant import AnalyticPlant


class _Hostile(AnalyticPlant):
    """The analytic plant under the plugin's own name (a fault overrides what it needs)."""

    default = False

    def _honest(self, scene, settings, t_end, progress):
        tr = super()._simulate(scene, settings, t_end, progress)
        return dataclasses.replace(tr, engine=self.engine)

    def _simulate(self, scene, settings, t_end, progress):
        return self._honest(scene, settings, t_end, progress)


class ExitPlant(_Hostile):
    """``os._exit(0)`` in its run: the process it runs in ends, no exception, no cleanup."""

    engine = "exit0"
    label = "Exit0"

    def _simulate(self, scene, settings, t_end, progress):
        os._exit(0)


class SystemExitPlant(_Hostile):
    """``raise SystemExit(0)`` in its run."""

    engine = "sysexit"
    label = "SysExit"

    def _simulate(self, scene, settings, t_end, progress):
        raise SystemExit(0)


class KilledPlant(_Hostile):
    """Its run's process receives SIGKILL (as from ``kill -9`` or the out-of-memory killer)."""

    engine = "killed"
    label = "Killed"

    def _simulate(self, scene, settings, t_end, progress):
        os.kill(os.getpid(), signal.SIGKILL)


class SegfaultPlant(_Hostile):
    """A segmentation fault in its run (a read of address 0)."""

    engine = "segv"
    label = "Segv"

    def _simulate(self, scene, settings, t_end, progress):
        ctypes.string_at(0)


class HangPlant(_Hostile):
    """A run that never returns and never reports progress."""

    engine = "hang"
    label = "Hang"

    def _simulate(self, scene, settings, t_end, progress):
        while True:
            time.sleep(0.05)


class LiarPlant(_Hostile):
    """An honest run returned under the analytic plant's name."""

    engine = "liar"
    label = "Liar"

    def _simulate(self, scene, settings, t_end, progress):
        tr = super()._simulate(scene, settings, t_end, progress)
        return dataclasses.replace(tr, engine="analytic")


MUTATED_NAME = "mutated_by_a_plugin"
MUTATED_T_END = 99.0


class MutatorPlant(_Hostile):
    """Changes the scene it is given, in place: the body's inertia doubled (the array made
    writable first, as numpy allows an array that owns its memory), the name and ``t_end`` set
    through ``object.__setattr__``; then runs."""

    engine = "mutator"
    label = "Mutator"

    def _simulate(self, scene, settings, t_end, progress):
        inertia = scene.body.inertia
        inertia.setflags(write=True)
        inertia *= 2.0
        object.__setattr__(scene, "name", MUTATED_NAME)
        object.__setattr__(scene.output, "t_end", MUTATED_T_END)
        return self._honest(scene, settings, t_end, progress)


class BadShapePlant(_Hostile):
    """Returns ``q`` with 3 columns."""

    engine = "badshape"
    label = "BadShape"

    def _simulate(self, scene, settings, t_end, progress):
        tr = self._honest(scene, settings, t_end, progress)
        return dataclasses.replace(tr, q=np.ascontiguousarray(tr.q[:, :3]))


class NonePlant(_Hostile):
    """Returns None."""

    engine = "returnsnone"
    label = "ReturnsNone"

    def _simulate(self, scene, settings, t_end, progress):
        return None


class CheckRaisesPlant(_Hostile):
    """``check_scene`` raises ``RuntimeError`` (not the ``ValueError`` of a refusal)."""

    engine = "checkraises"
    label = "CheckRaises"

    def check_scene(self, scene):
        raise RuntimeError("check_scene blew up")


class DescribeRaisesPlant(_Hostile):
    """``describe`` raises."""

    engine = "describeraises"
    label = "DescribeRaises"

    def describe(self, settings):
        raise RuntimeError("describe blew up")


HOSTILE = (
    ExitPlant, SystemExitPlant, KilledPlant, SegfaultPlant, HangPlant, LiarPlant, MutatorPlant,
    BadShapePlant, NonePlant, CheckRaisesPlant, DescribeRaisesPlant,
)


def install(target: Path) -> Path:
    """Write ``tumble_hostile-0.1.0.dist-info`` declaring every plant of :data:`HOSTILE` into
    ``target`` (created); return ``target``, to put on ``PYTHONPATH``."""
    info = target / "tumble_hostile-0.1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: tumble-hostile\nVersion: 0.1.0\n")
    lines = "".join(f"{cls.engine} = {__name__}:{cls.__name__}\n" for cls in HOSTILE)
    (info / "entry_points.txt").write_text(f"[tumbling_testbed.plants]\n{lines}")
    return target
