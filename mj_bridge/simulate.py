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
from typing import TYPE_CHECKING

import numpy as np

from analytic.effects import MjIntegrator, SpringModel
from analytic.progress import takes_state
from analytic.scene import Scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from mj_bridge.mujoco_settings import ControllerSource
from mj_bridge.plan import plan_steps

if TYPE_CHECKING:
    from model_xml import BodyFrame


def simulate(
    scene: Scene,
    integrator: MjIntegrator | str | None = None,
    dt: float | None = None,
    t_end: float | None = None,
    *,
    controller: ControllerSource | str = ControllerSource.ANALYTIC_FAST,
    body_frame: BodyFrame | None = None,
    progress: Callable[..., None] | None = None,
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
        progress: called with the simulated time reached after each output sample, s, and the
            sample's ``q`` for a callback that takes it (``progress(t, q)``:
            :mod:`analytic.progress`).
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
    import mujoco  # here: importing this module (mj_bridge.simulate) costs neither MuJoCo nor numba

    from analytic.assemble import assemble
    from mj_bridge.callbacks import bad_warnings
    from mj_bridge.twin import Twin

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
    rec: dict[str, list] = {
        k: [] for k in ("t", "qpos", "qvel", "qacc", "control", "aux", "energy_mj")
    }
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

    q_of = tw.tm.paper_q_of() if takes_state(progress) else None
    wall0 = time.perf_counter()
    nsteps = 0
    with tw.callbacks():
        sample(float(times[0]))
        try:
            for i, k in enumerate(ksteps, start=1):
                tw.step(int(k))
                nsteps += int(k)
                # MuJoCo's own verdict first: after a bad qacc it resets the state and evaluates it
                # again (one more controller call), so the count below is off whenever it warned
                bad = bad_warnings(d)
                if bad:
                    status = RunStatus.FAILED
                    message = f"MuJoCo warning before t = {times[i]:.6g} s: {'; '.join(bad)}"
                    break
                if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
                    status, message = RunStatus.FAILED, f"non-finite state at t = {times[i]:.6g} s"
                    break
                if tw.needs_control_cb and acc.calls != stages * k:
                    raise RuntimeError(
                        f"controller called {acc.calls} times in {k} steps; expected {stages} per "
                        f"step for {tw.integrator.value}"
                    )
                d.time = float(times[i])
                sample(float(times[i]))
                if q_of is not None and progress is not None:  # the sample, as the trajectory's row
                    progress(float(times[i]), q_of(d.qpos))
                elif progress is not None:
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
