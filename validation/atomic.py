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
        # "x": never follow or reuse an existing name; mode 0o666 & ~umask like any new file.
        with open(tmp, "xb") as f:
            view = memoryview(data)
            while view:  # a short write (full disk) returns fewer bytes: loop until an error
                n = f.write(view)
                if not n:
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
                view = view[n:]
            f.flush()
            os.fsync(f.fileno())
            size = os.fstat(f.fileno()).st_size
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
