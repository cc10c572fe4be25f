"""A torque-free rigid body, integrated on its own: Euler's equations ``J ω̇ = (J ω) × ω`` and
``u̇ = ½ u ⊗ (0, ω)`` (body-axis ω, u body → inertial, w first), scipy's DOP853.

It shares no code with the model's equations (the quaternion product is
:func:`analytic.kinematics.quat_mul`, which the model does not use, not the paper's ``H(u)``). It is the exact motion of a scene whose masses all rest at C (none, or
every one at ``p = 0`` on a rod through C, at rest and at equilibrium): nothing moves them off C,
and the body turns as one rigid body of inertia ``J_BR + Σ J_i`` (Remark 1).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from analytic.effects import Effect
from analytic.kinematics import quat_mul
from analytic.scene import Scene

RTOL = 1e-13
"""DOP853's relative tolerance: four decades below the tightest bound it judges (1e-9); the
reference then stays within ~4e-9 of itself at rtol 2.5e-14 over the fastest case (200 rad/s)."""


def rigid_inertia(scene: Scene) -> np.ndarray:
    """``J_BR + Σ J_i`` (kg·m², body axes, shape (3, 3)) of a scene whose masses all rest at C.

    Raises:
        ValueError: naming the field of a mass that is not at rest at C (``rod.offset``,
            ``initial.p``, ``initial.pdot``, ``masses.p_e``): the reference would not be exact.
    """
    if scene.n:
        for name, v in (
            ("rod.offset", scene.rod.offset),
            ("initial.p", scene.initial.p),
            ("initial.pdot", scene.initial.pdot),
            ("masses.p_e", scene.masses.p_e),
        ):
            if np.any(np.asarray(v) != 0.0):
                raise ValueError(
                    f"{name}: the Euler reference needs every mass at rest at C "
                    f"(must be zero, got {np.asarray(v).tolist()!r})"
                )
    J = np.diag(scene.body.inertia)
    if scene.n and scene.has(Effect.MASS_INERTIA):
        J = J + np.sum(scene.masses.inertia, axis=0)
    return J


def torque_free(
    J: np.ndarray, omega0: np.ndarray, u0: np.ndarray, t: np.ndarray, rtol: float = RTOL
) -> tuple[np.ndarray, np.ndarray]:
    """ω (rad/s, body axes) and u at the times ``t`` (s, shape (N,)) from ω(0), u(0); shapes
    (N, 3), (N, 4). ``RuntimeError`` when DOP853 fails."""
    J = np.asarray(J, float)
    Jinv = np.linalg.inv(J)

    def f(_t, y):
        w, u = y[:3], y[3:]
        return np.concatenate([Jinv @ np.cross(J @ w, w), 0.5 * quat_mul(u, np.r_[0.0, w])])

    sol = solve_ivp(
        f,
        (t[0], t[-1]),
        np.concatenate([omega0, u0]),
        method="DOP853",
        t_eval=t,
        rtol=rtol,
        atol=1e-14 * max(1.0, float(np.max(np.abs(omega0)))),
    )
    if not sol.success:
        raise RuntimeError(f"Euler reference failed: {sol.message}")
    return sol.y[:3].T, sol.y[3:].T


def intermediate_axis(J: np.ndarray) -> int:
    """The body axis (0-based) of the intermediate diagonal entry of ``J``: for a diagonal ``J``
    (principal body axes) the unstable spin axis (the Dzhanibekov flip)."""
    return int(np.argsort(np.diag(np.asarray(J, float)))[1])


__all__ = ["RTOL", "intermediate_axis", "rigid_inertia", "torque_free"]
