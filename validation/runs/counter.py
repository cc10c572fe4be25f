"""A counted advance (``done`` of ``total``) shown as the display policy says: a tqdm bar with the
count and an ETA on a terminal, plain lines at a steady interval elsewhere, nothing when off.

Contract:

* :class:`Counter` ``(label, total, display=...)``: :meth:`~Counter.set` the amount done (or
  :meth:`~Counter.advance` it), :meth:`~Counter.close` at the end (also as a context manager).
  Every report first raises an interrupt compiled code swallowed
  (:func:`validation.runs.interrupts.raise_pending`), whatever the display.
* ``BAR`` (:class:`validation.runs.display.Mode`): one tqdm bar on the display's stream, drawn
  after the display's delay, with the count (``3/12 series``, or ``t = 5.00/20 s`` for simulated
  time), the elapsed time and tqdm's ETA; kept on screen at the end.
* ``PLAIN``: after the delay, one line at the first report, then one at the first report after
  each interval (:data:`validation.runs.display.PLAIN_INTERVAL_S`), each ``tumble: <label>:
  <count> (<percent>), <elapsed> elapsed, ETA <eta>``; at :meth:`~Counter.close` one last line
  (``done in`` or ``stopped at``) when any line was written. The ETA assumes the rate so far
  holds, ``elapsed × (total - done) / done`` (a run's simulated time: from its first report on);
  with a ``deadline_s`` (a campaign given minutes), the time left before it when that comes
  sooner. A caller that waits for work in a loop calls :meth:`~Counter.tick` while it waits, so
  a long item still shows time passing. No thread is started: the tool forks its workers only from a single-threaded process
  (:func:`validation.runs.workers.can_fork`), and a progress thread would make it run them here.
* ``OFF``: nothing is written.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from validation.runs.display import Display, Mode, current, write_line
from validation.runs.interrupts import raise_pending


def duration(seconds: float) -> str:
    """A wall time as a person reads it: ``4.2 s``, ``38 s``, ``3 min 05 s``, ``1 h 02 min``."""
    s = max(0.0, float(seconds))
    if s < 10:
        return f"{s:.1f} s"
    if s < 60:
        return f"{s:.0f} s"
    if s < 3600:
        m, r = divmod(round(s), 60)
        return f"{m} min {r:02d} s"
    h, r = divmod(round(s) // 60, 60)
    return f"{h} h {r:02d} min"


def items(unit: str) -> Callable[[float, float | None], str]:
    """The count as ``3/12 <unit>`` (``3 <unit>`` without a total)."""

    def fmt(done: float, total: float | None) -> str:
        count = f"{done:g}/{total:g}" if total is not None else f"{done:g}"
        return f"{count} {unit}".rstrip()

    return fmt


def simulated(done: float, total: float | None) -> str:
    """The count as simulated time, ``t = 5.000 / 20 s``."""
    return f"t = {done:.3f} / {total:g} s" if total is not None else f"t = {done:.3f} s"


def eta(elapsed: float, done: float, total: float | None) -> float | None:
    """Seconds left if the rate so far holds; ``None`` before any advance or without a total."""
    if total is None or done <= 0 or elapsed <= 0:
        return None
    return max(0.0, elapsed * (total - done) / done)


class Counter:
    """``done`` of ``total`` shown as ``display`` says (module docstring).

    Args:
        label: what advances (``sweep paper_example1``); the line's and the bar's name.
        total: the amount at the end (> 0), or ``None`` when unknown (no percentage, no ETA
            unless ``deadline_s``).
        unit: what is counted (``series``, ``scenes``); with ``fmt`` omitted, ``3/12 <unit>``.
        fmt: ``fmt(done, total) -> str``, the count in a plain line (:func:`items`,
            :func:`simulated`).
        display: the policy (default: :func:`validation.runs.display.current`).
        deadline_s: the work stops this many seconds after the start (``--minutes``).
        simulated_time: the bar shows ``t = done/total s`` (a run's simulated time).
        from_first_report: the ETA's rate is measured from the first report on, not from the
            start (a run's first report comes once its kernels are loaded and its worker has
            started, which is no simulation); before a second report the ETA is unknown.

    Raises:
        ValueError: a total that is not a positive number.
    """

    def __init__(
        self,
        label: str,
        total: float | None,
        *,
        unit: str = "",
        fmt: Callable[[float, float | None], str] | None = None,
        display: Display | None = None,
        deadline_s: float | None = None,
        simulated_time: bool = False,
        from_first_report: bool = False,
    ):
        if total is not None and not (isinstance(total, int | float) and total > 0):
            raise ValueError(f"total: must be a positive number or None (got {total!r})")
        self.label = label
        self.total = None if total is None else float(total)
        self.unit = unit
        self.simulated_time = simulated_time
        self.fmt = fmt or (simulated if simulated_time else items(unit))
        self.display = display if display is not None else current()
        self.deadline_s = deadline_s
        self.note = ""  # beside the count (the stages' own times): set with describe()
        self.bar_format: str | None = None  # the bar's layout instead of the default one
        self.done = 0.0
        self.start = self.display.clock()
        self.lines = 0
        self._last_line: float | None = None
        self._bar: Any = None  # the tqdm bar, made at the first report on a terminal
        self._closed = False
        self.from_first_report = from_first_report
        self._first: tuple[float, float] | None = None  # (clock, done) at the first report

    # reports -------------------------------------------------------------------------------

    def set(self, done: float) -> None:
        """The amount done is ``done`` (it may go back: a run that restarted its stage)."""
        raise_pending()  # an interrupt compiled code swallowed stops the work here
        if self._closed:
            return
        self.done = float(done)
        if self._first is None:
            self._first = (self.display.clock(), self.done)
        mode = self.display.mode
        if mode is Mode.BAR:
            self._draw()
        elif mode is Mode.PLAIN:
            self._maybe_line()

    def tick(self) -> None:
        """No advance, but time has passed: the plain line when one is due, the bar redrawn (a
        caller waiting for a long item calls it while it waits)."""
        raise_pending()
        if self._closed:
            return
        if self.display.mode is Mode.PLAIN:
            self._maybe_line()
        elif self.display.mode is Mode.BAR:
            self._draw()  # the bar's elapsed time and ETA move on

    def advance(self, n: float = 1) -> None:
        """``n`` more done."""
        self.set(self.done + n)

    def relabel(self, label: str) -> None:
        """Name the work ``label`` from now on (the stages running)."""
        self.label = label
        if self._bar is not None:
            self._bar.set_description_str(label, refresh=False)

    def describe(self, note: str) -> None:
        """Say ``note`` beside the count from now on (each stage's time reached)."""
        self.note = note
        if self._bar is not None:
            self._bar.set_postfix_str(note, refresh=False)

    def retotal(self, total: float) -> None:
        """The amount at the end is ``total`` from now on (more stages than first known)."""
        self.total = float(total)
        if self._bar is not None:
            self._bar.total = self.total

    # what is shown -------------------------------------------------------------------------

    def elapsed(self) -> float:
        return self.display.clock() - self.start

    def eta(self) -> float | None:
        """Seconds left (module docstring)."""
        elapsed = self.elapsed()
        if not self.from_first_report:
            left = eta(elapsed, self.done, self.total)
        elif self._first is None:
            left = None
        else:
            t0, d0 = self._first
            total = None if self.total is None else self.total - d0
            left = eta(self.display.clock() - t0, self.done - d0, total)
        if self.deadline_s is not None:
            by_deadline = max(0.0, self.deadline_s - elapsed)
            left = by_deadline if left is None else min(left, by_deadline)
        return left

    def line(self) -> str:
        """The plain line for now (without the prefix)."""
        said = [f"{100 * min(self.done / self.total, 1.0):.0f} %"] if self.total else []
        said += [self.note] if self.note else []
        parts = [self.fmt(self.done, self.total) + (f" ({'; '.join(said)})" if said else "")]
        parts.append(f"{duration(self.elapsed())} elapsed")
        left = self.eta()
        parts.append(f"ETA {duration(left)}" if left is not None else "ETA unknown")
        return f"{self.label}: " + ", ".join(parts)

    def _maybe_line(self, final: bool = False) -> None:
        now = self.display.clock()
        if now - self.start < self.display.delay_s and not (final and self.lines):
            return
        if final:
            if not self.lines:
                return
            count, took = self.fmt(self.done, self.total), duration(now - self.start)
            if self.total is None or self.done >= self.total:
                text = f"{self.label}: {count}, done in {took}"
            else:
                text = f"{self.label}: stopped at {count} after {took}"
        elif self.total is not None and self.done >= self.total:
            return  # the end: said by the closing line
        elif self._last_line is None or now - self._last_line >= self.display.interval_s:
            text = self.line()
        else:
            return
        self._last_line = now
        self.lines += 1
        write_line(f"{self.display.prefix}{text}", self.display)

    def _draw(self) -> None:
        if self._bar is None:
            self._bar = _tqdm_bar(self)
        bar = self._bar
        bar.update(self.done - bar.n)

    # the end -------------------------------------------------------------------------------

    def close(self, final_line: bool = True) -> None:
        """End the display: the bar kept on screen, or the last plain line (when any was
        written and ``final_line``: a caller with a closing line of its own passes False).
        Idempotent."""
        if self._closed:
            return
        self._closed = True
        if self._bar is not None:
            self._bar.close()
        elif self.display.mode is Mode.PLAIN and final_line:
            self._maybe_line(final=True)

    def __enter__(self) -> Counter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _tqdm_bar(c: Counter):
    """The tqdm bar of ``c`` on its display's stream, drawn after its delay."""
    import tqdm  # deferred: ~60 ms, and only a terminal draws a bar

    tqdm.tqdm.monitor_interval = 0  # no monitor thread: workers fork from one thread only
    if c.bar_format is not None:
        fmt = c.bar_format
    elif c.simulated_time:
        fmt = "{desc}: t = {n:.3f}/{total:g} s {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]"
    elif c.total is None:
        fmt = "{desc}: {n:g} " + c.unit + " [{elapsed}]"
    else:
        fmt = "{desc}: {n:g}/{total:g} " + c.unit + " {percentage:3.0f}%|{bar}| "
        fmt += "[{elapsed}<{remaining}]"
    return tqdm.tqdm(
        total=c.total,
        desc=c.label,
        file=c.display.out,
        delay=c.display.delay_s,
        leave=True,
        dynamic_ncols=True,
        mininterval=0.25,
        bar_format=fmt,
        unit=c.unit or "it",
        postfix=c.note or None,
    )


__all__ = ["Counter", "duration", "eta", "items", "simulated"]
