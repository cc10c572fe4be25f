"""The lock of an output directory: one run writes into it at a time (an ``fcntl`` lock).

The lock file (``.<DIR name>.lock`` beside the directory, ``.tumble.lock`` inside a mount point) is
created with ``O_EXCL|O_NOFOLLOW``; one that exists already is only used (never truncated nor
written) if it is a regular file with one link, owned by this user, and is refused otherwise
(:class:`~validation.runs.manifest.NotOurs`). A second run while one holds it is refused
(:class:`OutputBusy`), never interleaved.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import stat
from collections.abc import Iterator
from pathlib import Path

from validation.runs.atomic import OutputError
from validation.runs.manifest import CLOEXEC, NOFOLLOW, NONBLOCK, NotOurs, lstat_or_none


class OutputBusy(ValueError):
    """Another run is writing into the same output directory right now."""


# ---------------------------------------------------------------------------------------------
# The lock
# ---------------------------------------------------------------------------------------------

_HELD_LOCKS: set[int] = set()
"""File descriptors of the locks this process holds. A process forked while one is held (a worker
of :mod:`validation.runs.workers`) closes its copy at once: an ``flock`` lives while any copy is open,
and the directory must be free as soon as its run ends."""


def _forget_held_locks() -> None:  # pragma: no cover - in a forked child
    for fd in _HELD_LOCKS:
        try:
            os.close(fd)
        except OSError:
            pass
    _HELD_LOCKS.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_held_locks)


def _check_lock_file(target: Path, lock: Path, st: os.stat_result) -> None:
    """Refuse an existing lock file that tumble cannot have created (see the module doc)."""
    mode = st.st_mode
    if stat.S_ISLNK(mode):
        what = "a symbolic link"
    elif not stat.S_ISREG(mode):
        what = "a FIFO" if stat.S_ISFIFO(mode) else "not a regular file"
    elif st.st_nlink != 1:
        what = f"a file with {st.st_nlink} hard links"
    elif hasattr(os, "geteuid") and st.st_uid != os.geteuid():
        what = f"owned by another user (uid {st.st_uid})"
    else:
        return
    raise NotOurs(
        f"{target}: its lock file {lock} is {what}, which tumble did not create; "
        "remove it or choose another output directory"
    )


def _open_lock(target: Path, lock: Path) -> tuple[int, bool]:
    """A descriptor to ``flock`` for ``target`` and whether this call created the file.

    A new file is created with ``O_CREAT|O_EXCL|O_NOFOLLOW``; an existing one is opened read-only
    with ``O_NOFOLLOW|O_NONBLOCK`` after :func:`_check_lock_file` and checked again on the open
    descriptor (it is never truncated nor written).
    """
    base = NOFOLLOW | NONBLOCK | CLOEXEC
    for _ in range(1000):
        try:
            return os.open(lock, os.O_RDWR | os.O_CREAT | os.O_EXCL | base, 0o644), True
        except FileExistsError:
            pass
        except OSError as exc:
            raise OutputError(lock, exc) from exc
        st = lstat_or_none(lock)
        if st is None:
            continue  # removed meanwhile by a run that finished
        _check_lock_file(target, lock, st)
        try:
            fd = os.open(lock, os.O_RDONLY | base)
        except OSError as exc:
            if exc.errno in (errno.ENOENT, errno.ELOOP):
                continue  # removed, or replaced by a link, meanwhile: look again
            raise OutputError(lock, exc) from exc
        fst = os.fstat(fd)
        if os.path.samestat(fst, st):
            try:
                _check_lock_file(target, lock, fst)
            except NotOurs:
                os.close(fd)
                raise
            return fd, False
        os.close(fd)
    raise OutputError(lock, "the lock file keeps changing")


def _same_file(fd: int, path: Path) -> bool:
    st = lstat_or_none(path)
    return st is not None and os.path.samestat(os.fstat(fd), st)


@contextlib.contextmanager
def hold_lock(target: Path, lock: Path) -> Iterator[None]:
    """An exclusive, non-blocking ``flock`` on ``lock``, for ``target``.

    Raises:
        OutputBusy: another run holds it.
        NotOurs: the lock path is something tumble did not create (a link, a FIFO ...).
    """
    while True:
        fd, created = _open_lock(target, lock)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = _lock_pid(fd)
            os.close(fd)
            raise OutputBusy(
                f"{target}: another tumble run (pid {pid}) is writing into this directory; "
                "not started"
            ) from None
        if _same_file(fd, lock):  # not removed by a run that finished meanwhile
            break
        os.close(fd)
    _HELD_LOCKS.add(fd)
    try:
        if created:
            with contextlib.suppress(OSError):
                os.write(fd, f"{os.getpid()}\n".encode())
        yield
    finally:
        if created and _same_file(fd, lock):
            with contextlib.suppress(OSError):
                lock.unlink()
        _HELD_LOCKS.discard(fd)
        os.close(fd)


def _lock_pid(fd: int) -> str:
    """The pid written in a held lock file, or "?" (unreadable, or no such process: a lock file
    a killed run left, reused as it was)."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii").strip()
        pid = int(text)
        os.kill(pid, 0)
    except ProcessLookupError:
        return "?"
    except PermissionError:
        return text  # alive, another user's
    except (OSError, UnicodeDecodeError, ValueError):
        return "?"
    return text



__all__ = ["OutputBusy", "hold_lock"]
