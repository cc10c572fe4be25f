"""A child process that ends when its parent does, however the parent ends (the lowest layer: no
physics, nothing else of the project; the tool's processes and the accelerated plants' engine
processes both use it).

A parent killed with SIGKILL runs none of its clean-up: without this a child it had started runs
on, re-parented to init. :func:`die_with_parent` is called in each child, first thing:

* on Linux it asks the kernel to send the child SIGKILL when its parent dies
  (``prctl(PR_SET_PDEATHSIG, SIGKILL)``, through ``ctypes`` and libc), then checks
  ``os.getppid()`` against the parent it expects: a parent that died between the start and the
  ``prctl`` would otherwise be missed (the child already belongs to init then);
* elsewhere (or where ``prctl`` is refused) a daemon thread compares ``os.getppid()`` with the
  expected parent every :data:`WATCH_S` s and ends the process when they differ.

The kernel's signal is tied to the parent *thread* that started the child: start children from a
thread that lives as long as its process (the main thread), never from a pool thread that may end
first. :func:`die_with` ties a process to one that is not its parent.
"""

from __future__ import annotations

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


__all__ = ["ORPHANED_EXIT", "PR_SET_PDEATHSIG", "WATCH_S", "die_with", "die_with_parent"]
