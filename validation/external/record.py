"""The record of a trajectory read from a file, and how it becomes a :class:`Trajectory`.

A file gives the motion ``q = [R, u, p]`` (Eq. 44) and, optionally, the velocities, the control
torque and the rod forces (:mod:`validation.external.columns`). :func:`external_trajectory` puts them
in a :class:`~analytic.trajectory.Trajectory` in the paper's coordinates, as a plant would, and
fills what the file cannot give with **NaN**, so a comparison tells "absent" from any value:

* ``q``: R, u, p as written, except the quaternion's sign (below); the file's time column is
  replaced by the scene's grid it was checked against (:data:`validation.external.table.GRID_TOL`).
* ``qdot = [Ṙ, u̇, ṗ]``: ``Ṙ`` from ``v``, ``u̇ = H(u)ᵀω / (4|u|²)`` from ``ω`` (Eq. 12 inverted on
  the tangent space, ``analytic.kinematics.udot_of``), ``ṗ`` from ``pdot``; NaN where absent.
* ``qddot``, ``residual_norm``, ``force_at_C``: NaN (no column holds them).
* ``torque`` from ``tau``, ``rod_forces`` from ``F``, NaN where absent; ``QC``: its rod part is
  ``F`` (``Q^C_p,i = F_i``, docs/errata.md C4), its R part and its u part (``Hᵀτ`` plus an unknown
  part along u) NaN.
* invariants (:func:`analytic.invariants.compute_invariants`) from q and q̇: the quaternion norm
  error always; momenta and energy NaN unless every velocity group is present. The quadratures
  (work ``W``, impulses ``I_L``, ``I_P``: :mod:`analytic.assemble`) from the ``work`` columns; without
  them, exact zeros when the scene has nothing that does work on the system (no control, no
  given torque), as every plant integrates them then, and NaN otherwise (integrating the sampled
  τ and F afterwards is too coarse to judge a balance: at 100 Hz the trapezoidal rule misses the
  controlled Example 1's work by 1.5e-4 relative, Simpson's by 9e-7, against the 1e-8 threshold).
* tracking errors (:func:`analytic.invariants.tracking_errors`): ``e_p`` from p; ``e_ω`` from ω,
  NaN without the omega columns.

**Quaternion sign.** ``u`` and ``−u`` are one attitude and a file may give either, row by row.
The reader keeps the sign that continues the previous row (``u_k · u_{k−1} ≥ 0``), the first row in
the hemisphere of the scene's initial attitude ``u(0)``: a plant's own trajectory (continuous, from
``u(0)``) reads back unchanged, and a file with any signs reads to that same q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analytic.effects import Effect
from analytic.invariants import compute_invariants, tracking_errors
from analytic.kinematics import udot_of
from analytic.model import TumblingModel
from analytic.scene import Scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from validation.external.columns import OPTIONAL_GROUPS, ColumnGroup, TrajectoryFormat


@dataclass(frozen=True)
class ExternalTrajectory:
    """Another engine's run of a scene, read from a trajectory file.

    Attributes:
        trajectory: the run in the paper's coordinates on the scene's output grid (module
            docstring: what is NaN when the file lacks it).
        present: the optional column groups the file holds (:data:`OPTIONAL_GROUPS`).
        format: CSV or Parquet.
        source: the file as given, for messages and reports.
        sha256: the SHA-256 of the file's bytes as read (hex; "" when not read from a file).
    """

    trajectory: Trajectory
    present: frozenset[ColumnGroup]
    format: TrajectoryFormat
    source: str
    sha256: str = ""

    @property
    def absent(self) -> frozenset[ColumnGroup]:
        """The optional groups the file does not hold."""
        return OPTIONAL_GROUPS - self.present

    def has(self, group: ColumnGroup) -> bool:
        """Whether the file holds ``group`` (the required groups always)."""
        return group.required or group in self.present

    @staticmethod
    def not_judged(group: ColumnGroup) -> str:
        """What a check that needs an absent group says: ``"not judged: no omega columns"``."""
        return f"not judged: no {group.value} columns"


def canonical_signs(u: np.ndarray, u0: np.ndarray) -> np.ndarray:
    """``u`` (N, 4) with each row's sign flipped where needed so that consecutive rows have a
    non-negative dot product and the first has one with ``u0`` (4,) (module docstring)."""
    u = np.asarray(u, dtype=float)
    if u.shape[0] == 0:
        return u.copy()
    step = np.where(np.sum(u[1:] * u[:-1], axis=1) < 0.0, -1.0, 1.0)
    first = -1.0 if float(u[0] @ u0) < 0.0 else 1.0
    signs = first * np.concatenate([[1.0], np.cumprod(step)])
    return u * signs[:, None]


def does_work(scene: Scene) -> bool:
    """Whether something does work on the system in ``scene`` (control, a given torque): then the
    balances need the file's ``work`` columns; else the quadratures are exact zeros."""
    return scene.controlled or scene.has(Effect.EXTERNAL_TORQUE)


def _nan(*shape: int) -> np.ndarray:
    return np.full(shape, np.nan)


def external_trajectory(
    scene: Scene,
    engine: Engine | str,
    groups: dict[ColumnGroup, np.ndarray],
    format: TrajectoryFormat,
    source: str,
    sha256: str = "",
) -> ExternalTrajectory:
    """The record of a checked table.

    Args:
        scene: the scene the file is a run of (its n, its grid, its requirements).
        engine: the plant name the run goes by in a comparison (``Trajectory.engine``).
        groups: each group present -> its columns, shape (N, k) (N, 1 for t), the required groups
            always; t already checked against the scene's grid.
        format, source, sha256: as :class:`ExternalTrajectory`.
    """
    n = scene.n
    t = scene.output.times()
    N = len(t)
    R = groups[ColumnGroup.POSITION]
    u = canonical_signs(groups[ColumnGroup.ATTITUDE], scene.initial.u)
    p = groups[ColumnGroup.ROD_POSITIONS].reshape(N, n)
    q = np.concatenate([R, u, p], axis=1)

    def given(group: ColumnGroup, k: int) -> np.ndarray:
        return groups[group].reshape(N, k) if group in groups else _nan(N, k)

    omega = given(ColumnGroup.ANGULAR_VELOCITY, 3)
    qdot = np.concatenate(
        [given(ColumnGroup.VELOCITY, 3), udot_of(u, omega), given(ColumnGroup.ROD_VELOCITIES, n)],
        axis=1,
    )
    torque = given(ColumnGroup.TORQUE, 3)
    rod = given(ColumnGroup.ROD_FORCES, n)
    QC = np.concatenate([_nan(N, 7), rod], axis=1)
    model = TumblingModel(scene)
    if ColumnGroup.WORK in groups:
        quad = groups[ColumnGroup.WORK].reshape(N, 7)
    else:
        quad = np.full((N, 7), np.nan if does_work(scene) else 0.0)
    invariants = compute_invariants(
        model,
        t,
        q,
        qdot,
        np.ascontiguousarray(quad[:, 0]),
        np.ascontiguousarray(quad[:, 1:4]),
        np.ascontiguousarray(quad[:, 4:7]),
    )
    present = frozenset(groups) & OPTIONAL_GROUPS
    trajectory = Trajectory(
        engine=str(engine),
        scene=scene.name,
        t=t,
        q=q,
        qdot=qdot,
        qddot=_nan(N, n + 7),
        QC=QC,
        torque=torque,
        rod_forces=rod,
        force_at_C=_nan(N, 3),
        residual_norm=_nan(N),
        invariants=invariants,
        tracking=tracking_errors(model, t, q, omega),
        status=RunStatus.OK,
        message="",
        info={
            "source": "trajectory file",
            "file": source,
            "format": format.value,
            "groups": sorted(g.value for g in present),
            **({"sha256": sha256} if sha256 else {}),
        },
    )
    return ExternalTrajectory(
        trajectory=trajectory, present=present, format=format, source=source, sha256=sha256
    )


__all__ = ["ExternalTrajectory", "canonical_signs", "does_work", "external_trajectory"]
