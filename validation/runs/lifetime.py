"""Every child process the tool starts ends when its parent does, however the parent ends.

A parent killed with SIGKILL (``subprocess.run(timeout=...)``, a CI runner's hard kill, the OOM
killer) runs none of its clean-up: without this a plant worker it had forked ran on, re-parented
to init, at 100 % CPU. :func:`die_with_parent` is called in each child, first thing:

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
import ctypes
import os
import select
import signal
import sys
import threading
import time

PR_SET_PDEATHSIG = 1
"""``<linux/prctl.h>``: the signal a process gets when its parent dies."""

WATCH_S = 0.5
"""How often the parent-watch thread (not Linux) looks at the parent, s."""

ORPHANED_EXIT = 1
"""The exit status of a child that finds its parent gone (nobody is left to read it)."""


def _pdeathsig() -> bool:
    """``prctl(PR_SET_PDEATHSIG, SIGKILL)`` for this process; whether the kernel took it."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent: int) -> None:
    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(WATCH_S)
        os._exit(ORPHANED_EXIT)

    threading.Thread(target=watch, name="tumble-parent-watch", daemon=True).start()


def die_with_parent(parent: int) -> None:
    """This process (a child of ``parent``, by pid) ends when ``parent`` does: at once if it
    has already (module docstring). Call it in the child, as early as possible after the fork."""
    if not _pdeathsig():
        _watch(parent)
    if os.getppid() != parent:
        os._exit(ORPHANED_EXIT)


def die_with(pid: int) -> None:
    """This process ends when process ``pid`` does, ``pid`` not its parent: a fork server's child
    (whose parent is the server) ends with the process that asked the server for it. A daemon
    thread waits for ``pid``'s end (a Linux pidfd; elsewhere ``os.kill(pid, 0)`` every
    :data:`WATCH_S` s); a ``pid`` already gone ends this process at once.

    The fork server cannot end first: every child it forks holds the pipe end whose closing
    tells the server that its clients are gone (``multiprocessing``'s design), so the server
    lives as long as its children do, and a child tied to the server alone outlived a killed
    client with it."""
    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:
        os._exit(ORPHANED_EXIT)
    except (AttributeError, OSError):  # not Linux 5.3+: polled
        fd = None

    def watch() -> None:
        if fd is not None:
            select.select([fd], [], [])
            os._exit(ORPHANED_EXIT)
        while True:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                os._exit(ORPHANED_EXIT)
            except OSError:  # another user's process by now: not ours
                os._exit(ORPHANED_EXIT)
            time.sleep(WATCH_S)

    threading.Thread(target=watch, name="tumble-client-watch", daemon=True).start()


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


__all__ = ["die_with", "die_with_parent", "forks_die_with_parent", "pool_initializer"]
