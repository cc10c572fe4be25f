"""MuJoCo's RK4 step, written out so that an engine without physics callbacks (MJX) runs the
controller in every stage, as the C plant does inside ``mj_step``. MuJoCo Warp has callbacks and
steps with its own RK4 (:mod:`mj_bridge.warp_plant`); it shares only this module's state map
(:func:`paper_state`), constants and quadrature rates (:mod:`mj_bridge.warp_control`).

Generic over an array namespace ``xp`` (``numpy`` or ``jax.numpy``: only elementwise arithmetic,
``sqrt``, ``sin``, ``cos``, ``where``, ``concatenate``, ``stack``, ``@`` and ``[..., k]``
indexing, no in-place writes), and over leading batch dimensions: every state below has shape
``(..., k)`` (one scene, or ``nworld`` of them; times ``t`` are scalars or shape ``(...)``).

The scheme is MuJoCo 4.0's ``mj_step`` with ``mjINT_RK4`` (its tableau :data:`RK4_A`,
:data:`RK4_B`, stage times ``t + C_i h`` with ``C`` the row sums of A, every sum in MuJoCo's
order, zero terms included):

* stage 0 is the forward dynamics at the step's start (``mj_step``'s ``mj_forward``);
* stage i = 1..3: ``dX = Σ_{j<i} A_ij [k_j, a_j]``, the positions ``mj_integratePos(q_0, dX_k,
  h)`` (:func:`integrate_pos`: the free joint's quaternion moved by ``mju_quatIntegrate``, the
  translation and the slides by ``h dX``), the velocities ``v_0 + h dX_a``, the forward dynamics
  at time ``t + C_{i-1} h``;
* the step: ``dX = Σ_j B_j [k_j, a_j]``, ``v = v_0 + h dX_a``, ``q = mj_integratePos(q_0, dX_k,
  h)``, ``t + h`` (``mj_advance``).

The position rates ``k_j`` are the stage velocities, except the free joint's angular part:
``k_j = dexpinv(h dX_k,j, ω_j)`` (:func:`dexpinv`), the Runge-Kutta-Munthe-Kaas form of RK4 on
the rotation group. MuJoCo's C source up to 3.x (and MJX 3.17's ``rungekutta4``) sums the
angular velocities themselves (``k_j = ω_j``); the MuJoCo 4.0.0 library's stage states and step
are reproduced to round-off only with the Munthe-Kaas rates (measured stage by stage through
``mjcb_control``: ``tests/mj_bridge/test_accelerated_scheme.py``), which differ from the plain
sum by ``O(h² |ω × ω̇|)`` per step (4e-13 in the quaternion per step of Example 1 at 2.5e-4 s).

So with the same forward dynamics this step is the C engine's RK4 to round-off, and any
difference between an accelerated plant and the C plant is the engine's forward dynamics or its
precision.

A *stage* (:func:`controlled_stage`) is the forward dynamics with the controller: the state
mapped to the paper's coordinates (:func:`paper_state`, BR's body frame at C), the controller's
torque, rod forces and force at C there plus the given torque, the actuators' ``ctrl`` exactly as
the C plant writes them (``torque · INV_GEAR`` on ``torque_x..z``, ``F · INV_GEAR`` on
``force1..N``, :mod:`mj_bridge.stages`) and the force at C for BR's ``xfrc_applied``; it returns
the engine's ``qacc`` and the rates of the quadratures ``[W, I_L (3), I_P (3)]``
(:func:`quadrature_rates`, :mod:`analytic.aux_rates`), summed by the step with the weights
``h B_j`` (:data:`mj_bridge.accumulator.STAGE_WEIGHTS`), as the C plant's accumulator sums them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from analytic.effects import MjIntegrator
from analytic.scene import Scene
from mj_bridge.accumulator import STAGE_WEIGHTS
from mj_bridge.stages import INV_GEAR
from mj_bridge.twin_model import TwinModel

MJ_MINVAL = 1e-15
"""MuJoCo's ``mjMINVAL`` (``mjtype.h``): the smallest norm ``mju_normalize3``/``4`` divide by."""

RK4_A = ((0.5,), (0.0, 0.5), (0.0, 0.0, 1.0))
"""The rows of MuJoCo's ``RK4_A`` (``engine_forward.c``) below the diagonal, stage 1..3."""

RK4_B = (1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0)
"""MuJoCo's ``RK4_B``: the stage weights of the step (the C plant's accumulator's too)."""

RK4_C = tuple(sum(row, 0.0) for row in RK4_A)
"""The stage times' fractions of the step, ``C_i = Σ_j A_ij`` as MuJoCo sums them."""

assert STAGE_WEIGHTS[MjIntegrator.RK4] == RK4_B  # the C plant's accumulator's weights

Stage = Callable[[Any, Any, Any], tuple[Any, Any]]
"""``stage(t, qpos, qvel) -> (qacc, rates)``: the forward dynamics with the controller applied,
and the quadratures' rates (..., 7)."""


# ----------------------------------------------------------------------------------------------
# MuJoCo's position integration
# ----------------------------------------------------------------------------------------------


def quat_integrate(xp, quat, vel, scale):
    """``mju_quatIntegrate(quat, vel, scale)``: ``quat`` (..., 4, w first) normalised as
    ``mju_normalize4`` does, times the rotation of ``scale |vel|`` about ``vel`` (``vel`` (..., 3),
    body axes): ``(cos(θ/2), n sin(θ/2))``, the identity for a zero angle."""
    v0, v1, v2 = vel[..., 0], vel[..., 1], vel[..., 2]
    norm = xp.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    small = norm < MJ_MINVAL
    inv = 1 / xp.where(small, 1.0, norm)
    n0 = xp.where(small, 1.0, v0 * inv)
    n1 = xp.where(small, 0.0, v1 * inv)
    n2 = xp.where(small, 0.0, v2 * inv)
    angle = scale * norm
    zero = angle == 0
    s = xp.sin(angle * 0.5)
    r0 = xp.where(zero, 1.0, xp.cos(angle * 0.5))
    r1 = xp.where(zero, 0.0, n0 * s)
    r2 = xp.where(zero, 0.0, n1 * s)
    r3 = xp.where(zero, 0.0, n2 * s)
    q0, q1, q2, q3 = quat[..., 0], quat[..., 1], quat[..., 2], quat[..., 3]
    qn = xp.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    tiny = qn < MJ_MINVAL
    rescale = xp.abs(qn - 1) > MJ_MINVAL
    qinv = 1 / xp.where(tiny | ~rescale, 1.0, qn)
    q0 = xp.where(tiny, 1.0, xp.where(rescale, q0 * qinv, q0))
    q1 = xp.where(tiny, 0.0, xp.where(rescale, q1 * qinv, q1))
    q2 = xp.where(tiny, 0.0, xp.where(rescale, q2 * qinv, q2))
    q3 = xp.where(tiny, 0.0, xp.where(rescale, q3 * qinv, q3))
    return xp.stack(
        [
            q0 * r0 - q1 * r1 - q2 * r2 - q3 * r3,
            q0 * r1 + q1 * r0 + q2 * r3 - q3 * r2,
            q0 * r2 - q1 * r3 + q2 * r0 + q3 * r1,
            q0 * r3 + q1 * r2 - q2 * r1 + q3 * r0,
        ],
        axis=-1,
    )


def integrate_pos(xp, qpos, vel, h):
    """``mj_integratePos`` of the twin (a free joint, then n slides): ``qpos`` (..., n+7),
    ``vel`` (..., n+6), step ``h`` s: the position ``R + h v``, the quaternion by
    :func:`quat_integrate`, each slide ``p + h ṗ``."""
    return xp.concatenate(
        [
            qpos[..., :3] + h * vel[..., :3],
            quat_integrate(xp, qpos[..., 3:7], vel[..., 3:6], h),
            qpos[..., 7:] + h * vel[..., 6:],
        ],
        axis=-1,
    )


# ----------------------------------------------------------------------------------------------
# The step
# ----------------------------------------------------------------------------------------------


def _weighted(terms):
    """``Σ_j c_j x_j`` from zero in the order given, as ``mju_zero`` + ``mju_addToScl``."""
    acc = None
    for c, x in terms:
        acc = x * c if acc is None else acc + x * c
    return acc


DEXPINV_SERIES = 0.1
"""Below this rotation angle (rad) the coefficient of :func:`dexpinv`'s last term is taken from
its series (``1/12 + θ²/720 + θ⁴/30240``, next term ``θ⁶/1209600``), whose closed form loses
digits to cancellation there."""


def dexpinv(xp, theta, v):
    """The inverse of the differential of the exponential map of rotations, applied to the
    body-axis angular velocity ``v`` (..., 3) at the rotation vector ``theta`` (..., 3):
    ``v + ½ θ×v + c(|θ|) θ×(θ×v)``, ``c(a) = (1 − (a/2) cot(a/2)) / a²``. What the stage's
    angular velocity contributes to the stage rotation of a Runge-Kutta-Munthe-Kaas step."""
    a2 = xp.sum(theta * theta, axis=-1)
    a = xp.sqrt(a2)
    small = a < DEXPINV_SERIES
    a_safe = xp.where(small, 1.0, a)
    half = 0.5 * a_safe
    exact = (1 - half * xp.cos(half) / xp.sin(half)) / (a_safe * a_safe)
    series = 1 / 12 + a2 / 720 + a2 * a2 / 30240
    c = xp.where(small, series, exact)[..., None]
    tv = _cross(xp, theta, v)
    return v + 0.5 * tv + c * _cross(xp, theta, tv)


def _rates(xp, qvel, dang, h):
    """The stage's position rates: ``qvel`` with the angular part replaced by
    :func:`dexpinv` at the stage's rotation vector ``h dang`` from the step's start."""
    w = qvel[..., 3:6] if dang is None else dexpinv(xp, h * dang, qvel[..., 3:6])
    return xp.concatenate([qvel[..., :3], w, qvel[..., 6:]], axis=-1)


def rk4_step(xp, stage: Stage, t, qpos, qvel, aux, h):
    """One MuJoCo RK4 step (module docstring) from ``(t, qpos, qvel)``, with the quadratures
    ``aux`` (..., 7) advanced by ``Σ_j (h B_j) rates_j``. Returns ``(qpos, qvel, aux)`` at
    ``t + h`` (the caller advances ``t`` by ``h``, as ``mj_advance`` does)."""
    qacc, rates = stage(t, qpos, qvel)
    K = [_rates(xp, qvel, None, h)]  # the position rates of each stage
    F = [qacc]
    R = [rates]
    for i, row in enumerate(RK4_A, start=1):
        dv = _weighted((row[j], K[j]) for j in range(i))
        da = _weighted((row[j], F[j]) for j in range(i))
        q_i = integrate_pos(xp, qpos, dv, h)
        v_i = qvel + da * h
        a_i, r_i = stage(t + RK4_C[i - 1] * h, q_i, v_i)
        K.append(_rates(xp, v_i, dv[..., 3:6], h))
        F.append(a_i)
        R.append(r_i)
    dv = _weighted((RK4_B[j], K[j]) for j in range(4))
    da = _weighted((RK4_B[j], F[j]) for j in range(4))
    for j in range(4):
        aux = aux + (h * RK4_B[j]) * R[j]
    return integrate_pos(xp, qpos, dv, h), qvel + da * h, aux


# ----------------------------------------------------------------------------------------------
# The stage: the paper's state, the controller, the actuators, the quadratures
# ----------------------------------------------------------------------------------------------


def paper_state(xp, qpos, qvel):
    """MuJoCo ``(qpos (..., n+7), qvel (..., n+6))`` of a twin whose body frame is at C -> the
    paper's ``(q, q̇)`` (..., n+7): u the quaternion as given, ``u̇ = H(u)ᵀ ω / (4|u|²)``
    (:func:`model_xml.coordinates.mujoco_to_paper_state`)."""
    u0, u1, u2, u3 = qpos[..., 3], qpos[..., 4], qpos[..., 5], qpos[..., 6]
    w0, w1, w2 = qvel[..., 3], qvel[..., 4], qvel[..., 5]
    k = 0.5 / (u0 * u0 + u1 * u1 + u2 * u2 + u3 * u3)
    udot = xp.stack(
        [
            (-u1 * w0 - u2 * w1 - u3 * w2) * k,
            (u0 * w0 - u3 * w1 + u2 * w2) * k,
            (u3 * w0 + u0 * w1 - u1 * w2) * k,
            (-u2 * w0 + u1 * w1 + u0 * w2) * k,
        ],
        axis=-1,
    )
    q = xp.concatenate([qpos[..., :3], qpos[..., 3:7], qpos[..., 7:]], axis=-1)
    qdot = xp.concatenate([qvel[..., :3], udot, qvel[..., 6:]], axis=-1)
    return q, qdot


def _rotate(xp, u, v):
    """``S(u/|u|) v`` row-wise (:func:`model_xml.rotations.quat_to_mat`): u (..., 4), v (..., 3)."""
    n = xp.sqrt(u[..., 0] ** 2 + u[..., 1] ** 2 + u[..., 2] ** 2 + u[..., 3] ** 2)
    u0, u1, u2, u3 = u[..., 0] / n, u[..., 1] / n, u[..., 2] / n, u[..., 3] / n
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return xp.stack(
        [
            (2 * u0 * u0 - 1 + 2 * u1 * u1) * x
            + (2 * u1 * u2 - 2 * u0 * u3) * y
            + (2 * u1 * u3 + 2 * u0 * u2) * z,
            (2 * u1 * u2 + 2 * u0 * u3) * x
            + (2 * u0 * u0 - 1 + 2 * u2 * u2) * y
            + (2 * u2 * u3 - 2 * u0 * u1) * z,
            (2 * u1 * u3 - 2 * u0 * u2) * x
            + (2 * u2 * u3 + 2 * u0 * u1) * y
            + (2 * u0 * u0 - 1 + 2 * u3 * u3) * z,
        ],
        axis=-1,
    )


def _cross(xp, a, b):
    return xp.stack(
        [
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ],
        axis=-1,
    )


@dataclass(frozen=True)
class StageConstants:
    """The numbers a stage needs beyond the engine and the controller (numpy, float64; cast by
    :meth:`arrays`).

    Attributes:
        a (3,), d (3,): the rod's axis and offset, body axes (m); m (n,): the masses, kg;
        mu0: their sum, kg; m_T: the total mass, kg (the moment of a force at C about the system
        centre of mass, :mod:`analytic.aux_rates`).
        P_tau (3, nu), P_rod (n, nu): ``ctrl = τ P_tau + F P_rod`` (entries ``INV_GEAR`` at the
        actuators ``torque_x..z`` and ``force1..N`` of the C plant's twin, zero elsewhere: each
        ``ctrl`` is one product, exactly the C plant's ``torque * INV_GEAR``).
    """

    a: np.ndarray
    d: np.ndarray
    m: np.ndarray
    mu0: float
    m_T: float
    P_tau: np.ndarray
    P_rod: np.ndarray

    @classmethod
    def of(cls, scene: Scene, tm: TwinModel) -> StageConstants:
        """The constants of ``scene``'s twin ``tm`` (the C plant's actuator ids)."""
        n, nu = scene.n, tm.m.nu
        P_tau = np.zeros((3, nu))
        P_rod = np.zeros((n, nu))
        if tm.torque_ids is not None:
            P_tau[np.arange(3), tm.torque_ids] = INV_GEAR
        if tm.force_ids is not None:
            P_rod[np.arange(n), tm.force_ids] = INV_GEAR
        m = np.asarray(scene.masses.mass, float)
        mu0 = float(np.sum(m))
        return cls(
            a=np.asarray(scene.rod.axis, float),
            d=np.asarray(scene.rod.offset, float),
            m=m,
            mu0=mu0,
            m_T=float(scene.body.mass) + mu0,
            P_tau=P_tau,
            P_rod=P_rod,
        )

    def arrays(self, xp, dtype) -> dict[str, Any]:
        """The constants as ``xp`` arrays of ``dtype`` (a pytree of arrays for JAX)."""
        return {
            k: xp.asarray(getattr(self, k), dtype=dtype)
            for k in ("a", "d", "m", "mu0", "m_T", "P_tau", "P_rod")
        }


def quadrature_rates(xp, c: dict, q, qdot, omega, tau, rod, fC):
    """``[Ẇ, İ_L (3), İ_P (3)]`` (..., 7) at a stage, as the C plant's stage sums them
    (:meth:`mj_bridge.stages.Stages.finish`): ``Ẇ = τ·ω + F·ṗ + F_C·Ṙ`` (τ the control plus
    the given torque, body axes), ``İ_L = S(u)τ + (R − c)×F_C`` with ``R − c = −(μ1 S a + μ0 S d)
    / m_T``, ``İ_P = F_C``. ``c``: :meth:`StageConstants.arrays`."""
    power = (xp.sum(tau * omega, axis=-1) + xp.sum(rod * qdot[..., 7:], axis=-1)) + xp.sum(
        fC * qdot[..., :3], axis=-1
    )
    u = q[..., 3:7]
    mu1 = xp.sum(c["m"] * q[..., 7:], axis=-1)
    Sa = _rotate(xp, u, c["a"])
    Sd = _rotate(xp, u, c["d"])
    R_minus_c = -(mu1[..., None] * Sa + c["mu0"] * Sd) / c["m_T"]
    moment = _rotate(xp, u, tau) + _cross(xp, R_minus_c, fC)
    return xp.concatenate([power[..., None], moment, fC], axis=-1)


Control = Callable[[Any, Any, Any], tuple[Any, Any, Any]]
"""``control(t, q, q̇) -> (τ (..., 3), F (..., n), F_C (..., 3))``: what the controller applies
at a paper state (zeros for an uncontrolled scene; the given torque not included)."""

Forward = Callable[[Any, Any, Any, Any, Any], Any]
"""``forward(t, qpos, qvel, ctrl, force_at_C) -> qacc``: the engine's forward dynamics with those
actuator controls and that inertial force at C on BR (its ``xfrc_applied[BR, :3]``)."""


def controlled_stage(xp, forward: Forward, control: Control, given, c: dict) -> Stage:
    """The stage of an accelerated plant (module docstring): ``given(t) -> τ_g (..., 3)`` the
    given torque (zeros when that effect is off), ``c`` :meth:`StageConstants.arrays`."""

    def stage(t, qpos, qvel):
        q, qdot = paper_state(xp, qpos, qvel)
        tau, rod, fC = control(t, q, qdot)
        tau_tot = tau + given(t)
        ctrl = tau_tot @ c["P_tau"] + rod @ c["P_rod"]
        qacc = forward(t, qpos, qvel, ctrl, fC)
        return qacc, quadrature_rates(xp, c, q, qdot, qvel[..., 3:6], tau_tot, rod, fC)

    return stage


__all__ = [
    "MJ_MINVAL",
    "RK4_A",
    "RK4_B",
    "RK4_C",
    "Control",
    "Forward",
    "Stage",
    "StageConstants",
    "controlled_stage",
    "dexpinv",
    "integrate_pos",
    "paper_state",
    "quadrature_rates",
    "quat_integrate",
    "rk4_step",
]
