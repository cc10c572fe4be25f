"""Rerun streams that never touch the disk: a recording is encoded in memory and written by
:mod:`validation.runs.atomic`, read back first (:func:`check_rrd`).

* :func:`new_stream`: an explicit :class:`rerun.RecordingStream` (not the global one, so one process
  can write several files) without the wall-clock timeline (a file depends only on its data);
* :func:`binary_stream`: the same, with its in-memory sink attached;
* :func:`check_rrd`: refuse a file that does not read back whole (footer included);
* :func:`atomic_stream`: ``with atomic_stream(path) as rec:`` log, and ``path`` appears, checked,
  when the block ends (or keeps its previous contents).
"""

from __future__ import annotations

import contextlib
import uuid
import warnings
from collections.abc import Iterator
from enum import StrEnum
from pathlib import Path
from typing import Any

from validation.runs.atomic import write_bytes

RRD_FLUSH_TIMEOUT_S = 120.0
"""Longest wait for Rerun's batcher to hand over a recording's bytes (memory only, no disk): a
recording of a 60 s run takes well under a second, so two minutes means it is stuck, not slow."""


class AppId(StrEnum):
    """Rerun's application id of each kind of recording. The viewer remembers a layout per
    application id, so each kind has its own: a run's layout is never applied to the demo.
    (Rerun 0.41 takes an id as a catalog entry name: letters, digits, ``-`` and ``_``; it
    rewrites any other, with a warning.)"""

    VALIDATE = "tumbling-testbed-validate"
    DEMO = "tumbling-testbed-demo"
    SWEEP = "tumbling-testbed-sweep"


def new_stream(app_id: str = AppId.VALIDATE, recording_id: str | None = None):
    """An explicit stream (not the global one) without the wall-clock timeline, under Rerun
    application id ``app_id`` (an :class:`AppId`: one per kind of file)."""
    # deferred: rerun ~0.25 s (python -X importtime), only when a recording is made
    import rerun as rr

    rec = rr.RecordingStream(app_id, recording_id=recording_id or str(uuid.uuid4()))
    rec.set_log_time_enabled(False)
    return rec


def binary_stream(app_id: str = AppId.VALIDATE, recording_id: str | None = None):
    """``(rec, sink)``: a :func:`new_stream` and its in-memory sink (``rec.binary_stream()``);
    read the encoded bytes with :func:`rrd_bytes`."""
    rec = new_stream(app_id, recording_id)
    return rec, rec.binary_stream()


def rrd_bytes(rec, sink) -> bytes:
    """Flush ``rec``, disconnect it and return everything ``sink`` holds: a whole ``.rrd`` (the
    footer is written on disconnect). ``rec`` cannot be logged into afterwards."""
    try:
        rec.flush(timeout_sec=RRD_FLUSH_TIMEOUT_S)
        data = sink.read(flush=True, flush_timeout_sec=RRD_FLUSH_TIMEOUT_S) or b""
    finally:
        rec.disconnect()
    return data + (sink.read(flush=False) or b"")  # anything the disconnect wrote (the footer)


def check_rrd(path: str | Path) -> None:
    """Raise ``ValueError`` unless ``path`` is a whole ``.rrd`` (it reads back, footer included)."""
    from rerun.chunk import RrdReader

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # "no footer" is only a warning in rerun
            RrdReader(str(path)).store()
    except Exception as exc:
        raise ValueError(f"{path}: not a complete recording ({exc})".splitlines()[0]) from exc


@contextlib.contextmanager
def atomic_stream(
    path: str | Path,
    app_id: AppId,
    blueprint: Any = None,
    recording_id: str | None = None,
) -> Iterator[Any]:
    """``with atomic_stream(path) as rec:`` log into ``rec``; ``path`` appears when the block ends.

    Rerun encodes into memory (:func:`binary_stream`), never onto the disk, so a full disk cannot
    stall its writer; the bytes are then written by :func:`validation.runs.atomic.write_bytes`, read
    back (:func:`check_rrd`) and only then moved over ``path``. On any exception, or when the
    recording is incomplete, ``path`` keeps its previous contents. ``blueprint`` (a
    ``rerun.blueprint.Blueprint``) is stored in the file as its active and default layout: the
    viewer opens the file in it, whatever layout it remembers for ``app_id``, and *Reset to
    default blueprint* returns to it.

    With a live viewer (:func:`validation.recording.live.current`), the file, once written, is
    also sent to it under the same ids (:func:`validation.recording.live.send_file`; a viewer
    that cannot be reached is a warning, never this file's failure).
    """
    from validation.recording.live import send_file

    path = Path(path)
    recording_id = recording_id or str(uuid.uuid4())
    rec, sink = binary_stream(app_id, recording_id)
    if blueprint is not None:
        rec.send_blueprint(blueprint, make_active=True, make_default=True)
    try:
        yield rec
    except BaseException:
        rec.disconnect()
        raise
    write_bytes(path, rrd_bytes(rec, sink), check=check_rrd)
    send_file(path, app_id, recording_id, blueprint)


__all__ = [
    "RRD_FLUSH_TIMEOUT_S",
    "AppId",
    "atomic_stream",
    "binary_stream",
    "check_rrd",
    "new_stream",
    "rrd_bytes",
]
