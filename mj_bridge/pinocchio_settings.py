"""How the Pinocchio plant integrates (its settings record) and how large a scene it holds, apart
from the plant: choosing plants does not import Pinocchio's integrator and its scipy dependencies."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from mj_bridge.scipy_loop_settings import ScipyLoopSettings

if TYPE_CHECKING:
    from analytic.scene import Scene


@dataclass(frozen=True)
class PinocchioSettings(ScipyLoopSettings):
    """How the Pinocchio plant integrates
    (:class:`~mj_bridge.scipy_loop_settings.ScipyLoopSettings`)."""


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
