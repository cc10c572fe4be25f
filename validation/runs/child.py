"""The worker process's side of a job (:mod:`validation.runs.workers`): what a forked or served
child does from its start to its last message.

A child ends with its parent and with the process that asked a fork server for it
(:mod:`validation.runs.lifetime`); closes the parent's ends of every worker's pipes; honours the
first SIGINT or SIGTERM and ignores the ones after it (an interrupt compiled code swallows is kept
for the task's next progress report, :mod:`validation.runs.interrupts`); prepares (at idle priority
when asked, :mod:`validation.runs.priority`), waits for its inputs when they come later, runs the
task and sends back, on its one pipe, ``("msg", message)`` for each report, then one outcome:
``("ok", result)``, ``("err", type name, first line, interrupted)`` or, for a file it could not
write, ``("output", path, reason, errno)``.
"""

from __future__ import annotations

import signal
from typing import Any

from validation.runs.atomic import OutputError
from validation.runs.interrupts import keep_swallowed
from validation.runs.lifetime import die_with, die_with_parent
from validation.runs.priority import set_idle

LATER = object()
"""A job's inputs, before they are given (:meth:`validation.runs.workers.Job.give`)."""

PARENT_ENDS: list[Any] = []
"""The parent's ends of every worker's pipes (results in, inputs out). A child closes its copies
first thing: else a child whose parent is gone would wait forever for inputs (a sibling holding
the write end) or block writing its result into a pipe it holds the read end of."""


def one_line(exc: BaseException) -> str:
    """The first line of ``exc``'s message ("" for none)."""
    return str(exc).splitlines()[0] if str(exc) else ""


def _close_parent_ends() -> None:  # pragma: no cover - in a child
    for end in PARENT_ENDS:
        try:
            end.close()
        except OSError:
            pass
    PARENT_ENDS.clear()


def _first_interrupt_only(signum, frame):  # pragma: no cover - in a child
    """A child's SIGINT/SIGTERM handler: the first one interrupts the task, the later ones are
    ignored (the partial result is being sent)."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    raise KeyboardInterrupt("interrupted")


def _child_signals() -> None:  # pragma: no cover - in a child
    """The child's signal handling (module docstring): the first interrupt counts, once, and one
    that compiled code swallows is kept for the task's next progress report."""
    keep_swallowed()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _first_interrupt_only)


def _send_error(conn, exc: BaseException) -> None:  # pragma: no cover - in a child
    """Send the task's exception: an interrupt as interrupted, a file that could not be written
    as an ``OutputError`` (path and reason), anything else by its type name and first line."""
    if isinstance(exc, KeyboardInterrupt):
        msg = ("err", type(exc).__name__, one_line(exc) or "interrupted", True)
    elif isinstance(exc, OutputError):
        msg = ("output", str(exc.path), exc.reason, exc.errno)
    else:
        msg = ("err", type(exc).__name__, one_line(exc), False)
    try:
        conn.send(msg)
    except Exception:  # the parent is gone
        pass


def child_main(
    conn, inbox, prepare, task, args, idle: bool, parent: int | None, client: int | None = None
) -> None:  # pragma: no cover - in a child
    """The worker process: prepare, wait for the inputs if they come later, run, send back. It
    ends with ``parent`` (its parent's pid, :func:`validation.runs.lifetime.die_with_parent`;
    None: armed at the fork already, a fork server's child) and with ``client`` (the process
    that asked the fork server for it, :func:`validation.runs.lifetime.die_with`)."""
    if parent is not None:
        die_with_parent(parent)
    if client is not None:
        die_with(client)
    _close_parent_ends()
    _child_signals()
    try:
        if idle:
            set_idle(True)
        if prepare is not None:
            prepare()
        if args is LATER:
            args = inbox.recv()
            if args is None:  # the parent gave up on this job
                return
        if idle:
            set_idle(False)
        out = task(*args, report=lambda msg: conn.send(("msg", msg)))
        for sig in (signal.SIGINT, signal.SIGTERM):  # a late interrupt must not lose the result
            signal.signal(sig, signal.SIG_IGN)
        conn.send(("ok", out))
    except BaseException as exc:  # an interrupt before a result, or the task's error
        _send_error(conn, exc)
    finally:
        try:
            conn.close()
        except Exception:
            pass


__all__ = ["LATER", "PARENT_ENDS", "child_main", "one_line"]
