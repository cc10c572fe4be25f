"""A plant of its own: Newton-Euler equations of the body and the masses, scipy's integrators.

The analytic plant integrates the paper's quaternion coordinates under the fundamental equation.
This plant shares none of that: its state is ``[R, u, Ṙ, ω (body), p, ṗ]``, the attitude moved by
``u̇ = ½ u ⊗ (0, ω)``, and each right-hand side solves the ``6 + n`` Newton-Euler equations for
``[R̈ (body axes), ω̇, p̈]``:

* all of it, linear: ``m_T R̈ + Σ m_i (ω̇ × ρ_i + p̈_i a + c_i) = m_T g + F_C``;
* all of it, turning about C: ``J ω̇ + ω × Jω + Σ ρ_i × m_i (r̈_i - g) = τ + τ_g``;
* mass i along its rod: ``m_i a · (r̈_i - g) = F_i + F^S_i``;

with ``ρ_i = p_i a + d``, ``r̈_i = R̈ + ω̇ × ρ_i + p̈_i a + c_i`` and
``c_i = ω × (ω × ρ_i) + 2 ṗ_i ω × a`` (body axes), ``J`` the body's inertia (plus the masses' own
with ``mass_inertia``), ``F^S_i`` the spring chain's force on mass i. The controller is the
project's one (``FastModel``), evaluated at this plant's state mapped to the paper's coordinates;
the plant applies its torque ``τ``, rod forces ``F_i`` and force at C ``F_C``. The work and the
impulses that the balances check ride along as quadratures, computed here in numpy.

:class:`SlippedNewtonPlant` is the same engine with the Coriolis term ``2 ṗ_i ω × a`` dropped: a
deliberately wrong plant that the referee must name the outlier.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from analytic.effects import Effect, SolverMethod
from analytic.plant import Plant, check_positive, coerce_enum, tighter_rtol

MAX_MASSES = 64
"""The most masses this plant takes: it solves a dense ``(6 + n)²`` system per evaluation."""


@dataclass(frozen=True)
class NewtonSettings:
    """How the Newton-Euler plant integrates: a scipy method and its tolerances."""

    method: SolverMethod = SolverMethod.DOP853
    rtol: float = 1e-12
    atol: float = 1e-13

    def __post_init__(self) -> None:  # bad settings: a ValueError naming the field and the value
        coerce_enum(self, "method", SolverMethod)
        check_positive(self, "rtol")
        check_positive(self, "atol")


def rotation(u: np.ndarray) -> np.ndarray:
    """Body -> inertial rotation of the w-first quaternion ``u``."""
    w, x, y, z = u
    return 2.0 * np.array(
        [
            [w * w + x * x - 0.5, x * y - w * z, x * z + w * y],
            [x * y + w * z, w * w + y * y - 0.5, y * z - w * x],
            [x * z - w * y, y * z + w * x, w * w + z * z - 0.5],
        ]
    )


def quat_times_vector(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``u ⊗ (0, v)``."""
    w, x, y, z = u
    return np.array(
        [
            -x * v[0] - y * v[1] - z * v[2],
            w * v[0] + y * v[2] - z * v[1],
            w * v[1] + z * v[0] - x * v[2],
            w * v[2] + x * v[1] - y * v[0],
        ]
    )


def cross_matrix(v: np.ndarray) -> np.ndarray:
    """``[v]×`` with ``[v]× w = v × w``; v shape (..., 3)."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


class NewtonEulerPlant(Plant):
    """The body and the masses by Newton-Euler (module docstring), under the project's controller."""

    engine = "newton"
    label = "Newton-Euler"
    settings_type = NewtonSettings
    effects = frozenset(  # what its equations below implement, each by name
        {
            Effect.GRAVITY,
            Effect.SPRINGS_LINEAR,
            Effect.SPRINGS_CUBIC,
            Effect.MASS_INERTIA,
            Effect.EXTERNAL_TORQUE,
            Effect.CONTROL_OMEGA,
            Effect.CONTROL_MASSES,
        }
    )
    coriolis = 2.0
    """The factor of ``ṗ_i ω × a`` in the masses' acceleration: 2 (the physics)."""

    def default_settings(self, scene) -> NewtonSettings:
        return NewtonSettings(scene.solver.method, scene.solver.rtol, scene.solver.atol)

    def describe(self, settings: NewtonSettings) -> str:
        return f"{self.label} {settings.method.value} rtol {settings.rtol:g}"

    def tightened(self, scene, settings: NewtonSettings) -> NewtonSettings | None:
        tight = tighter_rtol(settings.rtol, settings.atol)  # tolerances / TIGHTER_RTOL, floored
        return (
            None if tight is None else dataclasses.replace(settings, rtol=tight[0], atol=tight[1])
        )

    def check_scene(self, scene) -> None:
        super().check_scene(scene)  # the effects
        if scene.n > MAX_MASSES:
            raise ValueError(
                f"masses.mass: the {self.engine} plant holds at most {MAX_MASSES} masses "
                f"(got {scene.n})"
            )

    def _simulate(self, scene, settings, t_end, progress):
        from analytic.assemble import N_AUX, assemble
        from analytic.fast import FastModel
        from analytic.stepping import NonFinite, step_and_sample

        fast = FastModel(scene)  # the controller (compiled; FastModel.model is the numpy model)
        n = scene.n
        m, a, d = np.array(scene.masses.mass), np.array(scene.rod.axis), np.array(scene.rod.offset)
        m_T = float(scene.body.mass) + float(m.sum())
        J = np.diag(np.array(scene.body.inertia, dtype=float))
        if scene.has(Effect.MASS_INERTIA) and n:
            J = J + scene.masses.inertia.sum(axis=0)
        g = np.array(scene.gravity) if scene.has(Effect.GRAVITY) else np.zeros(3)
        k_l = np.array(scene.springs.k_linear) if scene.has(Effect.SPRINGS_LINEAR) else None
        k_n = np.array(scene.springs.k_cubic) if scene.has(Effect.SPRINGS_CUBIC) else None
        p_e = np.array(scene.masses.p_e)
        torque_g = scene.has(Effect.EXTERNAL_TORQUE)
        axd = np.cross(a, d)
        nfev = [0]

        def spring_forces(p):
            """The spring chain's force on each mass: spring i joins mass i-1 and mass i."""
            ext = np.diff(np.concatenate([[0.0], p - p_e, [0.0]]))
            f = np.zeros(n + 1)
            if k_l is not None:
                f += k_l * ext
            if k_n is not None:
                f += k_n * ext**3
            return f[1:] - f[:-1]

        def paper(y):
            """``(q, q̇)`` of this plant's state ``y``, in the paper's coordinates (Eq. 44)."""
            u, omega = y[3:7], y[10:13]
            q = np.concatenate([y[0:3], u, y[13 : 13 + n]])
            qdot = np.concatenate(
                [y[7:10], 0.5 * quat_times_vector(u, omega), y[13 + n : 13 + 2 * n]]
            )
            return q, qdot

        def control(t, y):
            """``(τ + τ_g, F, F_C)`` of the project's controller at this state."""
            if scene.controlled:
                q, qdot = paper(y)
                _, tau, rod, f_c, _ = fast.qddot_and_forces(t, q, qdot)
                tau, rod, f_c = tau.copy(), rod.copy(), f_c.copy()
            else:
                tau, rod, f_c = np.zeros(3), np.zeros(n), np.zeros(3)
            if torque_g:
                tau = tau + scene.external_torque.at(t)
            return tau, rod, f_c

        def accelerations(t, y):
            """``R̈`` (inertial), ``ω̇``, ``p̈`` from the Newton-Euler equations, and the control."""
            u, omega, p, pd = y[3:7], y[10:13], y[13 : 13 + n], y[13 + n : 13 + 2 * n]
            S = rotation(u)
            tau, rod, f_c = control(t, y)
            gb = S.T @ g
            rho = np.outer(p, a) + d  # (n, 3), body axes
            c = np.cross(omega, np.cross(omega, rho)) + self.coriolis * np.outer(
                pd, np.cross(omega, a)
            )
            X = cross_matrix(rho)  # [ρ_i]×
            A = np.zeros((6 + n, 6 + n))
            b = np.zeros(6 + n)
            A[0:3, 0:3] = m_T * np.eye(3)  # linear
            A[0:3, 3:6] = -np.einsum("i,ijk->jk", m, X)
            A[0:3, 6:] = np.outer(a, m)
            b[0:3] = m_T * gb + S.T @ f_c - m @ c
            A[3:6, 0:3] = np.einsum("i,ijk->jk", m, X)  # turning about C
            A[3:6, 3:6] = J - np.einsum("i,ijk,ikl->jl", m, X, X)
            A[3:6, 6:] = (X @ a).T * m
            b[3:6] = (
                tau - np.cross(omega, J @ omega) - np.einsum("i,ij->j", m, np.cross(rho, c - gb))
            )
            A[6:, 0:3] = np.outer(m, a)  # each mass along its rod
            A[6:, 3:6] = -np.outer(m, axd)  # a · (ω̇ × ρ_i) = ω̇ · (d × a)
            A[6:, 6:] = np.diag(m * (a @ a))
            b[6:] = m * (gb @ a) + rod + spring_forces(p) - m * (c @ a)
            z = np.linalg.solve(A, b)
            return S @ z[0:3], z[3:6], z[6:], tau, rod, f_c, S

        def f(t, y):
            nfev[0] += 1
            u, V, omega = y[3:7], y[7:10], y[10:13]
            p, pd = y[13 : 13 + n], y[13 + n : 13 + 2 * n]
            acc, omega_dot, pdd, tau, rod, f_c, S = accelerations(t, y)
            arm = -S @ (float(m @ p) * a + float(m.sum()) * d) / m_T  # R - c
            rates = np.concatenate(
                [
                    [tau @ omega + rod @ pd + f_c @ V],  # Ẇ
                    S @ tau + np.cross(arm, f_c),  # İ_L
                    f_c,  # İ_P
                ]
            )
            out = np.concatenate(
                [V, 0.5 * quat_times_vector(u, omega), acc, omega_dot, pd, pdd, rates]
            )
            if not np.all(np.isfinite(out)):
                raise NonFinite(f"non-finite Newton-Euler rates at t = {t:.6g} s")
            return out

        init = scene.initial
        y0 = np.concatenate(
            [init.R, init.u, init.Rdot, init.omega, init.p, init.pdot, np.zeros(N_AUX)]
        )
        times = scene.output.with_t_end(t_end).times()
        run = step_and_sample(
            f,
            times,
            y0,
            method=settings.method,
            rtol=settings.rtol,
            atol=settings.atol,
            n_motion=13 + 2 * n,
            max_step=scene.solver.max_step,
            progress=progress,
        )
        qs, qdots, qddots, controls = [], [], [], []
        for t, y in zip(run.t, run.y, strict=True):
            q, qdot = paper(y)
            acc, omega_dot, pdd, *_ = accelerations(t, y)
            u, omega = y[3:7], y[10:13]
            udd = 0.5 * (quat_times_vector(qdot[3:7], omega) + quat_times_vector(u, omega_dot))
            qs.append(q)
            qdots.append(qdot)
            qddots.append(np.concatenate([acc, udd, pdd]))
            controls.append(fast.acceleration(t, q, qdot)[1] if scene.controlled else None)
        info = {
            "formulation": "Newton-Euler",
            "solver": settings.method.value,
            "rtol": settings.rtol,
            "atol": settings.atol,
            "nfev": nfev[0],
            "nsteps": run.nsteps,
            "wall_time_s": run.wall_time_s,
        }
        return assemble(
            fast.model,
            self.engine,
            run.t,
            np.array(qs),
            np.array(qdots),
            np.array(qddots),
            controls,
            run.y[:, 13 + 2 * n :],
            run.status,
            run.message,
            info,
            omega=run.y[:, 10:13],
        )


class SlippedNewtonPlant(NewtonEulerPlant):
    """The Newton-Euler plant with the Coriolis term of the masses dropped: deliberately wrong."""

    engine = "newton_slip"
    label = "Newton-Euler (slipped)"
    default = False  # asked for by name only
    coriolis = 0.0
