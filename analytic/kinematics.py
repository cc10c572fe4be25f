"""Quaternion kinematics of the paper, Eqs. (11)-(43).

Notation as in Koganti & Udwadia (2017): ``u = [u0, u1, u2, u3]`` (w first) is the attitude
quaternion, ``S(u)`` the active rotation body -> inertial written in the form ``2u0² - 1 + 2ui²``
(Eq. 11; a rotation only for unit u), ``ω = H(u) u̇`` the body-axis angular velocity (Eqs. 12-13),
``S_i`` the columns of S with ``∂S_i/∂u = L_i`` (Eqs. 23-26), ``L_a = Σ a_i L_i`` (Eq. 29) and
``L_d = Σ d_i L_i`` (Eq. 34).

``H`` and every ``L`` are linear in u, so their time derivatives are the same maps evaluated at u̇:
``Ḣ = H(u̇)``, ``L̇_a = L_a(u̇)``. Each is stored as a constant tensor ``T`` of shape (3, 4, 4) with
``X(u) = T @ u``; building ``L_a`` for a given axis is then one small contraction.
"""

from __future__ import annotations

import numpy as np


def _tensor(rows: list[list[list[tuple[float, int]]]]) -> np.ndarray:
    """Build T (3, 4, 4) from entries given as (coefficient, index of u)."""
    T = np.zeros((3, 4, 4))
    for r, row in enumerate(rows):
        for c, entry in enumerate(row):
            for coef, k in entry:
                T[r, c, k] += coef
    return T


# H(u), Eq. (13)
T_H = _tensor(
    [
        [[(-2, 1)], [(2, 0)], [(2, 3)], [(-2, 2)]],
        [[(-2, 2)], [(-2, 3)], [(2, 0)], [(2, 1)]],
        [[(-2, 3)], [(2, 2)], [(-2, 1)], [(2, 0)]],
    ]
)
# L_1(u), Eq. (23)
T_L1 = _tensor(
    [
        [[(4, 0)], [(4, 1)], [], []],
        [[(2, 3)], [(2, 2)], [(2, 1)], [(2, 0)]],
        [[(-2, 2)], [(2, 3)], [(-2, 0)], [(2, 1)]],
    ]
)
# L_2(u), Eq. (26)
T_L2 = _tensor(
    [
        [[(-2, 3)], [(2, 2)], [(2, 1)], [(-2, 0)]],
        [[(4, 0)], [], [(4, 2)], []],
        [[(2, 1)], [(2, 0)], [(2, 3)], [(2, 2)]],
    ]
)
# L_3(u), Eq. (26)
T_L3 = _tensor(
    [
        [[(2, 2)], [(2, 3)], [(2, 0)], [(2, 1)]],
        [[(-2, 1)], [(-2, 0)], [(2, 3)], [(2, 2)]],
        [[(4, 0)], [], [], [(4, 3)]],
    ]
)
T_L = np.stack([T_L1, T_L2, T_L3])  # (3, 3, 4, 4): T_L[i] gives L_{i+1}


def S(u: np.ndarray) -> np.ndarray:
    """Active rotation body -> inertial, Eq. (11), in the paper's form ``2u0² - 1 + 2ui²`` (a
    rotation only for unit u; docs/errata.md C2). Works for any u, and for a batch: u shape (..., 4)
    -> (..., 3, 3). The one numpy ``S(u)`` of the project (the compiled one is
    :func:`analytic.kernel.kinematics.rotation`, the same formulas)."""
    u = np.asarray(u)
    u0, u1, u2, u3 = u[..., 0], u[..., 1], u[..., 2], u[..., 3]
    out = np.empty((*u.shape[:-1], 3, 3), dtype=np.result_type(u, 1.0))  # complex u: complex S
    out[..., 0, 0] = 2 * u0 * u0 - 1 + 2 * u1 * u1
    out[..., 0, 1] = 2 * u1 * u2 - 2 * u0 * u3
    out[..., 0, 2] = 2 * u1 * u3 + 2 * u0 * u2
    out[..., 1, 0] = 2 * u1 * u2 + 2 * u0 * u3
    out[..., 1, 1] = 2 * u0 * u0 - 1 + 2 * u2 * u2
    out[..., 1, 2] = 2 * u2 * u3 - 2 * u0 * u1
    out[..., 2, 0] = 2 * u1 * u3 - 2 * u0 * u2
    out[..., 2, 1] = 2 * u2 * u3 + 2 * u0 * u1
    out[..., 2, 2] = 2 * u0 * u0 - 1 + 2 * u3 * u3
    return out


S_batch = S
"""Eq. (11) for a batch, u shape (N, 4) -> (N, 3, 3): the same function as :func:`S`."""


def H(u: np.ndarray) -> np.ndarray:
    """Eq. (13), shape (3, 4): ``ω = H(u) u̇``; ``Ḣ = H(u̇)``."""
    return T_H @ u


def L(i: int, u: np.ndarray) -> np.ndarray:
    """``L_i(u)`` (1-based i as in the paper), Eqs. (23), (26), shape (3, 4)."""
    return T_L[i - 1] @ u


def tensor_along(v: np.ndarray) -> np.ndarray:
    """``T_v = Σ v_i T_{L_i}`` so that ``L_v(u) = T_v @ u`` (Eqs. 29, 34), shape (3, 4, 4)."""
    return np.tensordot(v, T_L, axes=1)


def omega_of(u: np.ndarray, udot: np.ndarray) -> np.ndarray:
    """Body-axis angular velocity ``ω = H(u) u̇`` (Eq. 12). Batched: (N, 4), (N, 4) -> (N, 3)."""
    return np.einsum("rck,...k,...c->...r", T_H, u, udot)


def udot_of(u: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Inverse of Eq. (12) on the tangent space: ``u̇ = H(u)ᵀ ω / (4|u|²)`` (= ¼Hᵀω for unit u)."""
    Hu = np.einsum("rck,...k->...rc", T_H, u)
    return np.einsum("...rc,...r->...c", Hu, omega) / (4.0 * np.sum(u * u, axis=-1))[..., None]


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a ⊗ b`` (w first), shape (4,): the rotation b followed by a."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def axis_angle_quat(axis: np.ndarray, angle: float) -> np.ndarray:
    """Unit quaternion (w first) of the rotation by ``angle`` (rad) about the unit ``axis``."""
    half = 0.5 * float(angle)
    return np.concatenate([[np.cos(half)], np.sin(half) * np.asarray(axis, float)])


def matrix_quat(m: np.ndarray) -> np.ndarray:
    """Unit quaternion (w first) of the rotation matrix ``m`` (3, 3), by the largest of the four
    candidate components (Shepperd's method; scipy's ``Rotation.from_matrix`` makes the same
    choice, so the sign agrees with it too; no sign is imposed on w)."""
    m = np.asarray(m, float)
    tr = float(np.trace(m))
    c = int(np.argmax([m[0, 0], m[1, 1], m[2, 2], tr]))
    q = np.empty(4)  # x, y, z, w
    if c == 3:
        q[:] = [m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1], 1.0 + tr]
    else:
        i, j, k = c, (c + 1) % 3, (c + 2) % 3
        q[i] = 1.0 - tr + 2.0 * m[i, i]
        q[j] = m[j, i] + m[i, j]
        q[k] = m[k, i] + m[i, k]
        q[3] = m[k, j] - m[j, k]
    q /= np.linalg.norm(q)
    return np.array([q[3], q[0], q[1], q[2]])
