"""Output directories: paths never come from scene data; a directory is one run, whole.

Faults are planted (a writer that raises ENOSPC part way, an exception or a KeyboardInterrupt in
the middle of a run, a second run holding the lock) and the directory is inspected afterwards:
either the new run's files, all listed in its manifest with their hashes, or the previous run's,
byte for byte.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from validation.cli import EXIT_FAILED, EXIT_SIGINT, EXIT_SIGTERM, EXIT_USAGE, main
from validation.runs import atomic as atomic_mod
from validation.runs.atomic import OutputError, write_bytes, write_text
from validation.runs.outputs import (
    MANIFEST,
    SLUG_MAX_LEN,
    STAGING_MARKER,
    OutputBusy,
    RunState,
    default_out_dir,
    output_run,
    slug,
)

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "analytic" / "scenes" / "paper_example1.toml"


def _snapshot(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def _leftovers(parent: Path) -> list[str]:
    """Hidden staging directories, temporary files or locks left beside or inside runs."""
    return sorted(
        str(p.relative_to(parent))
        for p in parent.rglob(".*")
        if p.name.endswith((".partial", ".old", ".tmp", ".lock"))
    )


def _scene_named(tmp_path: Path, name: str) -> Path:
    """paper_example1 with its [scene] name replaced (TOML basic-string escaped)."""
    text = SCENE.read_text(encoding="utf-8")
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip().startswith("name"))
    lines[i] = f"name = {json.dumps(name)}"
    p = tmp_path / "scene.toml"
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


# ---------------------------------------------------------------------------------------------
# Paths never come from scene data
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("paper_example1", "paper_example1"),
        ("../../../escaped_dir", "escaped_dir"),
        ("/tmp/anywhere/sim", "tmp_anywhere_sim"),
        ("a/b\\c", "a_b_c"),
        ("..hidden", "hidden"),
        ("my scene (v2)", "my_scene_v2"),
        ("ωτ-scene", "scene"),
    ],
)
def test_slug_keeps_names_inside_one_directory(name, expected):
    s = slug(name)
    assert s == expected
    assert "/" not in s and "\\" not in s and not s.startswith(".")
    p = default_out_dir("validate_", name)
    assert p.parent == Path("out") and p.name == f"validate_{expected}"


@pytest.mark.parametrize("name", ["", "..", "../..", "/", "___", "ωτ", "a\x00b", "line\nbreak"])
def test_unsafe_names_are_refused_naming_the_field(name):
    with pytest.raises(ValueError, match=r"^scene\.name: "):
        slug(name)


def test_very_long_names_are_cut_and_stay_distinct():
    a, b = "x" * 5000 + "a", "x" * 5000 + "b"
    sa, sb = slug(a), slug(b)
    assert len(sa) <= SLUG_MAX_LEN and len(sb) <= SLUG_MAX_LEN and sa != sb
    assert slug(a) == sa  # the same name always gives the same directory


@pytest.mark.parametrize(
    ("command", "name", "expected"),
    [
        ("simulate", "../../../escaped_dir", "out/simulate_escaped_dir/trajectory.npz"),
        ("simulate", "/tmp/anywhere/sim", "out/simulate_tmp_anywhere_sim/trajectory.npz"),
        ("export-mjcf", "/tmp/anywhere/sim", "out/tmp_anywhere_sim.xml"),
        ("export-mjcf", "../../x" + "y" * 300, None),
    ],
)
def test_cli_writes_only_under_out(tmp_path, monkeypatch, capsys, command, name, expected):
    """A hostile scene name decides nothing about where files go: all of them land in ./out."""
    cwd = tmp_path / "work" / "deep"
    cwd.mkdir(parents=True)
    scene = _scene_named(tmp_path, name)
    monkeypatch.chdir(cwd)
    argv = [command, str(scene)] + (["--t-end", "0.05"] if command == "simulate" else [])
    assert main(argv) == 0, capsys.readouterr().err
    written = sorted(
        str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file() and p != scene
    )
    assert written, "nothing written"
    assert all(w.startswith("work/deep/out/") for w in written), written
    if expected is not None:
        assert f"work/deep/{expected}" in written
    assert not Path("/tmp/anywhere").exists()


# ---------------------------------------------------------------------------------------------
# One run, whole
# ---------------------------------------------------------------------------------------------


def _fake_run(target: Path, files: dict[str, bytes], command: str = "test"):
    with output_run(target, command) as run:
        for name, data in files.items():
            write_bytes(run.path / name, data)
    return run


def test_second_run_replaces_the_first_entirely(tmp_path):
    """A controlled run's tracking.png must not survive into an uncontrolled run's directory."""
    out = tmp_path / "v"
    _fake_run(out, {"report.md": b"first", "tracking.png": b"png"})
    run = _fake_run(out, {"report.md": b"second"})
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "report.md"]
    man = json.loads((out / MANIFEST).read_text())
    assert man["run_id"] == run.run_id and man["state"] == RunState.COMPLETE.value
    assert man["files"]["report.md"]["sha256"] == hashlib.sha256(b"second").hexdigest()
    assert _leftovers(tmp_path) == []


def test_manifest_lists_every_file_with_its_hash(tmp_path):
    out = tmp_path / "v"
    _fake_run(out, {"a.txt": b"alpha", "b.bin": bytes(range(256))})
    man = json.loads((out / MANIFEST).read_text())
    assert set(man["files"]) == {p.name for p in out.iterdir()} - {MANIFEST}
    for name, entry in man["files"].items():
        data = (out / name).read_bytes()
        assert entry == {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}


@pytest.mark.parametrize(
    ("exc", "state"),
    [
        (RuntimeError("plant exploded"), RunState.FAILED),
        (KeyboardInterrupt(), RunState.INTERRUPTED),
    ],
)
def test_failed_or_interrupted_run_keeps_its_partial_set_marked(tmp_path, exc, state):
    out = tmp_path / "v"
    _fake_run(out, {"report.md": b"old", "run.rrd": b"old"})
    with pytest.raises(type(exc)), output_run(out, "test") as run:
        write_text(run.path / "run.rrd", "partial")
        raise exc
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "run.rrd"]
    man = json.loads((out / MANIFEST).read_text())
    assert man["state"] == state.value and man["run_id"] == run.run_id
    assert (out / "run.rrd").read_text() == "partial"
    assert _leftovers(tmp_path) == []


def _enospc_after(monkeypatch, n_ok: int) -> None:
    """Let ``n_ok`` atomic writes through, then fail every write with ENOSPC part way."""
    real = os.fsync
    calls = {"n": 0}

    def fsync(fd):
        calls["n"] += 1
        if calls["n"] > n_ok:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd)

    monkeypatch.setattr(atomic_mod.os, "fsync", fsync)


@pytest.mark.parametrize("n_ok", [0, 1, 2, 3])
def test_full_disk_leaves_the_previous_run_whole(tmp_path, monkeypatch, n_ok):
    """ENOSPC at any file (the manifest included): one OutputError, the old set byte for byte."""
    out = tmp_path / "v"
    _fake_run(out, {"report.md": b"good", "run.rrd": b"good rrd"})
    before = _snapshot(out)
    _enospc_after(monkeypatch, n_ok)
    with pytest.raises(OutputError) as info:
        _fake_run(out, {"report.md": b"new", "run.rrd": b"new rrd", "x.png": b"png"})
    monkeypatch.undo()
    msg = str(info.value)
    assert "\n" not in msg and "No space left on device" in msg and str(out) in msg
    assert ".partial" not in msg  # the user's path, not the staging directory
    assert _snapshot(out) == before
    assert _leftovers(tmp_path) == []


def test_disk_filling_up_part_way_through_a_file(tmp_path, monkeypatch):
    """A writer that gets a short write, then ENOSPC, half way through a 3 MiB recording."""
    target = tmp_path / "run.rrd"
    write_bytes(target, b"good")
    real = os.write
    budget = {"left": 3 * atomic_mod.WRITE_CHUNK // 2}

    def write(fd, data):
        if budget["left"] <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        n = real(fd, bytes(data[: budget["left"]]))  # a short write at the boundary
        budget["left"] -= n
        return n

    monkeypatch.setattr(atomic_mod.os, "write", write)
    with pytest.raises(OutputError, match="No space left on device") as info:
        write_bytes(target, bytes(3 * atomic_mod.WRITE_CHUNK))
    monkeypatch.undo()
    assert str(target) in str(info.value) and "\n" not in str(info.value)
    assert target.read_bytes() == b"good" and os.listdir(tmp_path) == ["run.rrd"]


def test_atomic_write_checks_size_and_removes_its_temporary(tmp_path, monkeypatch):
    target = tmp_path / "f.json"
    write_text(target, "old")
    _enospc_after(monkeypatch, 0)
    with pytest.raises(OutputError, match="No space left on device"):
        write_text(target, "new")
    monkeypatch.undo()
    assert target.read_text() == "old" and os.listdir(tmp_path) == ["f.json"]


def test_refused_check_keeps_the_old_file(tmp_path):
    target = tmp_path / "run.rrd"
    write_bytes(target, b"old")

    def refuse(p: Path) -> None:
        raise OutputError(p, "not a complete recording")

    with pytest.raises(OutputError, match="not a complete recording"):
        write_bytes(target, b"truncated", check=refuse)
    assert target.read_bytes() == b"old" and os.listdir(tmp_path) == ["run.rrd"]


def test_a_second_concurrent_run_is_refused(tmp_path):
    out = tmp_path / "v"
    with output_run(out, "first") as run:
        write_text(run.path / "report.md", "first")
        with pytest.raises(OutputBusy, match=r"another tumble run \(pid \d+\)"):
            with output_run(out, "second"):
                pytest.fail("the second run must not start")
    assert (out / "report.md").read_text() == "first"
    assert _leftovers(tmp_path) == []


def test_cli_refuses_concurrent_run_in_one_line(tmp_path, capsys):
    out = tmp_path / "v"
    with output_run(out, "holder"):
        rc = main(["simulate", "paper_example1", "--t-end", "0.05", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == EXIT_USAGE and len(err) == 1 and "another tumble run" in err[0]


def test_foreign_directories_are_never_replaced(tmp_path):
    out = tmp_path / "home"
    out.mkdir()
    (out / "thesis.tex").write_text("years of work")
    with pytest.raises(ValueError, match="no tumble run wrote"):
        _fake_run(out, {"report.md": b"x"})
    assert sorted(p.name for p in out.iterdir()) == ["thesis.tex"]
    assert _leftovers(tmp_path) == []


def test_stale_staging_of_a_killed_run_is_cleaned(tmp_path):
    """A killed run's staging directory (it carries the marker with its run id) is removed; a
    look-alike without the marker is the user's and stays."""
    out = tmp_path / "v"
    stale = tmp_path / ".v.20000101T000000Z-deadbeef.partial"
    stale.mkdir()
    (stale / STAGING_MARKER).write_text("20000101T000000Z-deadbeef\n")
    (stale / "run.rrd").write_bytes(b"half")
    lookalike = tmp_path / ".v.20000101T000000Z-0badf00d.partial"
    lookalike.mkdir()
    (lookalike / "run.rrd").write_bytes(b"mine")
    _fake_run(out, {"report.md": b"x"})
    assert not stale.exists()
    assert (lookalike / "run.rrd").read_bytes() == b"mine"


def test_outputs_are_created_0644(tmp_path):
    old = os.umask(0o022)
    try:
        out = tmp_path / "v"
        _fake_run(out, {"report.md": b"x", "trajectory.npz": b"y"})
    finally:
        os.umask(old)
    for p in out.iterdir():
        assert p.stat().st_mode & 0o777 == 0o644, p.name


def test_cli_full_disk_is_one_line_exit_1(tmp_path, monkeypatch, capsys):
    out = tmp_path / "v"
    _enospc_after(monkeypatch, 0)
    rc = main(["simulate", "paper_example1", "--t-end", "0.05", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == EXIT_FAILED and len(err) == 1 and "No space left on device" in err[0]
    assert not out.exists() and _leftovers(tmp_path) == []


def test_cli_interrupt_during_start_up_is_one_line(tmp_path, monkeypatch, capsys):
    import validation.scenes

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(validation.scenes, "resolve_scene", interrupted)
    rc = main(["validate", "--out", str(tmp_path / "v")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == EXIT_SIGINT and len(err) == 1 and "interrupted" in err[0]
    assert not (tmp_path / "v").exists()


def test_cli_interrupt_part_way_keeps_partial_trajectory_marked(tmp_path, monkeypatch, capsys):
    """Ctrl-C during the plant: exit 130, the samples so far kept, marked interrupted."""
    sim_mod = sys.modules["analytic.simulate"]
    real = sim_mod.simulate

    def simulate(*args, progress=None, **kwargs):
        def stop(t):
            if t > 0.02:
                raise KeyboardInterrupt

        return real(*args, progress=stop, **kwargs)

    monkeypatch.setattr(sim_mod, "simulate", simulate)
    out = tmp_path / "v"
    rc = main(["simulate", "paper_example1", "--t-end", "0.2", "--out", str(out)])
    assert rc == EXIT_SIGINT
    man = json.loads((out / MANIFEST).read_text())
    assert man["state"] == "interrupted" and "trajectory.npz" in man["files"]
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"


def test_sigterm_is_handled_like_ctrl_c(tmp_path):
    """A real process, terminated while it runs: exit 143, one line, nothing half-written."""
    out = tmp_path / "v"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "validation.cli",
            "simulate",
            "paper_example1",
            "--t-end",
            "500",
            "--out",
            str(out),
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120  # a cold numba cache compiles first
    while not list(tmp_path.glob(".v.*.partial")) and time.monotonic() < deadline:
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == EXIT_SIGTERM, err
    assert len(err.strip().splitlines()) == 1 and "terminated" in err and "Traceback" not in err
    man = json.loads((out / MANIFEST).read_text())
    assert man["state"] == "interrupted"
    assert _leftovers(tmp_path) == []


def _signal_inside_a_c_callback(signum: int) -> None:
    """Deliver ``signum`` while Python code runs as a C callback (as llvmlite's object-cache
    callback does while numba compiles): the handler's KeyboardInterrupt ends the callback and
    the C caller swallows it."""
    import ctypes

    @ctypes.CFUNCTYPE(None)
    def callback():
        signal.raise_signal(signum)
        for _ in range(3):  # the handler runs at the next bytecodes, still inside the callback
            pass

    callback()


@pytest.mark.parametrize(
    ("signum", "status", "word"),
    [(signal.SIGTERM, EXIT_SIGTERM, "terminated"), (signal.SIGINT, EXIT_SIGINT, "interrupted")],
)
def test_a_signal_swallowed_by_compiled_code_still_stops_the_run(
    tmp_path, monkeypatch, capfd, signum, status, word
):
    """A signal landing in a C callback (numba compiling in the process) is not lost: the run
    stops at its next progress report, exit 143/130, the partial trajectory kept, marked
    interrupted, and no "Exception ignored" traceback."""
    import importlib

    simulate_mod = importlib.import_module("analytic.simulate")  # the module, not the function
    real = simulate_mod.simulate

    def signalled_then_run(*args, **kwargs):
        _signal_inside_a_c_callback(signum)
        return real(*args, **kwargs)

    import threading

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("a signal's handler runs in the main thread; this runner runs tests in another")
    monkeypatch.setattr(simulate_mod, "simulate", signalled_then_run)
    # a command's SIGINT is Python's own handler (KeyboardInterrupt); code run before this test
    # in the same process may have left another (ignored), so set it for the command
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        out = tmp_path / "v"
        code = main(["simulate", "paper_example1", "--t-end", "2", "--out", str(out)])
    finally:
        signal.signal(signal.SIGINT, previous)
    err = capfd.readouterr().err
    assert code == status, err
    assert len(err.strip().splitlines()) == 1 and word in err and "Exception" not in err
    man = json.loads((out / MANIFEST).read_text())
    assert man["state"] == "interrupted"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert _leftovers(tmp_path) == []


def test_interrupt_keeping_is_undone_after_the_command():
    """Outside a command the interpreter's own hook and SIGTERM handler are back."""
    hook, handler = sys.unraisablehook, signal.getsignal(signal.SIGTERM)
    assert main(["scene-reference", "--out", os.devnull]) == 0
    assert sys.unraisablehook is hook and signal.getsignal(signal.SIGTERM) is handler


def test_validate_controlled_then_uncontrolled_leaves_only_the_second_run(tmp_path):
    """End to end on both plants: the first run's tracking.png does not outlive it."""
    from validation.validate import run_validation

    out = tmp_path / "v"
    first = run_validation("paper_example1_controlled", out, t_end=0.05)
    assert (out / "tracking.png").exists()
    second = run_validation("paper_example1", out, t_end=0.05)
    man = json.loads((out / MANIFEST).read_text())
    assert man["run_id"] != json.loads(json.dumps({"id": first.files["report.json"].name})).get(
        "id"
    )
    assert set(man["files"]) | {MANIFEST} == {p.name for p in out.iterdir()}
    assert "tracking.png" not in man["files"]
    report = json.loads((out / "report.json").read_text())
    assert report["run"]["run_id"] == man["run_id"]
    assert set(second.files) == {p.name for p in out.iterdir()}
    assert _leftovers(tmp_path) == []


def test_interrupt_while_figures_are_drawn_is_not_lost(tmp_path, monkeypatch):
    """Ctrl-C in the last stage still stops the run: no PASS, the set marked interrupted."""
    from validation.report import report
    from validation.validate import run_validation

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "figure_invariants", interrupted)
    out = tmp_path / "v"
    with pytest.raises(KeyboardInterrupt):
        run_validation("paper_example1_controlled", out, t_end=0.05)
    man = json.loads((out / MANIFEST).read_text())
    assert man["state"] == "interrupted"
    if "report.json" in man["files"]:  # a report written after the stop says so, first
        assert json.loads((out / "report.json").read_text())["passed"] is False
        assert "INTERRUPTED" in (out / "report.md").read_text().splitlines()[0]
    assert set(man["files"]) | {MANIFEST} == {p.name for p in out.iterdir()}
