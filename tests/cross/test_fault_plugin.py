"""Faults the pytest plugin survives: what it finds in a test directory or in the session's shared
temporary directory is never trusted as it is.

| fault | what the plugin does |
|---|---|
| a FIFO named ``test_*.toml`` | not opened to block: collection goes on |
| a run planted in the shared directory of an xdist session | not unpickled: its signature fails |
| a shared run altered after it was stored | not unpickled: its signature fails |
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from validation.testing import session_runs

pytestmark = pytest.mark.faults


def test_fifo_named_like_a_scene_does_not_block_collection(tmp_path: Path) -> None:
    """A FIFO named ``test_x.toml`` beside the tests -> collection finishes at once (no writer
    ever comes), and the FIFO is not collected."""
    os.mkfifo(tmp_path / "test_x.toml")
    (tmp_path / "test_plain.py").write_text("def test_plain():\n    pass\n")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "1 passed" in done.stdout


class _Planted:
    """A pickle whose loading writes a file: the proof that it was unpickled."""

    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (Path.write_text, (self.marker, "unpickled"))


def test_planted_shared_run_is_not_unpickled(tmp_path: Path) -> None:
    """A pickle put in the shared directory without the session's secret (unsigned, or signed with
    another key) -> not loaded: the worker runs the scene itself."""
    marker = tmp_path / "marker"
    store = tmp_path / "run.pickle"
    data = pickle.dumps(_Planted(marker))
    secret = os.urandom(32)
    for planted in (b"\0" * 32 + data, data, b""):
        store.write_bytes(planted)
        assert session_runs._load_signed(store, secret) is None
    session_runs._store_signed(store, os.urandom(32), data)  # another session's key
    assert session_runs._load_signed(store, secret) is None
    assert not marker.exists()


def test_altered_shared_run_is_not_unpickled(tmp_path: Path) -> None:
    """A run stored by a worker and then altered (one byte) -> not loaded; unaltered -> loaded."""
    store = tmp_path / "run.pickle"
    secret = os.urandom(32)
    session_runs._store_signed(store, secret, pickle.dumps({"passed": True, "n": 45}))
    assert session_runs._load_signed(store, secret) == {"passed": True, "n": 45}
    blob = bytearray(store.read_bytes())
    blob[-2] ^= 1
    store.write_bytes(bytes(blob))
    assert session_runs._load_signed(store, secret) is None
