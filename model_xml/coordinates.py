"""The maps between the paper's coordinates and each engine's state and accelerations, batched numpy.

Every map takes one sample (1-D arrays) or N samples (2-D arrays, one row per sample; shapes below
are written for N) and returns the same. The compiled stages that map one state inside an integrator stage
(:mod:`mj_bridge.fast_stage`, :mod:`mj_bridge.pinocchio_plant`) are tested against these.

Paper (Eq. 44): ``q = [R, u, p]``, ``q̇ = [Ṙ, u̇, ṗ]`` (n + 7 each) with R the centre of mass C of BR
(inertial, m), u the w-first quaternion of BR's principal axes (body -> inertial), ``ω = H(u) u̇``
(Eqs. 12-13) in body axes, ``S = S(u)`` of Eq. (11).

**MuJoCo** (free joint + n slides; :mod:`model_xml.builder`): ``qpos = [x_b, q_b, p]`` (n + 7),
``qvel = [v_b, ω_b, ṗ]``, ``qacc = [a_b, ω̇_b, p̈]`` (n + 6) with x_b, q_b the pose of BR's *body
frame*, v_b the inertial velocity of its origin and ω_b the angular velocity in the body frame. The
inertial frame (C, principal axes) sits at ``ipos`` with orientation ``iquat`` in the body frame
(``MjModel.body_ipos``, ``body_iquat``; zero and identity unless a :class:`model_xml.BodyFrame`
moves the body frame). With ``r = R_b ipos`` (inertial, from the body origin to C) and
``R_I = Rot(iquat)``:

* ``u = q_b ⊗ iquat``, ``R = x_b + r``, ``ω = R_Iᵀ ω_b``, ``Ṙ = v_b + ω_w × r`` (``ω_w = R_b ω_b``);
* ``u̇ = H(u)ᵀ ω / (4|u|²)`` (``¼ Hᵀ ω`` for unit u), ``ü = ¼ (H(u̇)ᵀ ω + H(u)ᵀ ω̇)``;
* ``R̈ = a_b + α_w × r + ω_w × (ω_w × r)`` (``α_w = R_b ω̇_b``).

**Pinocchio** (free flyer at C + n prismatic joints; :mod:`mj_bridge.pinocchio_model`):
``q_pin = [R, qx, qy, qz, qw, p]`` (n + 7: the quaternion **scalar last**), ``v_pin = [v, ω, ṗ]``
(n + 6), the free flyer's twist in its **local** frame: ``v = Sᵀ Ṙ`` (body axes, m/s) and ω the
body-axis angular velocity; ``a_pin = v̇_pin`` (what ``pin.aba`` returns): ``R̈ = S (v̇ + ω × v)``.
The Pinocchio plant integrates ``x = [q_pin, Ṙ, ω, ṗ]`` (2n + 13): Pinocchio's configuration and
its velocity with the linear part in the inertial frame (:mod:`mj_bridge.pinocchio_plant` says
why); that velocity is MuJoCo's ``qvel`` for a body frame at C.

Every product is taken per sample (rotations times vectors as a stacked ``matmul`` or an ``einsum``
over the samples), so a batch gives each sample exactly, to the last bit, what it gives alone. With BR's body frame at C the
frame terms are skipped (they are exact zeros and identities there).
"""

from __future__ import annotations

import numpy as np

from analytic.kinematics import S, S_batch, omega_of
from model_xml.rotations import quat_conj, quat_to_mat

IPOS_AT_C = np.zeros(3)
"""``ipos`` of a body frame at C, m."""
IQUAT_AT_C = np.array([1.0, 0.0, 0.0, 0.0])
"""``iquat`` of a body frame along the principal axes (w first)."""


# ----------------------------------------------------------------------------------------------
# Row-wise quaternion algebra
# ----------------------------------------------------------------------------------------------


def _rows(*arrays: np.ndarray) -> tuple[bool, list[np.ndarray]]:
    """``(single, arrays as (N, k) float)``: single when the first array is 1-D."""
    single = np.ndim(arrays[0]) == 1
    return single, [np.atleast_2d(np.asarray(a, dtype=float)) for a in arrays]


def _out(single: bool, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    return tuple(a[0] for a in arrays) if single else arrays


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``A x`` per sample: A (3, 3) or (N, 3, 3), x (N, 3) -> (N, 3)."""
    return (A @ x[:, :, None])[:, :, 0]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` row-wise, (N, 3) each (the arithmetic of ``np.cross``, without its overhead)."""
    a0, a1, a2 = a.T
    b0, b1, b2 = b.T
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[:, 0] = a1 * b2 - a2 * b1
    out[:, 1] = a2 * b0 - a0 * b2
    out[:, 2] = a0 * b1 - a1 * b0
    return out


def quat_mul_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a ⊗ b`` row-wise (w first): a (N, 4), b (4,) or (N, 4) -> (N, 4)."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = np.asarray(b).T
    out = np.empty(a.shape)
    out[:, 0] = aw * bw - ax * bx - ay * by - az * bz
    out[:, 1] = aw * bx + ax * bw + ay * bz - az * by
    out[:, 2] = aw * by - ax * bz + ay * bw + az * bx
    out[:, 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


def rotation_rows(q: np.ndarray) -> np.ndarray:
    """Rotation matrices of (N, 4) w-first quaternions, normalised first, shape (N, 3, 3): the
    project's one numpy ``S(u)`` (:func:`analytic.kinematics.S`, Eq. 11) of the unit quaternions."""
    return S(q / np.linalg.norm(q, axis=-1, keepdims=True))


# ½ H(u)ᵀ w (Eq. 13) = [-u1 w0 - u2 w1 - u3 w2, u0 w0 - u3 w1 + u2 w2, u3 w0 + u0 w1 - u1 w2,
# -u2 w0 + u1 w1 + u0 w2]: for each w_j a signed permutation of u, summed in the order j = 0, 1, 2.
_HT_INDEX = np.array([1, 0, 3, 2, 2, 3, 0, 1, 3, 2, 1, 0])
_HT_SIGN = np.array([-1.0, 1, 1, -1, -1, -1, 1, 1, -1, 1, -1, 1])


def _half_Ht(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``½ H(u)ᵀ w`` row-wise, (N, 4) and (N, 3) -> (N, 4)."""
    T = (u[:, _HT_INDEX] * _HT_SIGN).reshape(-1, 3, 4)
    T *= w[:, :, None]
    return np.add.reduce(T, axis=1)


# ----------------------------------------------------------------------------------------------
# Paper <-> MuJoCo
# ----------------------------------------------------------------------------------------------


def _at_c(ipos: np.ndarray, iquat: np.ndarray) -> bool:
    """Whether the body frame is the inertial frame (``ipos = 0``, ``iquat = 1``): then ``r = 0``,
    ``R_b = S(u)``, ``R_I = I`` and the frame terms of the maps vanish exactly."""
    return ipos.tolist() == [0.0, 0.0, 0.0] and iquat.tolist() == [1.0, 0.0, 0.0, 0.0]


def paper_to_mujoco_state(
    q: np.ndarray,
    qdot: np.ndarray,
    ipos: np.ndarray = IPOS_AT_C,
    iquat: np.ndarray = IQUAT_AT_C,
) -> tuple[np.ndarray, np.ndarray]:
    """Paper ``(q, q̇)`` ((N, n+7) each) -> MuJoCo ``(qpos (N, n+7), qvel (N, n+6))``.

    u is normalised (MuJoCo's quaternions are unit); ω is ``H(u) u̇`` evaluated at the given,
    possibly non-unit, u. ``ipos`` (3,), m, and ``iquat`` (4,): BR's inertial frame in its body
    frame.
    """
    single, (q, qdot) = _rows(q, qdot)
    ipos = np.asarray(ipos, dtype=float)
    iquat = np.asarray(iquat, dtype=float)
    u_raw = q[:, 3:7]
    u = u_raw / np.linalg.norm(u_raw, axis=-1, keepdims=True)
    omega = omega_of(u_raw, qdot[:, 3:7])
    if _at_c(ipos, iquat):
        qpos = np.concatenate([q[:, :3], u, q[:, 7:]], axis=1)
        qvel = np.concatenate([qdot[:, :3], omega, qdot[:, 7:]], axis=1)
        return _out(single, qpos, qvel)
    q_b = quat_mul_rows(u, quat_conj(iquat))
    Rb = rotation_rows(q_b)
    r = Rb @ ipos
    omega_b = _mv(quat_to_mat(iquat), omega)
    omega_w = _mv(Rb, omega_b)
    qpos = np.concatenate([q[:, :3] - r, q_b, q[:, 7:]], axis=1)
    qvel = np.concatenate([qdot[:, :3] - _cross(omega_w, r), omega_b, qdot[:, 7:]], axis=1)
    return _out(single, qpos, qvel)


def _mujoco_to_paper(qpos, qvel, qacc, ipos, iquat) -> tuple[np.ndarray, ...]:
    """``(q, q̇, ω)`` or, with ``qacc``, ``(q, q̇, q̈, ω)`` of (N, ·) MuJoCo samples."""
    ipos = np.asarray(ipos, dtype=float)
    iquat = np.asarray(iquat, dtype=float)
    at_c = _at_c(ipos, iquat)
    q_b = qpos[:, 3:7]
    omega_b = qvel[:, 3:6]
    if at_c:
        u, omega = q_b, omega_b.copy()
        R, Rdot = qpos[:, :3], qvel[:, :3]
    else:
        u = quat_mul_rows(q_b, iquat)
        Rb = rotation_rows(q_b)
        RIt = quat_to_mat(iquat).T
        r = Rb @ ipos
        omega = _mv(RIt, omega_b)
        omega_w = _mv(Rb, omega_b)
        R, Rdot = qpos[:, :3] + r, qvel[:, :3] + _cross(omega_w, r)
    udot = 0.5 * _half_Ht(u, omega) / np.add.reduce(u * u, axis=1)[:, None]  # ¼ Hᵀω / |u|²
    q = np.concatenate([R, u, qpos[:, 7:]], axis=1)
    qdot = np.concatenate([Rdot, udot, qvel[:, 6:]], axis=1)
    if qacc is None:
        return q, qdot, omega
    if at_c:
        Rdd, omega_dot = qacc[:, :3], qacc[:, 3:6]
    else:
        alpha_w = _mv(Rb, qacc[:, 3:6])
        omega_dot = _mv(RIt, qacc[:, 3:6])
        Rdd = qacc[:, :3] + _cross(alpha_w, r) + _cross(omega_w, _cross(omega_w, r))
    udd = 0.5 * (_half_Ht(udot, omega) + _half_Ht(u, omega_dot))  # ¼ (H(u̇)ᵀω + H(u)ᵀω̇)
    return q, qdot, np.concatenate([Rdd, udd, qacc[:, 6:]], axis=1), omega


def mujoco_to_paper_state(
    qpos: np.ndarray,
    qvel: np.ndarray,
    ipos: np.ndarray = IPOS_AT_C,
    iquat: np.ndarray = IQUAT_AT_C,
) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo ``(qpos (N, n+7), qvel (N, n+6))`` -> paper ``(q, q̇)`` ((N, n+7) each).

    u is MuJoCo's quaternion as given (not renormalised); ``u̇ = H(u)ᵀ ω / (4|u|²)``.
    """
    single, (qpos, qvel) = _rows(qpos, qvel)
    q, qdot, _ = _mujoco_to_paper(qpos, qvel, None, ipos, iquat)
    return _out(single, q, qdot)


def mujoco_to_paper_batch(
    qpos: np.ndarray,
    qvel: np.ndarray,
    qacc: np.ndarray,
    ipos: np.ndarray = IPOS_AT_C,
    iquat: np.ndarray = IQUAT_AT_C,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """MuJoCo's state and acceleration -> the paper's ``(q, q̇, q̈)`` and ω.

    Args:
        qpos (N, n+7), qvel (N, n+6), qacc (N, n+6): MuJoCo's state and ``qacc``.
        ipos (3,), iquat (4,): BR's inertial frame in its MuJoCo body frame.

    Returns:
        ``(q, q̇, q̈)`` ((N, n+7) each) and ω ((N, 3), body axes, rad/s).
    """
    single, (qpos, qvel, qacc) = _rows(qpos, qvel, qacc)
    return _out(single, *_mujoco_to_paper(qpos, qvel, qacc, ipos, iquat))


def mujoco_to_paper_acc(
    qpos: np.ndarray,
    qvel: np.ndarray,
    qacc: np.ndarray,
    ipos: np.ndarray = IPOS_AT_C,
    iquat: np.ndarray = IQUAT_AT_C,
) -> np.ndarray:
    """MuJoCo's ``qacc`` (N, n+6) at ``(qpos, qvel)`` -> the paper's ``q̈`` (N, n+7)."""
    return mujoco_to_paper_batch(qpos, qvel, qacc, ipos, iquat)[2]


def frame_to_inertial(
    frame_pos: np.ndarray, frame_quat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(ipos, iquat)`` of a body frame given by its pose in the paper's body frame
    (:class:`model_xml.builder.BodyFrame`: origin ``pos``, m, orientation ``quat``):
    ``ipos = -Rot(quat)ᵀ pos``, ``iquat = quat*``."""
    frame_quat = np.asarray(frame_quat, dtype=float)
    ipos = -quat_to_mat(frame_quat).T @ np.asarray(frame_pos, dtype=float)
    return ipos, quat_conj(frame_quat)


def paper_to_frame_state(
    q: np.ndarray, qdot: np.ndarray, frame_pos: np.ndarray, frame_quat: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`paper_to_mujoco_state` for a body frame given as in :func:`frame_to_inertial`."""
    return paper_to_mujoco_state(q, qdot, *frame_to_inertial(frame_pos, frame_quat))


# ----------------------------------------------------------------------------------------------
# Paper <-> Pinocchio
# ----------------------------------------------------------------------------------------------


def paper_to_pinocchio(q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper ``(q, q̇)`` ((N, n+7) each) -> Pinocchio ``(q_pin (N, n+7), v_pin (N, n+6))``.

    u is normalised (Pinocchio's quaternion is a rotation); ``ω = H(u) u̇`` is evaluated at the
    given, possibly non-unit, u (as :func:`paper_to_mujoco_state`), ``v = S(û)ᵀ Ṙ``.
    """
    single, (q, qdot) = _rows(q, qdot)
    u = q[:, 3:7] / np.linalg.norm(q[:, 3:7], axis=-1, keepdims=True)
    omega = omega_of(q[:, 3:7], qdot[:, 3:7])
    q_pin = np.concatenate([q[:, :3], u[:, 1:4], u[:, :1], q[:, 7:]], axis=1)
    v = _mv(np.swapaxes(S_batch(u), 1, 2), qdot[:, :3])
    v_pin = np.concatenate([v, omega, qdot[:, 7:]], axis=1)
    return _out(single, q_pin, v_pin)


def pinocchio_to_mujoco_layout(
    q_pin: np.ndarray, v_pin: np.ndarray, a_pin: np.ndarray | None = None
) -> tuple[np.ndarray, ...]:
    """Pinocchio's state (and acceleration) in MuJoCo's layout for a body frame at C.

    Args:
        q_pin (N, n+7), v_pin (N, n+6), a_pin (N, n+6) or None.

    Returns:
        ``qpos = [R, qw, qx, qy, qz, p]``, ``qvel = [S v, ω, ṗ]`` and, when ``a_pin`` is given,
        ``qacc = [S (v̇ + ω × v), ω̇, p̈]`` (S of the normalised quaternion).
    """
    single, (q_pin, v_pin) = _rows(q_pin, v_pin)
    quat = np.concatenate([q_pin[:, 6:7], q_pin[:, 3:6]], axis=1)  # w first
    qpos = np.concatenate([q_pin[:, :3], quat, q_pin[:, 7:]], axis=1)
    Sm = S_batch(quat / np.linalg.norm(quat, axis=1, keepdims=True))
    v, w = v_pin[:, :3], v_pin[:, 3:6]
    qvel = np.concatenate([np.einsum("nij,nj->ni", Sm, v), v_pin[:, 3:]], axis=1)
    if a_pin is None:
        return _out(single, qpos, qvel)
    a_pin = np.atleast_2d(np.asarray(a_pin, dtype=float))
    Rdd = np.einsum("nij,nj->ni", Sm, a_pin[:, :3] + _cross(w, v))
    qacc = np.concatenate([Rdd, a_pin[:, 3:]], axis=1)
    return _out(single, qpos, qvel, qacc)


def pinocchio_to_paper_batch(
    q_pin: np.ndarray, v_pin: np.ndarray, a_pin: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pinocchio ``(q_pin, v_pin, a_pin)`` -> paper ``(q, q̇, q̈)`` ((N, n+7) each) and ω
    ((N, 3), body axes, rad/s). u is the quaternion as given (not renormalised);
    ``u̇ = H(u)ᵀ ω / (4|u|²)``."""
    return mujoco_to_paper_batch(*pinocchio_to_mujoco_layout(q_pin, v_pin, a_pin))


def pinocchio_to_paper(q_pin: np.ndarray, v_pin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio ``(q_pin (N, n+7), v_pin (N, n+6))`` -> paper ``(q, q̇)``."""
    return mujoco_to_paper_state(*pinocchio_to_mujoco_layout(q_pin, v_pin))


def pinocchio_to_paper_acc(q_pin: np.ndarray, v_pin: np.ndarray, a_pin: np.ndarray) -> np.ndarray:
    """Pinocchio's ``v̇`` (N, n+6) at ``(q_pin, v_pin)`` -> the paper's ``q̈`` (N, n+7)."""
    return pinocchio_to_paper_batch(q_pin, v_pin, a_pin)[2]


def paper_to_pinocchio_plant(q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """Paper ``(q, q̇)`` -> the Pinocchio plant's motion state ``x = [q_pin, Ṙ, ω, ṗ]``
    (N, 2n+13): u normalised, ``ω = H(u) u̇``."""
    single, (q, qdot) = _rows(q, qdot)
    q_pin, v_pin = paper_to_pinocchio(q, qdot)
    x = np.concatenate([q_pin, qdot[:, :3], v_pin[:, 3:]], axis=1)
    return x[0] if single else x


def _plant_layout(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's ``(qpos, qvel)`` at C of plant states (N, 2n+13), the quaternion normalised."""
    nq = (x.shape[1] + 1) // 2
    quat = np.concatenate([x[:, 6:7], x[:, 3:6]], axis=1)
    quat = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    return np.concatenate([x[:, :3], quat, x[:, 7:nq]], axis=1), x[:, nq:]


def pinocchio_plant_to_pinocchio(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Pinocchio plant's state ``x`` (N, 2n+13) -> ``(q_pin, v_pin)`` as ``aba`` gets them:
    the quaternion normalised, ``v = Sᵀ Ṙ``."""
    single, (x,) = _rows(x)
    qpos, qvel = _plant_layout(x)
    u = qpos[:, 3:7]
    q_pin = np.concatenate([qpos[:, :3], u[:, 1:4], u[:, :1], qpos[:, 7:]], axis=1)
    v = _mv(np.swapaxes(S_batch(u), 1, 2), qvel[:, :3])
    return _out(single, q_pin, np.concatenate([v, qvel[:, 3:]], axis=1))


def pinocchio_plant_to_paper(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Pinocchio plant's state ``x`` (N, 2n+13) -> paper ``(q, q̇)`` as the controller gets
    them: u the normalised quaternion, ``u̇ = ¼ H(u)ᵀ ω``."""
    single, (x,) = _rows(x)
    q, qdot, _ = _mujoco_to_paper(*_plant_layout(x), None, IPOS_AT_C, IQUAT_AT_C)
    return _out(single, q, qdot)


__all__ = [
    "IPOS_AT_C",
    "IQUAT_AT_C",
    "frame_to_inertial",
    "mujoco_to_paper_acc",
    "mujoco_to_paper_batch",
    "mujoco_to_paper_state",
    "paper_to_frame_state",
    "paper_to_mujoco_state",
    "paper_to_pinocchio",
    "paper_to_pinocchio_plant",
    "pinocchio_plant_to_paper",
    "pinocchio_plant_to_pinocchio",
    "pinocchio_to_mujoco_layout",
    "pinocchio_to_paper",
    "pinocchio_to_paper_acc",
    "pinocchio_to_paper_batch",
    "quat_mul_rows",
    "rotation_rows",
]
