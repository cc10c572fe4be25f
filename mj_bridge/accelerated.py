"""What MuJoCo's accelerated engines (MJX on JAX, MuJoCo Warp) share as plants: the twin they run,
the process they run it in, and what they silently leave out of it.

* :func:`accelerated_twin`: the C plant's own twin (:meth:`mj_bridge.twin_model.TwinModel.build`,
  BR's body frame at C), changed only where an accelerated engine refuses a field outright: the
  energy flag (``opt.enableflags``: ``mjENBL_ENERGY``, which ``mjx.put_model`` rejects). What was
  changed is named in :attr:`AcceleratedTwin.changed`; nothing else is touched, so any other
  difference from the C engine is the engine's (a finding, never patched away).
* :func:`run_isolated`: ``fn(*args, **kwargs)`` in a fresh *spawned* process (never forked: JAX
  and CUDA do not survive a fork, and ``jax_enable_x64`` is process-wide, so float32 and float64
  never share a process) that ends with its parent (:mod:`analytic.runtime.lifetime`). Its
  result is returned; its ``ValueError`` is raised here as a ``ValueError`` with the same one
  line; any other exception, or the process dying without a result, is an
  :class:`IsolatedError` naming it (the exit status and signal of a crash). A
  ``KeyboardInterrupt`` here (Ctrl-C, or raised by ``progress``) is passed to the child as
  SIGINT: a child that returns what it reached (a plant's interrupted trajectory) has that
  returned, else the child is killed and the interrupt raised here.
* :func:`accelerated_trajectory`: the record of a run from MuJoCo's state at the samples.
* :func:`dropped_fields`: the fields of an ``MjModel`` with a value other than MuJoCo's default
  that an engine's model type has no field for, or carries but never reads (MJX 3.17's
  ``mjx.Model`` carries ``tendon_stiffnesspoly``, MuJoCo 4's cubic tendon stiffness, and its
  passive forces never read it), i.e. what that engine drops without a word: reports name it as
  the cause of a difference.

The MJX plant integrates with MuJoCo's RK4 written out around ``mjx.forward``
(:mod:`mj_bridge.accelerated_scheme`, the controller in every stage); the MuJoCo Warp plant with
Warp's own RK4, the controller in Warp's control callback (:mod:`mj_bridge.warp_plant`).
"""

from __future__ import annotations

import copy
import os
import signal
import time
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from analytic.runtime.lifetime import die_with_parent
from analytic.scene import Scene
from analytic.trajectory import RunStatus, Trajectory
from mj_bridge.twin_model import TwinModel

# ----------------------------------------------------------------------------------------------
# The twin
# ----------------------------------------------------------------------------------------------

ENERGY_OFF = "opt.enableflags: energy off"
"""How :attr:`AcceleratedTwin.changed` names the one change: ``mjENBL_ENERGY`` cleared (MJX's
``put_model`` raises ``NotImplementedError: mjtEnableBit.mjENBL_ENERGY``; the energy is computed
by the project's invariants from the samples instead, as for every plant)."""


@dataclass(frozen=True)
class AcceleratedTwin:
    """The twin an accelerated plant runs.

    Attributes:
        tm: the C plant's twin of the scene (:class:`TwinModel`, BR's body frame at C), untouched.
        model: a copy of ``tm.m`` with only the changes named in ``changed``.
        changed: each field changed from the C plant's model, named (``("opt.enableflags:
            energy off",)``).
    """

    tm: TwinModel
    model: mujoco.MjModel
    changed: tuple[str, ...]


def accelerated_twin(scene: Scene, timestep: float | None = None) -> AcceleratedTwin:
    """The C plant's twin of ``scene`` (its ``[mujoco]`` integrator, ``timestep`` s or the
    scene's), with the energy flag off in :attr:`AcceleratedTwin.model` (named in ``changed``)."""
    tm = TwinModel.build(scene, None, timestep)
    model = copy.copy(tm.m)
    changed: list[str] = []
    energy = int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    if model.opt.enableflags & energy:
        model.opt.enableflags &= ~energy
        changed.append(ENERGY_OFF)
    return AcceleratedTwin(tm=tm, model=model, changed=tuple(changed))


# ----------------------------------------------------------------------------------------------
# What an engine drops silently
# ----------------------------------------------------------------------------------------------


NOT_DYNAMICS = ("key_", "geom_aabb", "dof_M0", "dof_length", "_rgba", "_width")
"""Float fields of an ``MjModel`` that take no part in its forward dynamics (keyframes, drawing,
bounding boxes, MuJoCo's own precomputed diagonals): never reported as dropped (prefixes and
suffixes of the field names)."""


def dropped_fields(
    m: mujoco.MjModel, engine_fields: Iterable[str], read_fields: Iterable[str] | None = None
) -> tuple[str, ...]:
    """The float array fields of ``m`` with a non-zero value that an engine drops without a word:
    absent from ``engine_fields`` (the field names of the engine's model type), or, when
    ``read_fields`` is given (the names the engine's computation reads), carried but never read
    (MJX 3.17 carries ``tendon_stiffnesspoly`` and its passive forces never read it). Fields in
    :data:`NOT_DYNAMICS` are left out. Sorted ``MjModel`` names."""
    have = set(engine_fields)
    read = None if read_fields is None else set(read_fields)
    out = []
    for name in dir(m):
        if name.startswith("_") or name.startswith(NOT_DYNAMICS) or name.endswith(NOT_DYNAMICS):
            continue
        try:
            value = getattr(m, name)
        except Exception:  # a property MuJoCo computes on demand and refuses here: not data
            continue
        if not (isinstance(value, np.ndarray) and value.dtype.kind == "f" and np.any(value)):
            continue
        if name not in have or (read is not None and name not in read):
            out.append(name)
    return tuple(sorted(out))


# ----------------------------------------------------------------------------------------------
# The record of a run
# ----------------------------------------------------------------------------------------------


def accelerated_trajectory(
    scene: Scene,
    tm: TwinModel,
    engine: str,
    t: np.ndarray,
    qpos: np.ndarray,
    qvel: np.ndarray,
    qacc: np.ndarray,
    aux: np.ndarray,
    status: RunStatus,
    message: str,
    info: dict[str, Any],
    fast: Any = None,
) -> Trajectory:
    """The :class:`Trajectory` of an accelerated plant's N samples (MuJoCo's state of the twin
    ``tm``: ``qpos (N, n+7)``, ``qvel``, ``qacc (N, n+6)``, any float dtype; ``aux`` (N, 7) the
    quadratures ``[W, I_L, I_P]`` the plant summed over its stages), in the
    paper's coordinates (:meth:`TwinModel.to_paper_batch`), float64. The controller's output at
    each sample is the compiled controller's at the sample's paper state (``fast``, an
    ``analytic.fast.FastModel`` of the scene, built when None), as the C plant records it; ``D``
    of a dissipative effect is integrated over the samples by :func:`analytic.assemble.assemble`."""
    from analytic.assemble import assemble
    from analytic.fast import FastModel

    f64 = np.float64
    q, qd, qdd, omega = tm.to_paper_batch(
        np.asarray(qpos, f64), np.asarray(qvel, f64), np.asarray(qacc, f64)
    )
    fast = FastModel(scene) if fast is None else fast
    controls = [
        fast.acceleration(float(t[i]), q[i], qd[i])[1] if scene.controlled else None
        for i in range(len(t))
    ]
    return assemble(
        fast.model,
        engine,
        np.asarray(t, f64),
        q,
        qd,
        qdd,
        controls,
        np.asarray(aux, f64).reshape(len(t), -1),
        status,
        message,
        info,
        omega=omega,
    )


# ----------------------------------------------------------------------------------------------
# One process per engine call
# ----------------------------------------------------------------------------------------------

GRACE_S = 30.0
"""How long an interrupted child has to return what it reached before it is killed, s (one
chunk of steps, or a compile: the child answers an interrupt between chunks)."""

POLL_S = 0.1
"""How often the parent looks for the child's messages and its exit, s."""


class IsolatedError(RuntimeError):
    """An isolated call failed other than by ``ValueError``: the child's exception (type and one
    line; its traceback in :attr:`child_traceback`) or the child's end without a result."""

    def __init__(self, message: str, child_traceback: str = ""):
        super().__init__(message)
        self.child_traceback = child_traceback


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _signal_name(status: int | None) -> str:
    if status is None or status >= 0:
        return f"exit {status}"
    try:
        return f"exit {status}, {signal.Signals(-status).name}"
    except ValueError:
        return f"exit {status}"


def _child(conn, fn: Callable, args: tuple, kwargs: dict, with_progress: bool) -> None:
    """Run ``fn`` in the child, send back one message (module docstring)."""
    if with_progress:
        kwargs = dict(kwargs, progress=lambda t: conn.send(("progress", float(t))))
    try:
        result = fn(*args, **kwargs)
        message = ("ok", result)
    except KeyboardInterrupt:
        message = ("interrupted", "")
    except ValueError as exc:
        message = ("value", _one_line(exc) or "ValueError")
    except BaseException as exc:
        message = ("error", f"{type(exc).__name__}: {_one_line(exc)}", traceback.format_exc())
    try:
        conn.send(message)
    except Exception as exc:  # the result does not pickle: say so rather than vanish
        conn.send(("error", f"result not sent back: {type(exc).__name__}: {_one_line(exc)}", ""))
    conn.close()


def child_main(parent: int, request_fd: int, reply_fd: int) -> None:
    """The spawned process's entry (``python -c``): end with ``parent``, take the parent's
    ``sys.path``, then the call, from ``request_fd``; answer on ``reply_fd``."""
    import sys
    from multiprocessing.connection import Connection

    die_with_parent(parent)
    request, reply = Connection(request_fd, writable=False), Connection(reply_fd, readable=False)
    sys.path[:] = request.recv()
    try:
        fn, args, kwargs, with_progress = request.recv()
    except BaseException as exc:
        reply.send(("error", f"the call did not arrive: {type(exc).__name__}: {_one_line(exc)}"))
        return
    request.close()
    _child(reply, fn, args, kwargs, with_progress)


_CHILD = (
    "import sys; from mj_bridge.accelerated import child_main; child_main(*map(int, sys.argv[1:]))"
)
"""What the spawned interpreter runs: nothing of the caller's ``__main__`` (a script, a notebook,
stdin) is imported again, unlike ``multiprocessing``'s spawn."""


def _start(fn: Callable, args: tuple, kwargs: dict, with_progress: bool):
    """The child process and the parent's end of its reply pipe."""
    import subprocess
    import sys
    from multiprocessing.connection import Connection

    req_r, req_w = os.pipe()
    rep_r, rep_w = os.pipe()
    try:
        proc = subprocess.Popen(
            [sys.executable, "-c", _CHILD, str(os.getpid()), str(req_r), str(rep_w)],
            pass_fds=(req_r, rep_w),
            stdin=subprocess.DEVNULL,
        )
    finally:
        os.close(req_r)
        os.close(rep_w)
    reply = Connection(rep_r, writable=False)
    request = Connection(req_w, readable=False)
    try:
        request.send(list(sys.path))
        request.send((fn, args, kwargs, with_progress))
    except BaseException:
        proc.kill()
        proc.wait()
        reply.close()
        raise
    finally:
        request.close()
    return proc, reply


def _end(proc, wait_s: float = 5.0) -> None:
    """Reap ``proc``, killed if it has not ended within ``wait_s`` s."""
    import subprocess

    try:
        proc.wait(wait_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def run_isolated(
    fn: Callable, /, *args: Any, progress: Callable[[float], None] | None = None, **kwargs: Any
) -> Any:
    """``fn(*args, **kwargs)`` in a fresh spawned process that dies with this one (module
    docstring); its result.

    ``fn`` must be importable by name (a module-level function) and its arguments and result
    picklable. With ``progress``, ``fn`` is called with a ``progress`` keyword of its own; each
    time it is called in the child, ``progress(t)`` is called here (where a pending Ctrl-C or
    SIGTERM of the tool is raised as ``KeyboardInterrupt``).

    Raises:
        ValueError: the child's ``ValueError``, its one line.
        IsolatedError: any other exception of the child, or the child ended without a result
            (its exit status and signal named).
        KeyboardInterrupt: interrupted here, and the child did not return what it reached.
    """
    proc, parent_end = _start(fn, args, kwargs, progress is not None)
    interrupted: KeyboardInterrupt | None = None
    deadline = None
    try:
        while True:
            try:
                if deadline is not None and time.monotonic() > deadline:
                    raise interrupted
                if parent_end.poll(POLL_S):
                    try:
                        message = parent_end.recv()
                    except EOFError:
                        message = None
                    if message is None:
                        _end(proc)
                        raise IsolatedError(
                            f"the isolated process ended ({_signal_name(proc.returncode)}) "
                            f"without a result"
                        )
                    kind = message[0]
                    if kind == "progress":
                        if progress is not None and interrupted is None:
                            progress(message[1])
                        continue
                    if kind == "ok":
                        return message[1]
                    if kind == "value":
                        raise ValueError(message[1])
                    if kind == "interrupted":
                        raise interrupted or KeyboardInterrupt()
                    raise IsolatedError(message[1], message[2] if len(message) > 2 else "")
                if proc.poll() is not None and not parent_end.poll(0):
                    raise IsolatedError(
                        f"the isolated process ended ({_signal_name(proc.returncode)}) "
                        f"without a result"
                    )
            except KeyboardInterrupt as exc:
                if interrupted is not None:  # a second interrupt: stop waiting
                    raise
                interrupted = exc
                deadline = time.monotonic() + GRACE_S
                if proc.poll() is None:
                    os.kill(proc.pid, signal.SIGINT)
    except BaseException:
        _end(proc, 0.0)  # an error or interrupt here: the child goes at once
        raise
    finally:
        _end(proc)
        parent_end.close()


__all__ = [
    "ENERGY_OFF",
    "GRACE_S",
    "AcceleratedTwin",
    "IsolatedError",
    "accelerated_trajectory",
    "accelerated_twin",
    "dropped_fields",
    "run_isolated",
]
