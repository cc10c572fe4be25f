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

import time
from collections.abc import Callable

import mujoco
import numpy as np

from analytic.effects import MjIntegrator, SpringModel
from analytic.invariants import compute_invariants, tracking_errors
from analytic.scene import OutputSettings, Scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from mj_bridge.twin import ControllerSource, Twin, bad_warnings
from model_xml import BodyFrame
from model_xml.state import mujoco_to_paper_batch

# A sample interval must be a whole number of steps to this relative tolerance.
STEP_FIT_RTOL = 1e-9


def steps_between(times: np.ndarray, dt: float) -> np.ndarray:
    """Number of steps between consecutive output times; ValueError if dt does not divide them."""
    gaps = np.diff(times)
    k = np.rint(gaps / dt).astype(int)
    bad = np.abs(k * dt - gaps) > STEP_FIT_RTOL * np.maximum(gaps, dt)
    if np.any(bad) or np.any(k < 1):
        i = int(np.argmax(bad | (k < 1)))
        raise ValueError(
            f"dt: {dt!r} s does not divide the output interval {float(gaps[i])!r} s "
            f"(output.rate and t_end must be whole multiples of dt)"
        )
    return k


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
        t_end: horizon, s (default ``scene.output.t_end``).
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
    """
    tw = Twin(
        scene,
        integrator=integrator,
        dt=dt,
        body_frame=body_frame,
        controller=controller,
        native_callback=native_callback,
    )
    out = scene.output if t_end is None else OutputSettings(t_end=t_end, rate=scene.output.rate)
    if t_end is not None and not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end: must be a positive time in s (got {t_end!r})")
    times = out.times()
    ksteps = steps_between(times, tw.dt)
    d = tw.d
    tw.set_state(0.0, scene.initial.q0(), scene.initial.qdot0())
    tw.d.time = float(times[0])
    nq = tw.n + 7
    rec = {k: [] for k in ("t", "qpos", "qvel", "qacc", "QC", "tau", "rod", "fC", "res")}
    rec.update(W=[], IL=[], IP=[], energy_mj=[])
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
        c = tw.last_control if tw.controlled else None
        rec["QC"].append(c.QC if c is not None else np.zeros(nq))
        rec["tau"].append(c.torque if c is not None else np.zeros(3))
        rec["rod"].append(c.rod_forces if c is not None else np.zeros(tw.n))
        rec["fC"].append(c.force_at_C if c is not None else np.zeros(3))
        rec["res"].append(float(np.linalg.norm(c.residual)) if c is not None else 0.0)
        rec["W"].append(acc.work)
        rec["IL"].append(acc.angular_impulse.copy())
        rec["IP"].append(acc.linear_impulse.copy())
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
    q, qd, qdd, omega = mujoco_to_paper_batch(
        np.array(rec["qpos"]), np.array(rec["qvel"]), np.array(rec["qacc"]), tw.ipos, tw.iquat
    )
    N = len(t)
    model = tw.model
    tracking = tracking_errors(model, t, q, omega)
    inv = compute_invariants(
        model, t, q, qd, np.array(rec["W"]), np.array(rec["IL"]), np.array(rec["IP"])
    )
    return Trajectory(
        engine=Engine.MUJOCO,
        scene=scene.name,
        t=t,
        q=q,
        qdot=qd,
        qddot=qdd,
        QC=np.array(rec["QC"]),
        torque=np.array(rec["tau"]),
        rod_forces=np.array(rec["rod"]).reshape(N, tw.n),
        force_at_C=np.array(rec["fC"]),
        residual_norm=np.array(rec["res"]),
        invariants=inv,
        tracking=tracking,
        status=status,
        message=message,
        info={
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
    )
