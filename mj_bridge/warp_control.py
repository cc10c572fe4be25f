"""The project's controller for N worlds at once, on the host: what the MuJoCo Warp plant applies
in every integrator stage, and the work and impulses it does there.

:class:`HostController` holds N scenes of one structure (same n, same effects). At N states in the
paper's coordinates (``t`` (N,) s, ``q``, ``q̇`` (N, n+7)) :meth:`HostController.forces` gives the
channels a plant applies, as the C plant's stages (:mod:`mj_bridge.stages`): the body-axis torque
``τ + τ_g`` (N, 3) N·m (control plus the given torque), the rod forces ``F`` (N, n) N and the
inertial force at C ``F_C`` (N, 3) N; zeros where the scene has no such effect.
:meth:`HostController.rates` gives the quadratures' rates at those states (N, 7):
``[power (τ+τ_g)·ω + F·ṗ + F_C·Ṙ (W), moment S(u)(τ+τ_g) + (R − c) × F_C about the system's centre
of mass (inertial, N·m), F_C (N)]``, the terms the C plant's stages accumulate.

The control law itself is the project's one: the compiled analytic controller
(:class:`analytic.fast.FastModel`) of each world, float64, at the state the engine gives.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from analytic.effects import Effect
from analytic.scene import Scene
from model_xml.coordinates import rotation_rows


class HostController:
    """The controller of N worlds (module docstring); ``scenes`` share one structure."""

    def __init__(self, scenes: Sequence[Scene]):
        from analytic.fast import FastModel

        self.scenes = list(scenes)
        s0 = self.scenes[0]
        self.n = s0.n
        self.N = len(self.scenes)
        self.controlled = s0.controlled
        self.has_torque = s0.has(Effect.EXTERNAL_TORQUE)
        self.fast = [FastModel(s) for s in self.scenes] if self.controlled else []
        models = [FastModel(s).model for s in self.scenes] if not self.fast else [
            f.model for f in self.fast
        ]  # fmt: skip
        self.models = models
        self.m = np.array([md.m for md in models]).reshape(self.N, self.n)
        self.a = np.array([md.a for md in models])
        self.d = np.array([md.d for md in models])
        self.mu0 = np.array([md.mu0 for md in models])
        self.m_T = np.array([md.m_T for md in models])

    def forces(
        self, t: np.ndarray, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(τ + τ_g (N, 3), F (N, n), F_C (N, 3))`` at N paper states (module docstring)."""
        N, n = self.N, self.n
        tau = np.zeros((N, 3))
        rod = np.zeros((N, n))
        fC = np.zeros((N, 3))
        if self.controlled:
            for w, fm in enumerate(self.fast):
                _, tq, F, f, _ = fm.qddot_and_forces(float(t[w]), q[w], qdot[w])
                tau[w], rod[w], fC[w] = tq, F, f
        if self.has_torque:
            for w, md in enumerate(self.models):
                tau[w] += md.given_torque(float(t[w]))
        return tau, rod, fC

    def rates(
        self,
        q: np.ndarray,
        qdot: np.ndarray,
        omega: np.ndarray,
        tau: np.ndarray,
        rod: np.ndarray,
        fC: np.ndarray,
    ) -> np.ndarray:
        """The quadratures' rates (N, 7) at N paper states, ``omega`` (N, 3) body axes, under
        ``forces``' output (module docstring)."""
        Sm = rotation_rows(q[:, 3:7])
        power = (
            np.einsum("ij,ij->i", tau, omega)
            + np.einsum("ij,ij->i", rod, qdot[:, 7:])
            + np.einsum("ij,ij->i", fC, qdot[:, :3])
        )
        moment = np.einsum("nij,nj->ni", Sm, tau)
        if np.any(fC):
            mp = np.einsum("ij,ij->i", self.m, q[:, 7:])
            arm = (
                -(
                    mp[:, None] * np.einsum("nij,nj->ni", Sm, self.a)
                    + self.mu0[:, None] * np.einsum("nij,nj->ni", Sm, self.d)
                )
                / self.m_T[:, None]
            )
            moment = moment + np.cross(arm, fC)
        return np.concatenate([power[:, None], moment, fC], axis=1)


__all__ = ["HostController"]
