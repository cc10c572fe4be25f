"""Where a run's files are staged and how they are put at the target (rule 3 of
:mod:`validation.runs.outputs`).

:func:`place_for` decides, before the run starts, where the lock and the staging directory go and
the :class:`CommitMode`: ``SWAP`` (staging beside the target, swapped in by one ``renameat2``
exchange on Linux, two renames elsewhere) or ``IN_PLACE`` (a mount point or the working directory:
the files moved in one by one, the manifest last). :func:`clean_leftovers` removes only what a
killed tumble run provably left (:func:`~validation.runs.manifest.is_our_leftover`).
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import enum
import errno
import os
import re
import shutil
import stat
from dataclasses import dataclass
from pathlib import Path

from analytic.runtime.safe_files import open_regular
from validation.runs.atomic import OutputError
from validation.runs.manifest import (
    CLEAR_IT,
    CLOEXEC,
    DIRECTORY,
    MANIFEST,
    NOFOLLOW,
    STAGING_MARKER,
    NotOurs,
    Owned,
    is_our_leftover,
    lstat_or_none,
    prove_owned,
)
from validation.runs.paths import RUN_ID_PATTERN

_IN_MOUNT_LOCK = ".tumble.lock"
_IN_MOUNT_PREFIX = ".tumble."
_LOST_FOUND = "lost+found"

class CommitMode(enum.Enum):
    """How a run's files are put at the target (see the module docstring)."""

    SWAP = "swap"
    IN_PLACE = "in-place"


# ---------------------------------------------------------------------------------------------
# Where a run goes: the target, its lock, its staging directory
# ---------------------------------------------------------------------------------------------


class _Cwd(enum.Enum):
    """Where the working directory is relative to a target."""

    OUTSIDE = "outside"
    IS_TARGET = "is the target"
    INSIDE = "inside the target"


def _cwd_relation(target: Path) -> _Cwd:
    """Whether ``target`` is the working directory or one of its ancestors (by inode)."""
    try:
        here = Path(os.getcwd())
        t = os.stat(target)
    except OSError:
        return _Cwd.OUTSIDE
    for i, p in enumerate([here, *here.parents]):
        with contextlib.suppress(OSError):
            if os.path.samestat(os.stat(p), t):
                return _Cwd.IS_TARGET if i == 0 else _Cwd.INSIDE
    return _Cwd.OUTSIDE


def _unescape_mountinfo(field_: str) -> str:
    return re.sub(r"\\([0-7]{3})", lambda m: chr(int(m[1], 8)), field_)


def _is_mount_point(path: Path) -> bool:
    """Whether the directory ``path`` is a mount point (bind mounts of the same filesystem
    included, which ``os.path.ismount`` misses: they are found in ``/proc/self/mountinfo``)."""
    if os.path.ismount(path):
        return True
    try:
        with open("/proc/self/mountinfo", encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError:
        return False
    real = os.path.realpath(path)
    for line in text.splitlines():
        fields = line.split(" ")
        if len(fields) > 4 and _unescape_mountinfo(fields[4]) == real:
            return True
    return False


@dataclass(frozen=True)
class Place:
    """Where a run's lock and staging directory are, and how its files reach the target."""

    target: Path
    mode: CommitMode
    lock: Path
    staging_parent: Path
    staging_prefix: str
    inside: bool  # lock and staging inside the target (a mount point)

    def staging(self, run_id: str) -> Path:
        return self.staging_parent / f"{self.staging_prefix}{run_id}.partial"

    def leftover_run_id(self, name: str) -> str | None:
        """The run id in ``name`` if it is named like this place's staging (or ``.old``)."""
        tails = r"partial" if self.inside else r"partial|old"
        m = re.fullmatch(rf"{re.escape(self.staging_prefix)}({RUN_ID_PATTERN})\.(?:{tails})", name)
        return m[1] if m else None

    def is_own_entry(self, entry: os.DirEntry) -> bool:
        """Inside a mount point: whether ``entry`` is the filesystem's ``lost+found`` directory,
        the lock (a regular file) or a staging directory of a tumble run (a live one, or a
        leftover that is provably ours). None of these is ever deleted by a commit there."""
        if not self.inside:
            return False
        if entry.name == _LOST_FOUND:
            return entry.is_dir(follow_symlinks=False)
        if entry.name == _IN_MOUNT_LOCK:
            return entry.is_file(follow_symlinks=False)
        rid = self.leftover_run_id(entry.name)
        return rid is not None and is_our_leftover(Path(entry.path), rid)

    def prove_target(self) -> Owned | None:
        """:func:`prove_owned` of the target; None when nothing is there."""
        st = lstat_or_none(self.target)
        if st is None:
            return None
        _check_target_kind(self.target, st)
        return prove_owned(self.target, self.is_own_entry if self.inside else None)


def _check_target_kind(target: Path, st: os.stat_result) -> None:
    if stat.S_ISLNK(st.st_mode):
        raise NotOurs(
            f"{target}: is a symbolic link; tumble never writes through a link: give the "
            "directory itself"
        )
    if not stat.S_ISDIR(st.st_mode):
        raise NotOurs(f"{target}: exists and is not a directory")


def _beside(target: Path, mode: CommitMode) -> Place:
    """Lock and staging as hidden siblings of ``target``: ``.<name>.lock``, ``.<name>.<id>.partial``."""
    prefix = f".{target.name}."
    return Place(target, mode, target.with_name(f"{prefix}lock"), target.parent, prefix, False)


def place_for(target: Path) -> Place:
    """Decide, before anything runs, where the lock and staging go and how the files go in.

    Raises:
        NotOurs: the target is a link, not a directory, or holds the working directory.
    """
    st = lstat_or_none(target)
    if st is None:
        return _beside(target, CommitMode.SWAP)
    _check_target_kind(target, st)
    cwd = _cwd_relation(target)
    if cwd is _Cwd.INSIDE:
        raise NotOurs(
            f"{target}: holds the working directory {os.getcwd()}; choose another output directory"
        )
    if _is_mount_point(target):
        lock = target / _IN_MOUNT_LOCK
        return Place(target, CommitMode.IN_PLACE, lock, target, _IN_MOUNT_PREFIX, True)
    return _beside(target, CommitMode.IN_PLACE if cwd is _Cwd.IS_TARGET else CommitMode.SWAP)


def clean_leftovers(place: Place) -> None:
    """Remove staging/old directories that killed runs left (we hold the lock): only real
    directories named like ours that :func:`is_our_leftover` proves; anything else stays."""
    try:
        with os.scandir(place.staging_parent) as it:
            named = [(Path(e.path), place.leftover_run_id(e.name)) for e in it]
    except OSError:
        return
    for path, rid in named:
        if rid is not None and is_our_leftover(path, rid):
            shutil.rmtree(path, ignore_errors=True)  # never follows a link (fd-based on Linux)


def make_staging(place: Place, run_id: str) -> Path:
    """Create the staging directory with its marker (both new: ``mkdir``, ``O_EXCL``)."""
    staging = place.staging(run_id)
    try:
        staging.mkdir()
    except OSError as exc:
        raise OutputError(place.target, exc) from exc
    try:
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | NOFOLLOW | CLOEXEC
        fd = os.open(staging / STAGING_MARKER, flags, 0o644)
        try:
            os.write(fd, f"{run_id}\n".encode())
        finally:
            os.close(fd)
    except OSError as exc:
        shutil.rmtree(staging, ignore_errors=True)
        raise OutputError(place.target, exc) from exc
    return staging



# ---------------------------------------------------------------------------------------------
# Putting the files in
# ---------------------------------------------------------------------------------------------

_RENAME_NOREPLACE = 1  # linux/fs.h
_RENAME_EXCHANGE = 2


def _renameat2(a: Path, b: Path, flags: int) -> bool:
    """Linux ``renameat2(a, b, flags)``; False if the kernel or filesystem lacks it.

    Raises:
        OSError: any other failure (EEXIST, EBUSY, EXDEV ...).
    """
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    rc = fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), flags)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _renameat2_exchange(a: Path, b: Path) -> bool:
    """Atomically exchange two paths (Linux ``renameat2(RENAME_EXCHANGE)``); False if unsupported."""
    return _renameat2(a, b, _RENAME_EXCHANGE)


def _rename_noreplace(a: Path, b: Path) -> None:
    """Rename ``a`` to ``b`` only if nothing is at ``b`` (``FileExistsError`` otherwise)."""
    if _renameat2(a, b, _RENAME_NOREPLACE):
        return
    if lstat_or_none(b) is not None:
        raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(b))
    os.rename(a, b)


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY | DIRECTORY | CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _remove_previous(where: Path, previous: Owned) -> None:
    """Delete the previous run, moved to ``where``: the files proven to be its, its manifest,
    then the directory if nothing else is left (anything else stays where it is)."""
    for name in (*previous.files, MANIFEST):
        with contextlib.suppress(OSError):
            (where / name).unlink()
    with contextlib.suppress(OSError):
        where.rmdir()


def commit_swap(staging: Path, target: Path, previous: Owned | None) -> None:
    """Put ``staging`` at ``target`` by one rename (``SWAP``).

    Raises:
        OSError: nothing was changed (EBUSY/EXDEV: the target cannot be renamed).
    """
    if previous is None:
        _rename_noreplace(staging, target)
        _fsync_dir(target.parent)
        return
    if _renameat2_exchange(staging, target):
        old = staging  # staging now holds the previous run
    else:
        old = staging.with_name(staging.name.removesuffix(".partial") + ".old")
        _rename_noreplace(target, old)
        try:
            os.rename(staging, target)
        except BaseException:
            os.rename(old, target)  # put the previous run back
            raise
    _fsync_dir(target.parent)
    _remove_previous(old, previous)


def _copy_new(src: Path, dst: Path) -> None:
    """Copy the regular file ``src`` to the new file ``dst`` (``O_EXCL``), flushed to disk."""
    with open_regular(src) as sfd:
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | NOFOLLOW | CLOEXEC
        dfd = os.open(dst, flags, 0o666)
        try:
            while block := os.read(sfd, 1 << 20):
                view = memoryview(block)
                while view:
                    view = view[os.write(dfd, view) :]
            os.fsync(dfd)
            if os.fstat(dfd).st_size != os.fstat(sfd).st_size:
                raise OSError(errno.EIO, "short copy", str(dst))
        except BaseException:
            os.close(dfd)
            dst.unlink(missing_ok=True)
            raise
        os.close(dfd)


def _bring(src: Path, dst: Path) -> None:
    """Move ``src`` to the new name ``dst``: a rename, or a copy across filesystems."""
    try:
        _rename_noreplace(src, dst)
    except OSError as exc:
        if exc.errno != errno.EXDEV:
            raise
        _copy_new(src, dst)


class HalfCommitted(OutputError):
    """A per-file commit failed after its first rename: the target holds no manifest now."""


def commit_in_place(staging: Path, target: Path, previous: Owned | None, run_id: str) -> None:
    """Put the files of ``staging`` into ``target`` one by one (``IN_PLACE``; module doc).

    Raises:
        OSError: before the first rename at ``target``: nothing there was changed.
        HalfCommitted: after it (practically only if the directory changes meanwhile).
    """
    names = sorted(
        e.name for e in os.scandir(staging) if e.is_file(follow_symlinks=False)
    )
    order = [n for n in names if n != MANIFEST] + [MANIFEST]
    brought: dict[str, Path] = {}
    try:  # everything that can fail for space, before anything at the target changes
        for name in order:
            tmp = target / f".{name}.{run_id}.tmp"
            _bring(staging / name, tmp)
            brought[name] = tmp
        _fsync_dir(target)
    except BaseException:
        for tmp in brought.values():
            tmp.unlink(missing_ok=True)
        raise
    try:
        if previous is not None and previous.has_manifest:
            (target / MANIFEST).unlink(missing_ok=True)
        for name in order[:-1]:
            os.replace(brought.pop(name), target / name)
        for name in previous.files if previous is not None else ():
            if name not in names:
                (target / name).unlink(missing_ok=True)
        os.replace(brought.pop(MANIFEST), target / MANIFEST)
    except OSError as exc:
        for tmp in brought.values():
            tmp.unlink(missing_ok=True)
        raise HalfCommitted(
            target, f"{exc.strerror or exc}; it holds part of this run and no {MANIFEST}: {CLEAR_IT}"
        ) from exc
    _fsync_dir(target)
    shutil.rmtree(staging, ignore_errors=True)



__all__ = [
    "CommitMode",
    "HalfCommitted",
    "Place",
    "clean_leftovers",
    "commit_in_place",
    "commit_swap",
    "make_staging",
    "place_for",
]
