"""Independent stages of one command in forked worker processes, or in this process.

``tumble validate`` has stages that do not need each other: each plant's run, then the figures and
the recording. On a machine with more than one CPU they run side by side in child processes forked
from this one (they inherit its imports and its loaded kernels, so a child starts in milliseconds);
elsewhere, and whenever forking is not safe, each runs here, in order, with the same results.

* :func:`start` forks a :class:`Job` (or makes an in-process one). A job may be started before its
  inputs exist (``prepare`` runs at once: a child imports matplotlib or rerun while the plants run)
  and be given them later with :meth:`Job.give`.
* :func:`wait` collects jobs, forwarding each child's messages (a plant's progress) as they come.
* A job whose child dies (killed, ``kill -9``; or it exits, or crashes, on its own), or cannot
  deliver its result, raises :class:`WorkerLost` with the child's exit code; the caller decides
  whether to do that stage here (:mod:`validation.validate` does a built-in stage again after an
  outside ``kill -9``, and fails a stage whose child ended by its own doing).
* A job may have a wall-time limit (``time_limit_s``): a child still running past it is ended
  (SIGTERM, then SIGKILL) and its job raises :class:`OverTime`, whether or not its task ever
  reports progress. A job run here has the limit as a ``SIGALRM`` timer
  (:mod:`validation.runs.time_limit`): it stops Python code at its next bytecode, not a C call that
  never returns.
* Every child ends with its parent, even one killed with SIGKILL (:mod:`validation.runs.lifetime`:
  ``PR_SET_PDEATHSIG`` on Linux); so does every child of the fork server (:func:`start_served`).
* A file the child could not write (a full disk) comes back as the same
  :class:`validation.runs.atomic.OutputError`, never as a stage's ordinary error.

Forking is used only where it is safe and useful: the ``fork`` start method exists (Linux; macOS
frameworks are not fork-safe), this process runs one thread (a fork copies only the calling thread,
and locks held by the others would stay locked in the child), and more than one CPU is available to
this process. ``TUMBLE_WORKERS=0`` in the environment turns workers off (everything runs here).

What a child does, from its start to its last message, is :mod:`validation.runs.child`. A child's
exception comes back as :class:`WorkerError` (its type name and first line); a Ctrl-C
that reaches a child ends its task the way it would end here (a plant returns its partial run).
A child honours the first SIGINT or SIGTERM and ignores the ones after it (a terminal's Ctrl-C and
the parent's forwarded one arrive together; an interrupt compiled code swallows is kept and raised
at the task's next progress report, :mod:`validation.runs.interrupts`). When this process is
interrupted, :func:`wait` tells every running child at once and gives them
:data:`INTERRUPT_GRACE_S` to send what they reached; a child that has not by then is ended.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from multiprocessing.connection import wait as mp_wait
from typing import Any

from validation.runs.atomic import OutputError
from validation.runs.child import LATER, PARENT_ENDS, child_main
from validation.runs.priority import set_idle
from validation.runs.time_limit import OverTime, time_limited

ENV_SWITCH = "TUMBLE_WORKERS"
"""Set to ``0`` to run every stage in this process."""

POLL_S = 0.05
"""How often :func:`wait` looks at the children, s (it also wakes as soon as one sends)."""

LOST_GRACE_S = 5.0
"""How long a child whose process has ended, or which was interrupted, may take to deliver, s."""

INTERRUPT_GRACE_S = 1.0
"""After a Ctrl-C (or SIGTERM) here, how long the children (told at once: a terminal's Ctrl-C
reaches them directly, a signal sent to this process alone does not) may take to send their
partial results, s; then they are ended, and their stages reported as interrupted."""

Report = Callable[[Any], None]
"""``report(message)``: what a task calls to send a message (a plant's progress) to the parent."""


class WorkerLost(RuntimeError):
    """A worker process ended without delivering its result (killed, crashed, exited, or it could
    not pickle it). ``exitcode``: the child's (``-N``: ended by signal N; None: unknown)."""

    def __init__(self, message: str, exitcode: int | None = None):
        super().__init__(message)
        self.exitcode = exitcode

    @property
    def killed(self) -> bool:
        """Ended by SIGKILL: from outside (``kill -9``, the kernel's out-of-memory killer), as a
        child never ends itself; an exit, a crash signal (SIGSEGV, SIGABRT ...) is its own doing."""
        return self.exitcode == -signal.SIGKILL


class WorkerError(RuntimeError):
    """The task raised in the worker: ``kind`` is the exception's type name."""

    def __init__(self, kind: str, message: str):
        super().__init__(f"{kind}: {message}")
        self.kind = kind
        self.message = message


def _os_threads() -> int:
    """Threads of this process (Linux ``/proc``; Python's own count elsewhere)."""
    try:
        return len(os.listdir("/proc/self/task"))
    except OSError:
        return threading.active_count()


def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def can_fork() -> bool:
    """Whether :func:`start` forks here (module docstring)."""
    if os.environ.get(ENV_SWITCH, "").strip() == "0":
        return False
    if not sys.platform.startswith("linux") or "fork" not in mp.get_all_start_methods():
        return False
    return available_cpus() > 1 and _os_threads() == 1


def can_serve() -> bool:
    """Whether :func:`start_served` starts a child here: Linux with the ``forkserver`` start method
    (and workers not switched off, :data:`ENV_SWITCH`), whatever threads this process runs, in a
    process that is not daemonic. The fork server is a fresh, single-threaded interpreter started
    with ``fork`` + ``exec``, so forking from it is safe even when this process is multi-threaded
    (a Dask worker, a thread pool's caller).

    ``multiprocessing`` refuses children to a daemonic process (it would end without joining
    them). Dask's worker processes are daemonic unless its config says
    ``distributed.worker.daemon: False``: the ``--dask-workers`` cluster the tool starts says so
    (:func:`validation.studies.sweep.running.executor_for`); a user who starts Dask workers by
    hand sets it too (``DASK_DISTRIBUTED__WORKER__DAEMON=False``), else a run there falls back to
    the time limit checked at the plant's progress reports."""
    if os.environ.get(ENV_SWITCH, "").strip() == "0" or mp.current_process().daemon:
        return False
    return sys.platform.startswith("linux") and "forkserver" in mp.get_all_start_methods()


def _ignore(_msg: Any) -> None:
    pass


@dataclass(eq=False)
class Job:
    """One stage: in a child process (``process`` set) or to be run here.

    Attributes:
        name: what the stage is (for messages).
        task: ``task(*args, report=...)``.
        on_message: called with each message the task sends (in the parent).
        limit_s: wall-time limit of the task, s, from ``started`` (``time.monotonic``); None: none.
    """

    name: str
    task: Callable[..., Any]
    args: Any = LATER
    on_message: Report | None = None
    prepare: Callable[[], None] | None = None
    process: Any = None
    conn: Any = None
    inbox: Any = None
    done: bool = False
    outcome: tuple = ()
    interrupted: bool = False
    limit_s: float | None = None
    started: float = 0.0

    @property
    def forked(self) -> bool:
        return self.process is not None

    def give(self, *args: Any) -> None:
        """The inputs of a job started without them."""
        self.args = args
        if self.forked:
            set_idle(False, self.process.pid)  # what it still prepares is now on the way
            try:
                self.inbox.send(args)
            except (OSError, ValueError):  # the child is gone; result() says WorkerLost
                pass
            self.inbox.close()

    def cancel(self) -> None:
        """Give up on a job whose inputs will never come (its child exits)."""
        if self.forked and not self.done and self.args is LATER:
            try:
                self.inbox.send(None)
                self.inbox.close()
            except (OSError, ValueError):
                pass
        self.done = True
        self.outcome = ("cancelled",)

    def _receive(self) -> None:
        """Read what the child has sent (messages forwarded, the result kept)."""
        while not self.done and self.conn.poll():
            try:
                msg = self.conn.recv()
            except (EOFError, OSError):
                self.process.join(timeout=LOST_GRACE_S)
                code = self.process.exitcode
                self._finish(("lost", f"the worker process ended (exit {code}) without a result"))
                return
            if msg[0] == "msg":
                if self.on_message is not None:
                    self.on_message(msg[1])
            else:
                self._finish(msg)

    def _finish(self, outcome: tuple) -> None:
        """Keep the outcome. The child is not waited for: it exits on its own (multiprocessing
        reaps it when the next worker starts, or at exit), and freeing a large process's memory
        takes a tenth of a second nobody needs to wait."""
        self.done = True
        self.outcome = outcome
        self.conn.close()

    def result(self) -> Any:
        """The task's return value (running it here if it is not forked).

        Raises:
            WorkerLost: the child ended without a result (the caller does the stage itself).
            WorkerError: the task raised in the child.
            OutputError: the task could not write a file (a full disk ...), in the child too.
            KeyboardInterrupt: the task was interrupted in the child before it had a result.
        """
        if not self.forked:
            if not self.done:
                if self.args is LATER:
                    raise RuntimeError(f"{self.name}: no inputs were given")
                if self.prepare is not None:
                    self.prepare()
                self.done = True
                with time_limited(self.name, self.limit_s):
                    out = self.task(*self.args, report=self.on_message or _ignore)
                self.outcome = ("ok", out)
            return self.outcome[1]
        if wait([self]):
            self.interrupted = True
        kind = self.outcome[0]
        if kind == "ok":
            return self.outcome[1]
        if kind == "output":
            _, path, reason, code = self.outcome
            raise OutputError(path, OSError(code, reason))
        if kind == "err":
            _, name, message, interrupted = self.outcome
            if interrupted:
                raise KeyboardInterrupt(message)
            raise WorkerError(name, message)
        if kind == "overtime":
            raise OverTime(self.name, self.outcome[1])
        raise WorkerLost(f"{self.name}: {self.outcome[-1]}", self.process.exitcode)

    def over_time(self, now: float) -> bool:
        """Whether this forked job is still running past its limit at ``now``."""
        return (
            self.forked
            and not self.done
            and self.limit_s is not None
            and now - self.started >= self.limit_s
        )


def flush_std_streams() -> None:
    """Flush ``sys.stdout`` and ``sys.stderr`` before forking: else a child would print what this
    process had buffered a second time (a closed or missing stream is left alone)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):
            pass


def start(
    name: str,
    task: Callable[..., Any],
    *args: Any,
    later: bool = False,
    prepare: Callable[[], None] | None = None,
    on_message: Report | None = None,
    fork: bool = True,
    idle_until_given: bool = False,
    time_limit_s: float | None = None,
) -> Job:
    """Start ``task(*args, report=...)`` in a forked child when :func:`can_fork` (and ``fork``),
    else return a job that runs it here on :meth:`Job.result`.

    Args:
        name: what the stage is.
        task: the function; it takes ``report`` (send a message to ``on_message``) as a keyword.
        args: its inputs, unless ``later`` (then :meth:`Job.give` delivers them).
        prepare: run in the child at once (imports), before the inputs arrive.
        on_message: receives the task's messages in this process.
        fork: False runs the job here whatever the machine.
        idle_until_given: the child prepares at the lowest priority (Linux ``SCHED_IDLE``: only on
            a CPU nothing else wants, so the plants keep theirs) and runs at the normal one once
            it is given its inputs.
        time_limit_s: the task's wall-time limit, s, from now (None: none): past it the child
            is ended and :meth:`Job.result` raises :class:`OverTime` (module docstring).
    """
    job = Job(name, task, LATER if later else args, on_message, prepare, limit_s=time_limit_s)
    job.started = time.monotonic()
    if not (fork and can_fork()):
        return job

    ctx = mp.get_context("fork")
    conn, child_conn = ctx.Pipe(duplex=False)
    inbox_r, inbox_w = ctx.Pipe(duplex=False)
    flush_std_streams()  # a child must not print this process's buffer again
    PARENT_ENDS[:] = [end for end in PARENT_ENDS if not end.closed]
    PARENT_ENDS.extend((conn, inbox_w))
    proc = ctx.Process(
        target=child_main,
        args=(child_conn, inbox_r, prepare, task, job.args, idle_until_given, os.getpid()),
        name=f"tumble-{name}",
        daemon=True,
    )
    proc.start()
    job.started = time.monotonic()
    child_conn.close()
    inbox_r.close()
    job.process, job.conn, job.inbox = proc, conn, inbox_w
    if not later:
        inbox_w.close()
    return job


SERVER_WATCH = "validation.runs.server_watch"
"""The fork server's first preload: the server ends with the process that started it."""

CLIENT_ENV = "TUMBLE_FORK_SERVER_CLIENT"
"""The variable that names the server's client to it (:mod:`validation.runs.server_watch`, which
cannot import this module first: it is the server's lightest preload)."""

SERVER_SETUP = "validation.runs.server_setup"
"""The fork server's last preload: what its children inherit (warnings, a frozen heap)."""


def _main_module() -> list[str]:
    """This program's main module by name, when it was run as one (``python -m pkg.mod``), for the
    fork server to import once. Every served child runs the main module's code again before its
    task (multiprocessing's rule for a child that is not forked from its parent); its imports are
    then found loaded instead of made per run (33 ms per run measured for
    ``python -m validation.studies.fuzz.bench``). A script (``tumble``, ``pytest``) has no module
    name; the server's own ``"__main__"`` preload does not reach it on Python 3.11 (the server
    is passed no main path), so a child imports what the script imports: ``tumble`` about
    10 ms, ``pytest`` about 120 ms."""
    spec = getattr(sys.modules.get("__main__"), "__spec__", None)
    name = getattr(spec, "name", None)
    if not name or name == "__main__" or name.endswith(".__main__"):
        return []
    return [name]


def start_served(
    name: str,
    task: Callable[..., Any],
    *args: Any,
    preload: Sequence[str] = (),
    on_message: Report | None = None,
    time_limit_s: float | None = None,
) -> Job:
    """Start ``task(*args, report=...)`` in a child forked by ``multiprocessing``'s fork server
    when :func:`can_serve`, else return a job that runs it here on :meth:`Job.result`.

    The fork server is started once per process, on the first call, and imports ``preload``
    (module names) and this program's main module (:func:`_main_module`) once: every child forked
    from it has them, as a child of :func:`start` has this process's imports (the preload of the
    first call is the one kept). ``task`` and ``args``
    travel to the child pickled (module-level functions and picklable inputs, as for a process
    pool); the job is then a :class:`Job` like any other (:meth:`Job.result`, :func:`wait`,
    :func:`stop`), its ``time_limit_s`` as :func:`start`'s.
    """
    job = Job(name, task, args, on_message, None, limit_s=time_limit_s)
    job.started = time.monotonic()
    if not can_serve():
        return job
    # numba's cache checked (or its check inherited from this process's parent) here, before the
    # server starts: the server, a child of this process, then trusts that check instead of
    # making its own, which would delete the kernels compiled since the check as unknown ones
    # (a Dask worker never imports the kernels itself: its server would be the first to check)
    from analytic.runtime import cache_check

    cache_check.ensure_checked()
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload([SERVER_WATCH, *preload, *_main_module(), SERVER_SETUP])
    conn, child_conn = ctx.Pipe(duplex=False)
    flush_std_streams()
    proc = ctx.Process(
        target=child_main,
        args=(child_conn, None, None, task, args, False, None, os.getpid()),
        name=f"tumble-{name}",
        daemon=True,
    )
    previous = os.environ.get(CLIENT_ENV)
    os.environ[CLIENT_ENV] = str(os.getpid())  # read by the server if this starts it (server_watch)
    try:
        proc.start()
    finally:
        if previous is None:
            os.environ.pop(CLIENT_ENV, None)
        else:
            os.environ[CLIENT_ENV] = previous
        child_conn.close()
    job.started = time.monotonic()  # the limit is the task's: the fork server's own start is not
    job.process, job.conn = proc, conn
    return job


def wait(jobs: Sequence[Job], first: bool = False, interrupted: bool = False) -> bool:
    """Collect the forked ``jobs`` until each has its outcome (``first``: until one more has),
    forwarding their messages. In-process jobs are left for :meth:`Job.result`.

    A job past its time limit (:attr:`Job.limit_s`) is ended there and then, its outcome
    :class:`OverTime` (the others go on).

    Returns whether a Ctrl-C (or SIGTERM) reached this process meanwhile (``interrupted``: it
    had already). It does not stop the collecting: every running child is told at once
    (:func:`interrupt`) and sends its partial result, kept if it comes within
    :data:`INTERRUPT_GRACE_S`; a child that has not sent by then is ended and its job marked
    interrupted (a second Ctrl-C stops waiting and is raised).
    """
    deadline = None
    pending = [j for j in jobs if j.forked and not j.done]
    if interrupted:
        interrupt(pending)
        deadline = time.monotonic() + INTERRUPT_GRACE_S
    while pending:
        if deadline is not None and time.monotonic() >= deadline:
            for j in pending:
                j.interrupted = True
                j._finish(("lost", "interrupted before it sent a result"))
            stop(pending)
            break
        try:
            mp_wait([j.conn for j in pending] + [j.process.sentinel for j in pending], POLL_S)
            now = time.monotonic()
            for j in pending:
                j._receive()
                if j.over_time(now):
                    j._finish(("overtime", j.limit_s))
                    stop([j])
                    continue
                if not j.done and not j.process.is_alive():
                    j._receive()  # what it sent before it ended
                    if not j.done:
                        code = j.process.exitcode
                        j._finish(
                            ("lost", f"the worker process ended (exit {code}) without a result")
                        )
        except KeyboardInterrupt:
            if deadline is not None:
                raise
            interrupted = True
            interrupt(pending)
            deadline = time.monotonic() + INTERRUPT_GRACE_S
        still = [j for j in pending if not j.done]
        if first and len(still) < len(pending):
            break
        pending = still
    return interrupted


def interrupt(jobs: Sequence[Job]) -> None:
    """Send SIGINT to the running children of ``jobs``: each ends its task as a Ctrl-C would
    (a plant sends the run it reached); a child told twice ignores the second."""
    for j in jobs:
        if j.forked and not j.done and j.process.is_alive():
            with contextlib.suppress(OSError):
                os.kill(j.process.pid, signal.SIGINT)


STOP_GRACE_S = 0.5
"""How long :func:`stop` lets a child end on SIGTERM before it is killed, s."""


def stop(jobs: Sequence[Job]) -> None:
    """End the children of ``jobs`` that are still running (after an error or an interrupt in
    the parent): SIGTERM, then SIGKILL after :data:`STOP_GRACE_S`; each is reaped."""
    for j in jobs:
        if j.forked and (not j.done or j.process.is_alive()):
            if not j.done:
                j.cancel()
            if j.process.is_alive():
                j.process.terminate()
    for j in jobs:
        if j.forked:
            j.process.join(timeout=STOP_GRACE_S)
            if j.process.is_alive():
                j.process.kill()
                j.process.join(timeout=STOP_GRACE_S)


__all__ = [
    "ENV_SWITCH",
    "Job",
    "OverTime",
    "WorkerError",
    "WorkerLost",
    "available_cpus",
    "can_fork",
    "can_serve",
    "flush_std_streams",
    "interrupt",
    "start",
    "start_served",
    "stop",
    "wait",
]
