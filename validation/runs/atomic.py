"""Atomic, checked file writes: a temporary file beside the target, verified, then ``os.replace``.

Every file the project writes goes through :func:`write_bytes`:

* the bytes go to a hidden temporary file in the target's directory, created with the mode an
  ordinary file gets (``0o666`` minus the umask, so ``0644`` under the usual umask; ``mkstemp``'s
  ``0600`` would hide reports from the people they are for);
* the file is flushed and ``fsync``-ed, and its size is checked against what was meant to be
  written, so a full disk (``ENOSPC``, a short write) is found *before* anything is replaced;
* only then is it moved over the target. On any failure the temporary file is removed, the
  target keeps its previous contents, and :class:`OutputError` names the target and the cause.

Nothing is written through a link or into something that is not a file: a target that is a
symbolic link or a directory (or a socket, a block device) is refused with :class:`OutputError`
and left as it is; a target that is a character device or a FIFO (``/dev/null``, a named pipe a
reader waits on) is written into as a stream, never replaced by a regular file, and is opened
without blocking (a FIFO nobody reads is an :class:`OutputError` at once). Only the temporary file
this call created is ever removed.
"""

from __future__ import annotations

import enum
import errno
import os
import stat
import uuid
from collections.abc import Callable
from pathlib import Path

WRITE_CHUNK = 1 << 20
"""Bytes per ``os.write`` call (1 MiB): large enough to cost nothing, small enough that a full disk
is met part way through a recording rather than after one huge call."""


class OutputError(OSError):
    """A result could not be written (full disk, permissions ...); the target is unchanged.

    ``str()`` is one line: ``could not write PATH: CAUSE``.
    """

    def __init__(self, path: str | Path, cause: BaseException | str):
        reason = cause if isinstance(cause, str) else (getattr(cause, "strerror", None) or cause)
        code = getattr(cause, "errno", None) or errno.EIO
        super().__init__(code, f"could not write {path}: {reason}")
        self.path = Path(path)
        self.reason = str(reason)

    def __str__(self) -> str:
        return self.strerror or super().__str__()


_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)


def _temp_name(path: Path) -> Path:
    return path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")


class _Kind(enum.Enum):
    """What a write target is now, as far as :func:`write_bytes` is concerned."""

    NEW_OR_FILE = "file"  # absent or a regular file: written atomically beside it, then replaced
    STREAM = "stream"  # a character device or a FIFO: written into, never replaced


def _target_kind(path: Path) -> _Kind:
    """How ``path`` may be written (``lstat``: a link is never followed).

    Raises:
        OutputError: ``path`` is a symbolic link, a directory, a socket or a block device.
    """
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return _Kind.NEW_OR_FILE
    except OSError as exc:
        raise OutputError(path, exc) from exc
    mode = st.st_mode
    if stat.S_ISREG(mode):
        return _Kind.NEW_OR_FILE
    if stat.S_ISCHR(mode) or stat.S_ISFIFO(mode):
        return _Kind.STREAM
    if stat.S_ISLNK(mode):
        why = "is a symbolic link; not written through nor replaced (give the file it points to)"
    elif stat.S_ISDIR(mode):
        why = "is a directory"
    else:
        why = "is not a regular file"
    raise OutputError(path, why)


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:  # a short write (a disk filling up) writes fewer bytes: go on until it errs
        n = os.write(fd, view[:WRITE_CHUNK])
        if n <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        view = view[n:]


def _write_stream(path: Path, data: bytes) -> Path:
    """Write ``data`` into a character device or FIFO at ``path`` (opened without blocking)."""
    flags = os.O_WRONLY | os.O_NONBLOCK | _NOFOLLOW | _CLOEXEC
    try:
        fd = os.open(path, flags)  # a FIFO with no reader: ENXIO at once
        try:
            st = os.fstat(fd)
            if not (stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode)):
                raise OSError(errno.EINVAL, "changed while it was opened")
            os.set_blocking(fd, True)  # the reader sets the pace, as for any pipe
            _write_all(fd, data)
        finally:
            os.close(fd)
    except OSError as exc:
        raise OutputError(path, exc) from exc
    return path


def write_bytes(
    path: str | Path,
    data: bytes,
    *,
    check: Callable[[Path], None] | None = None,
) -> Path:
    """Write ``data`` to ``path`` atomically; returns ``path``.

    Args:
        path: the target file; its directory is created if missing. A character device or a FIFO
            is written into (``check`` is then not run); see the module docstring.
        data: the whole content.
        check: optional ``check(tmp_path)`` run on the finished temporary file before it replaces
            anything (e.g. reading a recording back); it raises to refuse the file.

    Raises:
        OutputError: the file could not be written completely, or ``path`` is a symbolic link, a
            directory or another thing that is not a file; ``path`` is unchanged.
    """
    path = Path(path)
    if _target_kind(path) is _Kind.STREAM:
        return _write_stream(path, data)
    tmp = _temp_name(path)
    created = False
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # O_EXCL|O_NOFOLLOW: never follow or reuse an existing name; mode 0o666 & ~umask.
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC, 0o666)
        created = True
        try:
            _write_all(fd, data)
            os.fsync(fd)
            size = os.fstat(fd).st_size
        finally:
            os.close(fd)
        if size != len(data):
            raise OSError(errno.EIO, f"wrote {size} of {len(data)} bytes")
        if check is not None:
            check(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        if created:
            tmp.unlink(missing_ok=True)
        if isinstance(exc, OutputError):
            raise
        raise OutputError(path, exc) from exc
    except BaseException:
        if created:
            tmp.unlink(missing_ok=True)
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """:func:`write_bytes` of ``text`` encoded as UTF-8."""
    return write_bytes(path, text.encode("utf-8"))


__all__ = ["OutputError", "write_bytes", "write_text"]
