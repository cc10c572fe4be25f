"""The work and impulses of the control, accumulated at MuJoCo's integrator stages.

MuJoCo integrates the motion; the quadratures that the scipy plants integrate along with it
(:mod:`analytic.assemble`: ``W``, ``I_L``, ``I_P``) are summed here instead, one term per stage of
the controller callback with the scheme's stage weights times the step: RK4 ``h/6, h/3, h/3, h/6``
(so they are integrated by the same RK4 as the motion, fourth order), Euler and the implicit schemes
``h`` at the left point (first order, like the schemes).
"""

from __future__ import annotations

import numpy as np

from analytic.effects import MjIntegrator

STAGE_WEIGHTS: dict[MjIntegrator, tuple[float, ...]] = {
    MjIntegrator.RK4: (1 / 6, 1 / 3, 1 / 3, 1 / 6),
    MjIntegrator.EULER: (1.0,),
    MjIntegrator.IMPLICIT: (1.0,),
    MjIntegrator.IMPLICITFAST: (1.0,),
}
"""Weights of the controller's stages in one step, per integrator (``mjcb_control`` calls)."""


class Accumulator:
    """Work and impulse integrals accumulated per integrator stage with the scheme's weights.

    Attributes:
        weights: the stage weights (:data:`STAGE_WEIGHTS`); h: the step, s.
        active: whether stages are being accumulated (off while sampling with ``mj_forward``).
        calls: stages accumulated since the caller last reset it.
        v: ``[W (J), angular impulse about the system CoM (3, inertial, N·m·s), linear impulse
            (3, inertial, N·s)]``, shape (7,) (also written by the compiled stages in place).
    """

    def __init__(self, weights: tuple[float, ...]):
        self.weights = weights
        self.h = 0.0
        self.active = False
        self.calls = 0
        self.v = np.zeros(7)

    def weight(self) -> float:
        """``h`` times the weight of the next stage (0 when not accumulating)."""
        if not self.active:
            return 0.0
        return self.h * self.weights[self.calls % len(self.weights)]

    def add(self, power: float, torque_world: np.ndarray, force: np.ndarray) -> None:
        """One stage: power (W), moment about the system CoM (inertial, N·m), force at C (N)."""
        w = self.h * self.weights[self.calls % len(self.weights)]
        self.calls += 1
        self.v[0] += w * power
        self.v[1:4] += w * torque_world
        self.v[4:7] += w * force

    @property
    def work(self) -> float:
        return float(self.v[0])

    @property
    def angular_impulse(self) -> np.ndarray:
        return self.v[1:4].copy()

    @property
    def linear_impulse(self) -> np.ndarray:
        return self.v[4:7].copy()


__all__ = ["STAGE_WEIGHTS", "Accumulator"]
