"""Derived initial quantities: a scene whose fields are each finite but whose products overflow.

Every field is checked finite on its own, but the plants and the comparison work with products
of them: u̇(0) from ω, energies m v² and k x⁴, momenta, the generalized force (k^n x³, m ω² ρ),
accelerations (force / mass) and the control's requirement (b σ, l λ², β e). A product beyond
the double range (1.8e308) would surface late, as a solver's "initial state must be finite"
after work was done; it is refused at load instead, naming the field that makes it overflow.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from analytic.effects import Effect
from analytic.effects.registry import SPRING_LAWS
from analytic.kinematics import S, udot_of
from analytic.scene.values import show

if TYPE_CHECKING:
    from analytic.scene.records import SceneRecord as Scene


def initial_fields(scene: Scene) -> dict[str, np.ndarray]:
    """The scene's numbers that the derived initial quantities use, by field name, as float
    arrays (zeros for an effect that is off, so it adds nothing)."""
    f = {
        "body.mass": np.array([scene.body.mass], float),
        "body.inertia": np.array(scene.body.inertia, float),
        "masses.mass": np.array(scene.masses.mass, float),
        "masses.p_e": np.array(scene.masses.p_e, float),
        "rod.offset": np.array(scene.rod.offset, float),
        "initial.R": np.array(scene.initial.R, float),
        "initial.Rdot": np.array(scene.initial.Rdot, float),
        "initial.omega": np.array(scene.initial.omega, float),
        "initial.p": np.array(scene.initial.p, float),
        "initial.pdot": np.array(scene.initial.pdot, float),
        "stabilization.delta1": np.array([scene.stabilization.delta1], float),
        "stabilization.delta2": np.array([scene.stabilization.delta2], float),
    }
    zeros3 = np.zeros(3)
    f["gravity.vector"] = np.array(scene.gravity, float) if scene.has(Effect.GRAVITY) else zeros3
    for law in SPRING_LAWS:
        on = scene.has(law.effect)
        f[law.key.dotted] = np.array(scene.springs.of(law), float) * (1.0 if on else 0.0)
    ext = scene.external_torque if scene.has(Effect.EXTERNAL_TORQUE) else None
    f["external_torque.constant"] = np.array(ext.constant, float) if ext else zeros3
    f["external_torque.amplitude"] = np.array(ext.amplitude, float) if ext else zeros3
    w = scene.control.omega if scene.has(Effect.CONTROL_OMEGA) else None
    if w is not None:
        f["control.omega.b"] = np.array(w.b, float)
        f["control.omega.sigma"] = np.array(w.sigma, float)
        gain = np.array(w.gain, float)
        if np.array_equal(gain, gain[0, 0] * np.eye(len(gain))):
            f["control.omega.gamma"] = np.array([gain[0, 0]])
        else:
            f["control.omega.gain"] = gain
    mt = scene.control.masses if scene.has(Effect.CONTROL_MASSES) else None
    if mt is not None:
        for key, attr in (("l", "l"), ("lambda", "lam"), ("alpha", "alpha"), ("beta", "beta")):
            f[f"control.masses.{key}"] = np.array(getattr(mt, attr), float)
    return f


_MOTION = ("initial.Rdot", "initial.omega", "initial.p", "initial.pdot", "rod.offset")
_MASS = ("body.mass", "body.inertia", "masses.mass")


def derived_quantities(
    scene: Scene, v: Mapping[str, np.ndarray]
) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
    """Each quantity derived at t = 0 from the fields ``v`` (:func:`initial_fields`, possibly
    altered): ``name -> (the fields it is computed from, its value)``. Magnitudes matter, not
    exact values: the forces and accelerations are the terms of Eq. (52) and their ratios to the
    masses and moments, taken separately (a sum may cancel, a term that overflows is refused).
    Call under ``np.errstate(all="ignore")``."""
    n = scene.n
    a = np.array(scene.rod.axis, float)
    u = np.array(scene.initial.u, float)
    Sm = S(u)
    m_BR, m = v["body.mass"][0], v["masses.mass"]
    J = np.diag(v["body.inertia"])
    if scene.has(Effect.MASS_INERTIA) and n:
        J = J + np.asarray(scene.masses.inertia, float).sum(axis=0)
    w, p, pd = v["initial.omega"], v["initial.p"], v["initial.pdot"]
    rho = v["rod.offset"][None, :] + p[:, None] * a[None, :]  # masses from C, body axes (n, 3)
    rhod = np.cross(w[None, :], rho) + pd[:, None] * a[None, :]
    vel = (Sm.T @ v["initial.Rdot"])[None, :] + rhod  # mass velocities, body axes (n, 3)
    udot = udot_of(u, w)
    out: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    out["attitude rate u̇ = Hᵀω/4"] = (("initial.omega",), udot)
    kinetic = (
        0.5 * m_BR * (v["initial.Rdot"] @ v["initial.Rdot"])
        + 0.5 * (w @ J @ w)
        + 0.5 * float(np.sum(m[:, None] * vel * vel))
    )
    out["kinetic energy"] = (_MASS + _MOTION, np.array([kinetic]))
    out["linear momentum"] = (_MASS + _MOTION, m_BR * v["initial.Rdot"] + Sm @ (m @ vel))
    out["angular momentum"] = (
        _MASS + _MOTION,
        J @ w + np.sum(m[:, None] * np.cross(rho, vel), axis=0),
    )
    out["moment of inertia of the masses about C"] = (
        ("masses.mass", "initial.p", "rod.offset"),
        np.array([np.sum(m * np.sum(rho * rho, axis=1))]),
    )
    # gravity: U = -m_T g·R - Σ m_i g·Sρ_i; its force on C, torque on BR, force along the rod
    g = v["gravity.vector"]
    m_T = m_BR + float(np.sum(m))
    gb = Sm.T @ g
    grav_fields = (
        "gravity.vector",
        "body.mass",
        "masses.mass",
        "initial.R",
        "initial.p",
        "rod.offset",
    )
    u_grav = -m_T * (g @ v["initial.R"]) - float(np.sum(m * (rho @ gb)))
    out["gravitational energy"] = (grav_fields, np.array([u_grav]))
    f_grav_rod = m * (a @ gb)
    torque = np.sum(m[:, None] * np.cross(rho, np.broadcast_to(gb, rho.shape)), axis=0)
    # springs: extensions e and their rates (n + 1), each law's energy c ψ(e) and tension
    # c φ(e, ė), the force along the rod on each mass
    spring_fields = (
        *(law.key.dotted for law in SPRING_LAWS),
        "initial.p",
        "masses.p_e",
        *(("initial.pdot",) if any(law.dissipation for law in SPRING_LAWS) else ()),
    )
    f_spring_rod = np.zeros(n)
    if n:
        x = p - v["masses.p_e"]
        ext = np.concatenate([x[:1], x[1:] - x[:-1], -x[-1:]])
        pd = v["initial.pdot"]
        ext_rate = np.concatenate([pd[:1], pd[1:] - pd[:-1], -pd[-1:]])
        u_spring = 0.0
        f = np.zeros(n + 1)
        for law in SPRING_LAWS:
            c = v[law.key.dotted]
            if law.potential is not None:
                u_spring += float(np.sum(c * law.potential(ext)))
            f = f + c * law.force(ext, ext_rate)
        f_spring_rod = f[1:] - f[:-1]
        out["spring energy"] = (spring_fields, np.array([u_spring]))
        out["spring forces"] = (spring_fields, f)
        out["energy"] = (
            _MASS + _MOTION + grav_fields + spring_fields,
            np.array([kinetic + u_grav + u_spring]),
        )
    # the inertial (centripetal and Coriolis) forces on the masses, Eq. (52)
    f_inertial = m[:, None] * (np.cross(w, np.cross(w, rho)) + 2.0 * np.cross(w, rhod))
    out["inertial forces on the masses"] = (("masses.mass", *_MOTION), f_inertial)
    tau = v["external_torque.constant"] + v["external_torque.amplitude"]
    out["given torque"] = (("external_torque.constant", "external_torque.amplitude"), tau)
    torque = torque + tau + np.sum(np.cross(rho, f_inertial), axis=0)
    force_fields = _MASS + _MOTION + grav_fields + spring_fields
    out["generalized force"] = (
        (*force_fields, "external_torque.constant", "external_torque.amplitude"),
        np.concatenate([m_T * g, torque, f_grav_rod, f_spring_rod]),
    )
    j_min = float(np.min(np.linalg.eigvalsh(J)))
    out["acceleration"] = (
        out["generalized force"][0],
        np.concatenate(
            [
                g,
                torque / j_min,
                (f_grav_rod + f_spring_rod) / m if n else np.zeros(0),
                np.sum(f_inertial, axis=1) / m if n else np.zeros(0),
            ]
        ),
    )
    out["quaternion-norm stabilisation"] = (
        ("stabilization.delta1", "stabilization.delta2", "initial.omega"),
        np.array([-v["stabilization.delta1"][0] * (u @ udot) - udot @ udot]),
    )
    out.update(_control_requirement(scene, v))
    return out


def _control_requirement(
    scene: Scene, v: Mapping[str, np.ndarray]
) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
    """The control's required accelerations at t = 0 and their amplitudes over time (Eqs. 81,
    84): ``b σ``, ``P (ω - b)``; ``l λ``, ``l λ²``, ``α ṗ``, ``β (p - p̄)``."""
    out: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    if "control.omega.b" in v:
        c = list(scene.control.omega.components)
        gain_key = "control.omega.gamma" if "control.omega.gamma" in v else "control.omega.gain"
        gain = v[gain_key]
        gain = gain[0] * np.eye(len(c)) if gain_key.endswith("gamma") else gain
        b, sigma = v["control.omega.b"][c], v["control.omega.sigma"][c]
        e = v["initial.omega"][c] - b
        out["angular-velocity requirement"] = (
            ("control.omega.b", "control.omega.sigma", gain_key, "initial.omega"),
            np.concatenate([b * sigma, gain @ e]),
        )
    if "control.masses.l" in v:
        i = list(scene.control.masses.indices)
        l, lam = v["control.masses.l"], v["control.masses.lambda"]
        err = v["initial.p"][i] - v["masses.p_e"][i] - l
        out["mass-position requirement"] = (
            (
                "control.masses.l",
                "control.masses.lambda",
                "control.masses.alpha",
                "control.masses.beta",
                "initial.p",
                "initial.pdot",
                "masses.p_e",
            ),
            np.concatenate(
                [
                    l * lam,
                    l * lam * lam,
                    v["control.masses.alpha"] * v["initial.pdot"][i],
                    v["control.masses.beta"] * err,
                ]
            ),
        )
    return out


def _blame(scene: Scene, fields: dict[str, np.ndarray], name: str, feeds: tuple[str, ...]) -> str:
    """The field that makes the quantity ``name`` overflow: the first (largest first) whose
    values, brought within [-1, 1], make it finite; else the largest."""
    order = sorted(dict.fromkeys(feeds), key=lambda k: -float(np.max(np.abs(fields[k]), initial=0)))
    for key in order:
        trial = dict(fields)
        trial[key] = np.clip(fields[key], -1.0, 1.0)
        if np.all(np.isfinite(derived_quantities(scene, trial)[name][1])):
            return key
    return order[0]


def check_initial_quantities(scene: Scene) -> None:
    """Refuse a scene whose initial state, energy, momenta, generalized force, acceleration or
    control requirement is not finite although every field is: ``ValueError`` naming the field
    that makes it overflow, its value, and the fields the quantity is computed from."""
    fields = initial_fields(scene)
    with np.errstate(all="ignore"):
        for name, (feeds, value) in derived_quantities(scene, fields).items():
            if np.all(np.isfinite(value)):
                continue
            key = _blame(scene, fields, name, feeds)
            got = fields[key].tolist()
            got = got[0] if len(got) == 1 and not isinstance(got[0], list) else got
            raise ValueError(
                f"{key}: makes the initial {name} overflow the double range (got {show(got)}; "
                f"it is computed from {', '.join(dict.fromkeys(feeds))})"
            )


__all__ = ["check_initial_quantities", "derived_quantities", "initial_fields"]
