"""Integrate ``ẏ = f(t, y)`` with scipy's ``OdeSolver`` classes one step at a time, sampled on an
output grid: the loop the analytic plant (:mod:`analytic.simulate`) and the Pinocchio plant
(:mod:`mj_bridge.pinocchio_plant`) share.

The state is ``y = [motion (n_motion), quadratures]``: the coordinates and velocities of a plant
(``y[3:7]`` its attitude quaternion, in either order of components) followed by integrals that ride
along (the work and impulses of :mod:`analytic.assemble`). The quadratures are left out of the error
control (their ``atol`` is huge) so that round-off in the power of a zero control cannot shrink the
steps; they are integrated with the steps the motion needs, to the same order. With the plant's
``groups`` (:class:`analytic.error_scale.ErrorGroups`) the motion's ``atol`` follows each group's
magnitude (:mod:`analytic.error_scale`): when a group's scale changes (its magnitude crosses a power
of two above 2; read every :data:`~analytic.error_scale.RESCALE_STEPS` steps) the solver is
rebuilt where it stands, with the size of its last step as its first;
and every :data:`~analytic.error_scale.PROBE_STEPS` steps a run whose step size is set by round-off
(:class:`~analytic.error_scale.RoundoffWatch`) ends ``failed`` with that reason.

Steps are taken one at a time (what ``solve_ivp`` does internally) and the samples between steps
come from the method's dense output, so a run that fails or is interrupted part way keeps every
sample it reached: a solver failure or a :class:`NonFinite` right-hand side ends it ``failed``, a
``KeyboardInterrupt`` ``interrupted``, a ``LinAlgError`` ``failed`` with the words the plant gives.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from analytic.effects import SolverMethod, Stepper
from analytic.error_scale import (
    PROBE_STEPS,
    QUADRATURE_ATOL,
    RESCALE_STEPS,
    ErrorGroups,
    RoundoffWatch,
    atol_vector,
    follow_scales,
    group_scales,
)
from analytic.progress import takes_state
from analytic.trajectory import RunStatus

SOLVERS: dict[SolverMethod, str] = {
    SolverMethod.DOP853: "DOP853",
    SolverMethod.RK45: "RK45",
    SolverMethod.RK23: "RK23",
    SolverMethod.RADAU: "Radau",
    SolverMethod.BDF: "BDF",
    SolverMethod.LSODA: "LSODA",
}
"""The name of scipy's ``OdeSolver`` class in ``scipy.integrate`` for each :class:`SolverMethod`
(looked up when a run starts: importing scipy's integrators costs 0.4 s)."""


def solver_class(method: SolverMethod) -> type:
    """scipy's ``OdeSolver`` class for ``method``."""
    from scipy import integrate

    return getattr(integrate, SOLVERS[method])


class NonFinite(ArithmeticError):
    """A right-hand side produced a NaN or an infinity (the run ends ``failed``)."""


@dataclass(frozen=True)
class Stepped:
    """The samples a run reached.

    Attributes:
        t: sample times reached, s, shape (N,) (the output grid up to where the run ended).
        y: the state at those times, shape (N, len(y0)).
        status: ``ok``, ``failed`` or ``interrupted``; message: why it ended early ("" when ok).
        nsteps: steps taken.
        max_quat_norm_error_at_steps: ``max | |y[3:7]|² - 1 |`` at the solver's own steps (the
            samples between steps come from the dense output, one order lower for DOP853).
        wall_time_s: wall time of the loop, s.
        stepper: the loop that ran (:data:`Stepper.SCIPY` here; :mod:`analytic.compiled_stepping`
            sets :data:`Stepper.COMPILED`).
        nfev_compiled: right-hand side evaluations the compiled loop made itself (0 here);
            evaluations through ``f`` are counted by the caller's ``f``.
        scipy_from_t: when a compiled run handed over to this loop part way, the time it did, s
            (None otherwise).
        rescales: times the motion's ``atol`` vector changed with the groups' scales (scipy's
            loop: solver rebuilds; the compiled loop: calls that started with a new vector).
    """

    t: np.ndarray
    y: np.ndarray
    status: RunStatus
    message: str
    nsteps: int
    max_quat_norm_error_at_steps: float
    wall_time_s: float
    stepper: Stepper = Stepper.SCIPY
    nfev_compiled: int = 0
    scipy_from_t: float | None = None
    rescales: int = 0

    def stepper_info(self) -> dict[str, object]:
        """What a plant's ``info`` records about the loop: ``stepper``, and ``scipy_from_t_s`` when
        a compiled run handed over to scipy's loop part way."""
        info: dict[str, object] = {"stepper": self.stepper.value}
        if self.scipy_from_t is not None:
            info["scipy_from_t_s"] = self.scipy_from_t
        if self.rescales:
            info["atol_rescales"] = self.rescales
        return info


def step_and_sample(
    f: Callable[[float, np.ndarray], np.ndarray],
    t_eval: np.ndarray,
    y0: np.ndarray,
    *,
    method: SolverMethod,
    rtol: float,
    atol: float,
    n_motion: int,
    max_step: float = np.inf,
    progress: Callable[..., None] | None = None,
    linalg_failure: str = "linear algebra failed",
    groups: ErrorGroups | None = None,
    state: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Stepped:
    """Integrate ``y' = f(t, y)`` from ``y0`` at ``t_eval[0]`` and sample it at ``t_eval``.

    Args:
        f: the right-hand side; raises :class:`NonFinite` for a non-finite ``ẏ``.
        t_eval: output times, s, increasing, shape (N,); the run ends at ``t_eval[-1]``.
        y0: the state at ``t_eval[0]``: ``n_motion`` components under error control, then the
            quadratures.
        method, rtol, max_step (s): passed to the solver; atol: of the motion components.
        progress: called with the time reached, s, after each step that passes a sample; with
            the state there too, ``progress(t, state(y))``, when ``state`` is given and the
            callback takes it (:func:`analytic.progress.takes_state`).
        linalg_failure: what the message says when ``f`` raises ``LinAlgError``.
        groups: the coupled groups of the motion components whose ``atol`` follows their
            magnitude (:mod:`analytic.error_scale`), with the round-off probe; None: ``atol`` on
            every one, fixed, and no probe.
        state: the plant's ``q`` (the trajectory's coordinates, a copy) of a state ``y``, for
            ``progress``; None: the progress carries no state.
    """
    if state is None or not takes_state(progress):
        state = None
    scales = None if groups is None else group_scales(y0, groups)
    atol_vec = atol_vector(atol, len(y0), n_motion, groups, scales)
    rescales = 0
    watch = RoundoffWatch(f, rtol, n_motion, t_eval[0], t_eval[-1])
    status, message = RunStatus.OK, ""
    ys = [y0]
    ts = [t_eval[0]]
    i_next = 1
    nsteps = 0
    norm_err_steps = 0.0
    wall0 = time.perf_counter()
    try:
        solver = solver_class(method)(
            f, t_eval[0], y0, t_eval[-1], rtol=rtol, atol=atol_vec, max_step=max_step
        )
        while solver.status == "running":
            msg = solver.step()
            nsteps += 1
            u_step = solver.y[3:7]
            norm_err_steps = max(norm_err_steps, abs(float(u_step @ u_step) - 1.0))
            if solver.status == "failed":
                status = RunStatus.FAILED
                message = f"{method.value} failed at t = {solver.t:.6g} s: {msg}"
                break
            j = np.searchsorted(t_eval, solver.t, side="right")
            if j > i_next:
                dense = solver.dense_output()
                for tt in t_eval[i_next:j]:
                    ys.append(dense(tt))
                    ts.append(tt)
                i_next = j
                if state is not None and progress is not None:
                    progress(float(solver.t), state(solver.y))
                elif progress is not None:
                    progress(float(solver.t))
            if (
                groups is not None
                and scales is not None  # None exactly when groups is
                and solver.status == "running"
                and nsteps % RESCALE_STEPS == 0
            ):
                if nsteps % PROBE_STEPS == 0:
                    why = watch.check(solver.t, solver.y, solver.step_size, atol_vec, nsteps)
                    if why:
                        status, message = RunStatus.FAILED, why
                        break
                now = follow_scales(scales, solver.y, groups)
                if now is not scales:
                    scales, rescales = now, rescales + 1
                    atol_vec = atol_vector(atol, len(y0), n_motion, groups, scales)
                    solver = solver_class(method)(
                        f, solver.t, solver.y.copy(), t_eval[-1], rtol=rtol, atol=atol_vec,
                        max_step=max_step, first_step=min(solver.step_size, t_eval[-1] - solver.t),
                    )  # fmt: skip
    except NonFinite as exc:
        status, message = RunStatus.FAILED, str(exc)
    except KeyboardInterrupt:
        status, message = RunStatus.INTERRUPTED, f"interrupted at t = {ts[-1]:.6g} s"
    except np.linalg.LinAlgError as exc:
        status, message = RunStatus.FAILED, f"{linalg_failure} near t = {ts[-1]:.6g} s ({exc})"
    wall = time.perf_counter() - wall0
    return Stepped(
        t=np.array(ts),
        y=np.array(ys),
        status=status,
        message=message,
        nsteps=nsteps,
        max_quat_norm_error_at_steps=norm_err_steps,
        wall_time_s=wall,
        rescales=rescales,
    )


__all__ = [
    "QUADRATURE_ATOL",
    "SOLVERS",
    "NonFinite",
    "Stepped",
    "solver_class",
    "step_and_sample",
]
