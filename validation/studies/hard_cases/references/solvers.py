"""The same plant integrated by another of scipy's methods: for the plants whose integrator is
scipy's ``solve_ivp`` family (the analytic plant, Pinocchio), a stiff case is run again with
implicit methods and compared with the plant's own run at the scene's method."""

from __future__ import annotations

from typing import Any

from analytic.effects import SolverMethod
from analytic.plant import AnalyticSettings
from analytic.trajectory import Engine
from mj_bridge.pinocchio_plant import PinocchioSettings

SCIPY_PLANTS = frozenset({Engine.ANALYTIC.value, Engine.PINOCCHIO.value})
"""Plants integrated by scipy's methods to the scene's tolerances."""


def settings(engine: str, method: SolverMethod, rtol: float, atol: float) -> Any:
    """Settings running the scipy plant ``engine`` with ``method`` at ``rtol``, ``atol``."""
    if engine == Engine.ANALYTIC.value:
        return AnalyticSettings(SolverMethod(method), rtol, atol)
    if engine == Engine.PINOCCHIO.value:
        return PinocchioSettings(SolverMethod(method), rtol, atol)
    raise ValueError(f"plants: {engine} is not integrated by scipy")


__all__ = ["SCIPY_PLANTS", "settings"]
