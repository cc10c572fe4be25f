"""An attitude quaternion off the unit sphere: the closed form of its norm error under the
stabilised constraint, and the loader's refusal of such a start unless it is allowed.

Eq. (58) makes ``φ = uᵀu - 1`` solve ``φ̈ + δ1 φ̇ + δ2 φ = 0`` exactly, whatever the forces, from
``φ(0) = |u(0)|² - 1`` and ``φ̇(0) = 2 u(0)·u̇(0)``.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

from analytic.scene import Scene, scene_from_dict

REFUSED_FIELD = "initial.attitude.quaternion"
"""The field the loader names when it refuses an off-unit start."""


def norm_error_closed_form(
    t: np.ndarray, phi0: float, phidot0: float, d1: float, d2: float
) -> np.ndarray:
    """Solution of ``φ̈ + δ1 φ̇ + δ2 φ = 0`` (Eq. 58) from φ(0), φ̇(0) at the times ``t`` (s,
    from 0), shape (N,)."""
    r = np.roots([1.0, d1, d2]).astype(complex)
    A = np.array([[1, 1], [r[0], r[1]]], dtype=complex)
    c = np.linalg.solve(A, np.array([phi0, phidot0], dtype=complex))
    return np.real(c[0] * np.exp(r[0] * t) + c[1] * np.exp(r[1] * t))


def norm_error_reference(scene: Scene, t: np.ndarray) -> np.ndarray:
    """``φ(t)`` of the scene's initial u, u̇ and ``δ1, δ2``, shape (N,)."""
    u0, ud0 = scene.initial.u, scene.initial.udot
    return norm_error_closed_form(
        t,
        float(u0 @ u0) - 1.0,
        2.0 * float(u0 @ ud0),
        scene.stabilization.delta1,
        scene.stabilization.delta2,
    )


def refused_unless_allowed(path: Path) -> bool:
    """Whether the loader refuses the scene file at ``path`` (a built-in hard case) once its
    ``initial.attitude.allow_off_manifold`` is removed, naming ``initial.attitude.quaternion``."""
    data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    data["initial"]["attitude"].pop("allow_off_manifold", None)
    try:
        scene_from_dict(data)
    except ValueError as exc:
        return str(exc).startswith(REFUSED_FIELD)
    return False


__all__ = [
    "REFUSED_FIELD",
    "norm_error_closed_form",
    "norm_error_reference",
    "refused_unless_allowed",
]
