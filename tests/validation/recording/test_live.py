"""The live viewer (``--spawn``, ``--connect [URL]``, ``--serve [PORT]``) against Rerun's own gRPC
server started here on 127.0.0.1: what each plant's worker streamed arrives (its entities, one row
per output sample of its run), under the recording's ids, beside the whole recording; a viewer
that is not there fails only the stream; without a flag nothing connects anywhere."""

from __future__ import annotations

import collections
import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from tests.support.tolerances import LIVE_STATE_F32_REL
from validation.cli import main
from validation.commands import EXIT_USAGE
from validation.recording import live
from validation.recording.live import LiveViewer, live_plant_task, proxy_url, watching
from validation.recording.stream import AppId, atomic_stream
from validation.recording.style import TIMELINE
from validation.runs.plant_runs import plant_task

ROOT = Path(__file__).resolve().parents[3]
PLANTS = ("analytic", "mujoco")
RUN = ("--plants", ",".join(PLANTS), "--t-end", "0.1", "--figure-format", "png")
ARRIVE_TIMEOUT_S = 60.0
"""Longest wait for a stream to arrive at the test's server (it arrives in about a second)."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _rows(path: Path) -> tuple[dict[str, int], list]:
    """``({entity: rows of temporal data}, [the file's stores])`` of an ``.rrd``, footer or not."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a file still being written has no footer
        reader = RrdReader(str(path))
        store = reader.stream().collect()
    rows: collections.Counter[str] = collections.Counter()
    for chunk in store.stream().filter(is_static=False).to_chunks():
        rows[str(chunk.entity_path)] += chunk.num_rows
    return dict(rows), [*reader.recordings(), *reader.blueprints()]


def _values(path: Path, entity: str, component: str) -> dict[int, np.ndarray]:
    """``{time in ns: the component's values}`` of an entity's temporal rows in an ``.rrd``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        store = RrdReader(str(path)).stream().collect()
    out: dict[int, np.ndarray] = {}
    for chunk in store.stream().filter(is_static=False).to_chunks():
        if str(chunk.entity_path) != entity:
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        times = batch.column(TIMELINE).cast(pa.int64()).to_numpy()
        for t, v in zip(times, batch.column(component), strict=True):
            if v.is_valid:
                out[int(t)] = np.asarray(v.as_py(), float).ravel()
    return out


@contextlib.contextmanager
def _saving_server(tmp_path: Path, connect_to: str | None = None):
    """Rerun's gRPC server on 127.0.0.1 saving what it receives (``rerun --serve-grpc --save``),
    or, with ``connect_to``, a client of that server saving what it is sent: ``(url, file)``."""
    port = _free_port()
    saved = tmp_path / f"received_{port}.rrd"
    cmd = [str(live.rerun_executable()), "--bind", "127.0.0.1", "--port", str(port)]
    cmd += ["--save", str(saved)]
    cmd += [connect_to] if connect_to else ["--serve-grpc"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = proxy_url(str(port))
    try:
        deadline = time.monotonic() + ARRIVE_TIMEOUT_S
        while not live.reachable(url, 0.2):
            assert proc.poll() is None and time.monotonic() < deadline, "the server did not start"
            time.sleep(0.1)
        yield url, saved
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def _wait_rows(saved: Path, wanted: set[str]) -> dict[str, int]:
    """The rows received once every entity of ``wanted`` is in the file and no more arrives."""
    deadline, last = time.monotonic() + ARRIVE_TIMEOUT_S, None
    while time.monotonic() < deadline:
        time.sleep(0.5)
        if not saved.exists():
            continue
        try:
            rows, _ = _rows(saved)
        except Exception:  # a chunk half written
            continue
        if wanted <= set(rows) and rows == last:
            return rows
        last = rows
    raise AssertionError(
        f"not received in {ARRIVE_TIMEOUT_S:g} s: {sorted(wanted - set(last or {}))}"
    )


def _tumble(*args: str, **kw) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen(
        [sys.executable, "-m", "validation", *args], cwd=ROOT, env=env, text=True, **kw
    )


def _expected(out: Path) -> tuple[str, dict[str, int]]:
    """The run id of the output set and each plant's output samples, read from ``run.rrd``
    (the body of each plant has one row per sample)."""
    run_id = json.loads((out / "manifest.json").read_text())["run_id"]
    rows, _ = _rows(out / "run.rrd")
    return run_id, {p: rows[f"/world/{p}/body"] for p in PLANTS}


def _check_arrived(
    rows: dict[str, int], stores: list, run_id: str, samples: dict[str, int], saved: Path, out: Path
):
    for plant, n in samples.items():
        assert n > 1
        live_rows = rows[f"/live/{plant}/state"]
        assert 1 <= live_rows <= n, (plant, rows)  # its states while it ran, throttled
        # each moved the recording's body; then the recording itself, sent whole, drew every one
        assert rows[f"/world/{plant}/body"] == n + live_rows, (plant, rows)
        assert rows[f"/live/{plant}/wall_s"] >= 1  # its progress while it ran
        _check_states_are_the_recordings(saved, out / "run.rrd", plant)
    assert {s.recording_id for s in stores if s.kind == "recording"} == {run_id}  # one recording
    assert {s.application_id for s in stores} == {AppId.VALIDATE}
    assert any(s.kind == "blueprint" for s in stores)  # the designed layout too


def _check_states_are_the_recordings(saved: Path, recording: Path, plant: str) -> None:
    """Every state streamed live at a sample time is the recording's body there (to float32:
    Rerun stores poses as float32): position R and attitude u (w first, normalised)."""
    streamed = _values(saved, f"/live/{plant}/state", "Scalars:scalars")
    moved = _values(recording, f"/world/{plant}/body", "Transform3D:translation")
    turned = _values(recording, f"/world/{plant}/body", "Transform3D:quaternion")
    common = sorted(set(streamed) & set(moved))
    assert common, (plant, sorted(streamed)[:3], sorted(moved)[:3])
    for t in common:
        q = streamed[t]
        u = q[3:7] / np.linalg.norm(q[3:7])
        for got, want in ((q[:3], moved[t]), (u[[1, 2, 3, 0]], turned[t])):
            scale = np.maximum(1.0, np.abs(want))
            assert np.all(np.abs(got - want) <= LIVE_STATE_F32_REL.value * scale), (plant, t)


def test_connect_streams_each_plant_and_the_recording(tmp_path):
    """``tumble validate --connect URL``: each plant's states while it runs (q, and the body's pose
    on the recording's own entity, equal to the recording's), its progress and the whole
    recording arrive at the server as one recording, the run's; the files are those of a run
    without a viewer."""
    out = tmp_path / "run"
    with _saving_server(tmp_path) as (url, saved):
        proc = _tumble("validate", *RUN, "--out", str(out), f"--connect={url}")
        assert proc.wait(timeout=300) == 0
        run_id, samples = _expected(out)
        rows = _wait_rows(
            saved, {f"/live/{p}/state" for p in PLANTS} | {f"/world/{p}/body" for p in PLANTS}
        )
    _check_arrived(rows, _rows(saved)[1], run_id, samples, saved, out)
    assert set(json.loads((out / "manifest.json").read_text())["files"]) >= {"run.rrd"}


@pytest.mark.slow
def test_serve_hosts_a_server_a_client_receives_from(tmp_path):
    """``tumble validate --serve PORT``: after the run the command keeps serving; a client that
    connects then receives every plant's stream and the recording; Ctrl-C ends the server and the
    command with the run's own status."""
    out, port = tmp_path / "run", _free_port()
    proc = _tumble(
        "validate", *RUN, "--out", str(out), "--serve", str(port), stderr=subprocess.PIPE
    )
    try:
        for line in proc.stderr:
            if line.startswith("serving the recording at"):
                break
        else:
            pytest.fail(f"never served (exit {proc.wait()})")
        url = proxy_url(str(port))
        assert url in line
        run_id, samples = _expected(out)
        with _saving_server(tmp_path, connect_to=url) as (_, saved):
            rows = _wait_rows(
                saved, {f"/live/{p}/state" for p in PLANTS} | {f"/world/{p}/body" for p in PLANTS}
            )
        _check_arrived(rows, _rows(saved)[1], run_id, samples, saved, out)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=30) == 0
        assert not live.reachable(url, 0.2)  # the server ended with the command
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_spawn_starts_rerun_spawns_viewer(tmp_path, monkeypatch):
    """``--spawn`` asks ``rerun.spawn`` for a viewer on Rerun's port and connects to it: a stand-in
    ``rerun`` first on PATH records how it was started and serves gRPC in the viewer's place."""
    fake, log = tmp_path / "bin" / "rerun", tmp_path / "spawned.txt"
    fake.parent.mkdir()
    fake.write_text(
        "#!/bin/sh\n"
        f'real="{live.rerun_executable()}"\n'
        'if [ "$1" = "--version" ]; then exec "$real" --version; fi\n'
        f'echo "$$ $*" >> "{log}"\n'
        "port=9876\n"
        'for a in "$@"; do case "$a" in --port=*) port="${a#--port=}";; esac; done\n'
        'exec "$real" --serve-grpc --bind 127.0.0.1 --port "$port"\n'
    )
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake.parent}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.delenv("_RERUN_TEST_FORCE_SAVE", raising=False)
    port = _free_port()
    viewer = live.spawn_viewer(port)
    pid, *argv = log.read_text().split()
    try:
        assert viewer == LiveViewer(proxy_url(str(port)), live.LiveMode.SPAWN)
        assert f"--port={port}" in argv
        assert live.reachable(viewer.url)
    finally:
        os.kill(int(pid), signal.SIGTERM)


class _Plant:
    engine = "analytic"


class _Run:
    t = np.linspace(0.0, 1.0, 11)
    q = np.tile([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], (11, 1))


def _task(pl, settings, sc, horizon, *, report):
    report(0.5)
    return _Run(), 0.1


def test_served_streams_reach_a_client_that_connects_later(tmp_path):
    """``serving``: Rerun's server on 127.0.0.1 keeps what a plant's stream and a recording sent
    for a client that connects afterwards, serves until SIGINT, then ends (the command line's
    ``--serve``; end to end in the slow test above)."""
    port = _free_port()
    url = proxy_url(str(port))
    got: dict = {}

    def client() -> None:  # connects once the streams are sent, then stops the server
        try:
            with _saving_server(tmp_path, connect_to=url) as (_, saved):
                got["rows"] = _wait_rows(saved, {"/live/analytic/state", "/file/x"})
            got["stores"] = _rows(saved)[1]
        finally:
            os.kill(os.getpid(), signal.SIGINT)

    thread = threading.Thread(target=client)
    with live.serving(port) as viewer, watching(viewer):
        live_plant_task(_task, AppId.VALIDATE, "rid")(_Plant(), None, None, 1.0, report=[].append)
        with atomic_stream(tmp_path / "x.rrd", AppId.VALIDATE, recording_id="rid") as rec:
            rec.send_columns(
                "file/x",
                indexes=[rr.TimeColumn("sim_time", duration=_Run.t)],
                columns=rr.Scalars.columns(scalars=_Run.t),
            )
        thread.start()
    thread.join(timeout=ARRIVE_TIMEOUT_S)
    rows = got["rows"]
    # a task that takes no watch: the states are sent when the run returns, every one
    assert rows["/live/analytic/state"] == rows["/world/analytic/body"] == _Run.t.size
    assert rows["/live/analytic/wall_s"] == 1 and rows["/file/x"] == _Run.t.size
    assert {(s.application_id, s.recording_id) for s in got["stores"] if s.kind == "recording"} == {
        (AppId.VALIDATE, "rid")
    }
    assert not live.reachable(url, 0.2)  # the server ended with the block


class _HeldPlant:
    """A plant whose run passes its states to its progress and then waits, part way, until the
    test lets it go on: what the server holds meanwhile was streamed during the run."""

    engine = "analytic"

    def __init__(self, states: bool = True):
        self.go_on = threading.Event()
        self.states = states

    def simulate(self, sc, settings, t_end, progress):
        half = _Run.t.size // 2
        for k, t in enumerate(_Run.t):
            if k == half:
                assert self.go_on.wait(ARRIVE_TIMEOUT_S), "the test never let the run go on"
            if self.states:
                progress(float(t), _Run.q[k] + [float(t), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            else:
                progress(float(t))  # a plugin written for progress(t) alone
        return _Run()


def _held_run(tmp_path, pl: _HeldPlant) -> tuple[dict[str, int], dict[str, int], list[float]]:
    """``pl`` run by the plants' task with a live stream to a server on 127.0.0.1: ``(rows the
    server held while the run waited, rows once it returned, the progress reported)``."""
    heard: list[float] = []
    with _saving_server(tmp_path) as (url, saved), watching(LiveViewer(url)):
        task = live_plant_task(plant_task, AppId.VALIDATE, "rid")
        run = threading.Thread(target=lambda: task(pl, None, None, 1.0, report=heard.append))
        run.start()
        try:
            # the first state, or without states the first progress, is sent at once
            wanted = {"/live/analytic/state", "/world/analytic/body"}
            during = _wait_rows(saved, wanted if pl.states else {"/live/analytic/wall_s"})
            assert run.is_alive()  # the run has not returned: it waits for go_on
        finally:
            pl.go_on.set()
            run.join(timeout=ARRIVE_TIMEOUT_S)
        after = _wait_rows(saved, {"/live/analytic/state"})
    return during, after, heard


def test_a_plants_states_arrive_while_it_runs(tmp_path):
    """The states a plant passes its progress reach the viewer while its run goes on (the run
    waits half way until they are there), on the recording's body too, at most
    ``LIVE_RATE_HZ`` a wall second: the first one at once, the horizon's always; the parent's
    progress gets times only."""
    during, after, heard = _held_run(tmp_path, _HeldPlant())
    assert during["/live/analytic/state"] == during["/world/analytic/body"] >= 1
    assert after["/live/analytic/state"] == after["/world/analytic/body"]
    # the run's states came in well under a wall second each side of the wait: the first and the
    # last of each burst at most, not one per sample
    assert during["/live/analytic/state"] < after["/live/analytic/state"] < _Run.t.size
    assert heard and all(isinstance(t, float) for t in heard) and heard[-1] == 1.0


def test_a_plant_that_passes_no_state_still_runs_and_is_sent_when_it_returns(tmp_path):
    """A plugin that calls ``progress(t)`` alone runs as before: its times stream while it runs,
    its states (one per sample) arrive once its run returns."""
    during, after, heard = _held_run(tmp_path, _HeldPlant(states=False))
    assert "/live/analytic/state" not in during and during["/live/analytic/wall_s"] >= 1
    assert after["/live/analytic/state"] == after["/world/analytic/body"] == _Run.t.size
    assert heard[-1] == 1.0


def test_serve_refuses_a_port_in_use(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(ValueError, match=f"--serve: port {port} is in use"):
            with live.serving(port):
                pass


def test_a_viewer_not_there_fails_only_its_stream(tmp_path):
    """A plant's run and a recording's file are made whole when nothing listens at the viewer's
    address: one warning each, no error, no wait beyond the connection attempt."""
    viewer = LiveViewer(proxy_url(str(_free_port())))
    heard: list[float] = []
    with watching(viewer), pytest.warns(UserWarning, match="nothing listens"):
        t0 = time.monotonic()
        tr, wall = live_plant_task(_task, AppId.VALIDATE, "rid")(
            _Plant(), None, None, 1.0, report=heard.append
        )
        with atomic_stream(tmp_path / "x.rrd", AppId.VALIDATE, recording_id="rid") as rec:
            rec.log("a", rr.TextDocument("x"), static=True)
    assert isinstance(tr, _Run) and wall == 0.1 and heard == [0.5]
    assert time.monotonic() - t0 < 10 * live.REACH_TIMEOUT_S
    assert "/a" in RrdReader(str(tmp_path / "x.rrd")).store().schema().entity_paths()


def test_without_a_flag_nothing_connects(tmp_path, monkeypatch):
    """No viewer option: the plants' task is the one given, and writing a recording tries no
    connection at all."""

    def refuse(*args, **kw):
        raise AssertionError("tried to connect")

    monkeypatch.setattr(live, "reachable", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    assert live.current() is None
    assert live_plant_task(_task, AppId.VALIDATE, "rid") is _task
    with atomic_stream(tmp_path / "x.rrd", AppId.VALIDATE) as rec:
        rec.log("a", rr.TextDocument("x"), static=True)
    assert (tmp_path / "x.rrd").stat().st_size > 0


@pytest.mark.parametrize(
    ("value", "url"),
    [
        (None, "rerun+http://127.0.0.1:9876/proxy"),
        ("9877", "rerun+http://127.0.0.1:9877/proxy"),
        ("rerun+http://10.0.0.2:9000/proxy", "rerun+http://10.0.0.2:9000/proxy"),
        ("rerun://host:1/proxy", "rerun://host:1/proxy"),
    ],
)
def test_connect_takes_a_url_or_a_port_as_rerun_does(value, url):
    assert proxy_url(value) == url


def test_a_bad_connect_url_is_one_line_before_any_work(tmp_path, capsys):
    rc = main(["validate", "--connect=http://host:9876", "--out", str(tmp_path / "v")])
    assert rc == EXIT_USAGE
    err = capsys.readouterr().err.strip()
    assert err.startswith("tumble: error: --connect:") and "\n" not in err
    assert not (tmp_path / "v").exists()


def test_viewer_options_are_exclusive(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["validate", "--spawn", "--serve", "--out", str(tmp_path)])
    assert exc.value.code == EXIT_USAGE
    assert "not allowed with" in capsys.readouterr().err
