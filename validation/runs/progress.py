"""Progress on stderr for runs that take more than a few seconds, with counts and an ETA.

* :class:`Progress`: ``progress(t)`` of one run (``tumble simulate``): the simulated time reached
  of the horizon.
* :class:`StageProgress`: ``progress(stage, t)`` of a run in stages (``tumble validate``'s
  plants, side by side): the stages' simulated time together, of the stages' horizons.
* :class:`RunsProgress`: runs of one horizon one after the other (``tumble reference``'s two,
  ``tumble demo``'s steps), counted together.
* :class:`Status`: free-text events (the kernels' compilation, :mod:`validation.runs.warmup`),
  one line each.
* :class:`ItemsProgress`: ``progress(item, i, total)`` before each item (``tumble
  hard-cases``' cases).
* :func:`counter`: any other counted work (a study's series, a campaign's scenes, the hard
  cases): a :class:`validation.runs.counter.Counter` under the display in force.

How each is shown is the display policy's (:mod:`validation.runs.display`, chosen once per
command, ``--quiet`` included): on a terminal a tqdm bar with the count and its ETA; elsewhere (a
pipe, a log file, CI) plain lines starting ``tumble: `` at a steady interval
(:data:`~validation.runs.display.PLAIN_INTERVAL_S`), each with the count, the elapsed time and
the ETA, without carriage returns; nothing when the display is off. A reporter given a
``stream`` decides for that stream itself (bars when it is a terminal, plain lines otherwise);
one given none follows the display in force, which is off unless a caller set one (the command
line does), so library calls stay silent.

Each report is also where an interrupt that compiled code swallowed is raised again
(:func:`validation.runs.interrupts.raise_pending`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TextIO

from validation.runs.counter import Counter
from validation.runs.display import PREFIX, Display, Mode, current, for_stream, write_line
from validation.runs.interrupts import checkpoint, raise_pending


def _display(stream: TextIO | None, delay: float | None) -> Display:
    """The policy for a reporter: its own stream's, or the one in force; ``delay`` overriding."""
    d = for_stream(stream) if stream is not None else current()
    return d if delay is None else d.with_(delay_s=delay)


def counter(
    label: str,
    total: float | None,
    unit: str = "",
    *,
    deadline_s: float | None = None,
    simulated_time: bool = False,
) -> Counter:
    """A :class:`~validation.runs.counter.Counter` of ``total`` ``unit`` (``series``, ``scenes``)
    under the display in force (silent unless a caller set one); use it as a context manager."""
    return Counter(label, total, unit=unit, deadline_s=deadline_s, simulated_time=simulated_time)


class ItemsProgress:
    """Callable ``progress(item, i, total)`` before each of ``total`` items (the hard cases): the
    items done counted (``3/14 cases``), the one running named; :meth:`close` ``(done)`` at the
    end, the count's last line.

    Args:
        label: what runs (``hard cases``).
        unit: what is counted (``cases``).
    """

    def __init__(self, label: str, unit: str):
        self.label, self.unit = label, unit
        self.counter: Counter | None = None  # made before the first item (its total known)

    def __call__(self, item: str, i: int, total: int) -> None:
        if self.counter is None:
            self.counter = counter(self.label, total, self.unit)
        self.counter.relabel(f"{self.label} [{item}]")
        self.counter.set(i)

    def close(self, done: int | None = None) -> None:
        """End the display; ``done``: the items done by then (default: as last reported)."""
        if self.counter is not None:
            if done is not None:
                self.counter.set(done)
            self.counter.close()


class Progress:
    """Callable ``progress(t)``: the simulated time ``t`` reached of ``t_end`` (module docstring).

    Args:
        label: what runs (``simulate paper_example1``).
        t_end: the horizon, s.
        delay: nothing is shown before this many seconds (default the display's).
        stream: decide for this stream (default: the display in force).
    """

    def __init__(
        self, label: str, t_end: float, delay: float | None = None, stream: TextIO | None = None
    ):
        self.label = label
        self.t_end = t_end
        self.counter = Counter(
            label,
            t_end if t_end > 0 else None,
            display=_display(stream, delay),
            simulated_time=True,
            from_first_report=True,
        )

    @property
    def enabled(self) -> bool:
        """Whether anything may be shown."""
        return self.counter.display.mode is not Mode.OFF

    def __call__(self, t: float) -> None:
        self.counter.set(min(max(float(t), 0.0), self.t_end) if self.t_end > 0 else float(t))

    def close(self) -> None:
        self.counter.close()


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


class RunsProgress:
    """Several runs of one horizon one after the other (a reference pack's two runs, the demo's
    steps), counted together: :meth:`run` ``(k)`` is run ``k``'s ``progress(t)``, :meth:`next` the
    next run's, each also :func:`validation.runs.interrupts.checkpoint` (a run started after a
    signal that code caught and went on from stops at its first report); the count reads
    ``run 2/5, t = 3.000 / 10 s``; use it as a context manager.

    Raises:
        ValueError: ``runs`` not a whole number ≥ 1, or ``t_end`` not positive.
    """

    def __init__(self, label: str, t_end: float, runs: int, stream: TextIO | None = None):
        if not isinstance(runs, int) or runs < 1:
            raise ValueError(f"runs: must be a whole number ≥ 1 (got {runs!r})")
        if not t_end > 0:
            raise ValueError(f"t_end: must be positive (got {t_end!r})")
        self.t_end, self.runs = float(t_end), runs

        def fmt(done: float, _total: float | None) -> str:
            k = min(int(done // self.t_end), runs - 1)
            return f"run {k + 1}/{runs}, t = {done - k * self.t_end:.3f} / {self.t_end:g} s"

        self.counter = Counter(
            label,
            runs * self.t_end,
            fmt=fmt,
            display=_display(stream, None),
            from_first_report=True,
        )

    def next(self):
        """The next run's ``progress(t)`` (the first call: run 0's)."""
        self._next = getattr(self, "_next", -1) + 1
        return self.run(self._next)

    def run(self, k: int):
        """Run ``k``'s (from 0) ``progress(t)``."""

        def progress(t: float) -> None:
            checkpoint()  # these runs report to nobody else: a received signal stops them here
            self.counter.set(k * self.t_end + min(max(float(t), 0.0), self.t_end))

        return progress

    def close(self) -> None:
        self.counter.close()

    def __enter__(self) -> RunsProgress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class StageProgress:
    """Callable ``progress(stage, t)`` for a run made of stages (each plant of ``tumble validate``).

    Args:
        label: what runs (``validate paper_example1``).
        t_end: the horizon every plant simulates, s.
        stream: decide for this stream (default: the display in force).
        delay: nothing is drawn before this many seconds (default the display's).
        stages: how many stages will run (the count's total is ``stages × t_end``); default the
            stages reported so far.

    The count is the stages' simulated time together, of ``stages × t_end``; its ETA assumes the
    rate so far holds. Not a terminal: one line when a stage starts (``tumble: <label>: analytic
    plant, 0 -> 20 s``; a plant plugin as :func:`plant_title` names it), the count's plain lines
    at the interval (each stage's time reached beside it) and, at :meth:`close`, one line with
    each stage's wall time. On a terminal: one bar, named after the stages running.
    """

    def __init__(
        self,
        label: str,
        t_end: float,
        stream: TextIO | None = None,
        delay: float | None = None,
        stages: int | None = None,
    ):
        if stages is not None and (not isinstance(stages, int) or stages < 1):
            raise ValueError(f"stages: must be a whole number ≥ 1 or None (got {stages!r})")
        self.label = label
        self.t_end = t_end
        self.stages = stages
        self.display = _display(stream, delay)
        self.counter: Counter | None = None  # made at the first report (its clock starts then)
        self.walls: dict[str, float] = {}
        self._started: dict[str, float] = {}
        self._reached: dict[str, float] = {}
        self._last: str | None = None

    def _counter(self, n: int) -> Counter:
        def fmt(done: float, total: float | None) -> str:
            return f"{done:.3g} of {total:g} plant-seconds"

        total = n * self.t_end if self.t_end > 0 else None
        c = Counter(self.label, total, display=self.display, from_first_report=True)
        c.fmt = fmt
        c.bar_format = "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}{postfix}]"
        return c

    @property
    def tty(self) -> bool:
        return self.display.mode is Mode.BAR

    def __call__(self, stage: str, t: float) -> None:
        """Stage ``stage`` has reached simulated time ``t``; stages may run side by side (their
        reports interleave), each is announced once."""
        raise_pending()
        now = self.display.clock()
        if self.counter is None:
            self.counter = self._counter(self.stages or 1)
        if stage not in self._started:
            self._started[stage] = now
            if self.display.mode is Mode.PLAIN:
                title = plant_title(stage)
                what = f"{title}, 0 -> {self.t_end:g} s" if title else stage
                write_line(f"{PREFIX}{self.label}: {what}", self.display)
            if self.stages is None and self.t_end > 0:  # the total grows with each stage seen
                self.counter.retotal(len(self._started) * self.t_end)
        self.walls[stage] = now - self._started[stage]
        self._reached[stage] = t
        self._last = stage
        running = [s for s, r in self._reached.items() if r < self.t_end]
        self.counter.relabel(f"{self.label} [{', '.join(running or [stage])}]")
        self.counter.describe(", ".join(f"{s} {r:.3g} s" for s, r in self._reached.items()))
        self.counter.set(sum(min(r, self.t_end) for r in self._reached.values()))

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
        if self.counter is not None:
            self.counter.close(final_line=False)  # the line below says more
            self.counter = None
        if self.walls and self.display.mode is Mode.PLAIN:
            short = any(t < self.t_end for t in self._reached.values())
            if not (stopped or short):
                if walls:
                    self.walls.update({s: float(w) for s, w in walls.items() if s in self.walls})
                times = ", ".join(f"{s} {w:.3g} s" for s, w in self.walls.items())
                line = f"stages done ({times})"
            else:
                reached = ", ".join(f"{s} t = {t:.6g} s" for s, t in self._reached.items())
                line = f"stages stopped (reached: {reached})"
            write_line(f"{PREFIX}{self.label}: {line}", self.display)
        self.walls = {}
        self._started = {}
        self._reached = {}
        self._last = None


class Status:
    """Free-text progress events, ``status(text)``, one line each (the kernels' compilation is a
    few events, each worth keeping on screen); prefixed ``tumble: `` when the stream is not a
    terminal; nothing when the display is off (``--quiet``).

    Args:
        stream: decide for this stream (default: the display in force).
    """

    def __init__(self, stream: TextIO | None = None):
        self.display = _display(stream, None)

    @property
    def tty(self) -> bool:
        return self.display.mode is Mode.BAR

    def __call__(self, text: str) -> None:
        raise_pending()
        if self.display.mode is not Mode.OFF:
            write_line(f"{self.display.prefix}{text.rstrip()}", self.display)

    def close(self) -> None:
        """Nothing to finish (kept for symmetry with the other reporters)."""


__all__ = [
    "ItemsProgress",
    "Progress",
    "RunsProgress",
    "StageProgress",
    "Status",
    "counter",
    "plant_title",
]
