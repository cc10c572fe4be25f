"""One :class:`~analytic.trajectory.Trajectory` from a plant's samples, the same for every plant.

A plant (analytic, MuJoCo, Pinocchio) samples its run on the output grid, maps the samples to the
paper's coordinates ``q = [R, u, p]`` (Eq. 44), evaluates the controller's output at each sample and
keeps the quadratures it integrated along with the motion; :func:`assemble` turns these into the
record: the control outputs as arrays, the invariants and their balances
(:func:`analytic.invariants.compute_invariants`) and the tracking errors
(:func:`analytic.invariants.tracking_errors`, Eqs. 77 and 82).

Quadratures, per sample (:func:`aux_count` columns, integrals since t = 0 with the rates of
:mod:`analytic.aux_rates`): ``[W (J), I_L (3, inertial, N·m·s), I_P (3, inertial, N·s)]``, the work
of the control and given torque, the angular impulse of the external moments about the system
centre of mass and the impulse of a force at C; then, only when a dissipative effect is on,
``D`` (J, column :data:`AUX_D`), the energy it took out of the motion (rate
:func:`analytic.model.dissipated_power`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from analytic.invariants import compute_invariants, dissipated_from_samples, tracking_errors
from analytic.kinematics import omega_of
from analytic.model import ControlOutput, TumblingModel, dissipates
from analytic.trajectory import RunStatus, Trajectory

N_AUX = 7
"""Quadratures every run integrates along with the motion: ``W``, ``I_L`` (3), ``I_P`` (3)."""

AUX_D = N_AUX
"""The column of ``D`` when a dissipative effect is on."""


def aux_count(model: TumblingModel) -> int:
    """How many quadratures a run of ``model`` integrates: :data:`N_AUX`, plus ``D`` when a
    dissipative effect is on (so a scene without one integrates exactly what it did before)."""
    return N_AUX + (1 if dissipates(model) else 0)


def assemble(
    model: TumblingModel,
    engine: str,
    t: np.ndarray,
    q: np.ndarray,
    qdot: np.ndarray,
    qddot: np.ndarray,
    controls: Sequence[ControlOutput | None],
    quadratures: np.ndarray,
    status: RunStatus,
    message: str,
    info: dict[str, Any],
    omega: np.ndarray | None = None,
) -> Trajectory:
    """The trajectory of N samples of one run.

    Args:
        model: the scene's model (constants, requirements of the controller).
        engine: the name of the plant that ran.
        t: sample times, s, shape (N,).
        q, qdot, qddot: the samples in the paper's coordinates (Eq. 44), shape (N, n+7) each.
        controls: the controller's output at each sample (N entries), None where there is none
            (uncontrolled, or not evaluated): zeros then.
        quadratures: ``[W, I_L, I_P(, D)]`` per sample, shape (N, aux_count(model)) (module
            docstring); a plant that does not integrate ``D`` along its motion gives the first
            :data:`N_AUX` and ``D`` is integrated over its samples
            (:func:`analytic.invariants.dissipated_from_samples`).
        status, message, info: how the run ended and the plant's metadata.
        omega: body-axis angular velocity per sample, rad/s, shape (N, 3), as the plant has it;
            default ``H(u) u̇`` (Eq. 12).

    Returns:
        the :class:`Trajectory`, invariants and tracking errors computed from the samples.
    """
    N = len(t)
    n = model.n
    QC = np.zeros((N, n + 7))
    torque = np.zeros((N, 3))
    rod = np.zeros((N, n))
    fC = np.zeros((N, 3))
    res = np.zeros(N)
    for i, c in enumerate(controls):
        if c is not None:
            QC[i], torque[i], rod[i], fC[i] = c.QC, c.torque, c.rod_forces, c.force_at_C
            res[i] = float(np.linalg.norm(c.residual))
    if omega is None:
        omega = omega_of(q[:, 3:7], qdot[:, 3:7])
    quadratures = np.asarray(quadratures, dtype=float).reshape(N, -1)
    if quadratures.shape[1] not in (N_AUX, aux_count(model)):
        raise ValueError(
            f"quadratures: {quadratures.shape[1]} columns, expected {aux_count(model)}"
        )
    dissipated = None
    if dissipates(model):
        dissipated = (
            np.ascontiguousarray(quadratures[:, AUX_D])
            if quadratures.shape[1] > AUX_D
            else dissipated_from_samples(model, t, q[:, 7:], qdot[:, 7:], qddot[:, 7:])
        )
    invariants = compute_invariants(
        model,
        t,
        q,
        qdot,
        np.ascontiguousarray(quadratures[:, 0]),
        np.ascontiguousarray(quadratures[:, 1:4]),
        np.ascontiguousarray(quadratures[:, 4:7]),
        dissipated,
    )
    return Trajectory(
        engine=engine,
        scene=model.scene.name,
        t=t,
        q=q,
        qdot=qdot,
        qddot=qddot,
        QC=QC,
        torque=torque,
        rod_forces=rod,
        force_at_C=fC,
        residual_norm=res,
        invariants=invariants,
        tracking=tracking_errors(model, t, q, omega),
        status=status,
        message=message,
        info=info,
    )


__all__ = ["AUX_D", "N_AUX", "assemble", "aux_count"]
