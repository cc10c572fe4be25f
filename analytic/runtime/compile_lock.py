"""One process compiles a kernel; another that needs it meanwhile waits, then loads it from disk.

numba's on-disk cache has no locking: two processes that need the same uncompiled kernel at the
same time both compile it (same result, twice the work): a warm-up's worker
(:mod:`validation.runs.warmup`) and a plant's interval, or plants run side by side in worker processes.

:func:`compiling` wraps the compile of a named kernel: it takes an exclusive lock on a file in the
kernel cache directory (``fcntl.flock``; released by the operating system if the holder dies), so a
second process waits there and then finds the code on disk. :func:`hold` / :func:`release` take
the same lock ahead of time. Within one process a held name is not waited for again. Where ``fcntl`` or a writable
cache directory is missing, nothing is locked (each process compiles, as numba does).
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
from collections.abc import Iterator
from typing import IO

from analytic.runtime.cache_dir import kernel_cache_dir

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None

RHS = "compiled-rhs"
"""The analytic plant's compiled right-hand side (:func:`analytic.compiled_stepping.prepare`)."""
PINOCCHIO = "pinocchio-stage"
"""The Pinocchio plant's compiled stage and copy (:meth:`mj_bridge.pinocchio_plant.
PinocchioDynamics.compile`)."""

_held: dict[str, IO[bytes]] = {}
"""The locks this process holds. A process forked meanwhile (a worker of
:mod:`validation.runs.workers`) closes its copies at once: it holds none of them itself (so it waits
like any other process), and an ``flock`` lives while any copy of its file is open (as for the
output directories' locks, :mod:`validation.runs.outputs`)."""


def _forget_held() -> None:  # pragma: no cover - in a forked child
    for f in _held.values():
        try:
            f.close()
        except OSError:
            pass
    _held.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_held)


def _open(name: str) -> IO[bytes] | None:
    if fcntl is None or not re.fullmatch(r"[a-z0-9-]+", name):
        return None
    where = kernel_cache_dir()
    if where is None:
        return None
    flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_CLOEXEC", 0)
    flags |= getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)  # never a link, a FIFO
    try:
        os.makedirs(where, exist_ok=True)
        fd = os.open(where / f"tumble-compiling-{name}.lock", flags, 0o644)
    except OSError:
        return None
    if not stat.S_ISREG(os.fstat(fd).st_mode):  # a FIFO or device there: nothing locked
        os.close(fd)
        return None
    return open(fd, "ab")  # kept open while held


def hold(name: str) -> bool:
    """Take the lock of ``name`` and keep it (until :func:`release`); waits while another process
    holds it. False when nothing could be locked here."""
    if name in _held:
        return True
    f = _open(name)
    if f is None:
        return False
    try:
        fcntl.flock(f, fcntl.LOCK_EX)
    except BaseException:
        f.close()
        raise
    _held[name] = f
    return True


def release(name: str) -> None:
    """Let go of the lock of ``name`` (nothing when not held here)."""
    f = _held.pop(name, None)
    if f is not None:
        try:
            fcntl.flock(f, fcntl.LOCK_UN)
        finally:
            f.close()


@contextlib.contextmanager
def compiling(name: str) -> Iterator[None]:
    """Around the compile (or load) of kernel ``name``: waits while another process compiles it;
    a lock this process already holds is kept as it is."""
    if name in _held:
        yield
        return
    hold(name)
    try:
        yield
    finally:
        release(name)


__all__ = ["RHS", "compiling", "hold", "release"]
