"""The paper's model and its closed-form controller in one array form that numpy and jax.numpy
both run: ``M(q)`` (Eq. 51), ``Q(q, q̇)`` (Eq. 52 and the force terms), the modeling constraint
(Eq. 59), the control constraints (Eqs. 80-88, Remark 4, B6) and the fundamental equation
(:func:`analytic.fundamental.solve_array`, Eqs. 48, 74, 89, B10).

Every function takes the array namespace ``xp`` (``numpy`` or ``jax.numpy``; this module never
imports jax), the static :class:`Structure` of the scene (what is on: Python branches only on it,
so the functions are ``jax.jit``-able with ``structure`` static, and ``jax.vmap``-able over the
parameters and the state) and the numbers of the scene as a dict of arrays (:func:`parameters`).
:class:`analytic.model.TumblingModel` (the numpy reference) evaluates its M, Q and constraints
through these functions with ``xp = numpy``, so each formula is written once.

Shapes: one scene is ``q, q̇`` of shape (nq,), ``nq = n + 7``, ``q = [R (3, inertial, m),
u (4, w first), p (n, m along the rod)]`` (Eq. 44), ``t`` s. Every function also takes leading
batch dimensions: ``q, q̇`` of shape (..., nq), ``t`` of shape (...) or scalar, parameters either
of one scene or stacked with the same leading shape (:func:`stack_parameters`); the leading
shapes broadcast. The dtype follows the parameters (float32 or float64, :func:`parameters`).

Spring laws are their declarations' own arithmetic (``law.force(e, ė)``, :mod:`analytic.effects`)
applied to xp arrays.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any, NamedTuple

import numpy as np

from analytic import fundamental
from analytic.array_ops import matvec, vecdot, vecmat
from analytic.effects import Effect, Weighting
from analytic.effects.declaration import SpringLaw
from analytic.effects.registry import SPRING_LAWS, spring_law
from analytic.kinematics import T_H, S, tensor_along

Params = Mapping[str, Any]
"""The numbers of one scene (or a stack of scenes), :func:`parameters`'s keys."""


@dataclass(frozen=True)
class Structure:
    """What is on in a scene, never a number: hashable, the static argument under ``jax.jit``.

    Attributes:
        n: number of masses (nq = n + 7).
        effects: the scene's effects.
        omega_components: the controlled body axes of ω, 0-based (Remark 4); () when off.
        mass_indices: the controlled masses, 0-based (Remark 4); () when off.
        weighting: the cost weighting N of Appendix B.
        laws: the spring-law effects that are on (``Effect`` values, in the order of
            :data:`~analytic.effects.registry.SPRING_LAWS`, the order their forces are summed).
    """

    n: int
    effects: frozenset[Effect]
    omega_components: tuple[int, ...]
    mass_indices: tuple[int, ...]
    weighting: Weighting
    laws: tuple[str, ...]

    @property
    def nq(self) -> int:
        return self.n + 7

    @property
    def k(self) -> int:
        """Number of control rows ``k_ω + k_p``."""
        return len(self.omega_components) + len(self.mass_indices)

    @property
    def controlled(self) -> bool:
        return self.k > 0

    def has(self, effect: Effect) -> bool:
        return effect in self.effects

    @cached_property  # (in the instance's __dict__: not a field, out of eq and hash)
    def spring_laws(self) -> tuple[SpringLaw, ...]:
        """The declarations of :attr:`laws`."""
        return tuple(spring_law(e) for e in self.laws)


def structure_of(scene) -> Structure:
    """The :class:`Structure` of a validated :class:`~analytic.scene.Scene`."""
    n = scene.n
    ctrl = scene.control
    comps = tuple(int(c) for c in ctrl.omega.components) if scene.has(Effect.CONTROL_OMEGA) else ()
    idx = (
        tuple(int(i) for i in ctrl.masses.indices) if n and scene.has(Effect.CONTROL_MASSES) else ()
    )
    return Structure(
        n=n,
        effects=frozenset(scene.effects),
        omega_components=comps,
        mass_indices=idx,
        weighting=Weighting(ctrl.weighting),
        laws=tuple(law.effect.value for law in SPRING_LAWS if n and scene.has(law.effect)),
    )


def parameters(scene, xp, dtype) -> dict[str, Any]:
    """Every number of ``scene`` the model needs, as xp arrays of ``dtype`` (SI units, body axes
    unless stated), only for the effects that are on:

    ``m_BR`` (), ``m`` (n,), ``mu0 = Σm`` (), ``m_T = m_BR + μ0`` (); ``J`` (3, 3) (with Remark 1's
    ``Σ P_iᵀJ_iP_i`` when mass_inertia is on, Eq. 54); ``a``, ``d`` (3,); ``T_a``, ``T_d``
    (3, 4, 4) with ``L_a(u) = T_a u`` (Eqs. 29, 34); ``p_e`` (n,); ``delta1``, ``delta2`` ()
    (Eq. 58); ``g`` (3,, inertial) with gravity; each spring law's coefficients under its key's
    name (``k_linear``, ...) (n + 1,); with ω control ``omega_b``, ``omega_sigma`` (k_ω,) and
    ``omega_gain`` (k_ω, k_ω) (Eqs. 76, 84, B6) for the controlled components; with mass control
    ``mass_l``, ``mass_lam``, ``mass_alpha``, ``mass_beta`` (k_p,) (Eqs. 75, 78); with the given
    torque ``torque_constant``, ``torque_amplitude`` (3,) N·m and ``torque_frequency`` () rad/s.
    """
    st = structure_of(scene)
    n = st.n
    m = np.array(scene.masses.mass, float)
    J = np.diag(scene.body.inertia).astype(float)
    if scene.has(Effect.MASS_INERTIA) and n:
        J = J + scene.masses.inertia.sum(axis=0)  # Remark 1, Eq. (54)
    a = np.array(scene.rod.axis, float)
    d = np.array(scene.rod.offset, float)
    out: dict[str, Any] = {
        "m_BR": float(scene.body.mass),
        "m": m,
        "mu0": float(m.sum()),
        "m_T": float(scene.body.mass) + float(m.sum()),
        "J": J,
        "a": a,
        "d": d,
        "T_a": tensor_along(a),
        "T_d": tensor_along(d),
        "p_e": np.array(scene.masses.p_e, float),
        "delta1": float(scene.stabilization.delta1),
        "delta2": float(scene.stabilization.delta2),
    }
    if st.has(Effect.GRAVITY):
        out["g"] = np.array(scene.gravity, float)
    for law in st.spring_laws:
        out[law.key.key] = np.array(scene.springs.of(law), float)
    if st.omega_components:
        w = scene.control.omega
        c = np.array(st.omega_components)
        out["omega_b"] = np.asarray(w.b, float)[c]
        out["omega_sigma"] = np.asarray(w.sigma, float)[c]
        out["omega_gain"] = np.asarray(w.gain, float)
    if st.mass_indices:
        mt = scene.control.masses
        out["mass_l"] = np.asarray(mt.l, float)
        out["mass_lam"] = np.asarray(mt.lam, float)
        out["mass_alpha"] = np.asarray(mt.alpha, float)
        out["mass_beta"] = np.asarray(mt.beta, float)
    if st.has(Effect.EXTERNAL_TORQUE):
        et = scene.external_torque
        out["torque_constant"] = np.asarray(et.constant, float)
        out["torque_amplitude"] = np.asarray(et.amplitude, float)
        out["torque_frequency"] = float(et.frequency)
    return {k: xp.asarray(v, dtype=dtype) for k, v in out.items()}


def stack_parameters(params: Sequence[Params], xp) -> dict[str, Any]:
    """Parameters of scenes of one structure stacked along a new leading axis (shape (N, ...))."""
    if not params:
        raise ValueError("params: at least one scene's parameters are needed")
    keys = set(params[0])
    for i, p in enumerate(params):
        if set(p) != keys:
            raise ValueError(
                f"params[{i}]: keys {sorted(p)} differ from params[0]'s {sorted(keys)}"
            )
    return {k: xp.stack([p[k] for p in params]) for k in params[0]}


# --------------------------------------------------------------------------------------------------
# Batched helpers (leading dimensions broadcast)
# --------------------------------------------------------------------------------------------------


def _outer(a, b):
    return a[..., :, None] * b[..., None, :]


def _tr(xp, A):
    return A.mT


def _bc(xp, x, shape):
    """``x`` broadcast to ``shape`` (x itself when it has it: no call on the one-state path)."""
    return x if x.shape == tuple(shape) else xp.broadcast_to(x, tuple(shape))


def _linear_map(xp, T, u):
    """``X(u) = T u`` for a tensor T (..., 3, 4, 4) of a map linear in u (``H``, ``L_a``, ``L_d``;
    :mod:`analytic.kinematics`): (..., 4) -> (..., 3, 4), one matrix-vector product."""
    X = matvec(T.reshape((*T.shape[:-3], 12, 4)), u)
    return X.reshape((*X.shape[:-1], 3, 4))


def _S_quadratic() -> np.ndarray:
    """``C`` (9, 16) with ``S(u) + I = C (u ⊗ u)`` (Eq. 11 is homogeneous quadratic in u but for
    its ``-1`` on the diagonal), by polarization of :func:`analytic.kinematics.S` (exact: its
    coefficients are small integers)."""
    E = np.eye(4)
    C = np.zeros((3, 3, 4, 4))
    for k in range(4):
        C[:, :, k, k] = S(E[k]) + np.eye(3)
        for j in range(k):
            mixed = (S(E[k] + E[j]) + np.eye(3)) - C[:, :, k, k] - C[:, :, j, j]
            C[:, :, k, j] = C[:, :, j, k] = 0.5 * mixed
    return C.reshape(9, 16)


_C_S = _S_quadratic()
_I9 = np.eye(3).reshape(9)


def H_of(xp, u):
    """``H(u)``, Eq. (13), (..., 4) -> (..., 3, 4): ``ω = H(u) u̇``, ``Ḣ = H(u̇)``."""
    return _linear_map(xp, xp.asarray(T_H, dtype=u.dtype), u)


def S_of(xp, u):
    """``S(u)``, Eq. (11), in the paper's form ``2u0² - 1 + 2ui²`` (a rotation only for unit u;
    docs/errata.md C2), body -> inertial, (..., 4) -> (..., 3, 3)."""
    uu = _outer(u, u)
    S9 = matvec(xp.asarray(_C_S, dtype=u.dtype), uu.reshape((*uu.shape[:-2], 16)))
    S9 = S9 - xp.asarray(_I9, dtype=u.dtype)
    return S9.reshape((*S9.shape[:-1], 3, 3))


@lru_cache(maxsize=256)
def _constant_rows(
    n: int, omega_components: tuple[int, ...], mass_indices: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(P, E, c, i)``: ``P = [0, I₄, 0]`` (4, nq), so that the ω rows ``[0, H_c, 0] = H_c P``
    (Eq. 86), the mass rows ``E`` (k_p, nq) of Eq. (80), unit rows at the tracked masses, and the
    components and indices as index arrays."""
    nq = n + 7
    P = np.zeros((4, nq))
    P[:, 3:7] = np.eye(4)
    E = np.zeros((len(mass_indices), nq))
    E[np.arange(len(mass_indices)), 7 + np.asarray(mass_indices, int)] = 1.0
    c = np.asarray(omega_components, int)
    i = np.asarray(mass_indices, int)
    for x in (P, E, c, i):
        x.flags.writeable = False
    return P, E, c, i


def element_differences(xp, x):
    """``x_j - x_{j-1}`` for the n + 1 spring elements, ``x_{-1} = x_n = 0`` (Eq. 38): their
    extensions from ``x = p - p_e``, their rates from ``ṗ``; (..., n) -> (..., n + 1)."""
    return xp.concatenate([x[..., :1], x[..., 1:] - x[..., :-1], -x[..., -1:]], axis=-1)


class Kinematics(NamedTuple):
    """Quantities shared by M, Q and the constraints at one state (batched like q).

    ``u`` (4), ``p`` (n), ``Sa = S(u) a``, ``Sd = S(u) d`` (3, inertial), ``Hm = H(u)`` (3, 4),
    ``La = L_a(u)``, ``Ld = L_d(u)`` (3, 4), ``mu1 = mᵀp``, ``mu2 = (p∘m)ᵀp`` (),
    ``B = μ1 L_a + μ0 L_d`` (3, 4) (``Σ m_i J_i``'s u block: M's R-u block, Eq. 51); with q̇:
    ``ud`` (4), ``pd`` (n), ``omega = H u̇`` (3, rad/s, Eq. 12), ``Hd = H(u̇)`` (3, 4); else None.
    """

    u: Any
    p: Any
    Sa: Any
    Sd: Any
    Hm: Any
    La: Any
    Ld: Any
    mu1: Any
    mu2: Any
    B: Any
    ud: Any = None
    pd: Any = None
    omega: Any = None
    Hd: Any = None


def kinematics(xp, structure: Structure, params: Params, q, qdot=None) -> Kinematics:
    """The :class:`Kinematics` at ``q`` (and ``q̇`` when given)."""
    u, p = q[..., 3:7], q[..., 7:]
    Sm = S_of(xp, u)
    Hm = H_of(xp, u)
    m = params["m"]
    La = _linear_map(xp, params["T_a"], u)  # Eq. (29)
    Ld = _linear_map(xp, params["T_d"], u)  # Eq. (34)
    mu1 = vecdot(m, p)
    kin = dict(
        u=u,
        p=p,
        Sa=matvec(Sm, params["a"]),
        Sd=matvec(Sm, params["d"]),
        Hm=Hm,
        La=La,
        Ld=Ld,
        mu1=mu1,
        mu2=vecdot(m * p, p),
        B=mu1[..., None, None] * La + params["mu0"][..., None, None] * Ld,  # {mᵀp}L_a + {mᵀ1}L_d
    )
    if qdot is not None:
        ud = qdot[..., 3:7]
        kin.update(ud=ud, pd=qdot[..., 7:], omega=matvec(Hm, ud), Hd=H_of(xp, ud))
    return Kinematics(**kin)


def _batch(xp, *shapes):
    """The broadcast of the leading shapes (the common one without a call when they agree)."""
    first = shapes[0]
    if all(sh == first for sh in shapes[1:]):
        return tuple(first)
    return xp.broadcast_shapes(*shapes)


def mass_matrix(xp, structure: Structure, params: Params, k: Kinematics):
    """``M(q)`` of Eq. (51) (Remark 1's inertia in ``J``), (..., nq, nq)."""
    n = structure.n
    m, mu0, J = params["m"], params["mu0"], params["J"]
    La, Ld, Sa, Hm = k.La, k.Ld, k.Sa, k.Hm
    mu1, mu2 = k.mu1[..., None, None], k.mu2[..., None, None]
    mu0_ = mu0[..., None, None]
    LaT, LdT = _tr(xp, La), _tr(xp, Ld)
    batch = _batch(xp, k.mu1.shape, mu0.shape)
    B = k.B  # {mᵀp}L_a + {mᵀ1}L_d, Eq. (51)
    LaLd = LaT @ Ld
    # HᵀJH + {(p∘m)ᵀp}L_aᵀL_a + A_d, Eq. (51)
    Muu = _tr(xp, Hm) @ J @ Hm + mu2 * (LaT @ La) + mu1 * (LaLd + _tr(xp, LaLd)) + mu0_ * (LdT @ Ld)
    I3 = xp.eye(3, dtype=mu0.dtype)
    MRR = params["m_T"][..., None, None] * I3

    def bc(x, r, c):
        return _bc(xp, x, (*batch, r, c))

    rows_R = [bc(MRR, 3, 3), bc(B, 3, 4)]
    rows_u = [bc(_tr(xp, B), 4, 3), bc(Muu, 4, 4)]
    if not n:
        return xp.concatenate(
            [xp.concatenate(rows_R, axis=-1), xp.concatenate(rows_u, axis=-1)], axis=-2
        )
    MRp = _outer(Sa, m)  # (Sa)mᵀ
    Mup = _outer(vecmat(Sa, La), k.p * m) + _outer(vecmat(Sa, Ld), m)  # L_aᵀSa(p∘m)ᵀ + L_dᵀSa mᵀ
    Mpp = (vecdot(Sa, Sa)[..., None] * m)[..., :, None] * xp.eye(
        n, dtype=mu0.dtype
    )  # {(Sa)ᵀSa}diag(m)
    rows_R.append(bc(MRp, 3, n))
    rows_u.append(bc(Mup, 4, n))
    rows_p = [bc(_tr(xp, MRp), n, 3), bc(_tr(xp, Mup), n, 4), bc(Mpp, n, n)]
    return xp.concatenate([xp.concatenate(r, axis=-1) for r in (rows_R, rows_u, rows_p)], axis=-2)


def given_torque(xp, structure: Structure, params: Params, t):
    """``τ_g(t) = τ_c + τ_a cos(f t)``, the given body-axis torque of Remark 2, N·m, (..., 3);
    zeros when the effect is off."""
    t = xp.asarray(t, dtype=params["mu0"].dtype)
    if not structure.has(Effect.EXTERNAL_TORQUE):
        return xp.zeros((*_batch(xp, t.shape, params["mu0"].shape), 3), dtype=t.dtype)
    c = xp.cos(params["torque_frequency"] * t)
    return params["torque_constant"] + params["torque_amplitude"] * c[..., None]


def generalized_force(xp, structure: Structure, params: Params, t, k: Kinematics):
    """``Q(q, q̇)`` of Eq. (52): the velocity terms ``Q_BR - Σ m_i J_iᵀ κ_i`` (Eq. 40) and the
    terms of the effects that are on (gravity, each spring law, Remark 2's torque), (..., nq)."""
    n = structure.n
    m, mu0, T_a, T_d = params["m"], params["mu0"], params["T_a"], params["T_d"]
    ud, pd, p = k.ud, k.pd, k.p
    mu1, mu2 = k.mu1[..., None], k.mu2[..., None]
    mu0_ = mu0[..., None]
    Lau = matvec(k.La, ud)  # L_a u̇ = Ṡa
    Lad_u = matvec(_linear_map(xp, T_a, ud), ud)  # L̇_a u̇
    Ldd_u = matvec(_linear_map(xp, T_d, ud), ud)  # L̇_d u̇
    mpd = vecdot(m, pd)[..., None]  # mᵀṗ
    mppd = vecdot(m * p, pd)[..., None]  # (p∘m)ᵀṗ
    sum_m_kappa = (2.0 * mpd) * Lau + mu1 * Lad_u + mu0_ * Ldd_u  # Σ m_i κ_i
    sum_mp_kappa = (2.0 * mppd) * Lau + mu2 * Lad_u + mu1 * Ldd_u  # Σ m_i p_i κ_i
    Q_R = -sum_m_kappa
    # -2ḢᵀJHu̇ - L_aᵀ Σ m_i p_i κ_i - L_dᵀ Σ m_i κ_i  (Eq. 52 second row with B_d)
    Q_u = (
        -2.0 * vecmat(matvec(params["J"], k.omega), k.Hd)
        - vecmat(sum_mp_kappa, k.La)
        - vecmat(sum_m_kappa, k.Ld)
    )
    Sa = k.Sa
    # -{(Sa)ᵀL̇_a u̇}(p∘m) - 2{(Sa)ᵀL_a u̇}(m∘ṗ) - {(Sa)ᵀL̇_d u̇}m, Eq. (52) third row
    Q_p = -m * (
        (2.0 * vecdot(Sa, Lau))[..., None] * pd
        + vecdot(Sa, Lad_u)[..., None] * p
        + vecdot(Sa, Ldd_u)[..., None]
    )
    if structure.has(Effect.GRAVITY):
        g = params["g"]  # inertial acceleration vector (paper: -g e3)
        Q_R = Q_R + params["m_T"][..., None] * g
        Q_u = Q_u + vecmat(g, k.B)
        Q_p = Q_p + vecdot(Sa, g)[..., None] * m
    if structure.laws:
        # Each law's tensions f = c φ(e, ė) on the n + 1 elements, Q_i = f_{i+1} - f_i
        # (F^S = -∂U_s/∂p for a conservative law; Eq. 53 corrected, docs/errata.md item 2).
        e = element_differences(xp, p - params["p_e"])
        ed = element_differences(xp, pd)
        for law in structure.spring_laws:
            f = params[law.key.key] * law.force(e, ed if law.dissipation is not None else None)
            Q_p = Q_p + (f[..., 1:] - f[..., :-1])
    if structure.has(Effect.EXTERNAL_TORQUE):
        Q_u = Q_u + vecmat(given_torque(xp, structure, params, t), k.Hm)  # Q_τ = Hᵀτ, Eq. (61)
    batch = _batch(xp, Q_R.shape[:-1], Q_u.shape[:-1], Q_p.shape[:-1])
    parts = [_bc(xp, x, (*batch, x.shape[-1])) for x in (Q_R, Q_u, Q_p)]
    return xp.concatenate(parts if n else parts[:2], axis=-1)


def modeling_constraint(xp, structure: Structure, params: Params, q, qdot):
    """``a_m = [0, u, 0]`` (..., nq) and ``b_m`` (...) of Eq. (59): ``φ̈ + δ1 φ̇ + δ2 φ = 0`` for
    ``φ = uᵀu - 1`` (Eq. 58)."""
    u, ud = q[..., 3:7], qdot[..., 3:7]
    z3 = xp.zeros_like(q[..., :3])
    a_m = xp.concatenate([z3, u, xp.zeros_like(q[..., 7:])], axis=-1)
    b_m = (
        -params["delta1"] * vecdot(u, ud)
        - 0.5 * params["delta2"] * (vecdot(u, u) - 1.0)
        - vecdot(ud, ud)
    )
    return a_m, b_m


def requirements(xp, structure: Structure, params: Params, t) -> dict[str, Any]:
    """The required ``ω̄, ω̄̇`` (Eq. 76) of the controlled components (..., k_ω) and ``p̄, p̄̇, p̄̈``
    (Eq. 75) of the controlled masses (..., k_p) at time t; keys absent when off."""
    t = xp.asarray(t, dtype=params["mu0"].dtype)[..., None]
    out: dict[str, Any] = {}
    if structure.omega_components:
        b, sigma = params["omega_b"], params["omega_sigma"]
        out["omega_bar"] = b * xp.cos(sigma * t)
        out["omega_bar_dot"] = -b * sigma * xp.sin(sigma * t)
    if structure.mass_indices:
        idx = _constant_rows(structure.n, structure.omega_components, structure.mass_indices)[3]
        l, lam = params["mass_l"], params["mass_lam"]
        cos, sin = xp.cos(lam * t), xp.sin(lam * t)
        out["p_bar"] = params["p_e"][..., idx] + l * cos
        out["p_bar_dot"] = -l * lam * sin
        out["p_bar_ddot"] = -l * lam**2 * cos
    return out


def control_constraints(xp, structure: Structure, params: Params, t, k: Kinematics):
    """``A_c`` (..., k, nq) and ``b_c`` (..., k) of Eqs. (80), (85): the ω rows ``[0, H_c, 0]``
    (Eq. 86) with ``b = ω̄̇ - P(ω_c - ω̄)`` (Eq. 84; gain P of Eq. B6 in place of γI), then the mass
    rows ``[0, 0, E]`` (Eq. 80) with ``b = p̄̈ - α(ṗ - p̄̇) - β(p - p̄)`` (Eq. 81); subsets per
    Remark 4."""
    dtype = params["mu0"].dtype
    P, E, c, i = _constant_rows(structure.n, structure.omega_components, structure.mass_indices)
    req = requirements(xp, structure, params, t)
    A_rows, b_rows = [], []
    if structure.omega_components:
        A_rows.append(k.Hm[..., c, :] @ xp.asarray(P, dtype=dtype))  # [0, H_c, 0] = H_c P
        e = k.omega[..., c] - req["omega_bar"]
        b_rows.append(req["omega_bar_dot"] - matvec(params["omega_gain"], e))
    if structure.mass_indices:
        A_rows.append(xp.asarray(E, dtype=dtype))
        b_rows.append(
            req["p_bar_ddot"]
            - params["mass_alpha"] * (k.pd[..., i] - req["p_bar_dot"])
            - params["mass_beta"] * (k.p[..., i] - req["p_bar"])
        )
    batch = _batch(xp, *(b.shape[:-1] for b in b_rows))
    A = xp.concatenate([_bc(xp, a, (*batch, *a.shape[-2:])) for a in A_rows], axis=-2)
    b = xp.concatenate([_bc(xp, x, (*batch, x.shape[-1])) for x in b_rows], axis=-1)
    return A, b


class ArrayControl(NamedTuple):
    """The controlled acceleration and the control at one state (batched like q).

    ``qddot`` (..., nq); ``QC`` (..., nq), the constraint force ``M q̈ - Q`` of Eq. (89) (control
    plus the norm-constraint reaction along ``[0, u, 0]``); ``torque = ¼ H Q^C_u`` (..., 3) N·m,
    body axes; ``rod_forces = Q^C_p`` (..., n) N; ``force_at_C = Q^C_R`` (..., 3) N, inertial;
    ``residual = A_c q̈ - b_c`` (..., k). Zeros for the control when the scene is uncontrolled.
    """

    qddot: Any
    QC: Any
    torque: Any
    rod_forces: Any
    force_at_C: Any
    residual: Any


def system(xp, structure: Structure, params: Params, t, q, qdot):
    """``(kin, M, Q, a_m, b_m, A_c, b_c)`` at one state: everything the fundamental equation needs
    (``A_c`` (..., 0, nq) and ``b_c`` (..., 0) when uncontrolled)."""
    kin = kinematics(xp, structure, params, q, qdot)
    M = mass_matrix(xp, structure, params, kin)
    Q = generalized_force(xp, structure, params, t, kin)
    a_m, b_m = modeling_constraint(xp, structure, params, q, qdot)
    if structure.controlled:
        A_c, b_c = control_constraints(xp, structure, params, t, kin)
    else:
        A_c = xp.zeros((*Q.shape[:-1], 0, structure.nq), dtype=Q.dtype)
        b_c = xp.zeros((*Q.shape[:-1], 0), dtype=Q.dtype)
    return kin, M, Q, a_m, b_m, A_c, b_c


def solution(xp, structure: Structure, params: Params, t, q, qdot, factor=None, pinv=None):
    """``(kin, sol)``: the kinematics and :func:`analytic.fundamental.solve_array`'s solution at
    one state (``factor``/``pinv`` as there: default LU solve and the masked rank decision)."""
    kin, M, Q, a_m, b_m, A_c, b_c = system(xp, structure, params, t, q, qdot)
    sol = fundamental.solve_array(
        xp, M, Q, a_m, b_m, A_c, b_c, structure.weighting, factor=factor, pinv=pinv
    )
    return kin, sol


def control_of(xp, kin: Kinematics, sol) -> ArrayControl:
    """The :class:`ArrayControl` of a fundamental-equation solution (``solution``'s pair)."""
    Qc = sol.control_force  # Q^C up to the norm reaction along [0, u, 0] (H u = 0)
    return ArrayControl(
        qddot=sol.qddot,
        QC=sol.constraint_force,
        torque=0.25 * matvec(kin.Hm, Qc[..., 3:7]),  # τ = ¼ H Q^C_u (docs/errata.md C4)
        rod_forces=Qc[..., 7:],
        force_at_C=Qc[..., :3],
        residual=sol.residual,
    )


def controlled_acceleration(xp, structure: Structure, params: Params, t, q, qdot) -> ArrayControl:
    """The constrained, controlled ``q̈`` (Eq. 89 / B10) and the control that produces it, as
    :meth:`analytic.model.TumblingModel.acceleration` (given torque included in Q when on)."""
    kin, sol = solution(xp, structure, params, t, q, qdot)
    return control_of(xp, kin, sol)


def control_forces(xp, structure: Structure, params: Params, t, q, qdot):
    """``(torque (..., 3) N·m body axes, rod_forces (..., n) N, force_at_C (..., 3) N inertial)``:
    what a plant applies to realise the control at this state; zeros when the scene is
    uncontrolled. The given torque of Remark 2 is not included (:func:`given_torque`)."""
    if not structure.controlled:
        dtype = params["mu0"].dtype
        batch = _batch(xp, q.shape[:-1], qdot.shape[:-1], params["mu0"].shape, np.shape(t))
        z = xp.zeros((*batch, 3), dtype=dtype)
        return z, xp.zeros((*batch, structure.n), dtype=dtype), z
    c = controlled_acceleration(xp, structure, params, t, q, qdot)
    return c.torque, c.rod_forces, c.force_at_C


def positions(xp, structure: Structure, params: Params, q):
    """Inertial positions of the masses ``r_i = R + p_i Sa + Sd`` (Eq. 21), (..., n, 3), m."""
    kin = kinematics(xp, structure, params, q)
    return q[..., None, :3] + kin.p[..., :, None] * kin.Sa[..., None, :] + kin.Sd[..., None, :]


__all__ = [
    "ArrayControl",
    "H_of",
    "Kinematics",
    "S_of",
    "Structure",
    "control_constraints",
    "control_forces",
    "control_of",
    "controlled_acceleration",
    "element_differences",
    "generalized_force",
    "given_torque",
    "kinematics",
    "mass_matrix",
    "modeling_constraint",
    "parameters",
    "positions",
    "requirements",
    "solution",
    "stack_parameters",
    "structure_of",
    "system",
]
