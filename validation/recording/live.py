"""Watching a run live in Rerun's viewer: ``--spawn``, ``--connect [URL]`` and ``--serve``.

Contract. Without a viewer (:func:`current` is None) nothing here runs and nothing connects
anywhere. With one (``with watching(viewer):``, or :func:`from_args` on the command line), every
stream this tool opens connects to one gRPC address, ``viewer.url``, under the application id and
the recording id of the file the command writes, so the viewer shows them as one recording:

* each plant's worker streams its own run (:func:`live_plant_task`) while it runs: the wall time it
  took to reach each simulated time (``live/{plant}/wall_s``) and the states its progress carries
  (``progress(t, q)``, :mod:`analytic.progress`), at most :data:`LIVE_RATE_HZ` per wall second,
  sent every :data:`SEND_EVERY_S`:
  q = [R, u, p] (``live/{plant}/state``) and the body where the recording's 3D view draws it
  (``world/{plant}/body``, its shape logged first), so the designed layout's 3D view moves as the
  plants run; a plant whose progress carries no state has its states sent when its run returns;
* the recording (``run.rrd``, ``demo.rrd``, ``sweep.rrd``) is sent whole, blueprint included, once
  its file is written (:func:`send_file`); the file itself is written exactly as without a viewer.

A stream that cannot reach the viewer, or loses it, is that stream's failure only: one warning
line, and the run, its files and its verdict go on unchanged.

Why not ``rerun.script_add_args`` / ``script_setup``: their options clash with the commands'
(``--save`` is a path where ours write a directory, ``--headless``, ``--stdout``, ``--connect``
without its URL beside ``--url``), ``script_setup`` spawns a viewer when no option is given (here
nothing may connect without one), and it logs through the global recording of *this* process.
Importing rerun starts threads, and a process with more than one thread no longer forks its plant
workers (:func:`validation.runs.workers.can_fork`). So this process never imports rerun for a live
viewer: the options are Rerun's names (``--connect`` takes a URL or a port as ``rerun --connect``
does), the viewer is spawned by ``rerun.spawn`` in a short helper process, ``--serve`` runs Rerun's
own server (``rerun --serve-web``: gRPC and a web viewer) as a child process on the loopback
interface, and every stream uses Rerun's sinks (``rerun.GrpcSink``) directly.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

DEFAULT_PORT = 9876
"""Rerun's default gRPC port (``rerun``, ``rerun.spawn``, ``rerun.GrpcSink``)."""

LOOPBACK = "127.0.0.1"

REACH_TIMEOUT_S = 1.0
"""How long a stream tries to reach the viewer's address before it gives up (a TCP connect on the
same machine or network answers in milliseconds; a second means nobody listens)."""

FLUSH_TIMEOUT_S = 10.0
"""Longest wait for a live stream to hand its data to the viewer when it closes: a plant's states
are a few hundred kB, sent in well under a second to a viewer that is there."""

START_TIMEOUT_S = 60.0
"""Longest wait for a spawned viewer or a served gRPC server to listen (the viewer's first start
on a cold disk takes seconds)."""

_URL = re.compile(r"^rerun(\+https?)?://[^/\s]+/proxy$")


class LiveMode(StrEnum):
    """How the viewer is reached: one spawned, one already running, or a server this command
    hosts until Ctrl-C."""

    SPAWN = "spawn"
    CONNECT = "connect"
    SERVE = "serve"


@dataclass(frozen=True)
class LiveViewer:
    """Where every live stream connects: ``url`` (``rerun+http://host:port/proxy``), reached
    as ``mode`` says."""

    url: str
    mode: LiveMode = LiveMode.CONNECT


def proxy_url(value: str | None, field: str = "--connect") -> str:
    """A viewer's gRPC address from a URL, a port (``9877`` is ``rerun+http://127.0.0.1:9877/proxy``,
    as ``rerun --connect`` reads it) or None (Rerun's default address); ``ValueError`` naming
    ``field`` otherwise."""
    if value is None or value == "":
        return f"rerun+http://{LOOPBACK}:{DEFAULT_PORT}/proxy"
    text = str(value).strip()
    if text.isdigit():
        port = int(text)
        if not 0 < port < 65536:
            raise ValueError(f"{field}: a port must be 1 to 65535 (got {value!r})")
        return f"rerun+http://{LOOPBACK}:{port}/proxy"
    if not _URL.match(text):
        raise ValueError(
            f"{field}: must be a port or a URL rerun+http://HOST:PORT/proxy "
            f"(rerun://, rerun+http:// or rerun+https://; got {value!r})"
        )
    return text


def address(url: str) -> tuple[str, int]:
    """``(host, port)`` of a viewer's URL (port 443 / 80 by scheme when it names none)."""
    netloc = url.split("://", 1)[1].split("/", 1)[0]
    host, _, port = netloc.rpartition(":")
    if not host or not port.isdigit():
        return netloc, 443 if url.startswith("rerun+https") else 80
    return host.strip("[]"), int(port)


def reachable(url: str, timeout_s: float = REACH_TIMEOUT_S) -> bool:
    """Whether something accepts TCP connections at the viewer's address."""
    try:
        with socket.create_connection(address(url), timeout=timeout_s):
            return True
    except OSError:
        return False


_current: LiveViewer | None = None


def current() -> LiveViewer | None:
    """The viewer this process streams to (None: none; inherited by forked workers)."""
    return _current


@contextlib.contextmanager
def watching(viewer: LiveViewer | None) -> Iterator[LiveViewer | None]:
    """``with watching(viewer):`` every stream opened in the block (and in the workers it forks)
    goes to ``viewer`` too; None changes nothing."""
    global _current
    before, _current = _current, viewer
    try:
        yield viewer
    finally:
        _current = before


def warn(text: str) -> None:
    """One warning line about a live stream (the run goes on)."""
    warnings.warn(f"live viewer: {text}", stacklevel=2)


# ----------------------------------------------------------------------------------------------
# One stream to the viewer
# ----------------------------------------------------------------------------------------------


class LiveStream:
    """A stream of this process to the viewer, or nothing: every method swallows a failure
    after one warning and makes the stream a no-op (:meth:`open` returns None when the viewer
    cannot be reached at all)."""

    def __init__(self, rec: Any, what: str):
        self._rec = rec
        self._what = what

    @classmethod
    def open(cls, viewer: LiveViewer, app_id: str, recording_id: str, what: str):
        """A stream to ``viewer`` under ``app_id`` / ``recording_id``, or None (warned)."""
        if not reachable(viewer.url):
            warn(f"{what}: nothing listens at {viewer.url}; its live stream is off")
            return None
        try:
            from validation.runs.environment import import_rerun

            import_rerun()  # first: NO_COLOR for rerun's first import only
            import rerun as rr

            rec = rr.RecordingStream(app_id, recording_id=recording_id)
            rec.set_log_time_enabled(False)
            rec.set_sinks(rr.GrpcSink(viewer.url))
        except Exception as exc:
            warn(f"{what}: {_one_line(exc)}; its live stream is off")
            return None
        return cls(rec, what)

    def do(self, action: Callable[[Any], None]) -> None:
        """``action(rec)``; a failure ends the stream (one warning)."""
        if self._rec is None:
            return
        try:
            action(self._rec)
        except Exception as exc:
            warn(f"{self._what}: {_one_line(exc)}; its live stream is off")
            self.close(flush=False)

    def close(self, flush: bool = True) -> None:
        """Hand over what is queued (at most :data:`FLUSH_TIMEOUT_S`) and disconnect."""
        rec, self._rec = self._rec, None
        if rec is None:
            return
        try:
            if flush:
                rec.flush(timeout_sec=FLUSH_TIMEOUT_S)
        except Exception as exc:
            warn(f"{self._what}: {_one_line(exc)}; what it had not sent is lost")
        finally:
            with contextlib.suppress(Exception):
                rec.disconnect()


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


def log_reached(rec: Any, entity: str, reached: Any) -> None:
    """A plant's progress in columns: ``reached`` ``[(t, wall_s)]``, the wall time ``wall_s`` it
    took to reach each simulated time ``t``, s."""
    import numpy as np
    import rerun as rr

    from validation.recording.style import TIMELINE

    t, wall = np.asarray(reached, float).reshape(-1, 2).T
    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn(TIMELINE, duration=t)],
        columns=rr.Scalars.columns(scalars=wall),
    )


def log_states(rec: Any, root: str, engine: str, t: Any, q: Any, scene: Any = None) -> None:
    """States of a plant in columns: ``{root}/state`` (q per time) and the body where the
    recording's 3D view draws it (:func:`validation.recording.world.send_poses`: its pose, its
    masses when ``scene`` is given). ``t`` (N,) s, ``q`` (N, n+7)."""
    import numpy as np
    import rerun as rr

    from validation.recording.style import TIMELINE
    from validation.recording.world import send_poses

    t = np.asarray(t, float)
    q = np.asarray(q, float)
    if t.size == 0:
        return
    col = rr.Scalars.columns(scalars=q.ravel()).partition([q.shape[1]] * t.size)
    rec.send_columns(f"{root}/state", indexes=[rr.TimeColumn(TIMELINE, duration=t)], columns=col)
    send_poses(rec, engine, scene, t, q)


LIVE_RATE_HZ = 30.0
"""At most this many states of each plant per wall second are kept for the viewer while it runs
(its first and its last always): a motion that reads as smooth."""

SEND_EVERY_S = 0.5
"""What a plant's stream keeps (its states, its progress) is sent in columns at most this often
(and at the horizon, and when the run returns): one call per entity for half a second of them
instead of one per row, which keeps the stream's cost in the plant's run near a few thousandths
of it (docs/cli.md, Watching live, gives the measured overhead), a delay a viewer does not
notice."""


class _Watcher:
    """One plant's run as its stream sees it: ``watch(t, q)`` keeps at most :data:`LIVE_RATE_HZ`
    states per wall second (the horizon's always), :meth:`reached` each progress with its wall
    time; what is kept is sent every :data:`SEND_EVERY_S` (:func:`log_states`, ``wall_s``), the
    rest by :meth:`flush`. ``rows`` counts the states kept."""

    def __init__(self, stream: LiveStream, root: str, engine: str, scene: Any, horizon: float):
        self.stream, self.root, self.engine, self.scene = stream, root, engine, scene
        self.horizon = float(horizon)
        self.every_s = 1.0 / LIVE_RATE_HZ
        self.t0 = time.perf_counter()
        self.last = self.sent = -float("inf")
        self.rows = 0
        self._t: list[float] = []
        self._q: list[Any] = []
        self._reached: list[tuple[float, float]] = []

    def __call__(self, t: float, q: Any) -> None:
        now = time.perf_counter()
        end = t >= self.horizon
        if now - self.last < self.every_s and not end:
            return
        import numpy as np

        self.last = now
        self._t.append(float(t))
        self._q.append(np.array(q, dtype=float).ravel())
        self.rows += 1
        self._send(now, end)

    def reached(self, t: float) -> None:
        """The run's progress: it reached ``t`` (s) now."""
        now = time.perf_counter()
        self._reached.append((float(t), now - self.t0))
        self._send(now, t >= self.horizon)

    def _send(self, now: float, end: bool) -> None:
        if end or now - self.sent >= SEND_EVERY_S:
            self.sent = now
            self.flush()

    def flush(self) -> None:
        """Send what is kept and not sent yet."""
        t, q, self._t, self._q = self._t, self._q, [], []
        reached, self._reached = self._reached, []
        if t:
            self.stream.do(lambda rec: log_states(rec, self.root, self.engine, t, q, self.scene))
        if reached:
            self.stream.do(lambda rec: log_reached(rec, f"{self.root}/wall_s", reached))


# ----------------------------------------------------------------------------------------------
# The plants' hook and the recording's
# ----------------------------------------------------------------------------------------------


def live_root(engine: str) -> str:
    """The entity root of plant ``engine``'s live stream."""
    from validation.recording.style import slug

    return f"live/{slug(engine)}"


def live_plant_task(
    task: Callable[..., Any], app_id: str, recording_id: str, reference: str | None = None
):
    """``task`` (a plant's run: ``task(plant, settings, scene, horizon, report=...)``, and
    ``watch=`` where it takes it, as :func:`validation.runs.plant_runs.plant_task` does) that also
    streams the plant to the current viewer under ``app_id`` (the recording's
    :class:`~validation.recording.stream.AppId`) and ``recording_id``; ``task`` itself when there
    is no viewer. ``reference``: the plant the recording draws solid (the first one compared)."""
    viewer = current()
    if viewer is None:
        return task
    # here, before the workers fork: the first state a worker logs then imports nothing (0.4 s);
    # the recording is drawn with it anyway, and it starts no thread (rerun is imported in the
    # workers only)
    import validation.recording.world  # noqa: F401

    return functools.partial(_streamed_run, task, viewer, app_id, recording_id, reference)


def _takes_watch(task: Callable[..., Any]) -> bool:
    import inspect

    try:
        params = inspect.signature(task).parameters
    except (TypeError, ValueError):
        return False
    return "watch" in params or any(p.kind is p.VAR_KEYWORD for p in params.values())


def _streamed_run(
    task, viewer, app_id, recording_id, reference, pl, settings, sc, horizon, *, report
):
    """One plant's run (in its worker) with its live stream: its progress and, as they come, the
    states its progress carries (:class:`_Watcher`); a plant that passed none has its states
    sent when it returns. The run's result is ``task``'s whatever happens to the stream."""
    engine = pl.engine
    stream = LiveStream.open(viewer, app_id, recording_id, f"{engine} plant")
    if stream is None:
        return task(pl, settings, sc, horizon, report=report)
    root = live_root(engine)
    watch = _Watcher(stream, root, engine, sc, horizon)

    def heard(t: Any) -> None:
        report(t)
        if isinstance(t, int | float):
            watch.reached(t)

    if sc is not None:
        from validation.recording.world import log_body_look

        solid = reference is None or reference == engine
        stream.do(lambda rec: log_body_look(rec, engine, sc, solid))
    extra = {"watch": watch} if _takes_watch(task) else {}
    try:
        tr, wall = task(pl, settings, sc, horizon, report=heard, **extra)
    except BaseException:  # an interrupt or the run's error: no wait for the viewer
        stream.close(flush=False)
        raise
    watch.flush()
    if not watch.rows:  # its progress carried no state: its trajectory's
        stream.do(lambda rec: log_states(rec, root, engine, tr.t, tr.q, sc))
    stream.close()
    return tr, wall


def send_file(path: str | Path, app_id: str, recording_id: str, blueprint: Any = None) -> None:
    """Send the recording written at ``path`` to the current viewer (nothing without one): its
    ``blueprint`` made active, then every chunk of the file. Never raises (one warning)."""
    viewer = current()
    if viewer is None:
        return
    stream = LiveStream.open(viewer, app_id, recording_id, Path(path).name)
    if stream is None:
        return

    def send(rec: Any) -> None:
        from rerun.chunk import RrdReader

        if blueprint is not None:
            rec.send_blueprint(blueprint, make_active=True, make_default=True)
        rec.send_chunks(RrdReader(str(path)).store())

    stream.do(send)
    stream.close()


# ----------------------------------------------------------------------------------------------
# The command line's viewer: spawned, connected to, or served
# ----------------------------------------------------------------------------------------------


def rerun_executable() -> Path:
    """The ``rerun`` executable of the installed ``rerun-sdk`` (not its Python wrapper, which would
    leave the server running when it is ended)."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is None or not spec.submodule_search_locations:
        raise ValueError("--serve: the rerun executable (rerun-sdk's rerun_cli) is not installed")
    return Path(next(iter(spec.submodule_search_locations))) / "rerun"


def _wait_listening(url: str, proc: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while not reachable(url, 0.2):
        if proc is not None and proc.poll() is not None:
            raise ValueError(f"--serve: rerun exited ({proc.returncode}) before it listened")
        if time.monotonic() > deadline:
            raise ValueError(f"nothing listens at {url} after {START_TIMEOUT_S:g} s")
        time.sleep(0.1)


def spawn_viewer(port: int = DEFAULT_PORT) -> LiveViewer:
    """A viewer spawned by ``rerun.spawn`` (a detached process that outlives the command, as
    Rerun's own ``--spawn``; one already listening on ``port`` is used instead), in a helper
    process so that this one never imports rerun. A viewer that does not listen once
    ``rerun.spawn`` returns (no display) is a warning, as Rerun's own: the streams then fail."""
    url = proxy_url(str(port))
    # rerun.spawn is a no-op without an enabled recording: rerun.init first (nothing is logged)
    code = f"import rerun; rerun.init('tumbling-testbed'); rerun.spawn(port={int(port)}, connect=False)"
    # the viewer inherits the helper's output: a file, not a pipe it would hold open
    with tempfile.TemporaryFile("w+") as said:
        done = subprocess.run(
            [sys.executable, "-c", code],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=said,
            timeout=START_TIMEOUT_S,
        )
        said.seek(0)
        last = (said.read().strip().splitlines() or ["no message"])[-1]
    if done.returncode != 0:
        raise ValueError(f"--spawn: the viewer could not be started ({last})")
    if not reachable(url):  # rerun.spawn waited for it already (a viewer without a display)
        warn(f"the spawned viewer does not listen at {url}; the run goes on, streaming when it can")
    return LiveViewer(url, LiveMode.SPAWN)


@contextlib.contextmanager
def serving(port: int = DEFAULT_PORT, web_port: int | None = None) -> Iterator[LiveViewer]:
    """Rerun's server (``rerun --serve-web``: a gRPC proxy that keeps what it is sent for the
    viewers that connect later, and a web viewer) on the loopback interface, for the block and
    then until Ctrl-C or SIGTERM; it ends with this process whatever happens."""
    from validation.runs.lifetime import die_with_parent

    url = proxy_url(str(port), "--serve")
    if reachable(url, 0.2):  # otherwise its server would be taken for the one started here
        raise ValueError(
            f"--serve: port {port} is in use on {LOOPBACK} (give another: --serve PORT)"
        )
    web_port = web_port or _free_port()
    parent = os.getpid()
    cmd = [str(rerun_executable()), "--serve-web", "--bind", LOOPBACK, "--port", str(port)]
    cmd += ["--web-viewer-port", str(web_port)]
    proc = subprocess.Popen(
        cmd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        preexec_fn=lambda: die_with_parent(parent),  # this process runs one thread
    )
    try:
        _wait_listening(url, proc)
        yield LiveViewer(url, LiveMode.SERVE)
        web = f"http://{LOOPBACK}:{web_port}/?url={url}"
        print(
            f"serving the recording at {url} (rerun --connect {url}; web viewer: {web}); "
            "Ctrl-C stops the server",
            file=sys.stderr,
            flush=True,
        )
        wait_for_stop()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def wait_for_stop(poll_s: float = 0.2) -> None:
    """Block until SIGINT or SIGTERM, taken here by handlers of its own (restored after), so the
    command that served ends with its own status, not as interrupted. Python runs a handler in
    the main thread whichever thread the signal lands on (rerun's threads included); the wait
    polls for it every ``poll_s`` seconds."""
    got: list[int] = []
    stops = (signal.SIGINT, signal.SIGTERM)
    before = {s: signal.signal(s, lambda signum, frame: got.append(signum)) for s in stops}
    try:
        while not got:
            time.sleep(poll_s)
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind((LOOPBACK, 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def from_args(args: Any) -> Iterator[LiveViewer | None]:
    """The viewer the command line asks for (``--spawn``, ``--connect [URL]``, ``--serve [PORT]``;
    :func:`validation.commands.options.add_viewer`), current for the block; none: nothing."""
    if getattr(args, "spawn", False):
        viewer = spawn_viewer()
    elif getattr(args, "connect", None) is not None:
        viewer = LiveViewer(proxy_url(args.connect), LiveMode.CONNECT)
        if not reachable(viewer.url):
            warn(f"nothing listens at {viewer.url} yet; the run goes on, streaming when it can")
    elif getattr(args, "serve", None) is not None:
        with serving(args.serve) as viewer, watching(viewer):
            yield viewer
        return
    else:
        yield None
        return
    with watching(viewer):
        yield viewer


__all__ = [
    "DEFAULT_PORT",
    "FLUSH_TIMEOUT_S",
    "LIVE_RATE_HZ",
    "REACH_TIMEOUT_S",
    "SEND_EVERY_S",
    "LiveMode",
    "LiveStream",
    "LiveViewer",
    "current",
    "from_args",
    "live_plant_task",
    "live_root",
    "log_states",
    "proxy_url",
    "reachable",
    "send_file",
    "serving",
    "spawn_viewer",
    "wait_for_stop",
    "watching",
]
