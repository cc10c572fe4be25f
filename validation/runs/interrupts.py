"""Ctrl-C and SIGTERM that are never lost, even when they arrive inside compiled code.

Every ``tumble`` command runs inside :func:`handled` (:func:`validation.cli.main`, installed before
any heavy import): SIGINT raises ``KeyboardInterrupt`` and SIGTERM :class:`Terminated` (a
``KeyboardInterrupt``), and the signal is *noted* for the rest of the block. The rest of this
module makes a noted signal end the command as INTERRUPTED whatever the code it lands in does
with the exception:

* Python runs a signal's handler in the main thread at the next bytecode; when that bytecode
  belongs to a Python function called back from C (llvmlite's object-cache callback while numba
  compiles or loads a kernel, MuJoCo's control callback), the interrupt ends the callback, and
  the C caller reports it as "Exception ignored" and goes on. :func:`handled` installs a
  ``sys.unraisablehook`` that keeps such an interrupt as *pending* instead of printing it, and
  :func:`raise_pending` raises it at the next safe point: every progress report
  (:mod:`validation.runs.progress`) calls it, so the run stops within one report of the signal.
* A C extension whose initialisation the interrupt cuts (MuJoCo's, pybind11's, while it imports
  its Python parts) raises ``ImportError: initialization failed`` instead; any other exception
  raised once a signal was noted is the signal's consequence too. :func:`interrupt_of` gives the
  interrupt such an exception stands for: the command's dispatch, the output directory's commit
  (:func:`validation.runs.outputs.output_run`) and code that turns exceptions into results (a
  hard case's ERROR row, a plugin left out) ask it first.
* A plant keeps the samples it reached when interrupted and returns them: code that does not
  re-raise (``Trajectory.raise_if_interrupted``) would go on. :func:`received` stays true, so the
  output directory is committed INTERRUPTED and the command exits 130 / 143 all the same.

:func:`received_sigterm` tells the exit status apart (143 vs 130) after code that catches the
interrupt has re-raised a plain ``KeyboardInterrupt``.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C: the run stops, its partial results are kept."""


_pending: KeyboardInterrupt | None = None
"""An interrupt swallowed by a C caller of a Python callback, to be raised at the next safe
point (:func:`raise_pending`)."""

_sigterm = False
"""Set when SIGTERM arrived (the exit status is decided from it)."""

_received = False
"""Set when SIGINT or SIGTERM arrived inside :func:`handled` (or was noted by another handler)."""


def note(signum: int) -> None:
    """Record that ``signum`` (SIGINT or SIGTERM) arrived; a handler other than this module's
    that catches the signal calls it, so that the command still ends as interrupted."""
    global _sigterm, _received
    _received = True
    if signum == signal.SIGTERM:
        _sigterm = True


def note_sigterm() -> None:
    """Record that SIGTERM arrived (a handler other than this module's caught it)."""
    note(signal.SIGTERM)


def _on_signal(signum, frame):
    note(signum)
    raise Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def _keeping_interrupts(previous):
    def hook(unraisable) -> None:
        global _pending
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            _pending = unraisable.exc_value
            return
        previous(unraisable)

    hook.keeps_interrupts = True
    return hook


def keep_swallowed() -> None:
    """For the rest of this process, keep an interrupt a C caller swallowed for
    :func:`raise_pending` (a worker process, :mod:`validation.runs.workers`; :func:`handled` does it
    for a block of the main process)."""
    if not getattr(sys.unraisablehook, "keeps_interrupts", False):
        sys.unraisablehook = _keeping_interrupts(sys.unraisablehook)


def interrupt_name() -> str:
    """``SIGTERM`` or ``Ctrl-C``: what stopped the run, for a report."""
    return "SIGTERM" if _sigterm else "Ctrl-C"


def raise_pending() -> None:
    """Raise the interrupt a C caller swallowed, if any (once); a no-op otherwise."""
    global _pending
    exc, _pending = _pending, None
    if exc is not None:
        raise exc


def checkpoint(t: float | None = None) -> None:
    """A plant's ``progress(t)`` for a run that reports to nobody: raises the interrupt a C caller
    swallowed (:func:`raise_pending`), and a new one once a signal was received at all (code
    that caught it went on: this run was started after it), so that such a run stops within one
    report of the signal (the plant returns the samples it reached, marked interrupted)."""
    raise_pending()
    if _received:
        raise interrupt()


def pending() -> bool:
    """Whether an interrupt was swallowed and has not been raised again yet."""
    return _pending is not None


def received() -> bool:
    """Whether SIGINT or SIGTERM arrived since :func:`handled` was entered (raised, swallowed by
    compiled code, or turned into an interrupted run's result: the run is interrupted in any
    case)."""
    return _received or _pending is not None


def received_sigterm() -> bool:
    """Whether SIGTERM arrived since :func:`handled` was entered."""
    return _sigterm


def interrupt() -> KeyboardInterrupt:
    """A new interrupt of the signal that arrived: :class:`Terminated` after SIGTERM."""
    return Terminated() if _sigterm else KeyboardInterrupt()


def interrupt_of(exc: BaseException) -> KeyboardInterrupt | None:
    """The interrupt ``exc`` stands for, or ``None`` when it is a fault of its own.

    ``exc`` itself when it is a ``KeyboardInterrupt``; one it was raised from or while handling
    (its ``__cause__`` / ``__context__`` chain: ``ImportError: initialization failed`` from a C
    extension whose initialisation a signal cut); and, once a signal arrived inside
    :func:`handled`, any exception at all (a new :func:`interrupt`, its cause ``exc``): code that
    fails after the signal fails because of it."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return e
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    if received():
        ki = interrupt()
        ki.__cause__ = exc
        return ki
    return None


def raise_if_interrupt(exc: BaseException) -> None:
    """Raise the interrupt ``exc`` stands for (:func:`interrupt_of`), if any; a no-op otherwise.
    For code that turns exceptions into results and goes on (``except Exception``)."""
    ki = interrupt_of(exc)
    if ki is exc:
        raise ki
    if ki is not None:
        raise ki from exc


@contextmanager
def handled() -> Iterator[None]:
    """SIGINT raises ``KeyboardInterrupt`` and SIGTERM :class:`Terminated`, each noted for
    :func:`received` (SIGINT left ignored where the process was started with it ignored, as
    Python itself does), and interrupts swallowed by C callers are kept for :func:`raise_pending`,
    inside the block; the previous handlers, hook and state come back after it. Main thread only
    (Python's rule for signal handlers)."""
    global _pending, _sigterm, _received
    _pending, _sigterm, _received = None, False, False
    previous_term = signal.signal(signal.SIGTERM, _on_signal)
    previous_int = signal.getsignal(signal.SIGINT)
    take_int = previous_int not in (signal.SIG_IGN, None)  # None: set outside Python, left as is
    if take_int:
        signal.signal(signal.SIGINT, _on_signal)
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _keeping_interrupts(previous_hook)
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        if take_int:
            signal.signal(signal.SIGINT, previous_int)
        signal.signal(signal.SIGTERM, previous_term)
        _pending, _sigterm, _received = None, False, False


@contextmanager
def signals_held(on_signal: Callable[[], None] | None = None, raise_after: bool = True):
    """SIGINT and SIGTERM do not cut the block: an import cut by Ctrl-C half way leaves a module
    half made (matplotlib then fails on its next import), so a preparing import finishes first
    and the interrupt (:class:`Terminated` for SIGTERM) is raised after it (unless not
    ``raise_after``: the caller reads the list the block is given, the signals caught so far, and
    acts on it itself).

    The signal is not blocked, only noted: ``on_signal()`` runs as soon as it arrives (telling the
    plants' workers to stop), so the job stops promptly. Main thread only; elsewhere the block
    runs as it is."""
    caught: list[int] = []

    def held_note(signum, frame) -> None:
        first = not caught
        caught.append(signum)
        if signum == signal.SIGTERM:
            note_sigterm()
        if first and on_signal is not None:
            with suppress(Exception):
                on_signal()

    held = (signal.SIGINT, signal.SIGTERM)
    try:
        previous = {sig: signal.signal(sig, held_note) for sig in held}
    except ValueError:  # not the main thread: no handlers to set
        yield caught
        return
    try:
        yield caught
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if caught and raise_after:
        raise Terminated() if signal.SIGTERM in caught else KeyboardInterrupt()
