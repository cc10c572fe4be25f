"""Reading a file the tool did not write itself, safely: never through a symbolic link, never
blocking, regular files only, never more than a limit.

Every file the tool reads that a user or another process could have put in place (a cache
entry, numba's cache files, a scene file collected by the pytest plugin, a ``sweep.csv``) is
opened by :func:`open_regular`: ``O_NOFOLLOW`` (a link is refused, not followed), ``O_NONBLOCK``
(a FIFO with no writer, or a device, cannot make the open wait) and an ``fstat`` of the open
descriptor (only a regular file is read). Standard library only.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import stat
from collections.abc import Iterator
from pathlib import Path

_READ_FLAGS = (
    os.O_RDONLY
    | getattr(os, "O_NOFOLLOW", 0)
    | getattr(os, "O_NONBLOCK", 0)
    | getattr(os, "O_CLOEXEC", 0)
)
_FOLLOW_FLAGS = _READ_FLAGS & ~getattr(os, "O_NOFOLLOW", 0)


class NotRegularFile(OSError):
    """Something other than a regular file (a link, FIFO, device, directory, socket) at a path
    the tool reads; ``str()`` names the path and what is there."""

    def __init__(self, path: str | Path, kind: str):
        super().__init__(errno.EINVAL, f"a {kind}, not a regular file", str(path))
        self.kind = kind

    def __str__(self) -> str:
        return f"{self.filename}: a {self.kind}, not a regular file"


def file_kind(mode: int) -> str:
    """What a file mode (``st_mode``) describes, in words: ``"regular file"``, ``"FIFO"`` ..."""
    kinds = (
        (stat.S_ISREG, "regular file"),
        (stat.S_ISDIR, "directory"),
        (stat.S_ISLNK, "symbolic link"),
        (stat.S_ISFIFO, "FIFO"),
        (stat.S_ISCHR, "character device"),
        (stat.S_ISBLK, "block device"),
        (stat.S_ISSOCK, "socket"),
    )
    return next((word for test, word in kinds if test(mode)), "special file")


@contextlib.contextmanager
def open_regular(path: str | Path, *, follow_links: bool = False) -> Iterator[int]:
    """A read-only descriptor of the regular file at ``path`` (closed on leaving the block).

    ``follow_links``: a symbolic link is followed to the file it names (a file the user names
    on the command line, such as a scene file), which must then be a regular file; by default
    a link is refused.

    Raises:
        FileNotFoundError: nothing at ``path``.
        NotRegularFile: a symbolic link, FIFO, device, directory or socket at ``path``.
        OSError: any other failure to open it (permissions ...).
    """
    try:
        fd = os.open(path, _FOLLOW_FLAGS if follow_links else _READ_FLAGS)
    except FileNotFoundError:
        raise
    except OSError as exc:  # ELOOP: a symbolic link; EISDIR; ENXIO: a socket ...
        try:
            kind = file_kind((os.stat if follow_links else os.lstat)(path).st_mode)
        except OSError:
            raise exc from None
        if kind != "regular file":
            raise NotRegularFile(path, kind) from exc
        raise
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise NotRegularFile(path, file_kind(mode))
        yield fd
    finally:
        os.close(fd)


def read_regular(path: str | Path, limit: int, *, follow_links: bool = False) -> bytes:
    """The bytes of the regular file at ``path`` (:func:`open_regular`, with ``follow_links``).

    Raises:
        OSError: as :func:`open_regular`; ``EFBIG`` when it holds more than ``limit`` bytes
            (checked while reading too, should the file grow).
    """
    with open_regular(path, follow_links=follow_links) as fd:
        if os.fstat(fd).st_size > limit:
            raise OSError(errno.EFBIG, f"larger than {limit:,} bytes", str(path))
        chunks, total = [], 0
        while chunk := os.read(fd, 1 << 20):
            chunks.append(chunk)
            total += len(chunk)
            if total > limit:
                raise OSError(errno.EFBIG, f"larger than {limit:,} bytes", str(path))
    return b"".join(chunks)


def file_digest(path: str | Path) -> tuple[str, int]:
    """``(hex SHA-256, size in bytes)`` of the regular file at ``path`` (:func:`open_regular`)."""
    h, size = hashlib.sha256(), 0
    with open_regular(path) as fd:
        while chunk := os.read(fd, 1 << 20):
            h.update(chunk)
            size += len(chunk)
    return h.hexdigest(), size


__all__ = ["NotRegularFile", "file_digest", "file_kind", "open_regular", "read_regular"]
