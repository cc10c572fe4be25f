"""Ctrl-C and SIGTERM that are never lost, even when they arrive inside compiled code.

Python runs a signal's handler in the main thread at the next bytecode; when that bytecode
belongs to a Python function called back from C (llvmlite's object-cache callback while numba
compiles or loads a kernel, MuJoCo's control callback), the ``KeyboardInterrupt`` the handler
raises ends the callback, and the C caller reports it as "Exception ignored" and goes on: the
run would finish as if nobody had asked it to stop. :func:`handled` installs a
``sys.unraisablehook`` that keeps such an interrupt as *pending* instead of printing it, and
:func:`raise_pending` raises it at the next safe point: every progress report
(:mod:`validation.runs.progress`) calls it, so the run stops within one report of the signal.

SIGTERM is handled like Ctrl-C (:class:`Terminated`, a ``KeyboardInterrupt``): the run stops and
its partial results are kept; :func:`received_sigterm` tells the exit status apart (143 vs 130)
after code that catches the interrupt has re-raised a plain ``KeyboardInterrupt``.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like Ctrl-C: the run stops, its partial results are kept."""


_pending: KeyboardInterrupt | None = None
"""An interrupt swallowed by a C caller of a Python callback, to be raised at the next safe
point (:func:`raise_pending`)."""

_sigterm = False
"""Set by the SIGTERM handler (the exit status is decided from it)."""


def _on_sigterm(signum, frame):
    global _sigterm
    _sigterm = True
    raise Terminated


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


def note_sigterm() -> None:
    """Record that SIGTERM arrived (a handler other than this module's caught it)."""
    global _sigterm
    _sigterm = True


def interrupt_name() -> str:
    """``SIGTERM`` or ``Ctrl-C``: what stopped the run, for a report."""
    return "SIGTERM" if _sigterm else "Ctrl-C"


def raise_pending() -> None:
    """Raise the interrupt a C caller swallowed, if any (once); a no-op otherwise."""
    global _pending
    exc, _pending = _pending, None
    if exc is not None:
        raise exc


def pending() -> bool:
    """Whether an interrupt was swallowed and has not been raised again yet."""
    return _pending is not None


def received_sigterm() -> bool:
    """Whether SIGTERM arrived since :func:`handled` was entered."""
    return _sigterm


@contextmanager
def handled() -> Iterator[None]:
    """SIGTERM raises :class:`Terminated`, and interrupts swallowed by C callers are kept for
    :func:`raise_pending`, inside the block; the previous handler and hook come back after it.
    Main thread only (Python's rule for signal handlers)."""
    global _pending, _sigterm
    _pending, _sigterm = None, False
    previous_handler = signal.signal(signal.SIGTERM, _on_sigterm)
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _keeping_interrupts(previous_hook)
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        signal.signal(signal.SIGTERM, previous_handler)
