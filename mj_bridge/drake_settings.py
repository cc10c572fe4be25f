"""How the Drake plant integrates (its settings record) and whether Drake is installed, apart from the
plant: constructing or checking the settings imports neither Drake nor scipy's integrators."""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from typing import TYPE_CHECKING

from analytic.effects import SolverMethod
from analytic.plant import check_positive, coerce_enum
from mj_bridge.mujoco_settings import ControllerSource

if TYPE_CHECKING:
    from analytic.scene import Scene

DRAKE_MISSING = (
    "the Drake plant needs the 'drake' package (>= 1.51): pip install 'drake>=1.51' "
    "(the [drake] extra)"
)
"""What :func:`drake_unavailable` says when ``pydrake`` cannot be imported."""


def drake_unavailable() -> str:
    """Why the Drake plant cannot run here (:data:`DRAKE_MISSING`), or "" when ``pydrake`` is
    installed (found without importing it)."""
    return DRAKE_MISSING if importlib.util.find_spec("pydrake") is None else ""


@dataclass(frozen=True)
class DrakeSettings:
    """How the Drake plant integrates.

    Attributes:
        method: scipy ``OdeSolver`` (default DOP853; Drake's own integrators were ~10x slower at
            equal accuracy when measured, see :mod:`mj_bridge.drake_plant`).
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


__all__ = ["DRAKE_MISSING", "DrakeSettings", "drake_unavailable"]
