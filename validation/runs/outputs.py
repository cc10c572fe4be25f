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

This module is the run itself (:class:`OutputRun`, :func:`output_run`, the commit); its parts, each
re-exported here: :mod:`validation.runs.paths` (slugs, default paths, run ids),
:mod:`validation.runs.manifest` (the manifest and the proof of ownership),
:mod:`validation.runs.locks` (the lock) and :mod:`validation.runs.staging` (where the staging
directory goes and how its files are put at the target).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import json
import os
import shutil
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from validation.runs import interrupts
from validation.runs.atomic import OutputError, write_text
from validation.runs.locks import OutputBusy, hold_lock
from validation.runs.manifest import (
    KNOWN_OUTPUT_NAMES,
    MANIFEST,
    MANIFEST_SCHEMA,
    STAGING_MARKER,
    ManifestEntry,
    NotOurs,
    Owned,
    RunState,
    lstat_or_none,
    parse_manifest,
    prove_owned,
    size_and_digest,
)
from validation.runs.paths import (
    DEFAULT_ROOT,
    RUN_ID_PATTERN,
    SLUG_MAX_LEN,
    default_out_dir,
    default_out_file,
    is_run_id,
    new_run_id,
    slug,
)
from validation.runs.staging import (
    CommitMode,
    HalfCommitted,
    Place,
    clean_leftovers,
    commit_in_place,
    commit_swap,
    make_staging,
    place_for,
)

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

    def keep_only(self, files: Mapping[str, Path]) -> None:
        """Remove from the staging directory (this run's own, created for it) every file
        ``files`` does not name (a figure drawn before an interrupt stopped the others, a
        recording left out): the committed set is what the run's report names, nothing more."""
        named = {p.name for p in files.values()}
        for p in self.path.iterdir():
            if not p.name.startswith(".") and p.is_file() and p.name not in named:
                p.unlink(missing_ok=True)

    def _manifest(self) -> dict:
        entries = {}
        with os.scandir(self.path) as it:
            found = sorted(
                (e for e in it if e.is_file(follow_symlinks=False)), key=lambda e: e.name
            )
        for e in found:
            if e.name == MANIFEST or e.name.startswith("."):
                continue
            size, digest = size_and_digest(Path(e.path))
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
    INTERRUPTED on KeyboardInterrupt, on an exception a signal caused, and when a signal arrived
    during a block that ended normally (another layer caught it: the set may be partial;
    :mod:`validation.runs.interrupts`), the interrupt raised after the commit. A ``ValueError`` (bad input
    found late) or an :class:`OutputError` (a file could not be written) commits nothing: the
    staging directory is removed and ``target`` left as it was.

    Raises:
        NotOurs: (a ValueError) ``target`` or its lock file is not the tool's to replace.
        OutputBusy: (a ValueError) another run holds ``target``.
        ValueError: ``run_id`` is not of :data:`RUN_ID_PATTERN`.
        OutputError: the set could not be written (full disk ...); ``target`` is unchanged.
    """
    rid = new_run_id() if run_id is None else run_id
    if not is_run_id(rid):
        raise ValueError(f"run_id: must look like 20240101T000000Z-0123abcd (got {rid!r:.40})")
    tgt = Path(os.path.abspath(os.fspath(target)))
    if tgt.parent == tgt:
        raise ValueError(f"{target}: cannot be an output directory")
    place = place_for(tgt)
    place.prove_target()
    try:
        tgt.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(tgt, exc) from exc
    with hold_lock(tgt, place.lock):
        clean_leftovers(place)
        place.prove_target()  # again, now that no other run can write there
        staging = make_staging(place, rid)
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
        except BaseException as exc:
            # an interrupt, or what a signal's interrupt became (an ImportError of an import
            # it cut ...; interrupts.interrupt_of): the set is interrupted, not failed
            pending = interrupts.interrupt_of(exc)
            if pending is None:
                pending = _public(exc, staging, tgt)
                run.mark_failed(f"{type(pending).__name__}: {pending}".splitlines()[0])
        else:
            if interrupts.received():  # a signal another layer caught (a plant's interrupted run)
                pending = interrupts.interrupt()
        if isinstance(pending, KeyboardInterrupt):
            run.state = RunState.INTERRUPTED
            run.reason = "; ".join(r for r in (run.reason, "interrupted") if r)
        try:
            _commit(run, place)
        except HalfCommitted:
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
        if lstat_or_none(target) is not None
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


def _commit(run: OutputRun, place: Place) -> None:
    """List the run in its manifest and put it at the target (see :class:`CommitMode`).

    Raises:
        OSError: nothing at the target was changed (or :class:`HalfCommitted`).
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
            commit_swap(run.path, run.target, previous)
        except OSError as exc:
            if exc.errno not in (errno.EBUSY, errno.EXDEV) or previous is None:
                raise
            run.mode = CommitMode.IN_PLACE  # a mount point not found up front
            commit_in_place(run.path, run.target, previous, run.run_id)
    else:
        commit_in_place(run.path, run.target, previous, run.run_id)
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
