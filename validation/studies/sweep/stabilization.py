"""The stabilisation study: the quaternion norm error under several (δ1, δ2) (Eq. 58).

``φ = uᵀu − 1`` obeys ``φ̈ + δ1 φ̇ + δ2 φ = 0``: started off the unit sphere it decays only when
δ1, δ2 > 0. One analytic run (DOP853) per (δ1, δ2, rtol, initial offset), a task of its own.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from analytic.scene import Scene, Stabilization
from validation.studies.sweep import running


def stabilization_row(
    scene: Scene, delta1: float, delta2: float, rtol: float, offset: float, t_end: float
) -> dict[str, Any]:
    """Quaternion norm error of one analytic run with (δ1, δ2), initial |u| = 1 + ``offset``."""
    u0 = scene.initial.u * (1.0 + offset)
    sc = scene.replace(
        stabilization=Stabilization(delta1=delta1, delta2=delta2),
        initial=dataclasses.replace(scene.initial, u=u0),
    )
    tr = running.analytic_run(sc, "DOP853", rtol, rtol * 0.1, t_end)
    e = tr.invariants.quat_norm_error
    return {
        "delta1": delta1,
        "delta2": delta2,
        "rtol": rtol,
        "initial_norm_error": float(u0 @ u0 - 1.0),
        "status": tr.status.value,
        "quat_norm_error_final": float(e[-1]),
        "quat_norm_error_max": float(np.max(np.abs(e))),
        "quat_norm_error_at_steps_max": float(tr.info["max_quat_norm_error_at_steps"]),
        "nfev": int(tr.info["nfev"]),
        "t_end": float(tr.t[-1]),
    }


__all__ = ["stabilization_row"]
