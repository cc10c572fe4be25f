"""``M`` and ``Q`` of the model agree with Lagrange's equations derived
independently (symbolically, :mod:`reference_lagrange`) from the paper's ``T - U``
(Eqs. 21, 32, 36-38, 45-47), at random states (u not unit), for n = 0..4 and random a, d, masses,
inertias, stiffnesses, gravity and given torque; and each effect contributes exactly its own term.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.model import TumblingModel
from analytic.scene import scene_from_dict

try:
    from tests.support.reference_lagrange import KINETIC_TERMS, POTENTIAL_TERMS, Params, reference
    from tests.support.scene_strategies import (
        FORCE_EFFECTS,
        random_scene_dict,
        random_state,
        rel_err,
    )
except ImportError:  # tests/ made a package
    from tests.support.reference_lagrange import KINETIC_TERMS, POTENTIAL_TERMS, Params, reference
    from tests.support.scene_strategies import (
        FORCE_EFFECTS,
        random_scene_dict,
        random_state,
        rel_err,
    )

RTOL = 1e-10
NS = (0, 1, 2, 3, 4)


def mass_inertia_sum(data: dict) -> np.ndarray:
    """Σ P_iᵀ J_i P_i (Remark 1) from the scene data: a thin ring about the rod has axial moment
    m r² and transverse m r²/2, i.e. m r²/2 (I + a aᵀ) in body axes."""
    ms = data.get("masses")
    if not ms:
        return np.zeros((3, 3))
    if "inertia_body" in ms:
        return np.sum(np.array(ms["inertia_body"], float), axis=0)
    a = np.array(data["rod"]["axis"], float)
    a = a / np.linalg.norm(a)
    m, r = np.array(ms["mass"]), np.array(ms["ring_radius"])
    return float(np.sum(m * r**2 / 2)) * (np.eye(3) + np.outer(a, a))


def params_of(data: dict, t: float, *, with_mass_inertia: bool) -> Params:
    """Reference parameters read from the raw scene data (not from the model)."""
    n = len(data["masses"]["mass"]) if data.get("masses") else 0
    J = np.diag(data["body"]["inertia"])
    if with_mass_inertia:
        J = J + mass_inertia_sum(data)
    et = data["external_torque"]
    tau = np.array(et["constant"]) + np.array(et["amplitude"]) * np.cos(et["frequency"] * t)
    a = np.array(data["rod"]["axis"], float)
    ms = data.get("masses") or {"mass": [], "p_e": []}
    sp_ = data.get("springs") or {"k_linear": [0.0], "k_cubic": [0.0]}
    return Params(
        m_BR=data["body"]["mass"],
        J=J,
        a=a / np.linalg.norm(a),
        d=np.array(data["rod"]["offset"], float),
        m=np.array(ms["mass"], float).reshape(n),
        p_e=np.array(ms["p_e"], float).reshape(n),
        g=np.array(data["gravity"]["vector"], float),
        k_l=np.array(sp_["k_linear"], float),
        k_n=np.array(sp_["k_cubic"], float),
        tau=tau,
    )


def ref_terms(effects) -> tuple[str, ...]:
    """Reference terms for a set of scene effects (kinetic terms always present)."""
    out = list(KINETIC_TERMS)
    out += [e for e in POTENTIAL_TERMS if e in effects]
    if "external_torque" in effects:
        out.append("external_torque")
    return tuple(out)


@pytest.fixture(scope="module", params=NS, ids=lambda n: f"n{n}")
def ref(request):
    return reference(request.param)


@pytest.mark.parametrize("inertia_kind", ["body", "ring"])
def test_M_and_Q_match_lagrange(ref, inertia_kind):
    n = ref.n
    rng = np.random.default_rng(1000 + 10 * n + (inertia_kind == "ring"))
    for _ in range(2):  # two random systems (a, d, masses, ...) per n
        data = random_scene_dict(rng, n, FORCE_EFFECTS, inertia_kind=inertia_kind)
        model = TumblingModel(scene_from_dict(data))
        for _ in range(3):  # three random states, u off the unit sphere
            q, qd = random_state(rng, n)
            t = float(rng.uniform(0, 5))
            par = params_of(data, t, with_mass_inertia=True)
            M_ref = ref.mass_matrix(q, par)
            Q_ref = ref.force(q, qd, par, ref_terms(FORCE_EFFECTS))
            M = model.mass_matrix(q)
            Q = model.generalized_force(t, q, qd)
            assert M.shape == (n + 7, n + 7) and Q.shape == (n + 7,)
            assert rel_err(M, M_ref) < RTOL, rel_err(M, M_ref)
            assert rel_err(Q, Q_ref) < RTOL, rel_err(Q, Q_ref)


def test_no_effects_is_free_motion(ref):
    """With no effect at all, M and Q are the pure kinetic terms (point masses, no forces)."""
    n = ref.n
    rng = np.random.default_rng(2000 + n)
    data = random_scene_dict(rng, n, [])
    model = TumblingModel(scene_from_dict(data))
    assert model.force_terms == ()
    q, qd = random_state(rng, n)
    par = params_of(data, 0.0, with_mass_inertia=False)
    assert rel_err(model.mass_matrix(q), ref.mass_matrix(q, par)) < RTOL
    assert rel_err(model.generalized_force(0.0, q, qd), ref.force(q, qd, par, KINETIC_TERMS)) < RTOL


@pytest.mark.parametrize("effect", FORCE_EFFECTS)
def test_switching_an_effect_off_removes_exactly_its_term(ref, effect):
    n = ref.n
    rng = np.random.default_rng(3000 + 7 * n + FORCE_EFFECTS.index(effect))
    data = random_scene_dict(rng, n, FORCE_EFFECTS)
    others = [e for e in FORCE_EFFECTS if e != effect]
    off = dict(data, scene=dict(data["scene"], effects=others))
    model_on = TumblingModel(scene_from_dict(data))
    model_off = TumblingModel(scene_from_dict(off))
    q, qd = random_state(rng, n)
    t = float(rng.uniform(0, 5))
    dM = model_on.mass_matrix(q) - model_off.mass_matrix(q)
    dQ = model_on.generalized_force(t, q, qd) - model_off.generalized_force(t, q, qd)
    Q_on = model_on.generalized_force(t, q, qd)
    par = params_of(data, t, with_mass_inertia=False)

    if effect == "mass_inertia":
        # Remark 1: J -> J_BR + Σ J_i adds the rotational energy ½ωᵀ(Σ J_i)ω, and nothing else.
        par.J = mass_inertia_sum(data)
        M_term = ref.mass_matrix(q, par, ("rotation",))
        Q_term = ref.force(q, qd, par, ("rotation",))
        if n == 0:
            assert np.all(dM == 0) and np.all(dQ == 0)
            return
        assert rel_err(dM, M_term) < RTOL
    else:
        Q_term = ref.force(q, qd, par, (effect,))
        # exact: M's code does not read the force effects (same operations on both models)
        assert np.all(dM == 0), "a force effect must not change M"
        if n == 0 and effect.startswith("springs"):
            assert np.all(dQ == 0) and effect not in model_on.force_terms
            return
        assert effect in model_on.force_terms and effect not in model_off.force_terms
    scale = max(np.linalg.norm(Q_term), np.linalg.norm(Q_on))
    assert np.linalg.norm(Q_term) > 1e-3 * scale, "term too small for the test to mean anything"
    assert np.linalg.norm(dQ - Q_term) < RTOL * scale


def test_reference_sanity_rigid_body_euler():
    """Guard on the reference itself: for n = 0 and unit u, its equations projected on the body
    axes are Euler's equations ``J ω̇ + ω × Jω = τ`` (with ``u̇ = ½ u ⊗ [0, ω]``)."""
    ref0 = reference(0)
    rng = np.random.default_rng(7)
    J = np.diag(rng.uniform(1.5, 3.0, 3))
    par = Params(
        m_BR=2.0,
        J=J,
        a=np.array([1.0, 0, 0]),
        d=np.zeros(3),
        m=np.zeros(0),
        p_e=np.zeros(0),
        g=np.zeros(3),
        k_l=np.zeros(1),
        k_n=np.zeros(1),
        tau=rng.normal(size=3),
    )
    u = rng.normal(size=4)
    u /= np.linalg.norm(u)
    w = rng.normal(size=3)
    wdot = np.linalg.solve(J, par.tau - np.cross(w, J @ w))

    def qmul(p, r):
        return np.r_[
            p[0] * r[0] - p[1:] @ r[1:], p[0] * r[1:] + r[0] * p[1:] + np.cross(p[1:], r[1:])
        ]

    ud = 0.5 * qmul(u, np.r_[0.0, w])
    udd = 0.5 * qmul(ud, np.r_[0.0, w]) + 0.5 * qmul(u, np.r_[0.0, wdot])
    q = np.r_[np.zeros(3), u]
    qd = np.r_[np.zeros(3), ud]
    M = ref0.mass_matrix(q, par)
    Q = ref0.force(q, qd, par, ("body_translation", "rotation", "external_torque"))
    res = M[3:7, 3:7] @ udd - Q[3:7]
    # Lagrange's u-equations hold up to a multiple of u (the norm constraint's reaction).
    res_perp = res - u * (u @ res)
    assert np.linalg.norm(res_perp) < 1e-12 * np.linalg.norm(Q[3:7] + 1.0)
    assert np.allclose(ref0.omega(q, qd).ravel(), w, rtol=0, atol=1e-14)
