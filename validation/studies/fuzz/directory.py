"""A campaign's directory: proven the campaign's own by its manifest, written file by file, read
back only as it was written.

A campaign grows while it runs (``scenes/``, ``counterexamples/``) and can be resumed, so it cannot
be staged and swapped in whole as a run of ``validate`` is (:mod:`validation.runs.outputs`). The
same ownership rule holds all the same:

* ``OUT`` may be new, empty, or a campaign's: its ``manifest.json`` of schema
  :data:`CAMPAIGN_SCHEMA` names the campaign (its configuration, a run id) and lists every file the
  campaign wrote (``campaign_config.json``, ``scenes/<i>.json``, ``counterexamples/<key>.toml`` /
  ``.json``, ``campaign.md`` / ``.json`` / ``.png`` / ``.html``) with its size and SHA-256. Anything else there
  (a user's file, a subdirectory, a link, a FIFO, an older campaign without a manifest, a run of
  another command) is refused in one line naming it, before any work (:class:`NotOurs`, a
  ``ValueError``: exit 2). ``OUT`` itself must not be a symbolic link.
* The manifest is written **before** each file: it lists the new file's size and SHA-256, then
  the file is written atomically (:func:`validation.runs.atomic.write_bytes`). A campaign killed in
  between leaves a listed file missing (the resume redoes it) or, for a file being replaced
  (``campaign.md`` at the end), the previous version, which the manifest still accepts until the
  replacement is written. A file there that the manifest does not list is never replaced.
* Every file read back on resume is opened without following a link and without blocking
  (:func:`analytic.runtime.safe_files.read_regular`) and must still match the manifest; one that does not
  (edited, truncated, forged, replaced by a link or a FIFO) is refused in one line naming it
  (:class:`ChangedRecord`, exit 2): delete it and the resume judges that scene again.
* One campaign at a time: the lock of :mod:`validation.runs.locks` (``.<OUT name>.lock`` beside
  ``OUT``) is held for the whole campaign; a second one into the same ``OUT`` is refused
  (:class:`~validation.runs.locks.OutputBusy`).

The manifest's ``state`` is ``running`` while the campaign runs (or when it was killed), then
``complete``, ``interrupted`` (Ctrl-C, SIGTERM) or ``failed``.
"""

from __future__ import annotations

import contextlib
import enum
import errno
import hashlib
import json
import os
import re
import stat
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.runtime.safe_files import NotRegularFile, file_kind, read_regular
from validation.runs.atomic import OutputError, write_bytes
from validation.runs.locks import hold_lock
from validation.runs.manifest import (
    MANIFEST,
    MANIFEST_SCHEMA,
    ManifestEntry,
    NotOurs,
    json_object,
    lstat_or_none,
    size_and_digest,
)
from validation.runs.paths import is_run_id, new_run_id
from validation.runs.staging import place_for

CAMPAIGN_SCHEMA = "tumble-campaign/1"
"""The ``schema`` field of a campaign's ``manifest.json``."""
CONFIG_FILE = "campaign_config.json"
SCENES_DIR = "scenes"
COUNTEREXAMPLES_DIR = "counterexamples"
SUBDIRS = (SCENES_DIR, COUNTEREXAMPLES_DIR)
CAMPAIGN_FILES = frozenset(
    {CONFIG_FILE, "campaign.md", "campaign.json", "campaign.png", "campaign.html"}
)
"""The campaign's own files at the top of ``OUT`` (they only choose a refusal's words)."""
MANIFEST_MAX_BYTES = 64 << 20
"""A campaign's manifest larger than this (64 MiB, some 400,000 files) is not read."""
RECORD_MAX_BYTES = 16 << 20
"""No file a campaign reads back is larger than this (16 MiB)."""
REDO = "delete it to have the campaign redo it, or give a new output directory"
_TEMP = re.compile(r"^\.(?P<name>.+)\.\d+\.[0-9a-f]{8}\.tmp$")
"""A temporary file of :func:`validation.runs.atomic.write_bytes` left by a killed write."""
_SHA256 = re.compile(r"^[0-9a-f]{64}$")


class CampaignState(enum.StrEnum):
    """The ``state`` of a campaign's manifest."""

    RUNNING = "running"
    COMPLETE = "complete"
    INTERRUPTED = "interrupted"
    FAILED = "failed"


class ChangedRecord(ValueError):
    """A file the campaign wrote is no longer what it wrote (edited, a link, a FIFO ...)."""


def _entry(d: Any) -> ManifestEntry | None:
    size = d.get("bytes") if isinstance(d, dict) else None
    digest = d.get("sha256") if isinstance(d, dict) else None
    if isinstance(size, int) and not isinstance(size, bool) and size >= 0 and (
        isinstance(digest, str) and _SHA256.fullmatch(digest)
    ):
        return ManifestEntry(size, digest)
    return None


def _plain(name: str) -> bool:
    return bool(name) and not name.startswith(".") and "/" not in name and "\x00" not in name


def _campaign_name(rel: object) -> bool:
    """A path a campaign writes: a plain name at the top or one level down in ``SUBDIRS``."""
    if not isinstance(rel, str) or rel == MANIFEST:
        return False
    top, _, rest = rel.partition("/")
    return _plain(rel) if not rest else top in SUBDIRS and _plain(rest)


@dataclass(frozen=True)
class _Manifest:
    run_id: str
    config: dict[str, Any]
    files: dict[str, ManifestEntry]
    previous: dict[str, ManifestEntry]


def _parse(data: bytes) -> _Manifest:
    """A campaign's manifest, or ValueError saying in a few words why ``data`` is not one."""
    doc = json_object(data)
    if doc.get("schema") != CAMPAIGN_SCHEMA:
        raise ValueError(f"schema {str(doc.get('schema'))[:40]!r}, not {CAMPAIGN_SCHEMA!r}")
    if not is_run_id(doc.get("run_id")):
        raise ValueError("no well-formed run_id")
    if not isinstance(doc.get("config"), dict):
        raise ValueError("no campaign configuration")
    if doc.get("state") not in {s.value for s in CampaignState}:
        raise ValueError("no known state")
    tables: list[dict[str, ManifestEntry]] = []
    for key in ("files", "previous"):
        raw = doc.get(key, {})
        if not isinstance(raw, dict):
            raise ValueError(f"no {key} list")
        table = {}
        for rel, e in raw.items():
            entry = _entry(e)
            if not _campaign_name(rel) or entry is None:
                raise ValueError(f"a malformed entry {str(rel)[:40]!r}")
            table[rel] = entry
        tables.append(table)
    return _Manifest(doc["run_id"], doc["config"], tables[0], tables[1])


def _kind(st: os.stat_result) -> str:
    return f"a {file_kind(st.st_mode)}"


@dataclass
class CampaignDir:
    """A campaign's directory, proven its own and locked (:func:`open_campaign`).

    Attributes:
        root: the directory (as given).
        run_id: the campaign's id (in its manifest), kept across resumes.
        config: the campaign's configuration (``FuzzConfig.to_dict()``).
        files: path relative to ``root`` -> what the campaign wrote there.
        state: what the manifest says now.
        reason: why the campaign failed ("" unless it did).
    """

    root: Path
    run_id: str
    config: dict[str, Any]
    files: dict[str, ManifestEntry] = field(default_factory=dict)
    previous: dict[str, ManifestEntry] = field(default_factory=dict)
    state: CampaignState = CampaignState.RUNNING
    reason: str = ""

    def path(self, rel: str) -> Path:
        return self.root / rel

    def _write_manifest(self) -> None:
        doc = {
            "schema": CAMPAIGN_SCHEMA,
            "run_id": self.run_id,
            "command": "fuzz",
            "state": self.state.value,
            "reason": self.reason,
            "config": self.config,
            "files": {k: vars(v) for k, v in sorted(self.files.items())},
        }
        if self.previous:
            doc["previous"] = {k: vars(v) for k, v in sorted(self.previous.items())}
        write_bytes(self.root / MANIFEST, (json.dumps(doc, indent=1) + "\n").encode())

    def write(self, rel: str, data: bytes) -> Path:
        """Write ``data`` at ``rel`` (a campaign file's path), listed in the manifest first.

        Raises:
            OutputError: something the campaign did not write is at ``rel`` (not replaced), or
                the file could not be written.
        """
        if not _campaign_name(rel):
            raise ValueError(f"{rel!r}: not a campaign file's name")  # a bug, not input
        path = self.path(rel)
        old = self.files.get(rel)
        st = lstat_or_none(path)
        if st is not None:
            ours = (
                old is not None
                and stat.S_ISREG(st.st_mode)
                and ManifestEntry(*size_and_digest(path)) in (old, self.previous.get(rel))
            )
            if not ours:
                raise OutputError(path, "it is not the file this campaign wrote there; not replaced")
        new = ManifestEntry(len(data), hashlib.sha256(data).hexdigest())
        if old is not None and st is not None and old != new:
            # the version there now stays accepted until the new one is in place
            self.previous[rel] = ManifestEntry(*size_and_digest(path))
        self.files[rel] = new
        self._write_manifest()
        write_bytes(path, data)
        if self.previous.pop(rel, None) is not None:
            self._write_manifest()
        return path

    def read(self, rel: str) -> bytes | None:
        """The bytes the campaign wrote at ``rel``; None when it wrote none there (or the file was
        deleted: it is then written again).

        Raises:
            ChangedRecord: what is there is not what the manifest lists (one line naming it).
        """
        want = self.files.get(rel)
        path = self.path(rel)
        if want is None:
            if lstat_or_none(path) is not None:
                raise ChangedRecord(
                    f"{path}: not written by this campaign ({MANIFEST} does not list it); "
                    "remove it or give a new output directory"
                )
            return None
        try:
            data = read_regular(path, RECORD_MAX_BYTES)
        except FileNotFoundError:
            return None
        except NotRegularFile as exc:
            raise ChangedRecord(f"{path}: is a {exc.kind}, not the file the campaign wrote; {REDO}") from None
        except OSError as exc:
            if exc.errno == errno.EFBIG:
                raise ChangedRecord(f"{path}: changed after the campaign wrote it (too large); {REDO}") from None
            raise
        got = ManifestEntry(len(data), hashlib.sha256(data).hexdigest())
        if got != want and got != self.previous.get(rel):
            raise ChangedRecord(
                f"{path}: changed after the campaign wrote it (its size or SHA-256 differs from "
                f"{MANIFEST}); {REDO}"
            )
        return data

    def read_json(self, rel: str) -> Any:
        """:meth:`read` parsed as JSON (None when absent); ChangedRecord naming the file if it
        is not JSON."""
        data = self.read(rel)
        if data is None:
            return None
        try:
            return json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as exc:
            raise ChangedRecord(f"{self.path(rel)}: not a record the campaign wrote ({exc}); {REDO}") from None

    def finish(self, state: CampaignState, reason: str = "") -> None:
        """Record how the campaign ended in its manifest."""
        self.state, self.reason = state, reason
        self._write_manifest()


def _refuse_unproven(root: Path, names: list[str], entries: dict[str, os.DirEntry]) -> None:
    """Raise NotOurs for a non-empty directory without a campaign's manifest."""
    ours = CAMPAIGN_FILES | set(SUBDIRS)
    if all(n in ours for n in names):
        raise NotOurs(
            f"out: {str(root)!r} holds {names[0]!r} but no {MANIFEST}: a campaign written before "
            "manifests existed cannot prove it is one; remove it or choose another output directory"
        )
    example = next(n for n in names if n not in ours)
    e = entries[example]
    kind = _kind(e.stat(follow_symlinks=False))
    raise NotOurs(
        f"out: {str(root)!r} holds {example!r} ({kind}), which no tumble campaign wrote (no "
        f"{MANIFEST}); give a new or empty output directory"
    )


def _check_entries(root: Path, m: _Manifest, ignore) -> None:
    """Every entry of ``root`` (and of its subdirectories) is the manifest's, unchanged."""

    def refuse(path: Path, why: str, redo: bool) -> None:
        raise (ChangedRecord if redo else NotOurs)(
            f"{path}: {why}; {REDO if redo else 'remove it or give a new output directory'}"
        )

    def walk(d: Path, prefix: str) -> None:
        with os.scandir(d) as it:
            entries = sorted(
                (e for e in it if not (prefix == "" and ignore(e))), key=lambda e: e.name
            )
        for e in entries:
            rel = prefix + e.name
            st = e.stat(follow_symlinks=False)
            if prefix == "" and e.name == MANIFEST:
                continue
            if prefix == "" and e.name in SUBDIRS:
                if not stat.S_ISDIR(st.st_mode):
                    refuse(Path(e.path), f"{_kind(st)}, not the campaign's "
                           "directory", False)
                walk(Path(e.path), rel + "/")
                continue
            tmp = _TEMP.match(e.name)
            if tmp and stat.S_ISREG(st.st_mode) and (
                prefix + tmp["name"] in m.files or prefix + tmp["name"] == MANIFEST
            ):
                continue  # a write killed part way: left alone, never read
            want = m.files.get(rel)
            if want is None:
                refuse(Path(e.path), f"{_kind(st)} that {MANIFEST} does not "
                       "list (no tumble campaign wrote it)", False)
            if not stat.S_ISREG(st.st_mode):
                refuse(Path(e.path), f"{_kind(st)}, not the file the campaign "
                       "wrote", True)
            got = ManifestEntry(*size_and_digest(Path(e.path)))
            if got != want and got != m.previous.get(rel):
                refuse(Path(e.path), f"changed after the campaign wrote it (its size or SHA-256 "
                       f"differs from {MANIFEST})", True)

    walk(root, "")


def _prove(root: Path, ignore) -> _Manifest | None:
    """The campaign's manifest of ``root``, None when ``root`` is absent or empty.

    Raises:
        NotOurs, ChangedRecord: in one line naming an entry (module docstring).
    """
    if lstat_or_none(root) is None:
        return None
    with os.scandir(root) as it:
        entries = {e.name: e for e in it if not ignore(e)}
    if not entries:
        return None
    names = sorted(entries)
    if MANIFEST not in entries:
        _refuse_unproven(root, names, entries)
    try:
        data = read_regular(root / MANIFEST, MANIFEST_MAX_BYTES)
    except OSError as exc:
        raise NotOurs(
            f"out: {str(root)!r}: its {MANIFEST} cannot be read as a campaign's ({exc}); remove "
            "it or choose another output directory"
        ) from None
    try:
        m = _parse(data)
    except ValueError as exc:
        other = None
        with contextlib.suppress(ValueError, UnicodeDecodeError):
            doc = json.loads(data.decode("utf-8"))
            if isinstance(doc, dict) and doc.get("schema") == MANIFEST_SCHEMA:
                other = doc.get("command")
        what = (
            f"holds a tumble {other} run, not a fuzz campaign"
            if isinstance(other, str)
            else f"its {MANIFEST} is not a campaign's ({exc})"
        )
        raise NotOurs(f"out: {str(root)!r} {what}; choose another output directory") from None
    _check_entries(root, m, ignore)
    return m


@contextlib.contextmanager
def open_campaign(out: str | Path, config: dict[str, Any]) -> Iterator[CampaignDir]:
    """``with open_campaign(out, cfg.to_dict()) as cd:`` the campaign's directory, new or resumed,
    held under its lock for the block; its manifest's state is set on leaving it (``complete``,
    ``interrupted`` on KeyboardInterrupt, ``failed`` on another exception: re-raised).

    Raises:
        NotOurs: ``out`` is a link, not a directory, or holds anything that is not this campaign's
            (another campaign: ``out: ... holds another campaign``).
        ChangedRecord: a file of the campaign was changed after it was written.
        OutputBusy: another campaign holds ``out``.
    """
    root = Path(out)
    place = place_for(Path(os.path.abspath(root)))  # a link or a file at out is refused here
    ignore = place.is_own_entry
    try:
        place.target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(place.target, exc) from exc
    with hold_lock(place.target, place.lock):
        m = _prove(root, ignore)
        if m is not None and m.config != config:
            raise ValueError(
                f"out: {str(root)!r} holds another campaign ({m.config}); give a new directory"
            )
        if m is None:
            cd = CampaignDir(root, new_run_id(), config)
            try:
                root.mkdir(exist_ok=True)
            except OSError as exc:
                raise OutputError(root, exc) from exc
            place.prove_target()  # again: still a real directory (not a link put there), empty
            if _prove(root, ignore) is not None:
                raise NotOurs(f"out: {str(root)!r} was filled while the campaign started; not used")
            cd._write_manifest()
        else:
            cd = CampaignDir(root, m.run_id, m.config, dict(m.files), dict(m.previous))
            cd._write_manifest()  # running again
        for sub in SUBDIRS:
            try:
                (root / sub).mkdir(exist_ok=True)
            except OSError as exc:
                raise OutputError(root / sub, exc) from exc
        try:
            yield cd
        except KeyboardInterrupt:
            cd.finish(CampaignState.INTERRUPTED, "interrupted")
            raise
        except BaseException as exc:
            with contextlib.suppress(OSError):
                cd.finish(CampaignState.FAILED, f"{type(exc).__name__}: {exc}".splitlines()[0])
            raise
        cd.finish(CampaignState.COMPLETE)


__all__ = [
    "CAMPAIGN_SCHEMA",
    "CONFIG_FILE",
    "COUNTEREXAMPLES_DIR",
    "SCENES_DIR",
    "CampaignDir",
    "CampaignState",
    "ChangedRecord",
    "open_campaign",
]
