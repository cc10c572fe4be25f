"""Atomic, checked file writes: a temporary file beside the target, verified, then ``os.replace``.

Every file the project writes goes through :func:`write_bytes`:

* the bytes go to a hidden temporary file in the target's directory, created with the mode an
  ordinary file gets (``0o666`` minus the umask, so ``0644`` under the usual umask; ``mkstemp``'s
  ``0600`` would hide reports from the people they are for);
* the file is flushed and ``fsync``-ed, and its size is checked against what was meant to be
  written, so a full disk (``ENOSPC``, a short write) is found *before* anything is replaced;
* only then is it moved over the target. On any failure the temporary file is removed, the
  target keeps its previous contents, and :class:`OutputError` names the target and the cause.
"""

from __future__ import annotations

import errno
import os
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


def _temp_name(path: Path) -> Path:
    return path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")


def write_bytes(
    path: str | Path,
    data: bytes,
    *,
    check: Callable[[Path], None] | None = None,
) -> Path:
    """Write ``data`` to ``path`` atomically; returns ``path``.

    Args:
        path: the target file; its directory is created if missing.
        data: the whole content.
        check: optional ``check(tmp_path)`` run on the finished temporary file before it replaces
            anything (e.g. reading a recording back); it raises to refuse the file.

    Raises:
        OutputError: the file could not be written completely; ``path`` is unchanged.
    """
    path = Path(path)
    tmp = _temp_name(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # O_EXCL: never follow or reuse an existing name; mode 0o666 & ~umask like any new file.
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
        try:
            view = memoryview(data)
            while view:  # a short write (a disk filling up) writes fewer bytes: go on until it errs
                n = os.write(fd, view[:WRITE_CHUNK])
                if n <= 0:
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
                view = view[n:]
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
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OutputError):
            raise
        raise OutputError(path, exc) from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """:func:`write_bytes` of ``text`` encoded as UTF-8."""
    return write_bytes(path, text.encode("utf-8"))


__all__ = ["OutputError", "write_bytes", "write_text"]
