"""How the Pinocchio plant integrates (its settings record) and how large a scene it holds, apart
from the plant: choosing plants does not import Pinocchio's integrator and its scipy dependencies."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from analytic.effects import SolverMethod
from analytic.plant import check_positive, coerce_enum
from mj_bridge.mujoco_settings import ControllerSource

if TYPE_CHECKING:
    from analytic.scene import Scene


@dataclass(frozen=True)
class PinocchioSettings:
    """How the Pinocchio plant integrates.

    Attributes:
        method: scipy ``OdeSolver`` (default DOP853).
        rtol, atol: tolerances on the motion (the quadratures are left out of the error control);
            None takes the scene's ``[solver]`` values.
        max_step: largest step, s; None takes the scene's.
        controller: ``analytic_fast`` (the compiled kernel, numpy where it declines) or
            ``analytic`` (the numpy model at every stage).
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


# Pinocchio's ``Data`` for this model (n prismatic joints under one free flyer) grows as the cube
# of n: ``pin.Model.createData()`` (pin 4.1) measured 0.04 s at n = 100, 2.2 s and 1.9 GB at
# n = 300, 7.6 s and 4.3 GB at n = 400, 24 s and 8.1 GB at n = 500 (about 64 n³ bytes), so 10⁴
# masses would need ~64 TB (it failed with an empty MemoryError after a minute). The Pinocchio
# plant refuses more masses than this up front; the analytic and MuJoCo plants are not limited.
PINOCCHIO_MAX_MASSES = 300


def check_pinocchio_size(scene: Scene) -> None:
    """``ValueError`` naming ``masses.mass`` when the scene has more masses than the Pinocchio plant
    holds (:data:`PINOCCHIO_MAX_MASSES`, and why)."""
    if scene.n > PINOCCHIO_MAX_MASSES:
        raise ValueError(
            f"masses.mass: the pinocchio plant holds at most {PINOCCHIO_MAX_MASSES} masses "
            f"(Pinocchio's data for n masses grows as n³: 1.9 GB at n = 300, ~64 TB at n = 10⁴; "
            f"run the other plants with --plants analytic,mujoco) (got {scene.n:,} masses)"
        )
