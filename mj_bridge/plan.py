"""MuJoCo's steps on the output grid, checked before anything is built: :func:`plan_steps`.

Light on purpose (numpy and the scene, not MuJoCo): the command line checks a run's arguments
with it before it starts the plants, and the process that starts them never imports MuJoCo.
"""

from __future__ import annotations

import math

import numpy as np

from analytic.effects import MjIntegrator
from analytic.scene import MAX_MUJOCO_STEPS, Scene, as_enum

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


__all__ = ["STEP_FIT_RTOL", "plan_steps", "steps_between"]
