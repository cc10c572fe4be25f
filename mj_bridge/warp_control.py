"""The project's controller for N worlds at once, on the host, in float32: what the MuJoCo Warp
plant applies in every integrator stage, and the work and impulses it does there.

:class:`HostController` holds N scenes of one structure (the same
:class:`analytic.array_model.Structure`: n, effects, controlled components, weighting). At the
engine's N stage states (MuJoCo ``qpos`` (N, n+7), ``qvel`` (N, n+6), float32, BR's body frame at
C; times ``t`` (N,) s) :meth:`HostController.stage` gives what the C plant's stages write
(:mod:`mj_bridge.stages`): the actuators' ``ctrl`` (N, nu) = ``(τ + τ_g) · INV_GEAR`` on
``torque_x..z`` and ``F · INV_GEAR`` on ``force1..N``, the inertial force at C ``F_C`` (N, 3) N for
BR's ``xfrc_applied``, and the quadratures' rates (N, 7) ``[Ẇ, İ_L (3), İ_P (3)]``
(:func:`mj_bridge.accelerated_scheme.quadrature_rates`).

The control law is the project's one array form (:mod:`analytic.array_model`, numpy), evaluated
for all worlds in one call in **float32**, the engine's precision, from the float32 state (mapped
by :func:`mj_bridge.accelerated_scheme.paper_state`); the quadratures' rates are computed in
float64 from those float32 values (the plant sums them over a run in float64).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from analytic import array_model as am
from analytic.scene import Scene
from mj_bridge.accelerated_scheme import StageConstants, paper_state, quadrature_rates
from mj_bridge.twin_model import TwinModel

DTYPE = np.float32
"""The controller's precision: MuJoCo Warp's."""


def _stacked_constants(consts: Sequence[StageConstants], dtype) -> dict[str, Any]:
    """:meth:`StageConstants.arrays` of N worlds stacked, the scalars as (N, 1) to broadcast."""
    out = {}
    for k in ("a", "d", "m", "mu0", "m_T"):
        v = np.stack([np.asarray(getattr(c, k), dtype=dtype) for c in consts])
        out[k] = v[:, None] if v.ndim == 1 else v
    out["P_tau"] = np.asarray(consts[0].P_tau, dtype=dtype)  # one twin layout: the same maps
    out["P_rod"] = np.asarray(consts[0].P_rod, dtype=dtype)
    return out


class HostController:
    """The controller of N worlds (module docstring); ``scenes`` share one structure, ``tms``
    their twins."""

    def __init__(self, scenes: Sequence[Scene], tms: Sequence[TwinModel]):
        self.structure = am.structure_of(scenes[0])
        for i, s in enumerate(scenes):
            if am.structure_of(s) != self.structure:
                raise ValueError(f"scenes[{i}]: its structure differs from scenes[0]'s")
        self.N = len(scenes)
        self.params = am.stack_parameters([am.parameters(s, np, DTYPE) for s in scenes], np)
        consts = [StageConstants.of(s, tm) for s, tm in zip(scenes, tms, strict=True)]
        self.c32 = _stacked_constants(consts, DTYPE)
        self.c64 = _stacked_constants(consts, np.float64)

    def stage(
        self, t: np.ndarray, qpos: np.ndarray, qvel: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ctrl (N, nu) float32, F_C (N, 3) float32, rates (N, 7) float64)`` at the N
        worlds' states (module docstring)."""
        st, p = self.structure, self.params
        t32 = np.asarray(t, dtype=DTYPE)
        q, qdot = paper_state(np, qpos.astype(DTYPE, copy=False), qvel.astype(DTYPE, copy=False))
        tau, rod, fC = am.control_forces(np, st, p, t32, q, qdot)
        tau = np.broadcast_to(tau, (self.N, 3)) + am.given_torque(np, st, p, t32)
        ctrl = tau @ self.c32["P_tau"] + rod @ self.c32["P_rod"]
        f64 = np.float64
        rates = quadrature_rates(
            np, self.c64, q.astype(f64), qdot.astype(f64), qvel[:, 3:6].astype(f64),
            tau.astype(f64), np.broadcast_to(rod, (self.N, st.n)).astype(f64), fC.astype(f64),
        )  # fmt: skip
        return ctrl.astype(DTYPE, copy=False), np.broadcast_to(fC, (self.N, 3)), rates


__all__ = ["DTYPE", "HostController"]
