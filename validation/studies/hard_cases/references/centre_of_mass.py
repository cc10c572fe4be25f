"""The system's centre of mass moves in closed form: no force but uniform gravity acts on the
system as a whole (springs and the rod's reactions are internal), so ``c(t) = c0 + ċ0 t + g t²/2``;
and the energy in the frame of c is conserved on its own.

:func:`system_com` and :func:`initial_com_velocity` use rotation matrices from
:func:`model_xml.rotations.quat_to_mat`, not the paper's ``S(u)``; :func:`split_energy` uses the
model's mass kinematics (it is a decomposition of the model's energy, checked against the
invariants by the tests).
"""

from __future__ import annotations

import numpy as np

from analytic.effects import Effect
from analytic.invariants import mass_kinematics
from analytic.kinematics import omega_of
from analytic.model import TumblingModel, spring_energy
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from model_xml.rotations import quat_to_mat


def gravity(scene: Scene) -> np.ndarray:
    """The scene's uniform gravity, m/s², inertial, shape (3,) (zero when the effect is off)."""
    return np.asarray(scene.gravity, float) if scene.has(Effect.GRAVITY) else np.zeros(3)


def system_com(scene: Scene, q: np.ndarray) -> np.ndarray:
    """Centre of mass of the whole system, ``R + S (Σ m_i (p_i a + d)) / m_T``, m, inertial,
    q shape (N, n+7) -> (N, 3)."""
    m = np.asarray(scene.masses.mass)
    mT = scene.body.mass + m.sum()
    a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
    out = np.empty((q.shape[0], 3))
    for k in range(q.shape[0]):
        out[k] = q[k, :3] + quat_to_mat(q[k, 3:7]) @ (float(m @ q[k, 7:]) * a + m.sum() * d) / mT
    return out


def initial_com_velocity(scene: Scene) -> np.ndarray:
    """``ċ(0)``, m/s, inertial, from the initial state (ω in body axes):
    ``Ṙ + S (ω × r̄ + Σ m_i ṗ_i a / m_T)`` with ``r̄ = Σ m_i (p_i a + d) / m_T``."""
    ini = scene.initial
    m = np.asarray(scene.masses.mass)
    mT = scene.body.mass + m.sum()
    a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
    rbar = (float(m @ ini.p) * a + m.sum() * d) / mT
    vbar = float(m @ ini.pdot) * a / mT
    return ini.Rdot + quat_to_mat(ini.u) @ (np.cross(ini.omega, rbar) + vbar)


def com_path(scene: Scene, t: np.ndarray) -> np.ndarray:
    """``c0 + ċ0 t + g t²/2`` from the scene's initial state, m, inertial, shape (N, 3)."""
    c0 = system_com(scene, scene.initial.q0()[None, :])[0]
    t = np.asarray(t, float) - float(t[0])
    return c0 + np.outer(t, initial_com_velocity(scene)) + 0.5 * np.outer(t**2, gravity(scene))


def split_energy(scene: Scene, tr: Trajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Energy in the frame of the system's centre of mass, and the centre of mass itself.

    Under uniform gravity ``E = E_int + (½ m_T |ċ|² - m_T g·c)``, each part conserved on its own.
    Over a long fall the second part's two terms grow huge and cancel (1000 s: 6.5e13 J each,
    against E = 3.9e8 J), so the total energy's relative drift measures the round-off of a 9.8 km/s
    velocity rather than the dynamics. ``E_int`` is computed from velocities relative to ``ċ``
    (gravity does no work in that frame), free of that cancellation:
    ``E_int = ½ ωᵀJω + ½ m_BR |Ṙ - ċ|² + Σ ½ m_i |ṙ_i - ċ|² + U_s``.

    Returns:
        ``E_int`` (N,), J; ``c`` (N, 3) and ``ċ`` (N, 3), inertial, m and m/s.
    """
    model = TumblingModel(scene)
    r, rd, _ = mass_kinematics(model, tr.q, tr.qdot)
    m_T = model.m_T
    c = (model.m_BR * tr.q[:, :3] + np.einsum("i,nij->nj", model.m, r)) / m_T
    cd = (model.m_BR * tr.qdot[:, :3] + np.einsum("i,nij->nj", model.m, rd)) / m_T
    w = omega_of(tr.u, tr.qdot[:, 3:7])
    vR = tr.qdot[:, :3] - cd
    vi = rd - cd[:, None, :]
    E_int = (
        0.5 * np.einsum("ni,ij,nj->n", w, model.J, w)
        + 0.5 * model.m_BR * np.sum(vR * vR, axis=1)
        + 0.5 * np.einsum("i,nij,nij->n", model.m, vi, vi)
        + spring_energy(model, tr.p)
    )
    return E_int, c, cd


__all__ = ["com_path", "gravity", "initial_com_velocity", "split_energy", "system_com"]
