"""Every child process the tool starts ends when its parent does, however the parent ends.

A parent killed with SIGKILL (``subprocess.run(timeout=...)``, a CI runner's hard kill, the OOM
killer) runs none of its clean-up: without this a plant worker it had forked ran on, re-parented
to init, at 100 % CPU. :func:`die_with_parent` (:mod:`analytic.runtime.lifetime`) is called in
each child, first thing:

* on Linux it asks the kernel to send the child SIGKILL when its parent dies
  (``prctl(PR_SET_PDEATHSIG, SIGKILL)``, through ``ctypes`` and libc), then checks
  ``os.getppid()`` against the parent it expects: a parent that died between the fork and the
  ``prctl`` would otherwise be missed (the child already belongs to init then);
* elsewhere (or where ``prctl`` is refused) a daemon thread compares ``os.getppid()`` with the
  expected parent every :data:`WATCH_S` s and ends the process when they differ.

The kernel's signal is tied to the parent *thread* that forked the child: the callers fork from a
process's only thread (:func:`validation.runs.workers.can_fork`) or from the fork server's one
thread, never from a pool thread that may end before its process does.

Where children come from: :func:`validation.runs.workers.start` (validate's plants, figures and
recording), the fork server's children (:func:`validation.runs.workers.start_served`: each ends
with the process that asked for it, :func:`die_with`, and with the server,
:func:`forks_die_with_parent` in :mod:`validation.runs.server_setup`) and the local process pools
(:func:`pool_initializer`). The fork server itself ends once its client and the children it
forked are gone (``multiprocessing`` watches a pipe they hold); a Dask worker process ends when
its nanny's process does (Dask's own parent pipe).
"""

from __future__ import annotations

import contextlib
import os

# The mechanism itself (the prctl, the parent watch, die_with) lives in the lowest layer, so that
# the engine plants below this package use it too; re-exported here for the tool's callers.
from analytic.runtime.lifetime import (
    ORPHANED_EXIT,
    PR_SET_PDEATHSIG,
    WATCH_S,
    die_with,
    die_with_parent,
)


def forks_die_with_parent() -> None:
    """Every process forked from this one from now on (in this process and in its children)
    calls :func:`die_with_parent` with the pid of the process that forked it, right after the
    fork (:func:`os.register_at_fork`). For a process of the tool's own (the fork server), never a
    user's process: the hook stays for the process's life."""
    forker = [os.getpid()]

    def before() -> None:
        forker[0] = os.getpid()

    def after_in_child() -> None:
        with contextlib.suppress(Exception):
            die_with_parent(forker[0])

    os.register_at_fork(before=before, after_in_child=after_in_child)


def pool_initializer(parent: int) -> None:
    """A ``ProcessPoolExecutor`` ``initializer``: the worker ends with its parent ``parent``
    (pass ``initargs=(os.getpid(),)``); a pool worker otherwise waits on its task queue, and
    finishes the task it runs, after its parent is gone. Its BLAS is on one thread too
    (:func:`validation.runs.environment.limit_blas_threads`: the pool's worker is the tool's).

    The kernel ties the signal to the thread that started the worker: a pool's workers start in
    the thread that submits to it, and the tool's pools are made, used and shut down by one
    thread in one block."""
    die_with_parent(parent)
    from validation.runs.environment import limit_blas_threads

    limit_blas_threads()


__all__ = [
    "ORPHANED_EXIT",
    "PR_SET_PDEATHSIG",
    "WATCH_S",
    "die_with",
    "die_with_parent",
    "forks_die_with_parent",
    "pool_initializer",
]
