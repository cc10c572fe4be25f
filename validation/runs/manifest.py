"""Ownership of an output directory: its ``manifest.json`` proves it is a tumble run's.

Rule 2 of :mod:`validation.runs.outputs`: a directory is the tool's only if a regular
``manifest.json`` of :data:`MANIFEST_SCHEMA` with a well-formed run id lists every entry of it as a
regular file whose size and SHA-256 still match (:func:`prove_owned`); anything else is the user's
and is refused (:class:`NotOurs`, a ``ValueError``) in one line naming an example entry. Everything
here reads what is there without following a link and without blocking.
"""

from __future__ import annotations

import enum
import errno
import json
import os
import re
import stat
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from analytic.runtime.safe_files import file_digest, read_regular
from validation.runs.atomic import OutputError
from validation.runs.paths import is_run_id


class RunState(enum.Enum):
    """How a run ended, as recorded in ``manifest.json``."""

    COMPLETE = "complete"
    FAILED = "failed"
    INTERRUPTED = "interrupted"


MANIFEST = "manifest.json"

MANIFEST_SCHEMA = "tumble-manifest/1"
"""The ``schema`` field of every ``manifest.json`` this tool writes."""

MANIFEST_MAX_BYTES = 4 << 20
"""A ``manifest.json`` larger than this (4 MiB) is not one of ours: it is not read."""

STAGING_MARKER = ".tumble-staging"
"""A file created (``O_EXCL``) in every staging directory as it is made, holding the run id: the
proof that a leftover staging directory of a killed run is the tool's to delete."""

_SHA256 = re.compile(r"^[0-9a-f]{64}$")

_LEGACY_MANIFEST_KEYS = frozenset(
    {"run_id", "command", "state", "reason", "started_utc", "finished_utc", "files"}
)
"""The keys of a manifest written before :data:`MANIFEST_SCHEMA` existed (accepted, same checks)."""

KNOWN_OUTPUT_NAMES = frozenset(
    {
        MANIFEST,
        "report.md",
        "report.html",
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
        "sweep.html",
        "sweep.rrd",
        "work_precision.png",
        "hard_cases.md",
        "hard_cases.html",
        "hard_cases.json",
        "bench.json",
        "demo.rrd",
        "demo.md",
    }
)
"""Every file name a tumble command writes into its directory. Names prove nothing: a directory
holding only these but no manifest (an older run) is refused all the same; the names only choose
the message ("remove it or choose another output directory")."""


class NotOurs(ValueError):
    """A path the run would replace, delete or write (the target, its lock) is not the tool's."""


# ---------------------------------------------------------------------------------------------
# Reading what is there: never through a link, never blocking
# ---------------------------------------------------------------------------------------------

NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
NONBLOCK = getattr(os, "O_NONBLOCK", 0)
CLOEXEC = getattr(os, "O_CLOEXEC", 0)
DIRECTORY = getattr(os, "O_DIRECTORY", 0)


def json_object(data: bytes) -> dict:
    """``data`` as a JSON object; ValueError "not JSON" / "not a JSON object" otherwise (the
    manifests' first test, this module's and the fuzzing campaign's)."""
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise ValueError("not JSON") from None
    if not isinstance(doc, dict):
        raise ValueError("not a JSON object")
    return doc


def lstat_or_none(path: Path) -> os.stat_result | None:
    """``os.lstat(path)`` (a link is not followed), None when nothing is there."""
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None


def size_and_digest(path: Path) -> tuple[int, str]:
    """``(bytes, SHA-256 hex)`` of the regular file ``path``, never through a link or blocking
    (:func:`analytic.runtime.safe_files.file_digest`)."""
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
    doc = json_object(data)
    schema = doc.get("schema")
    if schema is None and set(doc) != _LEGACY_MANIFEST_KEYS:
        raise ValueError(f"no schema {MANIFEST_SCHEMA!r}")
    if schema is not None and schema != MANIFEST_SCHEMA:
        raise ValueError(f"schema {str(schema)[:40]!r}, not {MANIFEST_SCHEMA!r}")
    rid = doc.get("run_id")
    if not is_run_id(rid):
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


CLEAR_IT = "remove it or choose another output directory"


def _refuse_unlisted(d: Path, entries: dict[str, os.DirEntry]) -> None:
    """Raise :class:`NotOurs` for a non-empty directory without a manifest."""
    names = sorted(entries)
    legacy = all(
        n in KNOWN_OUTPUT_NAMES and entries[n].is_file(follow_symlinks=False) for n in names
    )
    if legacy:
        raise NotOurs(
            f"{d}: holds {names[0]!r} but no {MANIFEST}: an older tumble run cannot prove it is "
            f"one, and tumble replaces only what it can prove it wrote; {CLEAR_IT}"
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
        raise NotOurs(
            f"{d}: its {MANIFEST} was not written by tumble ({why}); {CLEAR_IT}"
        ) from None
    files = []
    for name in sorted(entries):
        if name == MANIFEST:
            continue
        e = entries[name]
        if name not in listed:
            raise NotOurs(
                f"{d}: holds {name!r} ({_kind(e)}), which its {MANIFEST} does not list "
                f"(no tumble run wrote it); {CLEAR_IT}"
            )
        if not e.is_file(follow_symlinks=False):
            raise NotOurs(
                f"{d}: {name!r} is {_kind(e)}, not the file its {MANIFEST} lists; {CLEAR_IT}"
            )
        want = listed[name]
        if e.stat(follow_symlinks=False).st_size != want.bytes or size_and_digest(d / name) != (
            want.bytes,
            want.sha256,
        ):
            raise NotOurs(
                f"{d}: {name!r} was changed after its run (size or SHA-256 differs from "
                f"{MANIFEST}); {CLEAR_IT}"
            )
        files.append(name)
    return Owned(tuple(files), has_manifest=True)


def is_our_leftover(path: Path, run_id: str) -> bool:
    """Whether ``path`` is a real directory a killed tumble run left: it holds the staging marker
    with ``run_id``, or a manifest that proves it (:func:`prove_owned`)."""
    st = lstat_or_none(path)
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


def check_committed(target: Path, files: Mapping[str, Path]) -> None:
    """Every file of ``files`` (name -> path) is in the committed directory ``target``, whole:
    listed in its ``manifest.json`` (:func:`parse_manifest`) with the size found there (a run's
    verdict is given only then).

    Raises:
        OutputError: the manifest is not readable, or a file is missing or not the size its
            manifest records.
    """
    try:
        listed = parse_manifest((target / MANIFEST).read_bytes())
    except (OSError, ValueError) as exc:
        raise OutputError(target / MANIFEST, f"not readable after the commit ({exc})") from exc
    for name, path in files.items():
        if name == MANIFEST:
            continue
        try:
            size = path.stat().st_size
        except OSError as exc:
            raise OutputError(path, f"missing after the commit ({exc.strerror})") from exc
        recorded = listed[name].bytes if name in listed else None
        if recorded != size:
            raise OutputError(path, f"{size} bytes after the commit, the manifest says {recorded}")


__all__ = [
    "CLEAR_IT",
    "CLOEXEC",
    "DIRECTORY",
    "KNOWN_OUTPUT_NAMES",
    "MANIFEST",
    "MANIFEST_MAX_BYTES",
    "MANIFEST_SCHEMA",
    "NOFOLLOW",
    "NONBLOCK",
    "STAGING_MARKER",
    "ManifestEntry",
    "NotOurs",
    "Owned",
    "RunState",
    "check_committed",
    "is_our_leftover",
    "lstat_or_none",
    "parse_manifest",
    "prove_owned",
    "size_and_digest",
]
