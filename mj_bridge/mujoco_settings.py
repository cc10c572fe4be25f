"""How the MuJoCo plant steps (its settings record and where its control comes from), apart from
the plant: choosing plants and checking their settings does not import MuJoCo or the compiled
controller."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from analytic.effects import MjIntegrator
from analytic.plant import check_positive, coerce_enum


class ControllerSource(StrEnum):
    """Which implementation of the (same) control law drives the MuJoCo plant."""

    ANALYTIC = "analytic"
    """``analytic.TumblingModel.acceleration`` at MuJoCo's state (the paper's Eq. 89)."""
    ANALYTIC_FAST = "analytic_fast"
    """The same controller from the analytic side's compiled kernel (``analytic.fast.FastModel``,
    tested against the numpy model to 1e-12 there); the numpy model answers when numba is absent."""
    MUJOCO = "mujoco"
    """Udwadia–Kalaba from MuJoCo's own ``M`` and forces (Gauss weighting only)."""


@dataclass(frozen=True)
class MujocoRunSettings:
    """How the MuJoCo plant steps.

    Attributes:
        integrator: MuJoCo's integrator (``mjtIntegrator``).
        dt: time step, s; it must divide the output interval.
        controller: where the control comes from (:class:`ControllerSource`; the compiled
            analytic kernel by default).
        native_callback: the compiled controller as a native ``mjcb_control`` where it applies.
    """

    integrator: MjIntegrator = MjIntegrator.RK4
    dt: float = 2.5e-4
    controller: ControllerSource = ControllerSource.ANALYTIC_FAST
    native_callback: bool = True

    def __post_init__(self) -> None:
        coerce_enum(self, "integrator", MjIntegrator)
        coerce_enum(self, "controller", ControllerSource)
        check_positive(self, "dt", what="positive finite time step in s")


__all__ = ["ControllerSource", "MujocoRunSettings"]
