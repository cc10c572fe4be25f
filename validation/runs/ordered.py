"""Work submitted ahead to a ``concurrent.futures`` executor and taken back in index order; and
the executor that runs every task at once, here.

A study (the fuzzing campaign) keeps its executor's queue full by starting item ``i`` ahead of
need, at most ``window`` at a time, and takes the items back in index order whatever order they
finish in (:func:`in_index_order`): everything done with them after that is deterministic. Items
started but not taken when the work ends (its budget spent, an error, an interrupt) are cancelled.
:class:`SerialExecutor` is the executor of a serial run and of tests: a task runs at its
submission.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future
from contextlib import contextmanager
from typing import Any, TypeVar

T = TypeVar("T")


class SerialExecutor(Executor):
    """Every task run at once, here (an ``Executor`` for a serial campaign and for tests); an
    interrupt is raised at the submission, any other error kept in the future."""

    def submit(self, fn, /, *args, **kwargs):
        f: Future = Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            if isinstance(exc, KeyboardInterrupt):
                raise
            f.set_exception(exc)
        return f


@contextmanager
def in_index_order(
    start: Callable[[int], T],
    more: Callable[[int], bool],
    window: int,
    cancel: Callable[[T], Any],
) -> Iterator[Iterator[tuple[int, T]]]:
    """``with in_index_order(start, more, window, cancel) as items: for i, item in items: ...``:
    ``start(i)`` for ``i = 0, 1, ...`` while ``more(i)``, at most ``window`` started and not yet
    taken, each taken as ``(i, item)`` in index order; leaving the block (at the end, or on an
    error or an interrupt) calls ``cancel(item)`` on every item started and not taken."""
    pending: dict[int, T] = {}

    def items() -> Iterator[tuple[int, T]]:
        index = 0
        while True:
            while len(pending) < window and more(index):
                pending[index] = start(index)
                index += 1
            if not pending:
                return
            first = min(pending)
            yield first, pending.pop(first)

    try:
        yield items()
    finally:
        for item in pending.values():
            cancel(item)


__all__ = ["SerialExecutor", "in_index_order"]
