"""Progress on stderr for runs that take more than a few seconds.

* :class:`Progress`: ``progress(t)`` of one run; on a terminal a single updating line
  (``label: t / t_end s (%)``), silent when stderr is not a terminal (``tumble simulate``).
* :class:`StageProgress`: ``progress(stage, t)`` of a run in stages (``tumble validate``'s plants);
  on a terminal the same single updating line, naming the stage; elsewhere (a pipe, a log file,
  CI) one plain line when each stage starts and one when the last one ends, without carriage
  returns.
* :class:`Status`: free-text events (the kernels' compilation, :mod:`validation.runs.warmup`), one line
  each.

Each report is also where an interrupt that compiled code swallowed is raised again
(:func:`validation.runs.interrupts.raise_pending`).

Lines written when stderr is not a terminal start with ``tumble: `` so they read apart from the
results on stdout and from warnings (``tumble: warning: ...``).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping

from validation.runs.interrupts import raise_pending

PREFIX = "tumble: "


def _is_tty(stream) -> bool:
    return bool(getattr(stream, "isatty", lambda: False)())


class Progress:
    """Callable ``progress(t)`` printing ``label: t / t_end s`` at most a few times per second.

    Prints nothing when stderr is not a terminal, or before ``delay`` seconds have passed.
    """

    def __init__(self, label: str, t_end: float, delay: float = 2.0, stream=None):
        self.label = label
        self.t_end = t_end
        self.delay = delay
        self.stream = stream or sys.stderr
        self.enabled = _is_tty(self.stream)
        self.start = time.monotonic()
        self.last = 0.0
        self.shown = False

    def __call__(self, t: float) -> None:
        raise_pending()  # an interrupt compiled code swallowed stops the run here
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self.start < self.delay or now - self.last < 0.25:
            return
        self.last = now
        self.shown = True
        frac = min(max(t / self.t_end, 0.0), 1.0) if self.t_end > 0 else 1.0
        self.stream.write(f"\r{self.label}: t = {t:8.3f} / {self.t_end:g} s ({100 * frac:5.1f} %)")
        self.stream.flush()

    def close(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()


def plant_title(stage: str) -> str:
    """How a progress line names the stage ``stage`` when it is a plant, "" when it is not: every
    registered plant, built-in or plugin (:func:`mj_bridge.plants.registered`), is
    ``<name> plant``, followed by its ``label`` in parentheses where the label says more than the
    name (``newton plant (Newton-Euler)``; ``mujoco plant`` for MuJoCo)."""
    from mj_bridge.plants import registered  # loaded already by the run that reports

    cls = registered().get(str(stage))
    if cls is None:
        return ""
    label = str(cls.label)
    return f"{stage} plant" if label.lower() == str(stage).lower() else f"{stage} plant ({label})"


class StageProgress:
    """Callable ``progress(stage, t)`` for a run made of stages (each plant of ``tumble validate``).

    Args:
        label: what runs (``validate paper_example1``).
        t_end: the horizon every plant simulates, s.
        stream: default stderr.
        delay: on a terminal, nothing is drawn before this many seconds (short runs stay quiet).

    Not a terminal: one line when a stage starts (``tumble: <label>: analytic plant, 0 -> 20 s``;
    a plant plugin as :func:`plant_title` names it)
    and, at :meth:`close`, one line with each stage's wall time (from its first to its last
    report). On a terminal: one updating line.
    """

    def __init__(self, label: str, t_end: float, stream=None, delay: float = 2.0):
        self.label = label
        self.t_end = t_end
        self.stream = stream or sys.stderr
        self.tty = _is_tty(self.stream)
        self.bar = Progress(label, t_end, delay=delay, stream=self.stream)
        self.walls: dict[str, float] = {}
        self._started: dict[str, float] = {}
        self._reached: dict[str, float] = {}
        self._last: str | None = None

    def __call__(self, stage: str, t: float) -> None:
        """Stage ``stage`` has reached simulated time ``t``; stages may run side by side (their
        reports interleave), each is announced once."""
        now = time.monotonic()
        if stage not in self._started:
            self._started[stage] = now
            if not self.tty:
                title = plant_title(stage)
                what = f"{title}, 0 -> {self.t_end:g} s" if title else stage
                self.stream.write(f"{PREFIX}{self.label}: {what}\n")
                self.stream.flush()
        self.walls[stage] = now - self._started[stage]
        self._reached[stage] = t
        self._last = stage
        running = [s for s, r in self._reached.items() if r < self.t_end]
        shown = running or [stage]
        self.bar.label = f"{self.label} [{', '.join(shown)}]"
        self.bar(min(self._reached[s] for s in shown))

    @property
    def stage(self) -> str | None:
        """The stage reported last (None before any report)."""
        return self._last

    def close(self, walls: Mapping[str, float] | None = None, stopped: bool = False) -> None:
        """End the display; not on a terminal, one line: each stage's wall time, ``walls`` where
        given (the stages' own measurements: stages in worker processes report through pipes
        read in bursts, so first-to-last report can badly understate them), else from each
        stage's first to its last report; but when the run ``stopped`` (an interrupt, a full
        disk) or a stage fell short of the horizon, the simulated time each stage reached
        instead of a wall time."""
        self.bar.close()
        if self.walls and not self.tty:
            short = any(t < self.t_end for t in self._reached.values())
            if not (stopped or short):
                if walls:
                    self.walls.update({s: float(w) for s, w in walls.items() if s in self.walls})
                times = ", ".join(f"{s} {w:.3g} s" for s, w in self.walls.items())
                line = f"stages done ({times})"
            else:
                reached = ", ".join(f"{s} t = {t:.6g} s" for s, t in self._reached.items())
                line = f"stages stopped (reached: {reached})"
            self.stream.write(f"{PREFIX}{self.label}: {line}\n")
            self.stream.flush()
        self.walls = {}
        self._started = {}
        self._reached = {}
        self._last = None


class Status:
    """Free-text progress events, ``status(text)``, one line each (the kernels' compilation is a
    few events, each worth keeping on screen); prefixed ``tumble: `` when the stream is not a
    terminal."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.tty = _is_tty(self.stream)

    def __call__(self, text: str) -> None:
        raise_pending()
        self.stream.write(f"{'' if self.tty else PREFIX}{text.rstrip()}\n")
        self.stream.flush()

    def close(self) -> None:
        """Nothing to finish (kept for symmetry with the other reporters)."""
