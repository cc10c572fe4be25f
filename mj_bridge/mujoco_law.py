"""The control law computed a second way: Gauss's principle (Udwadia–Kalaba) in MuJoCo's own
coordinates, from MuJoCo's mass matrix and forces at the state in ``MjData``.

``M qacc = F + Aᵀμ`` with ``A qacc = b``: ``M`` from ``mj_fullM``, ``F = qfrc_passive − qfrc_bias``
(+ the spring actuators, + the given torque of Remark 2), A the tracked rows (ω̇ components on the
free joint's rotational dofs, q̈ of the tracked slide joints) and b the paper's stabilised
requirements (Eqs. 81, 84) at MuJoCo's state. MuJoCo's coordinates have no quaternion constraint,
so only Gauss's weighting ``M⁻¹`` (coordinate-invariant) is the paper's law here.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from analytic.effects import Weighting
from analytic.model import TumblingModel
from mj_bridge.twin_model import TwinModel


@dataclass(frozen=True)
class MjControl:
    """The control law evaluated from MuJoCo's matrices at one state.

    Attributes:
        torque: body-axis control torque, N·m, shape (3,).
        rod_forces: force along the rod on each mass, N, shape (n,).
        qacc: MuJoCo's controlled acceleration (MuJoCo coordinates), shape (n+6,).
        residual: ``A qacc - b``, the unattainable part of the requirements, shape (k,).
    """

    torque: np.ndarray
    rod_forces: np.ndarray
    qacc: np.ndarray
    residual: np.ndarray


def check_weighting(model: TumblingModel) -> None:
    """ValueError naming ``control.weighting`` unless the scene's weighting is Gauss's ``M⁻¹``."""
    weighting = model.scene.control.weighting
    if weighting is not Weighting.M_INV:
        raise ValueError(
            "control.weighting: the MuJoCo-coordinate Udwadia–Kalaba law is implemented for "
            f"Gauss's weighting M^-1 only, which is coordinate-invariant (got {weighting.value!r})"
        )


def mujoco_law(
    tm: TwinModel,
    model: TumblingModel,
    d: mujoco.MjData,
    t: float,
    in_callback: bool,
    M: np.ndarray | None = None,
) -> MjControl:
    """The law at the state in ``d`` (after ``mj_forward``, or inside ``mjcb_control``).

    Args:
        tm: the compiled twin; model: the scene's analytic model (requirements, given torque).
        d: MuJoCo's data at time ``t``, s.
        in_callback: called from ``mjcb_control``, where ``qfrc_actuator`` is not computed yet
            (the spring actuators' forces are then computed here, with every ctrl zero).
        M: a (nv, nv) buffer for ``mj_fullM`` (allocated when None).
    """
    m = tm.m
    nv = m.nv
    if M is None:
        M = np.zeros((nv, nv))
    mujoco.mj_fullM(m, d, M)
    F = d.qfrc_passive - d.qfrc_bias
    if len(tm.spring_act_ids):
        if in_callback:  # qfrc_actuator is computed after mjcb_control: springs only here
            d.ctrl[:] = 0.0
            mujoco.mj_fwdActuation(m, d)
        F = F + d.qfrc_actuator
    tau_g = model.given_torque(t)
    F = F.copy()
    F[3:6] += tm.R_I @ tau_g
    req = model.requirements(t)
    rows, rhs = [], []
    omega = tm.R_I.T @ d.qvel[3:6]
    if model.omega_track:
        c = model._w_comps
        gain = model.omega_track.gain
        e = omega[c] - req["omega_bar"]
        b_w = req["omega_bar_dot"] - gain @ e  # Eq. (84) / (B8)
        for j, comp in enumerate(c):
            row = np.zeros(nv)
            row[3:6] = tm.R_I.T[comp]  # ω̇_comp = (R_Iᵀ qacc[3:6])_comp
            rows.append(row)
            rhs.append(b_w[j])
    if model.mass_track:
        mt = model.mass_track
        idx = model._p_idx
        p, pd = d.qpos[7 + idx], d.qvel[6 + idx]
        b_p = (
            req["p_bar_ddot"] - mt.alpha * (pd - req["p_bar_dot"]) - mt.beta * (p - req["p_bar"])
        )  # Eq. (81)
        for j, i in enumerate(idx):
            row = np.zeros(nv)
            row[6 + i] = 1.0
            rows.append(row)
            rhs.append(b_p[j])
    A = np.array(rows).reshape(len(rows), nv)
    b = np.array(rhs)
    # M⁻¹ [F, Aᵀ] from MuJoCo's dense mass matrix (mj_fullM), symmetric positive definite
    from scipy.linalg import cho_factor, cho_solve  # here: 0.4 s of import, off the start-up

    Y = cho_solve(cho_factor(M), np.column_stack([F, A.T]))
    a0, MinvAt = Y[:, 0], Y[:, 1:]
    G = A @ MinvAt
    mu = np.linalg.lstsq(0.5 * (G + G.T), b - A @ a0, rcond=None)[0]
    Qc = A.T @ mu
    qacc = a0 + MinvAt @ mu
    return MjControl(
        torque=tm.R_I.T @ Qc[3:6],
        rod_forces=Qc[6:].copy(),
        qacc=qacc,
        residual=A @ qacc - b,
    )


__all__ = ["MjControl", "check_weighting", "mujoco_law"]
