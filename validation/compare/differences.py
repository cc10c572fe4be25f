"""What is compared between two plants, as numbers: each difference quantity per shared sample, and
the magnitude its bound's relative part scales by.

The quantities (:class:`Difference`, in report order), each a scalar per sample on the samples the
two runs share (:func:`common_samples`): position of C ``|R_a - R_b|`` (m, inertial); attitude, the
angle of the relative quaternion ``conj(u_a) ⊗ u_b``, ``2·atan2(|vec|, |w|)`` (rad, so q and -q
are the same attitude; :func:`attitude_angle`); rod positions ``max_i |p_a,i - p_b,i|`` (m);
velocity of C (m/s); rod velocities (m/s); body angular velocity ``|ω_a - ω_b|`` (rad/s, body
axes); control torque ``|τ_a - τ_b|`` (N·m, body axes); rod forces ``max_i |F_a,i - F_b,i|`` (N).
Quaternions are w first.

The magnitudes (:data:`MAGNITUDES`): the largest over time and over the two plants of C's
departure from its uniformly accelerated motion (position and velocity of C), ``|p_i|`` (rod
positions), ``|ṗ_i|``, ``|ω|``; non-finite samples are left out (a diverged run's difference is
infinite and fails anyway). A new difference quantity, or a change to one's formula or scale, costs
this module (and its threshold in :mod:`validation.compare.thresholds`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from analytic.effects import Effect
from analytic.trajectory import Trajectory
from validation.compare.reductions import largest, maxabs, norm

# Two sample times are the same sample when they agree to this (s).
TIME_MATCH_TOL = 1e-9


class Difference(StrEnum):
    """The quantities compared between two plants, in report order (the names of their
    thresholds in :mod:`validation.compare.thresholds`); the last two are relative to the reference
    plant's largest control force, ``rod_forces`` only with masses."""

    POSITION_C = "position_C"
    ATTITUDE = "attitude"
    ROD_POSITIONS = "rod_positions"
    VELOCITY_C = "velocity_C"
    ROD_VELOCITIES = "rod_velocities"
    ANGULAR_VELOCITY = "angular_velocity"
    CONTROL_TORQUE = "control_torque"
    ROD_FORCES = "rod_forces"


@dataclass(frozen=True)
class DifferenceValues:
    """One difference quantity of two runs on their shared samples.

    Attributes:
        quantity: which one.
        label: what it is, for people.
        unit: SI unit.
        values: shape (k,), k the number of shared samples.
    """

    quantity: Difference
    label: str
    unit: str
    values: np.ndarray


def attitude_angle(u_a: np.ndarray, u_b: np.ndarray) -> np.ndarray:
    """Angle of the relative rotation between two attitudes, rad, in [0, π].

    ``conj(u_a) ⊗ u_b = (w, vec)`` with ``w = u_a·u_b`` and ``vec = a0 b⃗ - b0 a⃗ - a⃗ × b⃗``; the
    angle is ``2·atan2(|vec|, |w|)``, so q and -q give 0. Quaternions need not be unit (the ratio is
    scale-free). Shapes (N, 4), (N, 4) -> (N,), or (4,), (4,) -> ().
    """
    a = np.asarray(u_a, float)
    b = np.asarray(u_b, float)
    if a.shape != b.shape or a.shape[-1] != 4:
        raise ValueError(f"u_b: shape must equal u_a's (..., 4) = {a.shape} (got {b.shape})")
    w = np.sum(a * b, axis=-1)
    vec = a[..., :1] * b[..., 1:] - b[..., :1] * a[..., 1:] - np.cross(a[..., 1:], b[..., 1:])
    return 2.0 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(w))


def common_samples(a: Trajectory, b: Trajectory) -> int:
    """Number of leading samples the two trajectories share (same times, to
    :data:`TIME_MATCH_TOL`); ``ValueError`` naming ``t`` when they start at different times."""
    n = min(a.t.shape[0], b.t.shape[0])
    if n == 0:
        return 0
    same = np.abs(a.t[:n] - b.t[:n]) <= TIME_MATCH_TOL * np.maximum(1.0, np.abs(a.t[:n]))
    if not same[0]:
        raise ValueError(
            f"t: the two trajectories start at different times ({a.t[0]} vs {b.t[0]} s)"
        )
    return int(np.argmin(same)) if not same.all() else n


def differences(a: Trajectory, b: Trajectory) -> tuple[np.ndarray, tuple[DifferenceValues, ...]]:
    """The shared sample times (s, shape (k,)) and every :class:`Difference` of ``a`` and ``b`` on
    them, in report order (module docstring). ``ValueError`` naming ``q`` for runs with different
    numbers of masses."""
    if a.n != b.n:
        raise ValueError(f"q: the trajectories have different numbers of masses ({a.n} vs {b.n})")
    k = common_samples(a, b)
    qa, qb, va, vb = a.q[:k], b.q[:k], a.qdot[:k], b.qdot[:k]
    D = Difference
    rows = (
        (D.POSITION_C, "position of C |R_a − R_m|", "m", norm(qa[:, :3] - qb[:, :3])),
        (
            D.ATTITUDE,
            "attitude angle of conj(u_a)⊗u_m",
            "rad",
            attitude_angle(qa[:, 3:7], qb[:, 3:7]),
        ),
        (D.ROD_POSITIONS, "rod positions max_i |p_a − p_m|", "m", maxabs(qa[:, 7:] - qb[:, 7:])),
        (D.VELOCITY_C, "velocity of C |Ṙ_a − Ṙ_m|", "m/s", norm(va[:, :3] - vb[:, :3])),
        (
            D.ROD_VELOCITIES,
            "rod velocities max_i |ṗ_a − ṗ_m|",
            "m/s",
            maxabs(va[:, 7:] - vb[:, 7:]),
        ),
        (
            D.ANGULAR_VELOCITY,
            "body angular velocity |ω_a − ω_m|",
            "rad/s",
            norm(a.omega[:k] - b.omega[:k]),
        ),
        (D.CONTROL_TORQUE, "control torque |τ_a − τ_m|", "N·m", norm(a.torque[:k] - b.torque[:k])),
        (
            D.ROD_FORCES,
            "rod forces max_i |F_a − F_m|",
            "N",
            maxabs(a.rod_forces[:k] - b.rod_forces[:k]),
        ),
    )
    return a.t[:k], tuple(DifferenceValues(*row) for row in rows)


def _departure(tr: Trajectory, k: int, g: np.ndarray, velocity: bool) -> float:
    """The largest departure of C's motion over the first ``k`` samples from the uniformly
    accelerated one its first sample and gravity ``g`` (inertial, m/s², zeros without the effect)
    give: ``|R - (R(0) + Ṙ(0) t + ½ g t²)|`` (m), or ``|Ṙ - (Ṙ(0) + g t)|`` (m/s) for
    ``velocity``. The uniformly accelerated part is a polynomial of degree two that both kinds of
    integrator (Runge-Kutta methods of order 4 and 8) reproduce to round-off, so it is not a scale
    of their error, however far it carries C."""
    k = min(k, tr.t.shape[0])
    if k == 0:
        return 0.0
    t = (tr.t[:k] - tr.t[0])[:, None]
    R, V = tr.q[:k, :3], tr.qdot[:k, :3]
    if velocity:
        return largest(V - (V[0] + g * t), True)
    return largest(R - (R[0] + V[0] * t + 0.5 * g * t * t), True)


MAGNITUDES: Mapping[str, Any] = {
    "position_C": lambda tr, k, g: _departure(tr, k, g, False),  # m
    "rod_positions": lambda tr, k, g: largest(tr.q[:k, 7:], False),  # |p_i|, m
    "velocity_C": lambda tr, k, g: _departure(tr, k, g, True),  # m/s
    "rod_velocities": lambda tr, k, g: largest(tr.qdot[:k, 7:], False),  # |ṗ_i|, m/s
    "angular_velocity": lambda tr, k, g: largest(tr.omega[:k], True),  # |ω|, rad/s (body axes)
}
"""Difference quantity -> ``(trajectory, k, g) -> its largest magnitude over the first k
samples``, in the quantity's unit: the scale of its bound's relative part (the pair's is the
larger of the two plants'). For C, its departure from the uniformly accelerated motion
(:func:`_departure`); for the others, their own magnitude. The attitude has none
(:data:`validation.compare.thresholds.SCALED`)."""


def scene_gravity(scene: Any) -> np.ndarray:
    """The scene's gravity vector (inertial, m/s², shape (3,)); zeros without the effect or
    without a scene."""
    if scene is None or not scene.has(Effect.GRAVITY):
        return np.zeros(3)
    return np.asarray(scene.gravity, float)


def pair_magnitude(
    name: str, a: Trajectory, b: Trajectory, k: int | None = None, scene: Any = None
) -> float:
    """The scale of difference ``name``'s relative part for plants ``a`` and ``b``: the largest
    magnitude over their first ``k`` samples (default all) and over the two, in the quantity's
    unit (:data:`MAGNITUDES`; ``scene`` gives C's gravity); 0 for a quantity without one."""
    of = MAGNITUDES.get(name)
    if of is None:
        return 0.0
    if k is None:
        k = min(a.t.shape[0], b.t.shape[0])
    g = scene_gravity(scene)
    return max(of(a, k, g), of(b, k, g))


__all__ = [
    "MAGNITUDES",
    "TIME_MATCH_TOL",
    "Difference",
    "DifferenceValues",
    "attitude_angle",
    "common_samples",
    "differences",
    "pair_magnitude",
    "scene_gravity",
]
