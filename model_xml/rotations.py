"""Small w-first quaternion helpers shared by ``model_xml`` and ``mj_bridge``.

Conventions: quaternions are ``[w, x, y, z]``; ``quat_to_mat(q)`` is the active rotation taking
vectors from the rotated (child/body) frame to the parent (world) frame, as in MuJoCo: the paper's
``S(u)`` (:func:`analytic.kinematics.S`) of the normalised quaternion.
"""

from __future__ import annotations

import numpy as np

from analytic.kinematics import S, quat_mul  # noqa: F401  (quat_mul is used from here too)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` for two 3-vectors (np.cross costs ~50x more on single vectors)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def quat_conj(q: np.ndarray) -> np.ndarray:
    """Conjugate (the inverse rotation for unit q), shape (4,)."""
    return np.array([q[0], -q[1], -q[2], -q[3]])


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a quaternion (normalised first), shape (3, 3): ``S(q / |q|)``."""
    q = np.asarray(q, float)
    return S(q / np.linalg.norm(q))


def mat_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w first, w >= 0) of a proper rotation matrix, shape (4,).

    Raises:
        ValueError: if R is not a proper rotation to 1e-9.
    """
    R = np.asarray(R, float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
        raise ValueError(f"R: must be a 3x3 rotation matrix (got {R.tolist()!r})")
    if np.linalg.det(R) < 0:
        raise ValueError(f"R: must be a proper rotation, det = +1 (got det {np.linalg.det(R)!r})")
    tr = np.trace(R)
    if tr > 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    q = np.array(q)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def quat_z_to(v: np.ndarray) -> np.ndarray:
    """A unit quaternion rotating the z axis onto the direction of v (MuJoCo cylinders/joints)."""
    v = np.asarray(v, float) / np.linalg.norm(v)
    z = np.array([0.0, 0.0, 1.0])
    c = float(z @ v)
    if c < -1.0 + 1e-15:
        return np.array([0.0, 1.0, 0.0, 0.0])
    axis = np.cross(z, v)
    q = np.array([1.0 + c, *axis])
    return q / np.linalg.norm(q)


def principal_frame(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending) and the quaternion of a right-handed principal frame.

    Args:
        inertia: symmetric inertia matrix, kg·m², shape (3, 3), in some frame F.

    Returns:
        ``(moments (3,), quat (4,))`` with ``inertia = Rot(quat) diag(moments) Rot(quat)ᵀ``.
    """
    w, V = np.linalg.eigh(0.5 * (inertia + inertia.T))
    if np.linalg.det(V) < 0:
        V[:, 2] = -V[:, 2]
    return w, mat_to_quat(V)


def attitude_angle(u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """Angle between attitudes (q and -q are the same attitude), rad; batched (..., 4) -> (...)."""
    u1 = np.asarray(u1, float)
    u2 = np.asarray(u2, float)
    u1 = u1 / np.linalg.norm(u1, axis=-1, keepdims=True)
    u2 = u2 / np.linalg.norm(u2, axis=-1, keepdims=True)
    w = np.sum(u1 * u2, axis=-1)
    # vector part of conj(u1) ⊗ u2
    v = u1[..., :1] * u2[..., 1:] - u2[..., :1] * u1[..., 1:] - np.cross(u1[..., 1:], u2[..., 1:])
    return 2.0 * np.arctan2(np.linalg.norm(v, axis=-1), np.abs(w))
