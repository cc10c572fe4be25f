"""The analytic plant's adaptive Runge-Kutta loop in compiled code: CyRK's C++ solver stepping the
compiled right-hand side :func:`analytic.fast_rhs.rhs_into`, sampled on the same output grid as
scipy's loop (:func:`analytic.stepping.step_and_sample`) and returning the same record
(:class:`analytic.stepping.Stepped`), so trajectory assembly is unchanged.

Why: scipy's ``OdeSolver`` steps from Python. For the 60 s controlled Example 1 at rtol 1e-12
(5020 DOP853 steps, ~80k evaluations of a ~2 µs right-hand side) about 80 % of the wall time was
that Python loop. Here the loop, its error control and the dense output run in C++ and call the
right-hand side through a numba ``cfunc``; Python only starts the calls and keeps the samples.

Which loop runs (:func:`choose`, the ``stepper`` setting, :class:`~analytic.effects.Stepper`):

* ``scipy``: scipy's loop, the reference.
* ``compiled``: this loop, or ``ValueError`` naming ``stepper`` where it cannot apply: a method
  other than DOP853 and RK45 (:data:`COMPILED_METHODS`), a right-hand side that is not compiled
  (backend ``numpy``, numba missing, see :class:`analytic.fast.FastModel`),
  or CyRK not usable (:func:`unavailable` says why).
* ``auto`` (the default): ``compiled`` where it applies, else ``scipy``.

Methods: CyRK's RK45 and DOP853 port scipy's (tableaus, error norms, safety factor 0.9, step
factors 0.2 to 10, the first-step rule, rtol floored at 100 eps), and the quadratures ride along
with ``atol`` :data:`~analytic.stepping.QUADRATURE_ATOL` as in scipy's loop: on the 60 s controlled
Example 1 both loops take 5020 steps. Samples come from the method's dense output, evaluated by
CyRK as it steps (for DOP853 the 7th-order interpolant and its three extra stages, only for steps
with a sample, as scipy's). RK23 stays on scipy's loop: its tableau has no stage at ``c = 1``, which
the right-hand side uses to find the steps' ends (below). Radau, BDF and LSODA stay there too:
CyRK's implicit methods would get no Jacobian here and are not checked against scipy's.

Steps and ``max |u|² - 1`` at them: CyRK keeps only the samples, so the right-hand side watches the
evaluations. In RK45 and DOP853 the last stage is at ``c = 1``, at the same time as the evaluation
that follows it, the derivative at the step's end; that pair marks a trial step's end state, which
becomes the pending candidate. An evaluation later than the candidate means that trial step was
accepted (the next step has begun): its ``|u|² - 1`` counts. A rejected trial is replaced by the
retry's (earlier) end; the dense-output stages fall before it and change nothing. The state where a
call stops is an accepted step too, and is counted from CyRK's state. So the maximum is over the
accepted steps exactly, as in scipy's loop.

Calls: the run is integrated in calls of at most :data:`CHUNK_STEPS` steps (CyRK's
``max_num_steps``) that also end at each whole multiple of :data:`PROGRESS_S` (1 s) of simulated
time, each from the state where the one before stopped, with the size of its last full step as the
first step. Between calls ``progress(t)`` is called (``progress(t, q)`` with the state there, for
a callback that takes it: :mod:`analytic.progress`) and a ``KeyboardInterrupt`` (Ctrl-C) takes
effect, ending the run ``interrupted`` with the samples reached: the granularity is ``CHUNK_STEPS``
steps or 1 s of simulated time, whichever comes first. Against one unbroken run a call costs one
more evaluation (the derivative at its start) and, when it ends on a whole second, a step cut short
to land there.

Tolerances: with the plant's ``groups`` the ``atol`` vector follows the coupled groups' magnitudes
(:mod:`analytic.error_scale`); CyRK takes a vector ``atol`` per call, fixed within it, so it is
recomputed from the state each call starts at (a call is at most :data:`CHUNK_STEPS` steps): on a
state that stays O(1) it is the fixed vector of every call, and the run is unchanged. Every
:data:`~analytic.error_scale.PROBE_STEPS` steps (checked between calls) the round-off probe may end
the run ``failed``, as in scipy's loop.

Failures: the right-hand side records a non-finite ``ẏ`` (:data:`analytic.fast_rhs.STATUS_NONFINITE`)
or a kernel that declines (any other nonzero status: the numpy model must answer) in an array shared
with Python, and from then on returns NaN, so the C++ loop stops within that call (its step size
underflows). A call that does not end cleanly (that flag, a CyRK failure status, no progress, a
non-finite sample) is discarded and scipy's loop takes over from its start for the rest of the run,
on the caller's Python right-hand side ``f``: a failure ends the run exactly as on the reference
path (``failed``, the samples reached, the same message), and a declined evaluation is answered by
the numpy model there, at scipy's speed. The plant's ``info`` records the hand-over time
(``scipy_from_t_s``).

Counting: ``nfev_compiled`` counts every call of the compiled right-hand side (the first-step probe
and the dense-output stages included, as scipy's count does); ``nsteps`` CyRK's accepted steps.

The CyRK entry point: ``CyRK.nbsolve2_ivp`` (CyRK 0.20; marked experimental, and to be renamed
``nbsolve_ivp``, replacing today's numba-only ``nbsolve_ivp``) is an ``njit`` function without an
on-disk cache: compiling it took ~18 s here, in every process. This module calls the C function it
wraps, ``CyRK.nb.numba_solver.c_numba_cysolve_ivp`` (a ctypes function; the same arguments), and the
result getters it uses, from Python: nothing of CyRK is compiled at run time. The rename does not
touch these names; ``pyproject.toml`` pins ``cyrk <0.21``, and when the names or the version differ
:func:`unavailable` says so and ``auto`` runs scipy's loop. The right-hand side ``cfunc`` is cached
on disk by numba like the kernel (:func:`analytic.runtime.jit.cfunc`).
"""

from __future__ import annotations

import functools
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType, SimpleNamespace
from typing import Any

import numpy as np

from analytic.assemble import aux_count
from analytic.effects import SolverMethod, Stepper
from analytic.error_scale import (
    PROBE_STEPS,
    ErrorGroups,
    RoundoffWatch,
    atol_vector,
    follow_scales,
    group_scales,
)
from analytic.progress import takes_state
from analytic.stepping import Stepped, step_and_sample
from analytic.trajectory import RunStatus

CHUNK_STEPS = 200
"""At most this many steps per call into the C++ loop: progress is reported, and Ctrl-C takes
effect, between calls."""

PROGRESS_S = 1.0
"""Calls into the C++ loop also end at every whole multiple of this simulated time, s, so that
progress is reported at least that often (a short, cheap run too). Each such end cuts a step short
and restarts the loop: on the 60 s controlled Example 1, 60 calls (~85 steps, a few ms of wall time
each) and ~1 % more evaluations than one unbroken run. The ends are fixed times, so a run's samples
do not depend on its horizon (up to its last step), as on scipy's loop."""

COMPILED_METHODS: dict[SolverMethod, str] = {
    SolverMethod.DOP853: "DOP853",
    SolverMethod.RK45: "RK45",
}
"""The methods this loop runs, by CyRK's ``ODEMethod`` names: scipy's explicit Runge-Kutta methods
whose last stage is at ``c = 1`` (module docstring)."""

CYRK_VERSIONS = ("0.20.",)
"""CyRK versions whose C entry point this module calls with ``nbsolve2_ivp``'s argument list."""

MAX_RAM_MB = 2000
"""CyRK's storage cap per call (its default; a call keeps only its samples)."""

# ----------------------------------------------------------------------------------------------
# The compiled right-hand side and CyRK's entry points (built on first use)
# ----------------------------------------------------------------------------------------------


def _rhs_modules() -> list[ModuleType]:
    """:mod:`analytic.fast_rhs` and every ``analytic`` module it reaches through its names: the
    sources the ``cfunc`` embeds."""
    from analytic import fast_rhs

    seen: dict[str, ModuleType] = {}
    stack: list[ModuleType] = [fast_rhs]
    while stack:
        mod = stack.pop()
        if mod.__name__ in seen:
            continue
        seen[mod.__name__] = mod
        for value in vars(mod).values():
            other = value if isinstance(value, ModuleType) else None
            if other is None:
                other = sys.modules.get(getattr(value, "__module__", None) or "")
            if (
                other is not None
                and other.__name__.startswith("analytic.")
                and getattr(other, "__file__", None)
            ):
                stack.append(other)
    return [seen[k] for k in sorted(seen)]


class _Unavailable(RuntimeError):
    """The compiled loop cannot run on this installation (the message says why)."""


@functools.cache
def _cyrk() -> SimpleNamespace:
    """CyRK's entry points (nothing compiled); :class:`_Unavailable` when something is missing."""
    from analytic.runtime.jit import HAVE_NUMBA

    if not HAVE_NUMBA:
        raise _Unavailable("numba is not installed")
    try:
        import CyRK
        from CyRK.nb import numba_solver as ns
    except Exception as exc:  # ImportError, or CyRK's CPU check (it needs AVX2 on x86-64)
        raise _Unavailable(f"CyRK is not usable: {exc}") from None
    version = getattr(CyRK, "__version__", "?")
    if not version.startswith(CYRK_VERSIONS):
        raise _Unavailable(
            f"CyRK {version} is installed; this loop calls the C entry point of CyRK "
            f"{', '.join(v + 'x' for v in CYRK_VERSIONS)}"
        )
    names = (
        "c_numba_cysolve_ivp",
        "c_get_status",
        "c_get_size",
        "c_get_steps",
        "c_get_t_ptr",
        "c_get_y_ptr",
        "c_get_t_now",
        "c_get_y_now",
        "c_free",
    )
    missing = [n for n in names if not hasattr(ns, n)]
    if missing:
        raise _Unavailable(f"CyRK {version} lacks {', '.join(missing)}")
    codes = CyRK.CyrkErrorCodes
    return SimpleNamespace(
        solve=ns.c_numba_cysolve_ivp,
        status=ns.c_get_status,
        size=ns.c_get_size,
        steps=ns.c_get_steps,
        t_ptr=ns.c_get_t_ptr,
        y_ptr=ns.c_get_y_ptr,
        t_now=ns.c_get_t_now,
        y_now=ns.c_get_y_now,
        free=ns.c_free,
        methods={m: int(getattr(CyRK.ODEMethod, name)) for m, name in COMPILED_METHODS.items()},
        clean={int(codes.SUCCESSFUL_INTEGRATION), int(codes.MAX_STEPS_USER_EXCEEDED)},
        version=version,
    )


@functools.cache
def _runtime(solver: int = -1) -> SimpleNamespace:
    """:func:`_cyrk`'s entry points with the compiled right-hand side's address, the ``cfunc``
    embedding the solve ``solver`` (an :class:`analytic.kernel.entry.Solver` value; the default
    ``ANY`` embeds both) (compiled, or loaded from numba's cache, on the first call)."""
    from analytic import compiled_rhs
    from analytic.kernel.entry import Solver
    from analytic.runtime import compile_lock
    from analytic.runtime.jit import source_fingerprint

    with compile_lock.compiling(compile_lock.RHS):  # another process may be compiling it
        cfunc = compiled_rhs.make(source_fingerprint(*_rhs_modules()), Solver(solver))
    return SimpleNamespace(**vars(_cyrk()), address=cfunc.address, cfunc=cfunc, layout=compiled_rhs)


def prepare(solver: int) -> bool:
    """Compile (or load) the loop's right-hand side ``cfunc`` embedding the solve ``solver`` (a
    :class:`analytic.kernel.entry.Solver` value) without running it; False when the compiled loop
    cannot run here. It calls the kernel's halves by address (:mod:`analytic.runtime.abi`), so it
    compiles before they do (a warm-up, :mod:`validation.runs.warmup`)."""
    if unavailable():
        return False
    _runtime(int(solver))
    return True


def unavailable() -> str:
    """Why the compiled loop cannot run on this installation ("" when it can). The first call
    imports CyRK (the right-hand side ``cfunc`` is compiled when a run first needs it)."""
    try:
        _cyrk()
    except _Unavailable as exc:
        return str(exc)
    return ""


# ----------------------------------------------------------------------------------------------
# Which loop
# ----------------------------------------------------------------------------------------------


def coerce_stepper(stepper: Any) -> Stepper:
    """``stepper`` as a :class:`Stepper`, or ``ValueError`` naming the field and the choices."""
    try:
        return Stepper(stepper)
    except ValueError:
        raise ValueError(
            f"stepper: must be one of {[s.value for s in Stepper]} (got {stepper!r})"
        ) from None


def why_not_compiled(method: SolverMethod, fast: Any) -> str:
    """Why the compiled loop cannot run this case ("" when it can).

    Args:
        method: the solver method.
        fast: the :class:`analytic.fast.FastModel` answering the right-hand side, or None (the numpy
            model answers).
    """
    if method not in COMPILED_METHODS:
        return (
            f"method {method.value!r} is not one of {', '.join(COMPILED_METHODS)} (the others run "
            "on scipy's loop)"
        )
    if fast is None or not getattr(fast, "compiled", False):
        return (
            "the right-hand side is not the compiled kernel (backend 'numpy', numba missing, or a "
            "weighting the kernel does not take)"
        )
    return unavailable()


def choose(stepper: Stepper | str, method: SolverMethod, fast: Any) -> Stepper:
    """The loop that runs: :data:`Stepper.COMPILED` or :data:`Stepper.SCIPY` (module docstring).

    Raises:
        ValueError: naming ``stepper``, for an unknown value or ``compiled`` where it cannot apply.
    """
    stepper = coerce_stepper(stepper)
    if stepper is Stepper.SCIPY:
        return Stepper.SCIPY
    why = why_not_compiled(SolverMethod(method), fast)
    if not why:
        return Stepper.COMPILED
    if stepper is Stepper.COMPILED:
        raise ValueError(f"stepper: 'compiled' cannot run this case: {why} (got 'compiled')")
    return Stepper.SCIPY


# ----------------------------------------------------------------------------------------------
# The loop
# ----------------------------------------------------------------------------------------------


class _Kernel:
    """The arrays the compiled right-hand side reads (kept alive here) and its ``args``."""

    def __init__(self, layout: ModuleType, fast: Any, ny: int):
        self.c = layout  # analytic.compiled_rhs: the slots of args and ctx
        self.fp = np.ascontiguousarray(fast.fp, dtype=np.float64)
        self.ip = np.ascontiguousarray(fast.ip, dtype=np.int64)
        self.work = np.empty(2 * fast.nq + 3 + fast.k)
        self.ctx = np.zeros(layout.N_CTX)
        addresses = [a.ctypes.data for a in (self.fp, self.ip, self.work, self.ctx)]
        if max(addresses) >= 2**53:  # pragma: no cover - no such address space today
            raise _Unavailable("an array address does not fit a float64 exactly")
        self.args = np.array(
            [ny, self.fp.size, self.ip.size, self.work.size, *addresses], dtype=np.float64
        )

    def start_call(self, t0: float) -> None:
        """Start the step watch of a call from ``t0`` (forgetting the call before's last
        evaluation and pending step)."""
        c = self.c
        self.ctx[[c.C_PREV_T, c.C_CAND_T, c.C_LAST_H]] = np.nan
        self.ctx[[c.C_CAND_E, c.C_MAX_E]] = 0.0
        self.ctx[c.C_LAST_T] = t0

    @property
    def nfev(self) -> int:
        """Evaluations of the compiled right-hand side so far."""
        return int(self.ctx[self.c.C_NFEV])

    @property
    def flagged(self) -> bool:
        """True once an evaluation returned a nonzero status (non-finite, or the kernel declined)."""
        return bool(self.ctx[self.c.C_STATUS] != 0.0)

    def steps_watched(self) -> tuple[float, float]:
        """``(max | |u|² - 1 |, size of the last step)`` of the accepted steps the watch counted in
        this call (the size is NaN when none was)."""
        return float(self.ctx[self.c.C_MAX_E]), float(self.ctx[self.c.C_LAST_H])


@dataclass(frozen=True)
class _Call:
    """What one call into the C++ loop reached (``ok`` False: discard it)."""

    ok: bool
    t_now: float = math.nan
    y_now: np.ndarray | None = None
    h_last: float = 0.0
    samples: np.ndarray | None = None
    steps: int = 0
    quat_err: float = 0.0


def _call(
    rt: SimpleNamespace,
    kernel: _Kernel,
    method_int: int,
    t0: float,
    y0: np.ndarray,
    t_end: float,
    t_samples: np.ndarray,
    rtol: np.ndarray,
    atols: np.ndarray,
    max_step: float,
    first_step: float,
) -> _Call:
    """At most :data:`CHUNK_STEPS` steps from ``(t0, y0)`` towards ``t_end``, sampled at those of
    ``t_samples`` (increasing, all > t0, contiguous) that they reach.

    Returns the samples, where the call stopped (an accepted step), the size of its last step not
    cut short to land on ``t_end`` (NaN when there is none), the steps taken and ``max |u|² - 1``
    at them.
    """
    ny = y0.size
    y0 = np.ascontiguousarray(y0, dtype=np.float64)
    kernel.start_call(t0)
    ptr = None
    try:
        ptr = rt.solve(
            rt.address, t0, t_end, y0.ctypes.data, ny, method_int,
            0,  # expected size: CyRK's guess
            0,  # extra outputs
            kernel.args.ctypes.data, kernel.args.nbytes,
            CHUNK_STEPS,  # max_num_steps
            MAX_RAM_MB,
            False,  # no stored interpolants: the samples are interpolated as the steps pass them
            t_samples.ctypes.data, t_samples.size,
            None, None, 0,  # no pre-eval function, no events
            rtol.ctypes.data, rtol.size, atols.ctypes.data, atols.size,
            max_step, first_step,
            True,  # keep the solver: its state where it stopped
        )  # fmt: skip
        if not ptr:
            return _Call(False)
        status = int(rt.status(ptr))
        steps = int(rt.steps(ptr))
        if kernel.flagged or status not in rt.clean or steps < 1:
            return _Call(False)
        size = int(rt.size(ptr))
        t_now = float(rt.t_now(ptr))
        y_now = np.ctypeslib.as_array(rt.y_now(ptr), (ny,)).copy()
        samples, times = np.empty((0, ny)), np.empty(0)  # a call that passed no sample
        if size:
            samples = np.ctypeslib.as_array(rt.y_ptr(ptr), (size * ny,)).reshape(size, ny).copy()
            times = np.ctypeslib.as_array(rt.t_ptr(ptr), (size,)).copy()
    finally:
        if ptr:
            rt.free(ptr)
    if not (
        t_now > t0
        and np.array_equal(times, t_samples[:size])
        and np.isfinite(y_now).all()
        and np.isfinite(samples).all()
    ):
        return _Call(False)
    u = y_now[3:7]
    watched, h_last = kernel.steps_watched()
    quat_err = max(watched, abs(float(u @ u) - 1.0))  # the step where it stopped counts too
    return _Call(True, t_now, y_now, h_last, samples, steps, quat_err)


def integrate(
    f: Callable[[float, np.ndarray], np.ndarray],
    t_eval: np.ndarray,
    y0: np.ndarray,
    *,
    method: SolverMethod,
    rtol: float,
    atol: float,
    n_motion: int,
    max_step: float = np.inf,
    progress: Callable[[float], None] | None = None,
    linalg_failure: str = "linear algebra failed",
    stepper: Stepper | str = Stepper.AUTO,
    fast: Any = None,
    groups: ErrorGroups | None = None,
    state: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Stepped:
    """Integrate and sample as :func:`analytic.stepping.step_and_sample`, on the loop
    :func:`choose` picks.

    Args:
        f: the Python right-hand side (scipy's loop, and the compiled loop's hand-over).
        t_eval, y0, method, rtol, atol, n_motion, max_step, progress, linalg_failure, groups,
            state: as for :func:`~analytic.stepping.step_and_sample` (here the ``atol`` vector
            follows the groups' scales at the start of each call, and ``progress`` is called
            between calls, with the state where the call stopped).
        stepper: ``auto``, ``compiled`` or ``scipy``.
        fast: the :class:`analytic.fast.FastModel` whose packed constants ``f`` evaluates with
            :func:`analytic.fast_rhs.rhs_into` (None: the numpy model answers; scipy's loop). With
            it, ``y0`` is ``[q, q̇, W, I_L, I_P(, D)]`` (``2 nq + 7``, ``+ 1`` with a dissipative
            effect: :func:`analytic.assemble.aux_count`) and ``n_motion = 2 nq``.

    Raises:
        ValueError: naming ``stepper`` (:func:`choose`), before any step.
    """
    kw = dict(
        method=method,
        rtol=rtol,
        atol=atol,
        n_motion=n_motion,
        max_step=max_step,
        progress=progress,
        linalg_failure=linalg_failure,
        groups=groups,
        state=state,
    )
    if choose(stepper, method, fast) is Stepper.SCIPY:
        return step_and_sample(f, t_eval, y0, **kw)
    ny = 2 * fast.nq + aux_count(fast.model)
    if len(y0) != ny or n_motion != 2 * fast.nq:
        raise ValueError(
            f"y0: the compiled loop integrates [q, q̇, W, I_L, I_P(, D)] of {ny} components "
            f"with {2 * fast.nq} under error control (got {len(y0)} and n_motion={n_motion})"
        )
    t_eval = np.ascontiguousarray(t_eval, dtype=np.float64)
    return _compiled(f, t_eval, np.asarray(y0, dtype=np.float64), fast, kw)


def _compiled(f: Callable, t_eval: np.ndarray, y0: np.ndarray, fast: Any, kw: dict) -> Stepped:
    """The compiled loop (module docstring): calls of :data:`CHUNK_STEPS` steps, hand-over to
    scipy's loop from the start of a call that does not end cleanly."""
    from analytic.kernel.entry import solver_of

    rt = _runtime(int(solver_of(np.asarray(fast.ip))))
    ny = y0.size
    kernel = _Kernel(rt.layout, fast, ny)
    method_int = rt.methods[SolverMethod(kw["method"])]
    rtol = np.array([float(kw["rtol"])])
    groups = kw["groups"]
    scales = None if groups is None else group_scales(y0, groups)
    atols = atol_vector(float(kw["atol"]), ny, kw["n_motion"], groups, scales)
    rescales = 0
    watch = RoundoffWatch(f, float(kw["rtol"]), kw["n_motion"], t_eval[0], t_eval[-1])
    max_step = float(kw["max_step"])
    progress = kw["progress"]
    state = kw["state"] if takes_state(progress) else None
    t_end = float(t_eval[-1])
    period = PROGRESS_S
    ts: list[np.ndarray] = [t_eval[:1]]
    ys: list[np.ndarray] = [y0[None, :]]
    status, message = RunStatus.OK, ""
    i_next, t_now, y_now, first = 1, float(t_eval[0]), y0, 0.0
    nsteps, norm_err, handed_over, probe_at = 0, 0.0, None, PROBE_STEPS
    wall0 = time.perf_counter()
    try:
        while t_now < t_end:
            if groups is not None and t_now > t_eval[0]:
                now = follow_scales(scales, y_now, groups)
                if now is not scales:
                    scales, rescales = now, rescales + 1
                    atols = atol_vector(float(kw["atol"]), ny, kw["n_motion"], groups, scales)
            t_stop = min(t_end, (math.floor(t_now / period) + 1) * period)
            c = _call(
                rt, kernel, method_int, t_now, y_now, t_stop, t_eval[i_next:], rtol, atols,
                max_step, min(first, 0.5 * (t_stop - t_now)),
            )  # fmt: skip
            if not c.ok:
                # scipy's loop takes over from the start of this call, on the Python right-hand
                # side: a failure then ends the run as on the reference path; a declined
                # evaluation is answered by the numpy model
                handed_over = t_now
                grid = np.concatenate([[t_now], t_eval[i_next:]])
                run = step_and_sample(f, grid, y_now, **kw)
                ts.append(run.t[1:])
                ys.append(run.y[1:])
                status, message = run.status, run.message
                nsteps += run.nsteps
                rescales += run.rescales
                norm_err = max(norm_err, run.max_quat_norm_error_at_steps)
                break
            ts.append(t_eval[i_next : i_next + len(c.samples)])
            ys.append(c.samples)
            i_next += len(c.samples)
            t_now, y_now = c.t_now, c.y_now
            if c.h_last > 0:  # else (no full step in the call) keep the one before
                first = c.h_last
            nsteps += c.steps
            norm_err = max(norm_err, c.quat_err)
            if state is not None:
                progress(t_now, state(y_now))
            elif progress is not None:
                progress(t_now)
            if groups is not None and nsteps >= probe_at and t_now < t_end:
                probe_at = nsteps + PROBE_STEPS
                why = watch.check(t_now, y_now, first, atols, nsteps)
                if why:
                    status, message = RunStatus.FAILED, why
                    break
    except KeyboardInterrupt:
        status = RunStatus.INTERRUPTED
    wall = time.perf_counter() - wall0
    n = min(sum(len(a) for a in ts), sum(len(a) for a in ys))  # an interrupt between two appends
    t_out = np.concatenate(ts)[:n]
    if status is RunStatus.INTERRUPTED:
        message = f"interrupted at t = {float(t_out[-1]):.6g} s"
    return Stepped(
        t=t_out,
        y=np.concatenate(ys)[:n],
        status=status,
        message=message,
        nsteps=nsteps,
        max_quat_norm_error_at_steps=norm_err,
        wall_time_s=wall,
        stepper=Stepper.COMPILED,
        nfev_compiled=kernel.nfev,
        scipy_from_t=handed_over,
        rescales=rescales,
    )


__all__ = [
    "CHUNK_STEPS",
    "COMPILED_METHODS",
    "PROGRESS_S",
    "choose",
    "coerce_stepper",
    "integrate",
    "unavailable",
    "why_not_compiled",
]
