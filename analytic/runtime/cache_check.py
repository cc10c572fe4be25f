"""numba's on-disk cache of this project's kernels, checked against content hashes before numba
may load any of it (standard library only: numba is not imported here).

numba keeps a compiled function as plain files: an index ``<module>.<function>-<line>.pyXY.nbi``
and data files ``<same>.<n>.nbc``, in ``__pycache__`` beside each source file that defines a cached
function, or, with ``NUMBA_CACHE_DIR``, in a directory below it named after the source directory
(:func:`cache_dirs`). numba trusts those files: a truncated or garbled one fails every later run
(``EOFError``, ``UnpicklingError``) and a data file of another kernel put in its place crashes the
process. So the tool keeps its own manifest of their SHA-256 digests (:data:`MANIFEST_NAME`, beside
the cache, written atomically under a lock) and, once per process, before the first kernel is
defined (:func:`ensure_checked`, called by :mod:`analytic.runtime.jit` at import):

* every ``.nbi`` / ``.nbc`` file of the project's kernels is hashed and compared with the manifest;
  a kernel whose index or data file is missing from it or differs is deleted (index and data files
  together), so numba compiles it again, and one line (:class:`NumbaCacheWarning`) names its
  source file and says so. A manifest that is missing, unreadable or fails its own digest counts
  as empty: every kernel is recompiled, said in one line;
* when the cache cannot be trusted or written as it is (less than :data:`MIN_FREE_BYTES` free, an
  entry that is not a regular file, a damaged file that cannot be deleted), numba is pointed
  (``NUMBA_CACHE_DIR``, its documented setting) at a private temporary directory for this run,
  removed at exit: the kernels are compiled and used, the cache itself is left as it is, and one
  line says it could not be written.

After a run's kernels are ready (:func:`record`: the end of :func:`validation.runs.warmup.warm_up`, and
the normal exit of the process that checked), the manifest is rewritten from the files present.
Processes started by a process that checked (the warm-up's pool, the plant workers) trust its check
(:data:`ENV_MARK`) and leave recording to it, so a file one of them has just written is never
taken for an unknown one by a sibling. A file numba wrote in a run killed before it was recorded
is unknown to the next run and recompiled (a few seconds, once).
"""

from __future__ import annotations

import atexit
import contextlib
import enum
import hashlib
import json
import os
import shutil
import stat
import tempfile
import time
import uuid
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from analytic.runtime.cache_dir import kernel_cache_dir
from analytic.runtime.safe_files import file_digest, file_kind, read_regular

MANIFEST_NAME = "tumble-numba-manifest.json"
"""The manifest's file, in :func:`analytic.runtime.cache_dir.kernel_cache_dir`."""
LOCK_NAME = "tumble-numba-manifest.lock"
"""The lock held while the manifest is read and rewritten (``fcntl.flock``)."""
MANIFEST_FORMAT = 1
MAX_MANIFEST_BYTES = 4 << 20
"""A larger manifest is not read (it counts as missing)."""
MIN_FREE_BYTES = 16 << 20
"""Free space the cache directory must have for numba to write to it (bytes): well above the whole
cache of the kernels (``docs/performance.md``), as numba fails a compile whose cache entry cannot be
saved."""
MIN_FREE_INODES = 64
LOCK_WAIT_S = 10.0
"""How long to wait for another process's manifest lock before going on without it (s)."""
ENV_MARK = "TUMBLE_NUMBA_CACHE_CHECKED"
"""Set by a process that checked the cache to ``<pid>:<mode>:<cache root>`` (:class:`Mode`); a
process whose parent is ``<pid>`` and whose cache root is the same trusts that check instead of
repeating it."""
PROJECT_PACKAGES = ("analytic", "mj_bridge")
"""The packages whose modules define cached kernels."""
SUFFIXES = (".nbi", ".nbc")


class NumbaCacheWarning(UserWarning):
    """Something found in numba's cache of the kernels and what was done about it (one line)."""


class Mode(enum.Enum):
    """Where numba keeps the kernels in this process after the check."""

    CACHE = "cache"  # the usual cache directory, checked
    PRIVATE = "private"  # a private temporary directory for this run (the cache is left alone)
    NONE = "none"  # no cache directory at all (numba's own fallback: compiled in memory)


@dataclass(frozen=True)
class Layout:
    """Where the manifest is and which directories hold the project's cache files.

    Attributes:
        manifest: the manifest file.
        dirs: ``(cache directory, source directory)`` pairs; numba's files for the functions
            defined in the source directory's modules live in the cache directory.
    """

    manifest: Path
    dirs: tuple[tuple[Path, Path], ...]

    @property
    def root(self) -> Path:
        return self.manifest.parent


@dataclass(frozen=True)
class CheckResult:
    """What :func:`check` found and did.

    Attributes:
        mode: where numba keeps the kernels from now on (:class:`Mode`).
        removed: the kernels deleted (their index file paths), to be recompiled.
        lines: what was said, one line each.
        problems: why the cache cannot be used as it is (empty: it can).
        files: cache files hashed; nbytes: their total size (bytes); seconds: the check's wall time.
    """

    mode: Mode
    removed: tuple[str, ...] = ()
    lines: tuple[str, ...] = ()
    problems: tuple[str, ...] = ()
    files: int = 0
    nbytes: int = 0
    seconds: float = 0.0


@dataclass
class _Scan:
    """The project's cache files present: regular ones by path, and what else sits there."""

    regular: dict[Path, str] = field(default_factory=dict)  # path -> kernel (group) name
    irregular: list[tuple[Path, str]] = field(default_factory=list)  # path, kind


# ----------------------------------------------------------------------------------------------
# Files
# ----------------------------------------------------------------------------------------------


def _write_atomic(path: Path, data: bytes) -> None:
    """``data`` to a new temporary file beside ``path`` (fsync-ed), then renamed over it."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    fd = os.open(tmp, flags | getattr(os, "O_CLOEXEC", 0), 0o644)
    try:
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view) :]
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def _locked(root: Path) -> Iterator[None]:
    """Hold the manifest's lock in ``root`` (waits up to :data:`LOCK_WAIT_S`, then goes on
    without it; nothing is locked where it cannot be)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(root / LOCK_NAME, flags | getattr(os, "O_CLOEXEC", 0), 0o644)
    except OSError:
        yield
        return
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            yield
            return
        deadline = time.monotonic() + LOCK_WAIT_S
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except OSError:
                if time.monotonic() > deadline:
                    break
                time.sleep(0.02)
        yield
    finally:
        os.close(fd)  # releases the lock


# ----------------------------------------------------------------------------------------------
# Where the files are
# ----------------------------------------------------------------------------------------------


def project_root_variants() -> list[Path]:
    """The directory holding the project's packages, as this module's path gives it and resolved
    (numba names cache directories after the path a module was imported from)."""
    here = Path(os.path.abspath(__file__)).parent.parent.parent
    roots = [here, here.resolve()]
    return list(dict.fromkeys(roots))


def source_dirs(root: Path) -> list[Path]:
    """The directories of :data:`PROJECT_PACKAGES` below ``root`` that hold Python modules."""
    found = []
    for pkg in PROJECT_PACKAGES:
        base = root / pkg
        if not base.is_dir():
            continue
        for d in [base, *sorted(p for p in base.rglob("*") if p.is_dir())]:
            if d.name != "__pycache__" and any(d.glob("*.py")):
                found.append(d)
    return found


def numba_subdir(source_dir: Path) -> str:
    """The directory numba makes below ``NUMBA_CACHE_DIR`` for the modules of ``source_dir``: its
    name, ``_``, the SHA-1 of its absolute path."""
    path = str(source_dir)
    return f"{os.path.basename(path)}_{hashlib.sha1(path.encode()).hexdigest()}"


def cache_dirs(source_dir: Path) -> list[Path]:
    """Where numba keeps the cache files of the functions defined in ``source_dir``."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        return [Path(env) / numba_subdir(source_dir)]
    return [source_dir / "__pycache__"]


def layout() -> Layout | None:
    """The manifest and the cache directories of this process (None: no writable cache
    directory, numba compiles in memory)."""
    root = kernel_cache_dir()
    if root is None:
        return None
    pairs: dict[Path, Path] = {}
    for proj in project_root_variants():
        for src in source_dirs(proj):
            for d in cache_dirs(src):
                pairs.setdefault(d, src)
    return Layout(Path(root) / MANIFEST_NAME, tuple(pairs.items()))


def kernel_name(filename: str) -> str | None:
    """The kernel (index file name) a cache file belongs to: ``X.nbi`` and ``X.<n>.nbc`` both give
    ``X.nbi``; None for any other file."""
    if filename.endswith(".nbi"):
        return filename
    if filename.endswith(".nbc"):
        stem, _, number = filename[: -len(".nbc")].rpartition(".")
        if stem and number.isdigit():
            return f"{stem}.nbi"
    return None


def scan(lay: Layout) -> _Scan:
    """The project's cache files present in ``lay``'s directories (``lstat``: nothing is
    opened)."""
    found = _Scan()
    for d, _src in lay.dirs:
        try:
            entries = list(os.scandir(d))
        except (FileNotFoundError, NotADirectoryError):
            continue
        except OSError:
            continue
        for e in entries:
            group = kernel_name(e.name)
            if group is None:
                continue
            path = Path(d) / e.name
            try:
                mode = os.lstat(path).st_mode
            except FileNotFoundError:
                continue
            if stat.S_ISREG(mode):
                found.regular[path] = str(Path(d) / group)
            else:
                found.irregular.append((path, file_kind(mode)))
    return found


def source_of(index: str, lay: Layout) -> str:
    """The source file whose function the kernel of index file ``index`` is (for messages)."""
    p = Path(index)
    src = dict(lay.dirs).get(p.parent)
    module = p.name.split(".", 1)[0]
    return str(src / f"{module}.py") if src is not None else p.name


# ----------------------------------------------------------------------------------------------
# The manifest
# ----------------------------------------------------------------------------------------------


def _manifest_digest(files: dict[str, str]) -> str:
    body = json.dumps({"format": MANIFEST_FORMAT, "files": files}, sort_keys=True)
    return hashlib.sha256(body.encode()).hexdigest()


def load_manifest(path: Path) -> tuple[dict[str, str] | None, str]:
    """``(path -> hex SHA-256, "")`` of the manifest at ``path``, or ``(None, why)`` when it is
    missing, unreadable, of another format or fails its own digest."""
    try:
        doc = json.loads(read_regular(path, MAX_MANIFEST_BYTES))
    except FileNotFoundError:
        return None, "no manifest of its contents"
    except (OSError, ValueError) as exc:
        return None, f"its manifest is unreadable ({exc})"
    files = doc.get("files") if isinstance(doc, dict) else None
    valid = (
        isinstance(files, dict)
        and doc.get("format") == MANIFEST_FORMAT
        and all(isinstance(k, str) and isinstance(v, str) for k, v in files.items())
        and doc.get("sha256") == _manifest_digest(files)
    )
    if not valid:
        return None, "its manifest failed its own content check"
    return files, ""


def write_manifest(path: Path, files: dict[str, str]) -> None:
    """The manifest of ``files`` (path -> hex SHA-256) at ``path``, atomically."""
    doc = {"format": MANIFEST_FORMAT, "files": files, "sha256": _manifest_digest(files)}
    _write_atomic(path, (json.dumps(doc, sort_keys=True, indent=0) + "\n").encode())


# ----------------------------------------------------------------------------------------------
# Check and record
# ----------------------------------------------------------------------------------------------


def room_short(lay: Layout) -> str:
    """Why numba could not save its cache in ``lay``'s root ("" when there is room); a root not
    made yet is judged by the filesystem of its nearest existing parent."""
    where = lay.root
    while not where.exists() and where.parent != where:
        where = where.parent
    try:
        st = os.statvfs(where)
    except OSError:
        return ""
    free = st.f_bavail * st.f_frsize
    if free < MIN_FREE_BYTES:
        return f"{lay.root} has {free // 1024} kB free"
    if st.f_files and st.f_favail < MIN_FREE_INODES:
        return f"{lay.root} has {st.f_favail} free inodes"
    return ""


def _delete_kernel(paths: list[Path]) -> bool:
    """Delete a kernel's index, then its data files (regular files only); False when one could
    not be deleted."""
    ok = True
    for p in sorted(paths, key=lambda p: not p.name.endswith(".nbi")):  # the index first
        try:
            if stat.S_ISREG(os.lstat(p).st_mode):
                os.unlink(p)
        except FileNotFoundError:
            pass
        except OSError:
            ok = False
    return ok


def check(lay: Layout) -> CheckResult:
    """Compare the cache files in ``lay`` with its manifest and delete every kernel that does not
    match (module docstring); the cache is left alone and :attr:`Mode.PRIVATE` returned when it
    cannot be trusted or written as it is."""
    t0 = time.perf_counter()
    lines: list[str] = []
    with _locked(lay.root) if lay.root.is_dir() else contextlib.nullcontext():
        found = scan(lay)
        known, why = load_manifest(lay.manifest) if found.regular else ({}, "")
        bad: dict[str, list[Path]] = {}
        differs: set[str] = set()  # kernels with a recorded file whose digest changed
        nbytes = 0
        for path, group in found.regular.items():
            try:
                digest, size = file_digest(path)
            except FileNotFoundError:
                continue
            except OSError:
                digest, size = "", 0
            nbytes += size
            if known is None or known.get(str(path)) != digest:
                bad.setdefault(group, [])
                if known is not None and str(path) in known:
                    differs.add(group)
        for path, group in found.regular.items():
            if group in bad:
                bad[group].append(path)
        undeletable = [g for g, paths in bad.items() if not _delete_kernel(paths)]
    if bad and known is None:
        n = len(bad)
        what = "compiled kernel was" if n == 1 else "compiled kernels were"
        lines.append(f"numba cache in {lay.root}: {why}; its {n} {what} deleted, to be recompiled")
    else:
        for group in sorted(bad):
            what = (
                "differs from its recorded SHA-256 (damaged or replaced)"
                if group in differs
                else "was not recorded by a finished run"
            )
            lines.append(
                f"numba cache of {source_of(group, lay)} ({Path(group).name}) {what}; "
                "deleted, it will be recompiled"
            )
    problems = [f"{p} is a {kind}" for p, kind in found.irregular]
    problems += [f"{g} could not be deleted" for g in undeletable]
    short = room_short(lay)
    problems += [short] if short else []
    mode = Mode.PRIVATE if problems else Mode.CACHE
    return CheckResult(
        mode,
        removed=tuple(sorted(bad)),
        lines=tuple(lines),
        problems=tuple(problems),
        files=len(found.regular),
        nbytes=nbytes,
        seconds=time.perf_counter() - t0,
    )


def record(lay: Layout | None = None) -> bool:
    """Rewrite the manifest from the cache files present (after a run's kernels are compiled or
    loaded; under the lock). False when it could not be written (the next run then recompiles
    what it does not know)."""
    lay = lay or _state.layout
    if lay is None or _state.mode is not Mode.CACHE:
        return False
    try:
        with _locked(lay.root):
            files = {}
            for path in scan(lay).regular:
                try:
                    files[str(path)] = file_digest(path)[0]
                except OSError:
                    continue
            write_manifest(lay.manifest, files)
    except OSError:
        return False
    return True


# ----------------------------------------------------------------------------------------------
# Once per process
# ----------------------------------------------------------------------------------------------


@dataclass
class _State:
    done: bool = False
    mode: Mode = Mode.CACHE
    layout: Layout | None = None
    result: CheckResult | None = None
    private_dir: Path | None = None
    pid: int = 0
    finished: bool = False


_state = _State()


def _say(line: str) -> None:
    warnings.warn(line, NumbaCacheWarning, stacklevel=3)


def _cache_root() -> str:
    """The cache root of this process as :data:`ENV_MARK` names it ("" for none)."""
    root = kernel_cache_dir()
    return str(root) if root is not None else ""


def _mark(mode: Mode) -> None:
    os.environ[ENV_MARK] = f"{os.getpid()}:{mode.value}:{_cache_root()}"


def _parent_checked() -> Mode | None:
    """The mode of the check the parent process made of this process's cache root
    (:data:`ENV_MARK`), None when it made none."""
    pid, _, rest = os.environ.get(ENV_MARK, "").partition(":")
    mode, _, root = rest.partition(":")
    if pid != str(os.getppid()) or root != _cache_root():
        return None
    try:
        return Mode(mode)
    except ValueError:
        return None


def _use_private_dir(why: str) -> None:
    """Point numba (``NUMBA_CACHE_DIR``) at a new private temporary directory for this process
    and the processes it starts; removed at exit."""
    d = Path(tempfile.mkdtemp(prefix="tumble-numba-"))
    os.environ["NUMBA_CACHE_DIR"] = str(d)
    _state.private_dir, _state.mode = d, Mode.PRIVATE
    _say(
        f"numba's cache could not be written or trusted as it is ({why}); the kernels are "
        "compiled for this run only and the cache is left as it is"
    )


def finish() -> None:
    """At the end of the process that checked (run at exit, and by ``tumble`` before it ends
    without Python's teardown): record the manifest (:func:`record`), or remove the private
    directory. Nothing in another process (a forked child) or a second time."""
    if os.getpid() != _state.pid or _state.finished or not _state.done:
        return
    _state.finished = True
    if _state.mode is Mode.CACHE and _state.result is not None:
        record()
    elif _state.private_dir is not None:
        shutil.rmtree(_state.private_dir, ignore_errors=True)


def ensure_checked() -> CheckResult | None:
    """Check numba's cache of the kernels once in this process (:func:`check`), before any kernel
    is defined; what it found is said in one line each. A process whose parent checked trusts
    it. Returns the result (None when trusted from the parent or there is no cache)."""
    if _state.done:
        return _state.result
    _state.done, _state.pid = True, os.getpid()
    inherited = _parent_checked()
    if inherited is not None:
        _state.mode = inherited
        _state.layout = layout() if inherited is Mode.CACHE else None
        _mark(inherited)
        return None
    lay = layout()
    if lay is None:
        _state.mode = Mode.NONE
        _mark(Mode.NONE)
        return None
    result = check(lay)
    for line in result.lines:
        _say(line)
    _state.layout, _state.result = lay, result
    if result.problems:
        _use_private_dir("; ".join(result.problems))
    _mark(_state.mode)
    atexit.register(finish)
    return result


def disk_cache_mode() -> Mode:
    """Where numba keeps the kernels in this process (:class:`Mode`)."""
    return _state.mode


def removed_any() -> bool:
    """Whether this process's check deleted kernels from the cache (they will be recompiled)."""
    return bool(_state.result and _state.result.removed)


__all__ = [
    "ENV_MARK",
    "MANIFEST_NAME",
    "CheckResult",
    "Layout",
    "Mode",
    "NumbaCacheWarning",
    "cache_dirs",
    "check",
    "disk_cache_mode",
    "ensure_checked",
    "file_digest",
    "finish",
    "kernel_name",
    "layout",
    "load_manifest",
    "record",
    "removed_any",
    "scan",
]
