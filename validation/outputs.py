"""Output directories: one run, whole, in a place the user chose.

Two rules hold for every command that writes a directory (``validate``, ``simulate``, ``sweep``,
``hard-cases``, ``bench --out``, ``demo``) and for the Python functions behind them:

1. **Paths never come from scene data.** A scene file is untrusted: its ``name`` only ever becomes a
   *slug* (:func:`slug`) inside a default directory under ``out/`` (:func:`default_out_dir`); a name
   that cannot be made safe is refused with a ``ValueError`` naming ``scene.name``. Inside a run
   directory every file name is a constant of the code.
2. **A directory is one run, whole** (:class:`OutputRun`). The run builds its files in a hidden
   sibling ``.<name>.<run id>.partial`` and swaps it in at the end (one ``renameat2`` exchange on
   Linux, two renames elsewhere), so after any run the directory holds either that run's files or
   the previous run's, never a mix. A run that fails or is interrupted (Ctrl-C, SIGTERM) still
   swaps in what it wrote, marked in ``manifest.json`` as ``failed`` or ``interrupted``; a run
   whose files cannot be written (a full disk) leaves the previous run untouched and raises
   :class:`~validation.atomic.OutputError`. ``manifest.json`` lists every file with its size and
   SHA-256 and the run id (which ``report.json`` and the recording also carry). A second run into
   the same directory while one is writing is refused (an ``fcntl`` lock on a hidden sibling file),
   never interleaved. An existing directory that holds anything but a tumble run is never replaced.
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
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from validation.atomic import OutputError, write_text

DEFAULT_ROOT = Path("out")
"""Where a command's default output directory goes, relative to the working directory."""

MANIFEST = "manifest.json"

SLUG_MAX_LEN = 64
"""Longest slug kept verbatim. Longer names are cut and given a hash of the whole name (so two
long names stay distinct); 64 + prefix + hash stays far below NAME_MAX (255 bytes) on every
common filesystem."""

_SLUG_OK = re.compile(r"[^A-Za-z0-9._-]+")

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
"""Every file name a tumble command writes into its directory. An existing directory that holds
only these (an older run without a manifest) may be replaced; anything else there is the user's."""


class RunState(enum.Enum):
    """How a run ended, as recorded in ``manifest.json``."""

    COMPLETE = "complete"
    FAILED = "failed"
    INTERRUPTED = "interrupted"


class OutputBusy(ValueError):
    """Another run is writing into the same output directory right now."""


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


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# ---------------------------------------------------------------------------------------------
# The directory swap
# ---------------------------------------------------------------------------------------------

_RENAME_EXCHANGE = 2  # linux/fs.h


def _renameat2_exchange(a: Path, b: Path) -> bool:
    """Atomically exchange two paths (Linux ``renameat2(RENAME_EXCHANGE)``); False if unsupported."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    rc = fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False  # filesystem or kernel without RENAME_EXCHANGE
    raise OSError(err, os.strerror(err), str(b))


def _swap_in(staging: Path, target: Path) -> Path | None:
    """Put ``staging`` at ``target``; returns where the previous contents went (None if none)."""
    if not target.exists():
        os.rename(staging, target)
        return None
    if _renameat2_exchange(staging, target):
        return staging  # staging now holds the previous run
    old = staging.with_name(staging.name.removesuffix(".partial") + ".old")
    os.rename(target, old)
    try:
        os.rename(staging, target)
    except BaseException:
        os.rename(old, target)  # put the previous run back
        raise
    return old


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


# ---------------------------------------------------------------------------------------------
# One run
# ---------------------------------------------------------------------------------------------


@dataclass
class OutputRun:
    """A run's output directory under construction (see the module docstring).

    Write files into :attr:`path` (the hidden staging directory); they appear at :attr:`target`
    when the ``with output_run(...)`` block ends. Attributes:

    Attributes:
        target: the directory the user named (absolute).
        path: the staging directory the run writes into.
        run_id: this run's id (in ``manifest.json``, ``report.json`` and recordings).
        command: what produced the run (``validate``, ``simulate`` ...).
        state: how the run ended; :meth:`mark_failed` sets FAILED with a reason.
        reason: one line saying why the run failed ("" if it did not).
        files: name -> final path of every file in the committed set (filled at the end).
    """

    target: Path
    path: Path
    run_id: str
    command: str
    state: RunState = RunState.COMPLETE
    reason: str = ""
    started: str = ""
    files: dict[str, Path] = field(default_factory=dict)

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
        for p in sorted(self.path.iterdir()):
            if p.name == MANIFEST or p.name.startswith("."):
                continue
            if p.is_file():
                entries[p.name] = {"bytes": p.stat().st_size, "sha256": _sha256(p)}
        return {
            "run_id": self.run_id,
            "command": self.command,
            "state": self.state.value,
            "reason": self.reason,
            "started_utc": self.started,
            "finished_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "files": entries,
        }


def _check_replaceable(target: Path) -> None:
    """Refuse to replace anything but a directory of tumble runs (or an empty one)."""
    if not target.exists():
        return
    if not target.is_dir():
        raise ValueError(f"{target}: exists and is not a directory")
    foreign = [
        p.name
        for p in target.iterdir()
        if p.name not in KNOWN_OUTPUT_NAMES and not (p.name.startswith(".") and p.is_file())
    ]
    if foreign:
        raise ValueError(
            f"{target}: holds files that no tumble run wrote (e.g. {sorted(foreign)[0]!r}); "
            "give a new or empty output directory"
        )


_HELD_LOCKS: set[int] = set()
"""File descriptors of the locks this process holds. A process forked while one is held (a worker
of :mod:`validation.workers`) closes its copy at once: an ``flock`` lives while any copy is open,
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


@contextlib.contextmanager
def _lock(target: Path) -> Iterator[None]:
    """An exclusive, non-blocking lock for ``target`` on the hidden file ``.<name>.lock`` beside it."""
    lock = target.with_name(f".{target.name}.lock")
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            try:
                pid = lock.read_text().strip() or "?"
            except OSError:
                pid = "?"
            raise OutputBusy(
                f"{target}: another tumble run (pid {pid}) is writing into this directory; "
                "not started"
            ) from None
        # The lock file may have been removed by a run that finished meanwhile: lock the new one.
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(lock))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    _HELD_LOCKS.add(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        yield
    finally:
        with contextlib.suppress(OSError):
            lock.unlink()
        _HELD_LOCKS.discard(fd)
        os.close(fd)


def _clean_stale(target: Path) -> None:
    """Remove staging/old siblings that killed runs left behind (we hold the lock)."""
    for p in target.parent.glob(f".{_glob_escape(target.name)}.*"):
        if p.is_dir() and (p.name.endswith(".partial") or p.name.endswith(".old")):
            shutil.rmtree(p, ignore_errors=True)


def _glob_escape(s: str) -> str:
    return re.sub(r"([*?\[])", r"[\1]", s)


@contextlib.contextmanager
def output_run(target: str | Path, command: str, run_id: str | None = None) -> Iterator[OutputRun]:
    """``with output_run(out_dir, "validate") as run:`` write into ``run.path``; see the module doc.

    On leaving the block the files are listed in ``manifest.json`` and swapped in at ``target``:
    state COMPLETE (or FAILED after :meth:`OutputRun.mark_failed`); FAILED when the block raised;
    INTERRUPTED on KeyboardInterrupt (re-raised after the commit). A ``ValueError`` (bad input
    found late) or an :class:`OutputError` (a file could not be written) commits nothing: the
    staging directory is removed and ``target`` left as it was.

    Raises:
        ValueError: ``target`` exists and is not a directory of tumble runs.
        OutputBusy: another run holds ``target``.
        OutputError: the set could not be written (full disk ...); ``target`` is unchanged.
    """
    tgt = Path(os.path.abspath(os.fspath(target)))
    if tgt.is_symlink():
        tgt = tgt.resolve()
    if tgt.parent == tgt:
        raise ValueError(f"{target}: cannot be an output directory")
    _check_replaceable(tgt)
    try:
        tgt.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(tgt, exc) from exc
    with _lock(tgt):
        _check_replaceable(tgt)  # again, now that nobody else can write there
        _clean_stale(tgt)
        rid = run_id or new_run_id()
        staging = tgt.with_name(f".{tgt.name}.{rid}.partial")
        try:
            staging.mkdir()
        except OSError as exc:
            raise OutputError(tgt, exc) from exc
        run = OutputRun(
            target=tgt,
            path=staging,
            run_id=rid,
            command=command,
            started=_dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
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
            _commit(run)
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
    path, reason = (err.path, err.reason) if isinstance(err, OutputError) else (target, err)
    kept = (
        f"{target} keeps its previous contents, unchanged"
        if target.exists()
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


def _commit(run: OutputRun) -> None:
    write_text(run.path / MANIFEST, json.dumps(run._manifest(), indent=2) + "\n")
    names = sorted(p.name for p in run.path.iterdir() if not p.name.startswith("."))
    for p in run.path.iterdir():  # leftovers of a writer that was interrupted mid-file
        if p.name.startswith(".") and p.is_file():
            p.unlink(missing_ok=True)
    old = _swap_in(run.path, run.target)
    _fsync_dir(run.target.parent)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    run.files = {n: run.target / n for n in names}


__all__ = [
    "DEFAULT_ROOT",
    "KNOWN_OUTPUT_NAMES",
    "MANIFEST",
    "SLUG_MAX_LEN",
    "OutputBusy",
    "OutputRun",
    "RunState",
    "default_out_dir",
    "default_out_file",
    "new_run_id",
    "output_run",
    "slug",
]
