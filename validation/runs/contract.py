"""What a plant is given and what it must give back, checked in one place.

A plant (a built-in or a plugin, ``docs/plugins.md``) is code this tool does not trust with
anything but its own run:

* :func:`plant_scene` is the scene a plant is given: a copy of its own, every array in it
  read-only, so a plant that changes what it is given (an inertia doubled in place, a name or a
  horizon set with ``object.__setattr__``) changes its own copy only, never the run's scene, its
  report or another plant's input.
* :func:`contract_problem` is what a plant's return value must be before it is compared: a
  :class:`analytic.trajectory.Trajectory` under the plant's own name, every array of the shape the
  scene's coordinates give it, its times a prefix of the scene's output grid up to the horizon
  (all of it for a run whose status is ``ok``), and finite values in a run that says it is ``ok``.
  A run that breaks it is that plant's failure (:class:`ContractError`), said in one line naming the
  plant; it is never compared, so it cannot stand in for another plant or break the comparison.

Used by every job that takes plant trajectories: ``tumble validate`` and ``tumble judge``
(:mod:`validation.validate`) and the fuzzer (:mod:`validation.studies.fuzz.judge`).
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import numpy as np

from analytic.scene import Scene, output_times
from analytic.trajectory import RunStatus, Trajectory

GRID_TOL = 1e-9
"""How far a returned sample time may sit from its output-grid time, relative to
``max(1, |t|)``: round-off, far below the grid's spacing (at most 1e6 Hz)."""


class ContractError(ValueError):
    """A plant's return value breaks the plant contract (:func:`contract_problem` says how)."""


def _read_only(obj: Any) -> Any:
    """``obj`` (a deep copy, made by the caller) with every array in it read-only, walked
    through dataclasses, tuples, lists and dicts."""
    if isinstance(obj, np.ndarray):
        obj.setflags(write=False)
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            _read_only(getattr(obj, f.name))
    elif isinstance(obj, tuple | list):
        for x in obj:
            _read_only(x)
    elif isinstance(obj, dict):
        for x in obj.values():
            _read_only(x)
    return obj


def plant_scene(scene: Scene) -> Scene:
    """A copy of ``scene`` for one plant's run: equal to it, sharing no array with it, every array
    read-only (a plant's change to it stays in its copy)."""
    return _read_only(copy.deepcopy(scene))


def _shape_problem(name: str, a: Any, shape: tuple[int, ...]) -> str:
    if not isinstance(a, np.ndarray):
        return f"{name} is a {type(a).__name__}, not a numpy array"
    if a.shape != shape:
        return f"{name} has shape {a.shape}, not {shape}"
    if not np.issubdtype(a.dtype, np.number) or np.iscomplexobj(a):
        return f"{name} has dtype {a.dtype}, not a real number type"
    return ""


def _arrays(tr: Trajectory, n: int, rows: int) -> list[tuple[str, Any, tuple[int, ...]]]:
    """Every array of ``tr`` with the shape it must have (``rows`` samples, ``n`` masses)."""
    dof = n + 7
    inv, trk = tr.invariants, tr.tracking
    return [
        ("q", tr.q, (rows, dof)),
        ("qdot", tr.qdot, (rows, dof)),
        ("qddot", tr.qddot, (rows, dof)),
        ("QC", tr.QC, (rows, dof)),
        ("torque", tr.torque, (rows, 3)),
        ("rod_forces", tr.rod_forces, (rows, n)),
        ("force_at_C", tr.force_at_C, (rows, 3)),
        ("residual_norm", tr.residual_norm, (rows,)),
        ("invariants.quat_norm_error", inv.quat_norm_error, (rows,)),
        ("invariants.linear_momentum", inv.linear_momentum, (rows, 3)),
        ("invariants.linear_momentum_expected", inv.linear_momentum_expected, (rows, 3)),
        ("invariants.angular_momentum", inv.angular_momentum, (rows, 3)),
        ("invariants.angular_impulse", inv.angular_impulse, (rows, 3)),
        ("invariants.energy", inv.energy, (rows,)),
        ("invariants.work", inv.work, (rows,)),
        ("tracking.e_omega", trk.e_omega, (rows, len(trk.omega_components))),
        ("tracking.e_p", trk.e_p, (rows, len(trk.mass_indices))),
    ]


def contract_problem(out: Any, engine: str, scene: Scene, horizon: float) -> str:
    """How ``out``, what plant ``engine`` returned for ``scene`` over ``horizon`` s, breaks the
    plant contract (module docstring), in a few words; "" when it keeps it."""
    if not isinstance(out, Trajectory):
        return f"returned {type(out).__name__}, not a Trajectory"
    if out.engine != engine:
        return f"returned a trajectory named {out.engine!r}, not its own name {engine!r}"
    if not isinstance(out.status, RunStatus):
        return f"returned the status {out.status!r}, not a RunStatus"
    t = out.t
    if not (isinstance(t, np.ndarray) and t.ndim == 1 and np.issubdtype(t.dtype, np.number)):
        return f"t is not a 1-D numeric array (got {type(t).__name__} {getattr(t, 'shape', '')})"
    grid = output_times(horizon, scene.output.rate)
    rows = t.shape[0]
    ok = out.status is RunStatus.OK
    if rows > grid.size or (ok and rows != grid.size):
        return f"t has {rows} samples, the output grid to t = {horizon:g} s has {grid.size}"
    if rows and not np.all(np.abs(t - grid[:rows]) <= GRID_TOL * np.maximum(1.0, np.abs(grid[:rows]))):
        k = int(np.argmax(np.abs(t - grid[:rows]) > GRID_TOL * np.maximum(1.0, np.abs(grid[:rows]))))
        return f"t[{k}] is {t[k]!r} s, not the output grid's {grid[k]!r} s"
    if not isinstance(out.tracking.omega_components, tuple) or not isinstance(
        out.tracking.mass_indices, tuple
    ):
        return "tracking.omega_components and tracking.mass_indices must be tuples"
    for name, a, shape in _arrays(out, scene.n, rows):
        why = _shape_problem(name, a, shape)
        if why:
            return why
        if ok and not np.all(np.isfinite(a)):
            return f"{name} has non-finite values in a run whose status is ok"
    if ok and not np.all(np.isfinite(t)):
        return "t has non-finite values in a run whose status is ok"
    return ""


def check_trajectory(out: Any, engine: str, scene: Scene, horizon: float) -> Trajectory:
    """``out`` when it keeps the plant contract (:func:`contract_problem`).

    Raises:
        ContractError: how it breaks it, naming the plant (one line).
    """
    why = contract_problem(out, engine, scene, horizon)
    if why:
        raise ContractError(f"broke the plant contract: {why}")
    return out


__all__ = ["ContractError", "check_trajectory", "contract_problem", "plant_scene"]
