"""A stage's wall-time limit when it runs in this process: a ``SIGALRM`` timer.

A stage in a worker process is ended by its parent past its limit (:mod:`validation.runs.workers`);
one run here is stopped by :func:`time_limited` at its next Python bytecode (a C call that never
returns cannot be). Either way the stage's outcome is :class:`OverTime`.
"""

from __future__ import annotations

import contextlib
import signal
import threading


class OverTime(RuntimeError):
    """A job passed its wall-time limit (``limit_s``, s) and was stopped."""

    def __init__(self, name: str, limit_s: float):
        super().__init__(f"{name}: over its time limit of {limit_s:g} s")
        self.name = name
        self.limit_s = limit_s


class _Alarm(BaseException):
    """The time limit's timer, in this process: a BaseException, so a task's ``except
    Exception`` does not swallow it (:func:`time_limited`)."""


@contextlib.contextmanager
def time_limited(name: str, limit_s: float | None):
    """The block stopped by :class:`OverTime` after ``limit_s`` s (a ``SIGALRM`` timer; main
    thread only, where ``setitimer`` exists and no one else's timer or ``SIGALRM`` handler is in
    place, such as a test runner's timeout, which is left alone: elsewhere the block runs as it
    is)."""
    usable = (
        limit_s is not None
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
        and signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
        and signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, None)
    )
    if not usable:
        yield
        return

    armed = [True]

    def over(signum, frame) -> None:
        if armed[0]:  # a signal delivered as the block ends is not raised in its cleanup
            raise _Alarm()

    previous = signal.signal(signal.SIGALRM, over)
    signal.setitimer(signal.ITIMER_REAL, limit_s)
    try:
        yield
    except _Alarm:
        raise OverTime(name, limit_s) from None
    finally:
        armed[0] = False
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


__all__ = ["OverTime", "time_limited"]
