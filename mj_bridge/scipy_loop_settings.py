"""The settings of a plant integrated by scipy's loop (:mod:`analytic.stepping`) with the analytic
controller in every derivative evaluation: the Pinocchio and Drake plants. One record, so both
engines check their settings alike; each plant keeps its own subclass (``Plant.settings_type``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

from analytic.effects import SolverMethod
from analytic.plant import check_positive, coerce_enum, tighter_rtol
from mj_bridge.mujoco_settings import ControllerSource

if TYPE_CHECKING:
    from analytic.scene import Scene


@dataclass(frozen=True)
class ScipyLoopSettings:
    """How a plant on scipy's loop integrates.

    Attributes:
        method: scipy ``OdeSolver`` (default DOP853).
        rtol, atol: tolerances on the motion (the quadratures are left out of the error control);
            None takes the scene's ``[solver]`` values.
        max_step: largest step, s; None takes the scene's.
        controller: ``analytic_fast`` (the compiled kernel, numpy where it declines) or
            ``analytic`` (the numpy model at every derivative evaluation).
    """

    method: SolverMethod = SolverMethod.DOP853
    rtol: float | None = None
    atol: float | None = None
    max_step: float | None = None
    controller: ControllerSource = ControllerSource.ANALYTIC_FAST

    def __post_init__(self):
        coerce_enum(self, "method", SolverMethod)
        try:
            ctrl = ControllerSource(self.controller)
        except ValueError:
            ctrl = None
        if ctrl not in (ControllerSource.ANALYTIC, ControllerSource.ANALYTIC_FAST):
            raise ValueError(
                f"controller: must be 'analytic' or 'analytic_fast' (got {self.controller!r})"
            )
        object.__setattr__(self, "controller", ctrl)
        check_positive(self, "rtol", allow_none=True, what="positive number")
        check_positive(self, "atol", allow_none=True, what="positive number")
        check_positive(self, "max_step", allow_none=True, allow_inf=True)

    def resolved(self, scene: Scene) -> tuple[float, float, float]:
        """``(rtol, atol, max_step)`` with the scene's values where these are None."""
        s = scene.solver
        return (
            s.rtol if self.rtol is None else float(self.rtol),
            s.atol if self.atol is None else float(self.atol),
            s.max_step if self.max_step is None else float(self.max_step),
        )


def tightened_scipy_loop(scene: Scene, settings: ScipyLoopSettings) -> ScipyLoopSettings | None:
    """``settings`` with its tolerances (the scene's where None) tightened as
    :meth:`analytic.plant.Plant.tightened` says; None when rtol is at scipy's floor already."""
    rtol, atol, _ = settings.resolved(scene)
    tight = tighter_rtol(rtol, atol)
    if tight is None:
        return None
    return dataclasses.replace(settings, rtol=tight[0], atol=tight[1])


__all__ = ["ScipyLoopSettings", "tightened_scipy_loop"]
