"""Integrate a scene with the analytic model (scipy's integrators), Sec. V and VII.

The state integrated is ``y = [q, q̇, W, I_L (3), I_P (3)]``: the paper's coordinates plus the work of
the control and given torque (``Ẇ = τ·ω + F·ṗ + F_C·Ṙ + τ_g·ω``), the angular impulse of the
external moments about the system centre of mass c (``İ_L = S(u)(τ + τ_g) + (R - c)×F_C``) and the impulse of a force at C, so that the momentum
and energy balances are integrated to the same tolerance as the motion.

Steps are taken one at a time with scipy's ``OdeSolver`` classes (:func:`analytic.stepping.
step_and_sample`, shared with the Pinocchio plant), so a run that fails or is interrupted part way
returns every sample it reached, marked failed, with the reason and the time; the record is built by
:func:`analytic.assemble.assemble`, as for every plant.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol, cast

import numpy as np

from analytic.effects import Backend, Effect, SolverMethod, Stepper
from analytic.error_scale import ErrorGroups
from analytic.trajectory import Engine, RunStatus, Trajectory

if TYPE_CHECKING:  # imported where they are used: ``import analytic`` stays cheap
    from analytic.model import TumblingModel
    from analytic.scene import Scene


def evaluator(model: TumblingModel, backend: Backend | str) -> Callable:
    """``accel(t, q, qdot) -> (q̈, ControlOutput)`` for the chosen backend."""
    try:
        backend = Backend(backend)
    except ValueError:
        allowed = ", ".join(repr(b.value) for b in Backend)
        raise ValueError(f"backend: unknown value {backend!r} (allowed: {allowed})") from None
    if backend is Backend.NUMPY:
        return model.acceleration
    from analytic import fast

    if not fast.available():
        if backend is Backend.NUMBA:
            raise ValueError("backend: 'numba' needs the numba package (got backend='numba')")
        return model.acceleration
    return fast.FastModel(model.scene, model).acceleration


class CountedRhs(Protocol):
    """The right-hand side ``ẏ = f(t, y)``; ``counter["nfev"]`` counts its evaluations."""

    counter: dict[str, int]

    def __call__(self, t: float, y: np.ndarray, /) -> np.ndarray: ...


def _rhs(model: TumblingModel, accel: Callable) -> CountedRhs:
    from analytic.assemble import aux_count
    from analytic.aux_rates import aux_rates
    from analytic.model import dissipated_power, dissipates
    from analytic.stepping import NonFinite

    nq = model.nq
    dissipating = dissipates(model)
    counter = {"nfev": 0}
    has_tau_g = model.scene.has(Effect.EXTERNAL_TORQUE)
    a, d, m = model.a, model.d, model.m
    mu0, m_T = float(model.mu0), float(model.m_T)

    def f(t: float, y: np.ndarray) -> np.ndarray:
        counter["nfev"] += 1
        q, qd = y[:nq], y[nq : 2 * nq]
        qdd, c = accel(t, q, qd)
        tau = c.torque + model.given_torque(t) if has_tau_g else c.torque
        out = np.empty_like(y)
        out[:nq] = qd
        out[nq : 2 * nq] = qdd
        # Work, and the external moments about the system centre of mass (analytic/aux_rates.py)
        aux_rates(q, qd, tau, c.rod_forces, c.force_at_C, a, d, m, mu0, m_T, out[2 * nq :])
        if dissipating:  # D (analytic.assemble)
            out[2 * nq + 7] = dissipated_power(model, q[7:], qd[7:])
        if not np.isfinite(out).all():
            raise NonFinite(f"non-finite acceleration at t = {t:.6g} s")
        return out

    fm = getattr(accel, "__self__", None)
    if fm is None or not getattr(fm, "compiled", False):
        f.counter = counter  # type: ignore[attr-defined]  # a function's own attribute
        return cast(CountedRhs, f)

    # The compiled path: the same lines in one numba call (analytic.fast_rhs); f answers where the
    # kernel declines (the numpy model then, as in FastModel).
    from analytic.fast_rhs import STATUS_NONFINITE, rhs_for

    fp, ip = fm.fp, fm.ip
    rhs_into = rhs_for(ip)  # embeds only the solve this scene needs
    work = np.empty(2 * nq + 3 + model.k)
    ny = 2 * nq + aux_count(model)

    def g(t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty(ny)
        status = rhs_into(float(t), y, fp, ip, work, out)
        if status != 0 and status != STATUS_NONFINITE:
            return f(t, y)  # the kernel declined: the numpy model answers (f counts it)
        counter["nfev"] += 1
        if status == STATUS_NONFINITE:
            raise NonFinite(f"non-finite acceleration at t = {t:.6g} s")
        return out

    g.counter = counter  # type: ignore[attr-defined]  # a function's own attribute
    return cast(CountedRhs, g)


def _solver_method(method: SolverMethod | str) -> SolverMethod:
    try:
        return SolverMethod(method)
    except ValueError:
        allowed = ", ".join(repr(m.value) for m in SolverMethod)
        raise ValueError(f"method: unknown value {method!r} (allowed: {allowed})") from None


def _positive(x: float, name: str) -> float:
    if isinstance(x, bool) or not isinstance(x, int | float) or not (math.isfinite(x) and x > 0):
        raise ValueError(f"{name}: must be a positive finite number (got {x!r})")
    return float(x)


def error_groups(nq: int) -> ErrorGroups:
    """The coupled groups of the state ``[R, u, p, Ṙ, u̇, ṗ, quadratures]`` (``n = nq - 7``):
    positions ``{R, p}``, ``u``, velocities ``{Ṙ, ṗ}``, ``u̇`` (:mod:`analytic.error_scale`)."""
    return ErrorGroups.of(
        2 * nq,
        np.r_[0:3, 7:nq],
        np.arange(3, 7),
        np.r_[nq : nq + 3, nq + 7 : 2 * nq],
        np.arange(nq + 3, nq + 7),
    )


def simulate(
    scene: Scene,
    *,
    method: SolverMethod | str | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    t_end: float | None = None,
    progress: Callable[[float], None] | None = None,
    backend: Backend | str = Backend.AUTO,
    stepper: Stepper | str = Stepper.AUTO,
    scale_atol: bool = True,
) -> Trajectory:
    """Integrate ``scene`` with the analytic model; returns the samples at the scene's output rate.

    Solver, tolerances and horizon default to the scene's (``[solver]``, ``[output]``).
    A failure (solver failure, non-finite state, KeyboardInterrupt) ends the run early with
    ``status = failed`` and the samples reached so far.

    ``backend``: ``auto`` (the compiled kernel of :mod:`analytic.fast` when numba is installed,
    else numpy), ``numpy`` (the reference :class:`TumblingModel`) or ``numba``.

    ``stepper``: ``auto`` (CyRK's compiled loop for DOP853, RK45 and RK23 on the compiled right-hand
    side, else scipy's), ``compiled`` or ``scipy`` (:mod:`analytic.compiled_stepping`).

    Samples: ``0, 1/rate, 2/rate, ...`` and ``t_end`` exactly (:meth:`analytic.scene.OutputSettings.times`).
    ``scale_atol``: the motion's ``atol`` follows the magnitude of each group of coupled
    components (:mod:`analytic.error_scale`, :func:`error_groups`); False keeps it fixed.

    A bad ``t_end``, ``method``, ``rtol``, ``atol``, ``backend`` or ``stepper`` raises ``ValueError`` naming it,
    before any work.
    """
    # Bad arguments are refused, naming them, before any work.
    out = scene.output.with_t_end(t_end, "t_end")
    method = _solver_method(method or scene.solver.method)
    rtol = scene.solver.rtol if rtol is None else _positive(rtol, "rtol")
    atol = scene.solver.atol if atol is None else _positive(atol, "atol")
    from analytic.assemble import aux_count
    from analytic.compiled_stepping import integrate
    from analytic.model import TumblingModel

    model = TumblingModel(scene)
    accel = evaluator(model, backend)
    t_eval = out.times()
    nq = model.nq
    y0 = np.concatenate([scene.initial.q0(), scene.initial.qdot0(), np.zeros(aux_count(model))])
    f = _rhs(model, accel)
    run = integrate(
        f,
        t_eval,
        y0,
        method=method,
        rtol=rtol,
        atol=atol,
        n_motion=2 * nq,
        max_step=scene.solver.max_step,
        progress=progress,
        linalg_failure="mass matrix not positive definite",
        stepper=stepper,
        fast=getattr(accel, "__self__", None),
        groups=error_groups(nq) if scale_atol else None,
        state=lambda y: y[:nq].copy(),  # y = [q, q̇, quadratures]: q as the trajectory's rows
    )
    return _assemble(
        model,
        accel,
        run.t,
        run.y,
        run.status,
        run.message,
        progress=progress,
        info={
            "method": method.value,
            "backend": "numba"
            if getattr(getattr(accel, "__self__", None), "compiled", False)
            else "numpy",
            "rtol": rtol,
            "atol": atol,
            "nfev": f.counter["nfev"] + run.nfev_compiled,
            "nsteps": run.nsteps,
            "wall_time_s": run.wall_time_s,
            "max_quat_norm_error_at_steps": run.max_quat_norm_error_at_steps,
            **run.stepper_info(),
        },
    )


ASSEMBLY_REPORT_SAMPLES = 500
"""How many samples of an interrupted run's record are made between two calls of its ``progress``
(:func:`_assemble`): some 50 ms of work."""


def _assemble(
    model: TumblingModel,
    accel: Callable,
    t: np.ndarray,
    Y: np.ndarray,
    status: RunStatus,
    message: str,
    info: dict,
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """The record of the samples ``Y`` (N, 2 nq + 7): q̈ and the controller's output evaluated at
    each sample (NaN and none where the model cannot be evaluated), then :func:`assemble`.

    An interrupted run's record is made with ``progress`` called again at the time reached after
    every :data:`ASSEMBLY_REPORT_SAMPLES` samples: when it raises ``KeyboardInterrupt`` (a caller
    that discards an interrupted run, :func:`validation.runs.interrupts.checkpoint`), the record
    ends at the samples made so far (still ``interrupted``, never fewer than
    :data:`ASSEMBLY_REPORT_SAMPLES`) instead of making every sample reached, some 100 µs each."""
    from analytic.assemble import assemble

    nq = model.nq
    report = progress if status is RunStatus.INTERRUPTED else None
    q, qd = Y[:, :nq], Y[:, nq : 2 * nq]
    qdd = np.zeros((len(t), nq))
    controls = []
    for i in range(len(t)):
        if report is not None and i and i % ASSEMBLY_REPORT_SAMPLES == 0:
            try:
                report(float(t[-1]))
            except KeyboardInterrupt:  # the caller discards the run: its record ends here
                t, Y, q, qd, qdd = t[:i], Y[:i], q[:i], qd[:i], qdd[:i]
                break
        try:
            qdd[i], c = accel(t[i], q[i], qd[i])
        except (np.linalg.LinAlgError, ValueError):
            qdd[i], c = np.nan, None
        controls.append(c)
    return assemble(
        model, Engine.ANALYTIC, t, q, qd, qdd, controls, Y[:, 2 * nq :], status, message, info
    )
