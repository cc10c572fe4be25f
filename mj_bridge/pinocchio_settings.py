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


PINOCCHIO_MAX_MASSES = 300
"""The most masses the Pinocchio plant holds: its ``Data`` for this model (n prismatic joints under
one free flyer) grows as n³ (``docs/performance.md``), so larger scenes are refused up front; the
analytic and MuJoCo plants are not limited."""


def check_pinocchio_size(scene: Scene) -> None:
    """``ValueError`` naming ``masses.mass`` when the scene has more masses than the Pinocchio plant
    holds (:data:`PINOCCHIO_MAX_MASSES`, and why)."""
    if scene.n > PINOCCHIO_MAX_MASSES:
        raise ValueError(
            f"masses.mass: the pinocchio plant holds at most {PINOCCHIO_MAX_MASSES} masses "
            f"(Pinocchio's data for n masses grows as n³: 1.9 GB at n = 300, ~64 TB at n = 10⁴; "
            f"run the other plants with --plants analytic,mujoco) (got {scene.n:,} masses)"
        )
