"""An independent symbolic derivation of the paper's equations of motion from its Lagrangian.

Nothing here imports ``analytic``: every quantity is written from the paper's *definitions*, not
from its derived matrices (no ``H``, ``L_i``, ``L_a`` or Eq. 51-53 are transcribed):

* ``S(u)`` is Eq. (11) written entry by entry (valid for any u, not only unit);
* the body-axis angular velocity is the quaternion product ``ω = 2 vec(conj(u) ⊗ u̇)``;
* ``r_i = R + p_i S(u) a + S(u) d`` (Eq. 21), ``ṙ_i = (∂r_i/∂q) q̇`` by the chain rule;
* ``T = ½ m_BR |Ṙ|² + ½ ωᵀ J ω + Σ ½ m_i |ṙ_i|²`` (Eqs. 36, 45; J may include the masses' own
  inertia, Remark 1, by passing ``J_BR + Σ J_i``);
* ``U = -m_BR g·R - Σ m_i g·r_i + U_s`` with the gravity *vector* g (Eqs. 37, 46) and the spring
  energy of Eq. (38) with ``p⁰ = pⁿ⁺¹ = p_e⁰ = p_eⁿ⁺¹ = 0``;
* a given body-axis torque τ does the virtual work ``τ·δθ`` with ``δθ = (∂ω/∂u̇) δu``.

Lagrange's equations ``d/dt ∂T/∂q̇ - ∂T/∂q + ∂U/∂q = Q_τ`` give ``M q̈ = Q`` with
``M = ∂²T/∂q̇²`` and ``Q = ∂(T-U)/∂q - (∂²T/∂q̇∂q) q̇ + Q_τ``.

Each physical term is derived and lambdified separately so that tests can switch terms on and off:
kinetic terms ``body_translation``, ``rotation`` (``½ωᵀJω`` with a symmetric J given numerically),
``masses``; potential terms ``gravity``, ``springs.linear``, ``springs.cubic``; and
``external_torque``. Parameters stay symbolic, so one derivation per n serves every random a, d,
mass, inertia, stiffness, gravity and torque.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
import sympy as sp

KINETIC_TERMS = ("body_translation", "rotation", "masses")
POTENTIAL_TERMS = ("gravity", "springs.linear", "springs.cubic")
ALL_TERMS = (*KINETIC_TERMS, *POTENTIAL_TERMS, "external_torque")


def rotation_eq11(u):
    """S(u) of Eq. (11), written out from the printed definition (any u)."""
    u0, u1, u2, u3 = u
    return sp.Matrix(
        [
            [2 * u0**2 - 1 + 2 * u1**2, 2 * u1 * u2 - 2 * u0 * u3, 2 * u1 * u3 + 2 * u0 * u2],
            [2 * u1 * u2 + 2 * u0 * u3, 2 * u0**2 - 1 + 2 * u2**2, 2 * u2 * u3 - 2 * u0 * u1],
            [2 * u1 * u3 - 2 * u0 * u2, 2 * u2 * u3 + 2 * u0 * u1, 2 * u0**2 - 1 + 2 * u3**2],
        ]
    )


def quat_mul(p, q):
    """Hamilton product of w-first quaternions (4-sequences)."""
    p0, pv = p[0], sp.Matrix(p[1:])
    q0, qv = q[0], sp.Matrix(q[1:])
    w = p0 * q0 - pv.dot(qv)
    v = p0 * qv + q0 * pv + pv.cross(qv)
    return [w, v[0], v[1], v[2]]


def body_angular_velocity(u, ud):
    """``ω = 2 vec(conj(u) ⊗ u̇)``: the body-axis angular velocity (for any u)."""
    conj = [u[0], -u[1], -u[2], -u[3]]
    prod = quat_mul(conj, ud)
    return sp.Matrix([2 * prod[1], 2 * prod[2], 2 * prod[3]])


@dataclass
class Params:
    """Numeric parameters of one system (SI units).

    ``J`` is the rotational inertia used in ``½ωᵀJω`` (3x3, body axes): ``J_BR`` or, with
    Remark 1, ``J_BR + Σ J_i``. ``g`` is the gravity acceleration vector (inertial).
    """

    m_BR: float
    J: np.ndarray
    a: np.ndarray
    d: np.ndarray
    m: np.ndarray
    p_e: np.ndarray
    g: np.ndarray
    k_l: np.ndarray
    k_n: np.ndarray
    tau: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def vector(self) -> np.ndarray:
        J = np.asarray(self.J, float)
        j6 = [J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]]
        return np.concatenate(
            [
                [self.m_BR],
                j6,
                self.a,
                self.d,
                self.m,
                self.p_e,
                self.g,
                self.k_l,
                self.k_n,
                self.tau,
            ]
        ).astype(float)


class LagrangeReference:
    """Lambdified per-term ``M_term(q, par)`` and ``Q_term(q, q̇, par)`` for n masses."""

    def __init__(self, n: int):
        self.n = n
        nq = n + 7
        q = sp.Matrix(sp.symbols(f"q0:{nq}", real=True))
        qd = sp.Matrix(sp.symbols(f"qd0:{nq}", real=True))
        m_BR = sp.Symbol("m_BR", positive=True)
        jxx, jyy, jzz, jxy, jxz, jyz = sp.symbols("jxx jyy jzz jxy jxz jyz", real=True)
        J = sp.Matrix([[jxx, jxy, jxz], [jxy, jyy, jyz], [jxz, jyz, jzz]])
        a = sp.Matrix(sp.symbols("a0:3", real=True))
        d = sp.Matrix(sp.symbols("d0:3", real=True))
        m = sp.symbols(f"m0:{n}", positive=True) if n else ()
        p_e = sp.symbols(f"pe0:{n}", real=True) if n else ()
        g = sp.Matrix(sp.symbols("g0:3", real=True))
        k_l = sp.symbols(f"kl0:{n + 1}", real=True)
        k_n = sp.symbols(f"kn0:{n + 1}", real=True)
        tau = sp.Matrix(sp.symbols("tau0:3", real=True))
        par = [m_BR, jxx, jyy, jzz, jxy, jxz, jyz, *a, *d, *m, *p_e, *g, *k_l, *k_n, *tau]

        R, Rd = q[0:3, 0], qd[0:3, 0]
        u, ud = list(q[3:7]), list(qd[3:7])
        p = list(q[7:])
        S = rotation_eq11(u)
        omega = body_angular_velocity(u, ud)
        r = [R + p[i] * (S * a) + S * d for i in range(n)]  # Eq. (21)
        rdot = [ri.jacobian(q) * qd for ri in r]  # chain rule

        kinetic = {
            "body_translation": m_BR * Rd.dot(Rd) / 2,
            "rotation": (omega.T * J * omega)[0, 0] / 2,
            "masses": sum((m[i] * rdot[i].dot(rdot[i]) / 2 for i in range(n)), sp.Integer(0)),
        }
        pp = [sp.Integer(0), *p, sp.Integer(0)]
        ppe = [sp.Integer(0), *p_e, sp.Integer(0)]
        ext = [pp[i] - pp[i - 1] - ppe[i] + ppe[i - 1] for i in range(1, n + 2)]  # Eq. (38)
        potential = {
            "gravity": -m_BR * g.dot(R)
            - sum((m[i] * g.dot(r[i]) for i in range(n)), sp.Integer(0)),
            "springs.linear": sum((k_l[i] * ext[i] ** 2 / 2 for i in range(n + 1)), sp.Integer(0)),
            "springs.cubic": sum((k_n[i] * ext[i] ** 4 / 4 for i in range(n + 1)), sp.Integer(0)),
        }

        self._M: dict[str, object] = {}
        self._Q: dict[str, object] = {}
        for name, T in kinetic.items():
            dT_dqd = sp.Matrix([sp.diff(T, v) for v in qd])
            M = dT_dqd.jacobian(qd)
            # d/dt(∂T/∂q̇) at q̈ = 0 is (∂²T/∂q̇∂q) q̇; T does not depend on t explicitly.
            Q = sp.Matrix([sp.diff(T, v) for v in q]) - dT_dqd.jacobian(q) * qd
            self._M[name] = sp.lambdify([list(q), par], M, modules="numpy", cse=True)
            self._Q[name] = sp.lambdify([list(q), list(qd), par], Q, modules="numpy", cse=True)
        for name, U in potential.items():
            Q = -sp.Matrix([sp.diff(U, v) for v in q])
            self._Q[name] = sp.lambdify([list(q), list(qd), par], Q, modules="numpy", cse=True)
        # Virtual work of a body-axis torque: τ·δθ with δθ = (∂ω/∂u̇) δu.
        dw_dud = omega.jacobian(qd)
        self._Q["external_torque"] = sp.lambdify(
            [list(q), list(qd), par], dw_dud.T * tau, modules="numpy", cse=True
        )
        self.omega = sp.lambdify([list(q), list(qd)], omega, modules="numpy")

    def mass_matrix(self, q, params: Params, terms=KINETIC_TERMS) -> np.ndarray:
        nq = self.n + 7
        pv = params.vector()
        out = np.zeros((nq, nq))
        for t in terms:
            if t in self._M:
                out += np.asarray(self._M[t](list(q), pv), float).reshape(nq, nq)
        return out

    def force(self, q, qd, params: Params, terms=ALL_TERMS) -> np.ndarray:
        nq = self.n + 7
        pv = params.vector()
        out = np.zeros(nq)
        for t in terms:
            out += np.asarray(self._Q[t](list(q), list(qd), pv), float).reshape(nq)
        return out


@cache
def reference(n: int) -> LagrangeReference:
    """The derivation for n masses (derived once per process)."""
    return LagrangeReference(n)
