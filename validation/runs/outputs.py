"""Output directories: one run, whole, in a place the user chose, and never anything else.

Three rules hold for every command that writes a directory (``validate``, ``simulate``, ``sweep``,
``hard-cases``, ``bench --out``, ``demo``) and for the Python functions behind them:

1. **Paths never come from scene data.** A scene file is untrusted: its ``name`` only ever becomes a
   *slug* (:func:`slug`) inside a default directory under ``out/`` (:func:`default_out_dir`); a name
   that cannot be made safe is refused with a ``ValueError`` naming ``scene.name``. Inside a run
   directory every file name is a constant of the code.
2. **Ownership is proven by the manifest, not by file names.** ``--out DIR`` may name a directory
   that does not exist, an empty one, or one that holds a tumble run: a regular ``manifest.json``
   of this tool's schema with a well-formed run id, listing every entry of the directory (dot-files
   and subdirectories included) as a regular file whose size and SHA-256 still match. Anything else
   is the user's and is refused in one line naming an example entry, before any plant runs (a
   ``ValueError``: ``tumble: error: ...``, exit 2). An older run written before manifests existed
   cannot prove it is one and is refused too ("remove it or choose another output directory"): a
   wrong delete is worse than an extra keystroke. ``DIR`` itself must not be a symbolic link, nor
   hold the working directory. Nothing beside ``DIR`` is deleted unless it is provably a leftover
   of a killed tumble run: a real directory named ``.<DIR name>.<run id>.partial`` / ``.old`` that
   holds the staging marker with that run id, or a manifest that proves it as above. The lock file
   ``.<DIR name>.lock`` is created with ``O_EXCL|O_NOFOLLOW``; one that exists already is only
   used (never truncated nor written) if it is a regular file with one link, owned by this user,
   and is refused otherwise (a symlink, a hard link, a FIFO ...).
3. **A directory is one run, whole** (:class:`OutputRun`). The run builds its files in a hidden
   staging directory and puts them at ``DIR`` at the end. A run that fails or is interrupted
   (Ctrl-C, SIGTERM) still puts in what it wrote, marked in ``manifest.json`` as ``failed`` or
   ``interrupted``; a run whose files cannot be written (a full disk) leaves the previous run
   untouched and raises :class:`~validation.runs.atomic.OutputError`. ``manifest.json`` lists every
   file with its size and SHA-256 and the run id (which ``report.json`` and the recording also
   carry). A second run into the same directory while one is writing is refused (an ``fcntl`` lock),
   never interleaved. How the files are put in (:class:`CommitMode`, chosen before the run starts):

   * ``SWAP`` (the usual case): staging is the sibling ``.<name>.<run id>.partial``, swapped in by one
     ``renameat2`` exchange on Linux (two renames elsewhere). After any run, even a killed one,
     ``DIR`` holds either that run's files or the previous run's, never a mix.
   * ``IN_PLACE``, for a directory that cannot be renamed: a mount point (a container volume; found
     up front from ``/proc/self/mountinfo``, or when the swap is refused with ``EBUSY``/``EXDEV``)
     or the working directory (``--out .``, which must stay the shell's directory). The files are
     moved in one by one (renames within ``DIR``; copies first when staging is on another
     filesystem): the previous manifest is removed first, the new files renamed over the old ones,
     the previous run's other files removed, and the new ``manifest.json`` renamed in last. A full
     disk still leaves the previous run untouched (everything that can fail for space happens
     before the first rename). What is weaker: a process killed in the few milliseconds of the
     renames leaves a mix of files **without** a manifest, never a manifest naming a mix, so the
     set is never mistaken for a complete run and the next run refuses the directory until the
     user clears it. On a mount point the staging directory and the lock live inside ``DIR``
     (``.tumble.<run id>.partial``, ``.tumble.lock``), since the parent of a volume may not be
     writable; these and the filesystem's own ``lost+found`` directory are not counted as the
     user's entries there (a per-file commit deletes only files the previous manifest lists).
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import datetime as _dt
import enum
import errno
import fcntl
import hashlib
import json
import os
import re
import shutil
import stat
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from analytic.safe_files import file_digest, open_regular, read_regular
from validation.runs.atomic import OutputError, write_text

DEFAULT_ROOT = Path("out")
"""Where a command's default output directory goes, relative to the working directory."""

MANIFEST = "manifest.json"

MANIFEST_SCHEMA = "tumble-manifest/1"
"""The ``schema`` field of every ``manifest.json`` this tool writes."""

MANIFEST_MAX_BYTES = 4 << 20
"""A ``manifest.json`` larger than this (4 MiB) is not one of ours: it is not read."""

STAGING_MARKER = ".tumble-staging"
"""A file created (``O_EXCL``) in every staging directory as it is made, holding the run id: the
proof that a leftover staging directory of a killed run is the tool's to delete."""

SLUG_MAX_LEN = 64
"""Longest slug kept verbatim. Longer names are cut and given a hash of the whole name (so two
long names stay distinct); 64 + prefix + hash stays far below NAME_MAX (255 bytes) on every
common filesystem."""

_SLUG_OK = re.compile(r"[^A-Za-z0-9._-]+")

RUN_ID_PATTERN = r"\d{8}T\d{6}Z-[0-9a-f]{8}"
"""Every run id (:func:`new_run_id`): UTC time to the second, a dash, 8 hex digits."""

_RUN_ID = re.compile(rf"^{RUN_ID_PATTERN}$")
_SHA256 = re.compile(r"^[0-9a-f]{64}$")

_LEGACY_MANIFEST_KEYS = frozenset(
    {"run_id", "command", "state", "reason", "started_utc", "finished_utc", "files"}
)
"""The keys of a manifest written before :data:`MANIFEST_SCHEMA` existed (accepted, same checks)."""

KNOWN_OUTPUT_NAMES = frozenset(
    {
        MANIFEST,
        "report.md",
        "report.json",
        "errors.png",
        "tracking.png",
        "invariants.png",
        "control.png",
        "run.rrd",
        "trajectory.npz",
        "summary.json",
        "sweep.csv",
        "sweep.json",
        "sweep.md",
        "sweep.rrd",
        "work_precision.png",
        "hard_cases.md",
        "hard_cases.json",
        "bench.json",
        "demo.rrd",
        "demo.md",
    }
)
"""Every file name a tumble command writes into its directory. Names prove nothing: a directory
holding only these but no manifest (an older run) is refused all the same; the names only choose
the message ("remove it or choose another output directory")."""

_IN_MOUNT_LOCK = ".tumble.lock"
_IN_MOUNT_PREFIX = ".tumble."
_LOST_FOUND = "lost+found"


class RunState(enum.Enum):
    """How a run ended, as recorded in ``manifest.json``."""

    COMPLETE = "complete"
    FAILED = "failed"
    INTERRUPTED = "interrupted"


class CommitMode(enum.Enum):
    """How a run's files are put at the target (see the module docstring)."""

    SWAP = "swap"
    IN_PLACE = "in-place"


class OutputBusy(ValueError):
    """Another run is writing into the same output directory right now."""


class NotOurs(ValueError):
    """A path the run would replace, delete or write (the target, its lock) is not the tool's."""


def slug(name: str, field: str = "scene.name") -> str:
    """A file-name-safe form of a scene name: ``[A-Za-z0-9._-]`` only, no leading dot.

    Separators, ``..``, spaces and any other character become ``_`` runs; names longer than
    :data:`SLUG_MAX_LEN` are cut and end in 8 hex digits of the whole name's SHA-256.

    Raises:
        ValueError: naming ``field`` when the name is not a string, holds a NUL or another control
            character, or has nothing left to name a directory by (e.g. ``"../.."``).
    """
    if not isinstance(name, str):
        raise ValueError(f"{field}: must be a string (got {name!r})")
    if any(ord(c) < 32 or ord(c) == 127 for c in name):
        raise ValueError(f"{field}: must not contain control characters (got {name[:40]!r})")
    s = _SLUG_OK.sub("_", name).strip("._-")
    if not s or not any(c.isalnum() for c in s):
        raise ValueError(
            f"{field}: cannot name an output directory (got {name[:40]!r}); "
            "use letters, digits, '.', '_' or '-'"
        )
    if len(s) > SLUG_MAX_LEN:
        digest = hashlib.sha256(name.encode("utf-8", "surrogatepass")).hexdigest()[:8]
        s = f"{s[: SLUG_MAX_LEN - 9].rstrip('._-')}-{digest}"
    return s


def default_out_dir(prefix: str, scene_name: str) -> Path:
    """``out/<prefix><slug(scene_name)>``: a default output directory, always under ``out/``."""
    return DEFAULT_ROOT / f"{prefix}{slug(scene_name)}"


def default_out_file(scene_name: str, suffix: str) -> Path:
    """``out/<slug(scene_name)><suffix>``: a default output file, always under ``out/``."""
    return DEFAULT_ROOT / f"{slug(scene_name)}{suffix}"


def new_run_id() -> str:
    """A fresh run id: UTC time to the second and 8 random hex digits (sortable, unique)."""
    now = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%SZ")
    return f"{now}-{uuid.uuid4().hex[:8]}"



# ---------------------------------------------------------------------------------------------
# Reading what is there: never through a link, never blocking
# ---------------------------------------------------------------------------------------------

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_NONBLOCK = getattr(os, "O_NONBLOCK", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_DIRECTORY = getattr(os, "O_DIRECTORY", 0)


def _lstat(path: Path) -> os.stat_result | None:
    """``os.lstat(path)`` (a link is not followed), None when nothing is there."""
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None


def _digest(path: Path) -> tuple[int, str]:
    """``(bytes, SHA-256 hex)`` of the regular file ``path``, never through a link or blocking
    (:func:`analytic.safe_files.file_digest`)."""
    digest, size = file_digest(path)
    return size, digest


def _kind(entry: os.DirEntry) -> str:
    """What a directory entry is, in a few words, for a refusal."""
    if entry.is_symlink():
        return "a symbolic link"
    if entry.is_dir(follow_symlinks=False):
        return "a directory"
    if entry.is_file(follow_symlinks=False):
        return "a file"
    return "a special file"


# ---------------------------------------------------------------------------------------------
# Ownership: a directory is the tool's only if its manifest proves it
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ManifestEntry:
    """One file a manifest lists: its size in bytes and its SHA-256 (64 lower-case hex)."""

    bytes: int
    sha256: str


def _plain_name(name: object) -> bool:
    """A name a run can have written: a non-hidden single path component."""
    return (
        isinstance(name, str)
        and bool(name)
        and not name.startswith(".")
        and "/" not in name
        and "\x00" not in name
    )


def parse_manifest(data: bytes) -> dict[str, ManifestEntry]:
    """The files a ``manifest.json`` written by this tool lists, by name.

    A manifest is this tool's when it is a JSON object with ``schema`` :data:`MANIFEST_SCHEMA`
    (or exactly the keys of a manifest written before the schema field existed), a ``run_id`` of
    :data:`RUN_ID_PATTERN`, a string ``command``, a known ``state`` and a ``files`` object mapping
    plain names (no ``/``, not hidden, not ``manifest.json``) to ``{"bytes": int >= 0, "sha256":
    64 hex}``.

    Raises:
        ValueError: saying in a few words why ``data`` is not such a manifest.
    """
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise ValueError("not JSON") from None
    if not isinstance(doc, dict):
        raise ValueError("not a JSON object")
    schema = doc.get("schema")
    if schema is None and set(doc) != _LEGACY_MANIFEST_KEYS:
        raise ValueError(f"no schema {MANIFEST_SCHEMA!r}")
    if schema is not None and schema != MANIFEST_SCHEMA:
        raise ValueError(f"schema {str(schema)[:40]!r}, not {MANIFEST_SCHEMA!r}")
    rid = doc.get("run_id")
    if not isinstance(rid, str) or not _RUN_ID.fullmatch(rid):
        raise ValueError("no well-formed run_id")
    if not isinstance(doc.get("command"), str):
        raise ValueError("no command")
    if doc.get("state") not in {s.value for s in RunState}:
        raise ValueError("no known state")
    files = doc.get("files")
    if not isinstance(files, dict):
        raise ValueError("no file list")
    listed: dict[str, ManifestEntry] = {}
    for name, e in files.items():
        size = e.get("bytes") if isinstance(e, dict) else None
        digest = e.get("sha256") if isinstance(e, dict) else None
        ok_size = isinstance(size, int) and not isinstance(size, bool) and size >= 0
        ok_digest = isinstance(digest, str) and _SHA256.fullmatch(digest) is not None
        if not _plain_name(name) or name == MANIFEST or not (ok_size and ok_digest):
            raise ValueError(f"a malformed entry {str(name)[:40]!r}")
        listed[name] = ManifestEntry(size, digest)
    return listed


def _read_manifest(path: Path) -> dict[str, ManifestEntry]:
    """:func:`parse_manifest` of the regular file ``path`` (at most :data:`MANIFEST_MAX_BYTES`).

    Raises:
        OSError: it cannot be opened as a regular file (a link, a FIFO ...).
        ValueError: it is not one of this tool's manifests.
    """
    try:
        data = read_regular(path, MANIFEST_MAX_BYTES)
    except OSError as exc:
        if exc.errno == errno.EFBIG:
            raise ValueError(f"larger than {MANIFEST_MAX_BYTES} bytes") from None
        raise
    return parse_manifest(data)


@dataclass(frozen=True)
class Owned:
    """An existing directory proven to be the tool's: empty, or one run whose manifest lists it.

    Attributes:
        files: the run's files present there now (``manifest.json`` not included); () if empty.
        has_manifest: whether it holds a ``manifest.json`` (False only for an empty directory).
    """

    files: tuple[str, ...] = ()
    has_manifest: bool = False


_CLEAR_IT = "remove it or choose another output directory"


def _refuse_unlisted(d: Path, entries: dict[str, os.DirEntry]) -> None:
    """Raise :class:`NotOurs` for a non-empty directory without a manifest."""
    names = sorted(entries)
    legacy = all(
        n in KNOWN_OUTPUT_NAMES and entries[n].is_file(follow_symlinks=False) for n in names
    )
    if legacy:
        raise NotOurs(
            f"{d}: holds {names[0]!r} but no {MANIFEST}: an older tumble run cannot prove it is "
            f"one, and tumble replaces only what it can prove it wrote; {_CLEAR_IT}"
        )
    example = next((n for n in names if n not in KNOWN_OUTPUT_NAMES), names[0])
    raise NotOurs(
        f"{d}: holds {example!r} ({_kind(entries[example])}), which no tumble run wrote "
        f"(no {MANIFEST}); give a new or empty output directory"
    )


def prove_owned(d: Path, ignore: Callable[[os.DirEntry], bool] | None = None) -> Owned:
    """Prove that the existing directory ``d`` may be replaced by a run (see the module doc).

    Every entry (hidden ones and subdirectories included; ``ignore`` may pass over the tool's own
    lock and staging directory inside a mount point) must be ``manifest.json`` or a regular file
    it lists with the same size and SHA-256. Files the manifest lists may be missing.

    Raises:
        NotOurs: one line naming ``d`` and an entry that is not the tool's, and what to do.
        OSError: ``d`` cannot be listed.
    """
    with os.scandir(d) as it:
        entries = {e.name: e for e in it if ignore is None or not ignore(e)}
    if not entries:
        return Owned()
    if MANIFEST not in entries:
        _refuse_unlisted(d, entries)
    try:
        listed = _read_manifest(d / MANIFEST)
    except (OSError, ValueError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise NotOurs(f"{d}: its {MANIFEST} was not written by tumble ({why}); {_CLEAR_IT}") from None
    files = []
    for name in sorted(entries):
        if name == MANIFEST:
            continue
        e = entries[name]
        if name not in listed:
            raise NotOurs(
                f"{d}: holds {name!r} ({_kind(e)}), which its {MANIFEST} does not list "
                f"(no tumble run wrote it); {_CLEAR_IT}"
            )
        if not e.is_file(follow_symlinks=False):
            raise NotOurs(
                f"{d}: {name!r} is {_kind(e)}, not the file its {MANIFEST} lists; {_CLEAR_IT}"
            )
        want = listed[name]
        if e.stat(follow_symlinks=False).st_size != want.bytes or _digest(d / name) != (
            want.bytes,
            want.sha256,
        ):
            raise NotOurs(
                f"{d}: {name!r} was changed after its run (size or SHA-256 differs from "
                f"{MANIFEST}); {_CLEAR_IT}"
            )
        files.append(name)
    return Owned(tuple(files), has_manifest=True)


def _is_our_leftover(path: Path, run_id: str) -> bool:
    """Whether ``path`` is a real directory a killed tumble run left: it holds the staging marker
    with ``run_id``, or a manifest that proves it (:func:`prove_owned`)."""
    st = _lstat(path)
    if st is None or not stat.S_ISDIR(st.st_mode):
        return False
    try:
        if read_regular(path / STAGING_MARKER, 64).decode("ascii").strip() == run_id:
            return True
    except (OSError, UnicodeDecodeError):
        pass
    try:
        return prove_owned(path).has_manifest
    except (NotOurs, OSError):
        return False


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
class _Place:
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
        return rid is not None and _is_our_leftover(Path(entry.path), rid)

    def prove_target(self) -> Owned | None:
        """:func:`prove_owned` of the target; None when nothing is there."""
        st = _lstat(self.target)
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


def _beside(target: Path, mode: CommitMode) -> _Place:
    """Lock and staging as hidden siblings of ``target``: ``.<name>.lock``, ``.<name>.<id>.partial``."""
    prefix = f".{target.name}."
    return _Place(target, mode, target.with_name(f"{prefix}lock"), target.parent, prefix, False)


def _place(target: Path) -> _Place:
    """Decide, before anything runs, where the lock and staging go and how the files go in.

    Raises:
        NotOurs: the target is a link, not a directory, or holds the working directory.
    """
    st = _lstat(target)
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
        return _Place(target, CommitMode.IN_PLACE, lock, target, _IN_MOUNT_PREFIX, True)
    return _beside(target, CommitMode.IN_PLACE if cwd is _Cwd.IS_TARGET else CommitMode.SWAP)


def _clean_leftovers(place: _Place) -> None:
    """Remove staging/old directories that killed runs left (we hold the lock): only real
    directories named like ours that :func:`_is_our_leftover` proves; anything else stays."""
    try:
        with os.scandir(place.staging_parent) as it:
            named = [(Path(e.path), place.leftover_run_id(e.name)) for e in it]
    except OSError:
        return
    for path, rid in named:
        if rid is not None and _is_our_leftover(path, rid):
            shutil.rmtree(path, ignore_errors=True)  # never follows a link (fd-based on Linux)


def _make_staging(place: _Place, run_id: str) -> Path:
    """Create the staging directory with its marker (both new: ``mkdir``, ``O_EXCL``)."""
    staging = place.staging(run_id)
    try:
        staging.mkdir()
    except OSError as exc:
        raise OutputError(place.target, exc) from exc
    try:
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC
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
    base = _NOFOLLOW | _NONBLOCK | _CLOEXEC
    for _ in range(1000):
        try:
            return os.open(lock, os.O_RDWR | os.O_CREAT | os.O_EXCL | base, 0o644), True
        except FileExistsError:
            pass
        except OSError as exc:
            raise OutputError(lock, exc) from exc
        st = _lstat(lock)
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
    st = _lstat(path)
    return st is not None and os.path.samestat(os.fstat(fd), st)


@contextlib.contextmanager
def _lock(target: Path, lock: Path) -> Iterator[None]:
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
    if _lstat(b) is not None:
        raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(b))
    os.rename(a, b)


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY | _DIRECTORY | _CLOEXEC)
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


def _commit_swap(staging: Path, target: Path, previous: Owned | None) -> None:
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
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC
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


class _HalfCommitted(OutputError):
    """A per-file commit failed after its first rename: the target holds no manifest now."""


def _commit_in_place(staging: Path, target: Path, previous: Owned | None, run_id: str) -> None:
    """Put the files of ``staging`` into ``target`` one by one (``IN_PLACE``; module doc).

    Raises:
        OSError: before the first rename at ``target``: nothing there was changed.
        _HalfCommitted: after it (practically only if the directory changes meanwhile).
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
        raise _HalfCommitted(
            target, f"{exc.strerror or exc}; it holds part of this run and no {MANIFEST}: {_CLEAR_IT}"
        ) from exc
    _fsync_dir(target)
    shutil.rmtree(staging, ignore_errors=True)


# ---------------------------------------------------------------------------------------------
# One run
# ---------------------------------------------------------------------------------------------


@dataclass
class OutputRun:
    """A run's output directory under construction (see the module docstring).

    Write files into :attr:`path` (the hidden staging directory); they appear at :attr:`target`
    when the ``with output_run(...)`` block ends.

    Attributes:
        target: the directory the user named (absolute).
        path: the staging directory the run writes into.
        run_id: this run's id (in ``manifest.json``, ``report.json`` and recordings).
        command: what produced the run (``validate``, ``simulate`` ...).
        state: how the run ended; :meth:`mark_failed` sets FAILED with a reason.
        reason: one line saying why the run failed ("" if it did not).
        files: name -> final path of every file in the committed set (filled at the end).
        mode: how the files are put at the target (chosen before the run started).
    """

    target: Path
    path: Path
    run_id: str
    command: str
    state: RunState = RunState.COMPLETE
    reason: str = ""
    started: str = ""
    files: dict[str, Path] = field(default_factory=dict)
    mode: CommitMode = CommitMode.SWAP

    def mark_failed(self, reason: str) -> None:
        """Record that the run failed (its files are still committed, marked failed)."""
        if self.state is RunState.COMPLETE:
            self.state = RunState.FAILED
        self.reason = "; ".join(r for r in (self.reason, reason) if r)

    def final(self, name: str) -> Path:
        """Where the file ``name`` of this run is once the run is committed."""
        return self.target / name

    def _manifest(self) -> dict:
        entries = {}
        with os.scandir(self.path) as it:
            found = sorted(
                (e for e in it if e.is_file(follow_symlinks=False)), key=lambda e: e.name
            )
        for e in found:
            if e.name == MANIFEST or e.name.startswith("."):
                continue
            size, digest = _digest(Path(e.path))
            entries[e.name] = {"bytes": size, "sha256": digest}
        return {
            "schema": MANIFEST_SCHEMA,
            "run_id": self.run_id,
            "command": self.command,
            "state": self.state.value,
            "reason": self.reason,
            "started_utc": self.started,
            "finished_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "files": entries,
        }


@contextlib.contextmanager
def output_run(target: str | Path, command: str, run_id: str | None = None) -> Iterator[OutputRun]:
    """``with output_run(out_dir, "validate") as run:`` write into ``run.path``; see the module doc.

    Everything that can refuse the target (a link, a directory the tool cannot prove is its own, a
    lock file it did not create, another run holding it) is checked before the block runs. On
    leaving the block the files are listed in ``manifest.json`` and put at ``target``: state
    COMPLETE (or FAILED after :meth:`OutputRun.mark_failed`); FAILED when the block raised;
    INTERRUPTED on KeyboardInterrupt (re-raised after the commit). A ``ValueError`` (bad input
    found late) or an :class:`OutputError` (a file could not be written) commits nothing: the
    staging directory is removed and ``target`` left as it was.

    Raises:
        NotOurs: (a ValueError) ``target`` or its lock file is not the tool's to replace.
        OutputBusy: (a ValueError) another run holds ``target``.
        ValueError: ``run_id`` is not of :data:`RUN_ID_PATTERN`.
        OutputError: the set could not be written (full disk ...); ``target`` is unchanged.
    """
    rid = new_run_id() if run_id is None else run_id
    if not isinstance(rid, str) or not _RUN_ID.fullmatch(rid):
        raise ValueError(f"run_id: must look like 20240101T000000Z-0123abcd (got {rid!r:.40})")
    tgt = Path(os.path.abspath(os.fspath(target)))
    if tgt.parent == tgt:
        raise ValueError(f"{target}: cannot be an output directory")
    place = _place(tgt)
    place.prove_target()
    try:
        tgt.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(tgt, exc) from exc
    with _lock(tgt, place.lock):
        _clean_leftovers(place)
        place.prove_target()  # again, now that no other run can write there
        staging = _make_staging(place, rid)
        run = OutputRun(
            target=tgt,
            path=staging,
            run_id=rid,
            command=command,
            started=_dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            mode=place.mode,
        )
        pending: BaseException | None = None
        try:
            yield run
        except (ValueError, OutputError) as exc:
            # Bad input found late (no run took place), or a result could not be written (a
            # full disk: the set would be damaged): nothing replaces the previous run.
            shutil.rmtree(staging, ignore_errors=True)
            if isinstance(exc, OutputError):
                raise _unchanged(_public(exc, staging, tgt), tgt) from exc
            raise
        except KeyboardInterrupt as exc:
            run.state = RunState.INTERRUPTED
            run.reason = "; ".join(r for r in (run.reason, "interrupted") if r)
            pending = exc
        except BaseException as exc:
            pending = _public(exc, staging, tgt)
            run.mark_failed(f"{type(pending).__name__}: {pending}".splitlines()[0])
        try:
            _commit(run, place)
        except _HalfCommitted:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        except OSError as exc:  # a full disk: nothing replaced, the previous run stays whole
            shutil.rmtree(staging, ignore_errors=True)
            raise _unchanged(_public(exc, staging, tgt), tgt) from pending
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        if pending is not None:
            raise pending


def _unchanged(err: BaseException, target: Path) -> OutputError:
    """The one line a user reads when a run's files could not be written."""
    if isinstance(err, OutputError):
        path, reason = err.path, err.reason
    else:
        path, reason = target, (getattr(err, "strerror", None) or err)
    kept = (
        f"{target} keeps its previous contents, unchanged"
        if _lstat(target) is not None
        else f"nothing was written to {target}"
    )
    return OutputError(path, f"{reason}; {kept}")


def _public(exc: BaseException, staging: Path, target: Path) -> BaseException:
    """An :class:`OutputError` about a staging file, restated about the file the user will see."""
    if isinstance(exc, OutputError):
        try:
            rel = exc.path.relative_to(staging)
        except ValueError:
            return exc
        new = OutputError(target / rel, exc.reason)
        new.__cause__ = exc.__cause__
        return new
    return exc


def _drop_hidden(staging: Path) -> None:
    """Remove the marker and the leftovers of writers interrupted mid-file from ``staging`` (all
    created there by this run); they are not part of the run."""
    with os.scandir(staging) as it:
        hidden = [e for e in it if e.name.startswith(".")]
    for e in hidden:
        if e.is_dir(follow_symlinks=False):
            shutil.rmtree(e.path, ignore_errors=True)
        else:
            os.unlink(e.path)


def _commit(run: OutputRun, place: _Place) -> None:
    """List the run in its manifest and put it at the target (see :class:`CommitMode`).

    Raises:
        OSError: nothing at the target was changed (or :class:`_HalfCommitted`).
    """
    try:  # again: the user may have put something there while the run went on
        previous = place.prove_target()
    except NotOurs as exc:
        raise OutputError(run.target, f"it changed during the run ({exc})") from None
    _drop_hidden(run.path)
    write_text(run.path / MANIFEST, json.dumps(run._manifest(), indent=2) + "\n")
    with os.scandir(run.path) as it:
        names = sorted(e.name for e in it)
    if place.mode is CommitMode.SWAP:
        try:
            _commit_swap(run.path, run.target, previous)
        except OSError as exc:
            if exc.errno not in (errno.EBUSY, errno.EXDEV) or previous is None:
                raise
            run.mode = CommitMode.IN_PLACE  # a mount point not found up front
            _commit_in_place(run.path, run.target, previous, run.run_id)
    else:
        _commit_in_place(run.path, run.target, previous, run.run_id)
    run.files = {n: run.target / n for n in names}


__all__ = [
    "DEFAULT_ROOT",
    "KNOWN_OUTPUT_NAMES",
    "MANIFEST",
    "MANIFEST_SCHEMA",
    "RUN_ID_PATTERN",
    "SLUG_MAX_LEN",
    "STAGING_MARKER",
    "CommitMode",
    "ManifestEntry",
    "NotOurs",
    "OutputBusy",
    "OutputRun",
    "Owned",
    "RunState",
    "default_out_dir",
    "default_out_file",
    "new_run_id",
    "output_run",
    "parse_manifest",
    "prove_owned",
    "slug",
]
