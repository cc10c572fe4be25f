"""State maps between the paper's coordinates and a free-floating MuJoCo body, pure numpy.

Paper (Eq. 44): ``q = [R, u, p]``, ``q̇ = [Ṙ, u̇, ṗ]`` with R the centre of mass C of BR (inertial, m),
u the w-first quaternion of BR's principal axes (body -> inertial) and ``ω = H(u) u̇`` in body axes.

MuJoCo (free joint + slides): ``qpos = [x_b, q_b, p]``, ``qvel = [v_b, ω_b, ṗ]`` with x_b, q_b the
pose of BR's *body frame*, v_b the world velocity of its origin and ω_b the angular velocity in the
body frame. The inertial frame (C, principal axes) sits at ``ipos`` with orientation ``iquat`` in
the body frame (``model.body_ipos``, ``model.body_iquat``), so these maps are right also when the
body frame is not at C.

Relations (with ``r = R_b ipos`` the world vector from the body origin to C, ``R_I = Rot(iquat)``):
``u = q_b ⊗ iquat``, ``R = x_b + r``, ``ω = R_Iᵀ ω_b``, ``Ṙ = v_b + ω_w × r``,
``R̈ = a_b + α_w × r + ω_w × (ω_w × r)``, ``u̇ = ¼ Hᵀ ω``, ``ü = ¼ (H(u̇)ᵀ ω + Hᵀ ω̇)`` (unit u).
"""

from __future__ import annotations

import numpy as np

from analytic.kinematics import H, omega_of
from model_xml.rotations import cross3, quat_conj, quat_mul, quat_to_mat


def paper_to_mujoco_state(
    q: np.ndarray, qdot: np.ndarray, ipos: np.ndarray, iquat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(q, q̇)`` (n+7 each) -> ``(qpos (n+7), qvel (n+6))``. u is normalised (MuJoCo's
    quaternions are unit); ω is ``H(u) u̇`` evaluated at the given, possibly non-unit, u."""
    q = np.asarray(q, float)
    qdot = np.asarray(qdot, float)
    u_raw = q[3:7]
    u = u_raw / np.linalg.norm(u_raw)
    omega = omega_of(u_raw, qdot[3:7])
    q_b = quat_mul(u, quat_conj(iquat))
    Rb = quat_to_mat(q_b)
    r = Rb @ ipos
    omega_b = quat_to_mat(iquat) @ omega
    omega_w = Rb @ omega_b
    qpos = np.concatenate([q[:3] - r, q_b, q[7:]])
    qvel = np.concatenate([qdot[:3] - cross3(omega_w, r), omega_b, qdot[7:]])
    return qpos, qvel


def mujoco_to_paper_state(
    qpos: np.ndarray, qvel: np.ndarray, ipos: np.ndarray, iquat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(qpos, qvel)`` -> ``(q, q̇)`` in the paper's coordinates (u̇ = ¼Hᵀω)."""
    qpos = np.asarray(qpos, float)
    qvel = np.asarray(qvel, float)
    q_b = qpos[3:7]
    u = quat_mul(q_b, iquat)
    Rb = quat_to_mat(q_b)
    r = Rb @ ipos
    omega_b = qvel[3:6]
    omega = quat_to_mat(iquat).T @ omega_b
    omega_w = Rb @ omega_b
    udot = 0.25 * H(u).T @ omega / float(u @ u)
    q = np.concatenate([qpos[:3] + r, u, qpos[7:]])
    qdot = np.concatenate([qvel[:3] + cross3(omega_w, r), udot, qvel[6:]])
    return q, qdot


def mujoco_to_paper_acc(
    qpos: np.ndarray,
    qvel: np.ndarray,
    qacc: np.ndarray,
    ipos: np.ndarray,
    iquat: np.ndarray,
) -> np.ndarray:
    """MuJoCo's ``qacc`` (n+6) at ``(qpos, qvel)`` -> the paper's ``q̈`` (n+7)."""
    q, qdot = mujoco_to_paper_state(qpos, qvel, ipos, iquat)
    u, udot = q[3:7], qdot[3:7]
    Rb = quat_to_mat(qpos[3:7])
    RI = quat_to_mat(iquat)
    r = Rb @ ipos
    omega_b = qvel[3:6]
    omega_w = Rb @ omega_b
    alpha_w = Rb @ qacc[3:6]
    omega = RI.T @ omega_b
    omega_dot = RI.T @ qacc[3:6]
    Rdd = qacc[:3] + cross3(alpha_w, r) + cross3(omega_w, cross3(omega_w, r))
    udd = 0.25 * (H(udot).T @ omega + H(u).T @ omega_dot)
    return np.concatenate([Rdd, udd, qacc[6:]])


def _quat_mul_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton product of (N, 4) quaternions with one (4,) or (N, 4), w first."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(np.broadcast_to(b, a.shape), -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def _mat_rows(q: np.ndarray) -> np.ndarray:
    """Rotation matrices of (N, 4) quaternions (normalised first), shape (N, 3, 3)."""
    w, x, y, z = np.moveaxis(q / np.linalg.norm(q, axis=-1, keepdims=True), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def _Ht_rows(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``H(u)ᵀ w`` row-wise (Eq. 13), (N, 4) and (N, 3) -> (N, 4)."""
    u0, u1, u2, u3 = np.moveaxis(u, -1, 0)
    w0, w1, w2 = np.moveaxis(w, -1, 0)
    return 2.0 * np.stack(
        [
            -u1 * w0 - u2 * w1 - u3 * w2,
            u0 * w0 - u3 * w1 + u2 * w2,
            u3 * w0 + u0 * w1 - u1 * w2,
            -u2 * w0 + u1 * w1 + u0 * w2,
        ],
        axis=-1,
    )


def mujoco_to_paper_batch(
    qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray, ipos: np.ndarray, iquat: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`mujoco_to_paper_state` and :func:`mujoco_to_paper_acc` for N samples at once.

    Args:
        qpos (N, n+7), qvel (N, n+6), qacc (N, n+6): MuJoCo's state and acceleration per sample.
        ipos (3,), iquat (4,): BR's inertial frame in its MuJoCo body frame.

    Returns:
        ``(q, q̇, q̈)`` (N, n+7 each) in the paper's coordinates and ω (N, 3), body axes, rad/s.
    """
    qpos, qvel, qacc = (np.atleast_2d(np.asarray(x, float)) for x in (qpos, qvel, qacc))
    iquat = np.asarray(iquat, float)
    q_b = qpos[:, 3:7]
    u = _quat_mul_rows(q_b, iquat)
    Rb = _mat_rows(q_b)
    RI = quat_to_mat(iquat)
    r = Rb @ np.asarray(ipos, float)
    omega_b = qvel[:, 3:6]
    omega = omega_b @ RI  # R_Iᵀ ω_b, row-wise
    omega_w = np.einsum("nij,nj->ni", Rb, omega_b)
    udot = 0.25 * _Ht_rows(u, omega) / np.sum(u * u, axis=1)[:, None]
    q = np.concatenate([qpos[:, :3] + r, u, qpos[:, 7:]], axis=1)
    qdot = np.concatenate([qvel[:, :3] + np.cross(omega_w, r), udot, qvel[:, 6:]], axis=1)
    alpha_w = np.einsum("nij,nj->ni", Rb, qacc[:, 3:6])
    omega_dot = qacc[:, 3:6] @ RI
    Rdd = qacc[:, :3] + np.cross(alpha_w, r) + np.cross(omega_w, np.cross(omega_w, r))
    udd = 0.25 * (_Ht_rows(udot, omega) + _Ht_rows(u, omega_dot))
    return q, qdot, np.concatenate([Rdd, udd, qacc[:, 6:]], axis=1), omega


def paper_to_frame_state(
    q: np.ndarray, qdot: np.ndarray, frame_pos: np.ndarray, frame_quat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """As :func:`paper_to_mujoco_state` for a body frame given by its pose in the paper's body
    frame (:class:`model_xml.builder.BodyFrame`): ``ipos = -Rot(quat)ᵀ pos``, ``iquat = quat*``."""
    frame_quat = np.asarray(frame_quat, float)
    ipos = -quat_to_mat(frame_quat).T @ np.asarray(frame_pos, float)
    return paper_to_mujoco_state(q, qdot, ipos, quat_conj(frame_quat))
