"""Where and how progress is shown: one policy per command, chosen once, read by every reporter.

Contract:

* :class:`Display` is the policy: its :class:`Mode` (``BAR``: tqdm bars on a terminal; ``PLAIN``:
  plain ``tumble: `` lines at a steady interval, for a pipe, a log file, CI; ``OFF``: nothing),
  the stream (``None``: ``sys.stderr`` as it is when written, so pytest's capture sees it), the
  interval between plain lines, the delay before anything is shown, and the clock (injected by
  tests).
* :func:`for_stream` chooses the mode from the stream (a terminal or not) and ``quiet``; it is
  the only place that asks ``isatty``.
* :func:`current` is the policy in force: ``OFF`` unless a caller set one with :func:`showing`
  (the ``tumble`` command line does, for the command's duration), so library calls stay silent
  unless asked.
* :func:`write_line` writes one whole line to the display's stream under one lock, through tqdm
  when bars are on that stream (the bars are cleared and drawn again below the line); the lock is
  held across ``fork`` (:func:`os.register_at_fork`), so a worker forked while another thread
  writes never inherits a held stream lock. Nothing here starts a thread.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import TextIO

PREFIX = "tumble: "
"""The start of every line written when the stream is not a terminal, so the tool's lines read
apart from the results on stdout."""

PLAIN_INTERVAL_S = 10.0
"""Seconds between two plain progress lines (not a terminal): a CI log shows the work advancing
without a line per report (a run reports hundreds of times a second)."""

START_DELAY_S = 2.0
"""Nothing is shown before this many seconds (on a terminal or not): a short run stays quiet, as
every test of one-line output expects, and a long one shows its first line soon enough."""


class Mode(StrEnum):
    """How progress is shown."""

    BAR = "bar"  # a terminal: tqdm bars with counts and an ETA
    PLAIN = "plain"  # not a terminal: plain lines at a steady interval, no carriage return
    OFF = "off"  # nothing (--quiet, or a library caller that asked for nothing)


@dataclass(frozen=True)
class Display:
    """A progress policy (module docstring).

    Attributes:
        mode: bars, plain lines or nothing.
        stream: where lines go; ``None`` for ``sys.stderr`` as it is when a line is written.
        interval_s: between two plain lines, s (> 0).
        delay_s: before the first line or bar, s (≥ 0).
        clock: monotonic seconds (``time.monotonic``; a test's fake clock).
    """

    mode: Mode = Mode.OFF
    stream: TextIO | None = None
    interval_s: float = PLAIN_INTERVAL_S
    delay_s: float = START_DELAY_S
    clock: Callable[[], float] = field(default=time.monotonic, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.mode, Mode):
            raise ValueError(f"mode: must be a Mode (got {self.mode!r})")
        if not self.interval_s > 0:
            raise ValueError(f"interval_s: must be positive (got {self.interval_s!r})")
        if not self.delay_s >= 0:
            raise ValueError(f"delay_s: must be ≥ 0 (got {self.delay_s!r})")

    @property
    def out(self) -> TextIO:
        """The stream lines are written to now."""
        return self.stream if self.stream is not None else sys.stderr

    @property
    def prefix(self) -> str:
        """``tumble: `` off a terminal, nothing on one (a terminal's lines are read by a person
        who knows which program runs)."""
        return "" if self.mode is Mode.BAR else PREFIX

    def with_(self, **changes) -> Display:
        """This policy with ``changes`` (``dataclasses.replace``)."""
        return replace(self, **changes)


def is_terminal(stream: object) -> bool:
    """Whether ``stream`` is a terminal (``False`` for anything without ``isatty``)."""
    try:
        return bool(getattr(stream, "isatty", lambda: False)())
    except (OSError, ValueError):  # a closed stream
        return False


def for_stream(stream: TextIO | None = None, *, quiet: bool = False, **settings) -> Display:
    """The policy for ``stream`` (default stderr): bars on a terminal, plain lines elsewhere,
    nothing when ``quiet``; ``settings`` as :class:`Display`'s fields."""
    if quiet:
        mode = Mode.OFF
    else:
        mode = Mode.BAR if is_terminal(stream if stream is not None else sys.stderr) else Mode.PLAIN
    return Display(mode, stream, **settings)


_STACK: list[Display] = [Display()]
"""The policies set by :func:`showing`, innermost last; the first is ``OFF`` (a module global,
not a context variable: the reporters of a command also run in its helper threads)."""


def current() -> Display:
    """The policy in force (``OFF`` unless a caller set one with :func:`showing`)."""
    return _STACK[-1]


@contextlib.contextmanager
def showing(display: Display) -> Iterator[Display]:
    """``display`` in force inside the block (nested blocks restore the outer one)."""
    if not isinstance(display, Display):
        raise ValueError(f"display: must be a Display (got {display!r})")
    _STACK.append(display)
    try:
        yield display
    finally:  # this block's entry (by identity: another policy may equal it)
        del _STACK[max(i for i, d in enumerate(_STACK) if d is display)]


_LOCK = threading.Lock()
"""Held while a line is written: lines from two threads never interleave."""


def _reset_lock_in_child() -> None:
    global _LOCK
    _LOCK = threading.Lock()


if hasattr(os, "register_at_fork"):  # held across fork: a child never inherits it held
    os.register_at_fork(
        before=lambda: _LOCK.acquire(),
        after_in_parent=lambda: _LOCK.release(),
        after_in_child=_reset_lock_in_child,
    )


def write_line(text: str, display: Display | None = None) -> None:
    """One line ``text`` (no newline in it) on the display's stream, whatever its mode; through
    tqdm when its bars may be on screen there, so they are drawn again below the line."""
    d = display if display is not None else current()
    stream = d.out
    with _LOCK:
        tqdm_module = sys.modules.get("tqdm") if d.mode is Mode.BAR else None
        try:
            if tqdm_module is not None:  # loaded only when a bar was made (import ~60 ms)
                tqdm_module.tqdm.write(text, file=stream)
            else:
                stream.write(f"{text}\n")
            stream.flush()
        except (OSError, ValueError):  # a closed or broken stream: progress is not the result
            pass


__all__ = [
    "PLAIN_INTERVAL_S",
    "PREFIX",
    "START_DELAY_S",
    "Display",
    "Mode",
    "current",
    "for_stream",
    "is_terminal",
    "showing",
    "write_line",
]
