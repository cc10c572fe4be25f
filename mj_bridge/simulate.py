"""Run a scene in MuJoCo and return the same :class:`analytic.trajectory.Trajectory` record as the
analytic engine, in the paper's coordinates (Eq. 44).

The controller runs inside MuJoCo's integrator: ``mjcb_control`` is called by MuJoCo at every
integrator stage (four per RK4 step) with that stage's time and state, evaluates the controller
there and writes the actuators' ``ctrl``. The control's work and impulses are accumulated in the same
callback with the scheme's stage weights (RK4: h/6, h/3, h/3, h/6), i.e. integrated by the same RK4
as the motion (fourth order); for Euler and implicitfast a left-point sum (first order, like the
schemes). Output samples are taken after ``mj_forward`` at the sample state (``d.energy`` and the
controller's outputs then describe that state).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import mujoco
import numpy as np

from analytic.assemble import assemble
from analytic.effects import MjIntegrator, SpringModel
from analytic.scene import MAX_MUJOCO_STEPS, Scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from mj_bridge.callbacks import bad_warnings
from mj_bridge.stages import ControllerSource
from mj_bridge.twin import Twin
from mj_bridge.twin_model import as_enum
from model_xml import BodyFrame

# A sample interval must be a whole number of steps to this relative tolerance.
STEP_FIT_RTOL = 1e-9


def steps_between(times: np.ndarray, dt: float, t_end_name: str = "t_end") -> np.ndarray:
    """Number of steps between consecutive output times; ValueError if dt does not divide them.

    The last interval ends at ``t_end`` (off the rate grid when it is not a multiple of
    ``1/rate``): when only that one does not fit, the error names ``t_end_name``.
    """
    gaps = np.diff(times)
    k = np.rint(gaps / dt).astype(np.int64)
    bad = (np.abs(k * dt - gaps) > STEP_FIT_RTOL * np.maximum(gaps, dt)) | (k < 1)
    if np.any(bad):
        i = int(np.argmax(bad))
        if i == len(gaps) - 1:  # only the interval that ends at t_end
            raise ValueError(
                f"{t_end_name}: not a whole number of MuJoCo steps after the last output sample at "
                f"{float(times[-2])!r} s (dt = {dt!r} s; t_end must be a multiple of dt) "
                f"(got {float(times[-1])!r})"
            )
        raise ValueError(
            f"dt: {dt!r} s does not divide the output interval {float(gaps[i])!r} s "
            f"(output.rate and t_end must be whole multiples of dt)"
        )
    return k


def plan_steps(
    scene: Scene,
    integrator: MjIntegrator | str | None = None,
    dt: float | None = None,
    t_end: float | None = None,
) -> tuple[MjIntegrator, float, np.ndarray, np.ndarray]:
    """Check a run's arguments against the scene before anything is built; ValueError naming the
    bad one. Returns ``(integrator, dt, output times, steps between them)``.

    The output grid is the analytic plant's (``0, 1/rate, ...`` and ``t_end`` exactly); MuJoCo
    needs every interval of it to be a whole number of steps of ``dt``, so ``t_end`` must be at
    least one step and a multiple of ``dt``, and a run at most ``MAX_MUJOCO_STEPS`` steps.
    """
    integ = as_enum(
        MjIntegrator, scene.mujoco.integrator if integrator is None else integrator, "integrator"
    )
    dt_name = "mujoco.timestep" if dt is None else "dt"
    h = scene.mujoco.timestep if dt is None else dt
    if isinstance(h, bool) or not isinstance(h, int | float) or not (math.isfinite(h) and h > 0):
        raise ValueError(f"{dt_name}: must be a positive finite time step in s (got {h!r})")
    h = float(h)
    out = scene.output.with_t_end(t_end, "t_end")
    t_name = "output.t_end" if t_end is None else "t_end"
    if out.t_end < h * (1 - STEP_FIT_RTOL):
        raise ValueError(
            f"{t_name}: shorter than one MuJoCo step ({dt_name} = {h!r} s) (got {out.t_end!r})"
        )
    steps = out.t_end / h
    if steps > MAX_MUJOCO_STEPS:
        # whichever is further from the paper scenes' 20 s and 2.5e-4 s
        name, value = (t_name, out.t_end) if out.t_end / 20.0 >= 2.5e-4 / h else (dt_name, h)
        raise ValueError(
            f"{name}: {out.t_end:g} s at {dt_name} = {h:g} s is {steps:.3g} MuJoCo steps, at most "
            f"{MAX_MUJOCO_STEPS:,} (got {value!r})"
        )
    times = out.times()
    return integ, h, times, steps_between(times, h, t_name)


def simulate(
    scene: Scene,
    integrator: MjIntegrator | str | None = None,
    dt: float | None = None,
    t_end: float | None = None,
    *,
    controller: ControllerSource | str = ControllerSource.ANALYTIC_FAST,
    body_frame: BodyFrame | None = None,
    progress: Callable[[float], None] | None = None,
    native_callback: bool = True,
) -> Trajectory:
    """Integrate ``scene`` in MuJoCo; samples at the scene's output rate.

    Args:
        scene: a validated scene.
        integrator: MuJoCo integrator (default ``scene.mujoco.integrator``, RK4).
        dt: time step, s (default ``scene.mujoco.timestep``); must divide the output interval.
        t_end: horizon, s (default ``scene.output.t_end``); at least one step and a multiple of
            ``dt``. Samples at ``0, 1/rate, ...`` and ``t_end`` exactly, as the analytic plant's.
        controller: the analytic controller, compiled (default; the numpy model answers where the
            kernel does not apply), or numpy (``analytic``), or the same law from MuJoCo's matrices.
        body_frame: BR's MuJoCo body frame relative to C (default at C).
        progress: called with the simulated time reached after each output sample, s.
        native_callback: run the compiled controller as a native ``mjcb_control`` where it applies
            (:mod:`mj_bridge.native`; same kernel, same numbers, no Python per stage); False keeps
            the Python callback.

    Returns:
        a :class:`Trajectory` with ``engine = mujoco``; a run that goes non-finite or is interrupted
        returns the samples reached with ``status = failed``.

    Raises:
        ValueError: naming a bad ``integrator``, ``dt`` or ``t_end`` (:func:`plan_steps`), before
            anything is built.
    """
    # Bad arguments are refused, naming them, before anything is built.
    integrator, dt, times, ksteps = plan_steps(scene, integrator, dt, t_end)
    tw = Twin(
        scene,
        integrator=integrator,
        dt=dt,
        body_frame=body_frame,
        controller=controller,
        native_callback=native_callback,
    )
    d = tw.d
    tw.set_state(0.0, scene.initial.q0(), scene.initial.qdot0())
    tw.d.time = float(times[0])
    rec = {k: [] for k in ("t", "qpos", "qvel", "qacc", "control", "aux", "energy_mj")}
    status, message = RunStatus.OK, ""
    acc = tw.acc
    stages = len(acc.weights)

    def sample(t: float) -> None:
        acc.active = False
        tw.forward_here()
        rec["t"].append(t)  # MuJoCo's state, mapped to the paper's coordinates after the run
        rec["qpos"].append(d.qpos.copy())
        rec["qvel"].append(d.qvel.copy())
        rec["qacc"].append(d.qacc.copy())
        rec["control"].append(tw.last_control if tw.controlled else None)
        rec["aux"].append(acc.v.copy())  # W, I_L, I_P
        rec["energy_mj"].append(float(d.energy[0] + d.energy[1]))

    wall0 = time.perf_counter()
    nsteps = 0
    with tw.callbacks():
        sample(float(times[0]))
        try:
            for i, k in enumerate(ksteps, start=1):
                tw.step(int(k))
                if tw.needs_control_cb and acc.calls != stages * k:
                    raise RuntimeError(
                        f"controller called {acc.calls} times in {k} steps; expected {stages} per "
                        f"step for {tw.integrator.value}"
                    )
                nsteps += int(k)
                bad = bad_warnings(d)
                if bad:
                    status = RunStatus.FAILED
                    message = f"MuJoCo warning before t = {times[i]:.6g} s: {'; '.join(bad)}"
                    break
                d.time = float(times[i])
                if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
                    status, message = RunStatus.FAILED, f"non-finite state at t = {times[i]:.6g} s"
                    break
                sample(float(times[i]))
                if progress is not None:
                    progress(float(times[i]))
        except KeyboardInterrupt:
            status, message = RunStatus.INTERRUPTED, f"interrupted at t = {rec['t'][-1]:.6g} s"
        except np.linalg.LinAlgError as exc:
            status, message = (
                RunStatus.FAILED,
                f"linear algebra failed after t = {rec['t'][-1]:.6g} s ({exc})",
            )
    wall = time.perf_counter() - wall0

    t = np.array(rec["t"])
    q, qd, qdd, omega = tw.tm.to_paper_batch(
        np.array(rec["qpos"]), np.array(rec["qvel"]), np.array(rec["qacc"])
    )
    return assemble(
        tw.model,
        Engine.MUJOCO,
        t,
        q,
        qd,
        qdd,
        rec["control"],
        np.array(rec["aux"]),
        status,
        message,
        {
            "integrator": tw.integrator.value,
            "dt": tw.dt,
            "nsteps": nsteps,
            "controller": tw.controller.value,
            "native_callback": tw.native,
            "native_redos": tw.native_redos,
            "spring_model": SpringModel(scene.mujoco.spring_model).value,
            "wall_time_s": wall,
            "mujoco_version": mujoco.__version__,
            "mujoco_energy": [float(e) for e in rec["energy_mj"]],
        },
        omega=omega,
    )
