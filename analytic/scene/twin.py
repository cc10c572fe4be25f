"""What the MuJoCo twin can represent, checked when a scene is loaded so that a scene is refused
naming its field, rather than by MuJoCo's compiler after the analytic plant has run.

The numbers and the one formula of the inertia the twin lends each point mass
(:func:`twin_point_inertia`) live here, below both the loader and ``model_xml`` (which builds the
twin from them): the loader cannot import ``model_xml`` (the layer rule of
``tests/cross/test_layers.py``), and the refusal stays at load (a scene MuJoCo cannot compile is
refused by every command, before any plant runs).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from analytic.effects import Effect
from analytic.scene.limits import GRID_RTOL, MAX_MASS, MAX_MUJOCO_STEPS

if TYPE_CHECKING:
    from analytic.scene.records import SceneRecord as Scene

# MuJoCo's mjMINVAL: its compiler refuses a moving body whose mass or any principal moment of
# inertia is below this (and one whose moments violate A + B >= C, checked exactly).
MJ_MINVAL = 1e-15
# model_xml gives each mass body without an inertia of its own an isotropic inertia
# eps = max(POINT_INERTIA_REL · min(J_BR), POINT_INERTIA_MIN) (MuJoCo refuses it without) and takes
# exactly that much off BR's principal moments, so the system's inertia is unchanged
# (model_xml.builder imports these two).
POINT_INERTIA_REL = 1e-9
POINT_INERTIA_MIN = 1e-12
# A mass's principal moments may violate A + B >= C by this much relative round-off (a ring's
# A + B = C after an eigen-decomposition); model_xml sets C = A + B then. Beyond it, MuJoCo refuses.
TRIANGLE_RTOL = 1e-12


def mass_in_range(x: float, name: str) -> float:
    if x < MJ_MINVAL:
        raise ValueError(
            f"{name}: must be at least {MJ_MINVAL:g} kg (MuJoCo's mjMINVAL: its compiler refuses "
            f"a lighter moving body) (got {x!r})"
        )
    if x > MAX_MASS:
        raise ValueError(f"{name}: must be at most {MAX_MASS:g} kg (got {x!r})")
    return x


def twin_point_inertia(scene: Scene) -> tuple[float, int]:
    """The isotropic inertia ``eps`` (kg·m²) that the MuJoCo twin gives each mass body without an
    inertia of its own, and how many masses get it (``model_xml.builder.mass_inertias``: the
    total ``count · eps`` is taken off BR's principal moments)."""
    eps = max(POINT_INERTIA_REL * float(np.min(scene.body.inertia)), POINT_INERTIA_MIN)
    if not scene.has(Effect.MASS_INERTIA):
        return eps, scene.n
    count = sum(1 for J in scene.masses.inertia if float(np.min(np.linalg.eigvalsh(J))) <= eps)
    return eps, count


def check_body_for_mujoco(scene: Scene) -> None:
    """BR's principal moments as the MuJoCo twin compiles them (less the point masses' padding):
    at least mjMINVAL each and A + B >= C exactly, as MuJoCo's compiler requires."""
    eps, count = twin_point_inertia(scene)
    J = np.asarray(scene.body.inertia, float)
    pad = eps * count
    Jp = J - pad  # as model_xml.builder computes them
    for i in range(3):
        if not Jp[i] >= MJ_MINVAL:
            given = f"less the {pad:.3g} kg·m² given to {count} point masses, " if count else ""
            raise ValueError(
                f"body.inertia[{i}]: too small for the MuJoCo twin: {given}below "
                f"mjMINVAL = {MJ_MINVAL:g} kg·m², which MuJoCo's compiler refuses "
                f"(got {float(J[i])!r})"
            )
    a, b, c = np.sort(Jp)
    if a + b < c:
        raise ValueError(
            f"body.inertia: principal moments {J.tolist()!r} leave no room for the {pad:.3g} kg·m² "
            f"the MuJoCo twin gives {count} point masses (A + B - C must be at least that, so "
            "that MuJoCo's A + B >= C holds)"
        )


def check_horizon_fits_mujoco(scene: Scene) -> None:
    """The scene's own horizon against its MuJoCo step: at least one step, at most
    MAX_MUJOCO_STEPS (the plants check overrides of t_end and dt themselves)."""
    t_end, dt = scene.output.t_end, scene.mujoco.timestep
    if t_end < dt * (1 - GRID_RTOL):
        raise ValueError(
            f"output.t_end: shorter than one MuJoCo step (mujoco.timestep = {dt!r} s) "
            f"(got {t_end!r})"
        )
    steps = t_end / dt
    if steps > MAX_MUJOCO_STEPS:
        field_name = "output.t_end" if t_end / 20.0 >= 2.5e-4 / dt else "mujoco.timestep"
        raise ValueError(
            f"{field_name}: {t_end:g} s at mujoco.timestep = {dt:g} s is {steps:.3g} MuJoCo steps, "
            f"at most {MAX_MUJOCO_STEPS:,} (got {t_end if field_name == 'output.t_end' else dt!r})"
        )


__all__ = [
    "MJ_MINVAL",
    "POINT_INERTIA_MIN",
    "POINT_INERTIA_REL",
    "TRIANGLE_RTOL",
    "check_body_for_mujoco",
    "check_horizon_fits_mujoco",
    "mass_in_range",
    "twin_point_inertia",
]
