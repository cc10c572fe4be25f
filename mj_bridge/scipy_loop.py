"""The run every engine plant on scipy's loop shares (Pinocchio, Drake): its dynamics stepped by
:func:`analytic.stepping.step_and_sample` at the settings' tolerances, and the ``info`` every such
trajectory carries (:func:`mj_bridge.scipy_plant.simulate` runs it, then records the samples)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from analytic.error_scale import ErrorGroups
from analytic.scene import OutputSettings, Scene
from analytic.stepping import Stepped, step_and_sample
from mj_bridge.scipy_loop_settings import ScipyLoopSettings


class LoopDynamics(Protocol):
    """What the loop needs of a plant's dynamics (``PinocchioDynamics``, ``DrakeDynamics``)."""

    nq: int
    nv: int
    nfev: int
    error_groups: ErrorGroups | None
    fallbacks: int
    controller: Any

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray: ...

    def initial_state(self) -> np.ndarray: ...

    # optional: ``paper_q(y)``, the paper's q of a state y (a new array), for the progress's state


def check_t_end(t_end: float | None) -> None:
    """``ValueError`` naming ``t_end`` unless it is None or a positive finite time (s)."""
    if t_end is not None and not (math.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end: must be a positive time in s (got {t_end!r})")


def integrate(
    plant: LoopDynamics,
    settings: ScipyLoopSettings,
    scene: Scene,
    t_end: float | None,
    progress: Callable[[float], None] | None,
) -> tuple[Stepped, dict[str, Any]]:
    """Step ``plant`` over the scene's output grid (to ``t_end`` when given) at the settings'
    tolerances (the scene's where None); returns the run and its ``info`` (method, tolerances,
    controller, evaluations, steps, controller fallbacks, wall time, largest quaternion-norm
    error at the steps), to which the plant adds its engine's version. The motion's ``atol``
    follows the magnitudes of the plant's ``error_groups`` (:mod:`analytic.error_scale`)."""
    rtol, atol, max_step = settings.resolved(scene)
    out = scene.output if t_end is None else OutputSettings(t_end=t_end, rate=scene.output.rate)
    run = step_and_sample(
        plant.rhs,
        out.times(),
        plant.initial_state(),
        method=settings.method,
        rtol=rtol,
        atol=atol,
        n_motion=plant.nq + plant.nv,
        max_step=max_step,
        progress=progress,
        groups=plant.error_groups,
        state=getattr(plant, "paper_q", None),  # q of y for a progress that takes it
    )
    info = {
        "method": settings.method.value,
        "rtol": rtol,
        "atol": atol,
        "controller": plant.controller.value,
        "nfev": plant.nfev,
        "nsteps": run.nsteps,
        "controller_fallbacks": plant.fallbacks,
        "wall_time_s": run.wall_time_s,
        "max_quat_norm_error_at_steps": run.max_quat_norm_error_at_steps,
        **({"atol_rescales": run.rescales} if run.rescales else {}),
    }
    return run, info


__all__ = ["LoopDynamics", "check_t_end", "integrate"]
