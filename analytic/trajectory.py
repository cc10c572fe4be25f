"""One record type for the trajectories of every engine, so every comparison is engine-agnostic.

All arrays are per output sample (N samples) in the paper's coordinates (Eq. 44):
``q = [R (3), u (4, w first), p (n)]``. Units SI; frames as stated per field.
"""

from __future__ import annotations

import io
import json
import os
import uuid
from dataclasses import asdict, dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np


class Engine(StrEnum):
    """The names of the three built-in plants. A plant's name is an open ``str``: these, the
    plants installed as plugins (``mj_bridge.plants``, ``docs/plugins.md``) and any label a
    trajectory read from a file is given."""

    ANALYTIC = "analytic"
    MUJOCO = "mujoco"
    PINOCCHIO = "pinocchio"


class RunStatus(StrEnum):
    OK = "ok"
    FAILED = "failed"
    INTERRUPTED = "interrupted"  # stopped by Ctrl-C / SIGTERM: the samples so far, kept


def energy_residual(
    energy: np.ndarray, work: np.ndarray, dissipated: np.ndarray | None
) -> np.ndarray:
    """The energy balance's residual ``E(t) - E(0) + D(t) - W(t)``, J, shape (N,): the energy
    ``E``, the work ``W`` of the control and the given torque, the energy ``D`` the dissipative
    effects took out (None: none is on). The one definition, for the record and the checks."""
    if dissipated is None:
        return energy - energy[0] - work
    return energy - energy[0] + dissipated - work


@dataclass(frozen=True)
class Invariants:
    """Invariants and their balances per sample.

    Attributes:
        quat_norm_error: ``e_u = uᵀu - 1`` (the paper's measure), shape (N,).
        linear_momentum: total linear momentum, inertial, kg·m/s, shape (N, 3).
        linear_momentum_expected: ``P(0) + m_T g t + ∫F_C dt`` (gravity and a force at C), (N, 3).
        angular_momentum: total angular momentum about the system centre of mass, inertial,
            kg·m²/s, shape (N, 3).
        angular_impulse: ``∫ S(u)(τ + τ_given) + (R - c)×F_C dt`` since t = 0 (the external
            moments about the system centre of mass c), inertial, N·m·s, shape (N, 3).
        energy: kinetic + gravitational + spring energy of the scene's effects, J, shape (N,).
        work: work done by the control (``τ·ω + F·ṗ + F_C·Ṙ``) and the given torque since t = 0,
            J, shape (N,).
        dissipated: ``D``, the energy the scene's dissipative effects took out of the motion
            since t = 0 (``∫ Σ c ė² dt`` of the spring dampers), J, shape (N,); zeros when none is
            on (the default).
    """

    quat_norm_error: np.ndarray
    linear_momentum: np.ndarray
    linear_momentum_expected: np.ndarray
    angular_momentum: np.ndarray
    angular_impulse: np.ndarray
    energy: np.ndarray
    work: np.ndarray
    dissipated: np.ndarray = None  # type: ignore[assignment]  # zeros, set below

    def __post_init__(self) -> None:
        if self.dissipated is None:
            object.__setattr__(self, "dissipated", np.zeros(np.shape(self.work)))

    def angular_momentum_balance(self) -> np.ndarray:
        """``L(t) - L(0) - ∫S τ dt``, shape (N, 3): zero for exact dynamics."""
        return self.angular_momentum - self.angular_momentum[0] - self.angular_impulse

    def energy_balance(self) -> np.ndarray:
        """``E(t) - E(0) + D(t) - W(t)``, shape (N,): zero for exact dynamics
        (:func:`energy_residual`)."""
        return energy_residual(self.energy, self.work, self.dissipated)

    def linear_momentum_balance(self) -> np.ndarray:
        return self.linear_momentum - self.linear_momentum_expected


@dataclass(frozen=True)
class Tracking:
    """Tracking errors of the controlled components (empty arrays when uncontrolled).

    Attributes:
        omega_components: 0-based body axes tracked.
        e_omega: ``ω - ω̄`` on those axes, rad/s, shape (N, k_ω).
        mass_indices: 0-based masses tracked.
        e_p: ``p - p̄`` for those masses, m, shape (N, k_p).
    """

    omega_components: tuple[int, ...]
    e_omega: np.ndarray
    mass_indices: tuple[int, ...]
    e_p: np.ndarray


@dataclass(frozen=True)
class Trajectory:
    """A run of one scene on one engine.

    Attributes:
        engine: the name of the plant that produced it (a plain ``str``: a built-in's
            :class:`Engine` value, a plugin's name or a label; an :class:`Engine` given is
            stored as its value).
        scene: the scene's name.
        t: sample times, s, shape (N,).
        q, qdot, qddot: coordinates and derivatives (Eq. 44), shape (N, n+7).
        QC: generalized control force (Eq. 89), shape (N, n+7).
        torque: body-axis control torque, N·m, shape (N, 3).
        rod_forces: rod force on each mass, N, shape (N, n).
        force_at_C: force at C, inertial, N, shape (N, 3).
        residual_norm: norm of the unattainable part of the requirements, shape (N,).
        invariants, tracking: see :class:`Invariants`, :class:`Tracking`.
        status: ``ok`` or ``failed`` (a failed run keeps the samples it reached).
        message: why it failed, or a note.
        info: engine metadata (solver, tolerances, evaluation counts, wall time ...).
    """

    engine: str
    scene: str
    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    qddot: np.ndarray
    QC: np.ndarray
    torque: np.ndarray
    rod_forces: np.ndarray
    force_at_C: np.ndarray
    residual_norm: np.ndarray
    invariants: Invariants
    tracking: Tracking
    status: RunStatus = RunStatus.OK
    message: str = ""
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.engine, str) or not self.engine:
            raise ValueError(f"engine: must be a non-empty plant name (got {self.engine!r})")
        object.__setattr__(self, "engine", str.__str__(self.engine))  # plain str, not an Engine

    @property
    def n(self) -> int:
        return self.q.shape[1] - 7

    @property
    def R(self) -> np.ndarray:
        return self.q[:, :3]

    @property
    def u(self) -> np.ndarray:
        return self.q[:, 3:7]

    @property
    def p(self) -> np.ndarray:
        return self.q[:, 7:]

    @property
    def omega(self) -> np.ndarray:
        """Body-axis angular velocity ``ω = H u̇``, rad/s, shape (N, 3)."""
        from analytic.kinematics import omega_of

        return omega_of(self.u, self.qdot[:, 3:7])

    def raise_if_interrupted(self) -> Trajectory:
        """``self``, or KeyboardInterrupt when the run was interrupted (Ctrl-C, SIGTERM).

        A plant keeps the samples it reached when interrupted and returns them
        (:attr:`RunStatus.INTERRUPTED`); a caller that runs several plants or cases calls this so
        that the user's interrupt stops the whole job instead of only the current run.
        """
        if self.status is RunStatus.INTERRUPTED:
            raise KeyboardInterrupt(self.message)
        return self

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Flat name -> array mapping (for ``.npz``)."""
        out = {
            "t": self.t,
            "q": self.q,
            "qdot": self.qdot,
            "qddot": self.qddot,
            "QC": self.QC,
            "torque": self.torque,
            "rod_forces": self.rod_forces,
            "force_at_C": self.force_at_C,
            "residual_norm": self.residual_norm,
            "omega": self.omega,
            "e_omega": self.tracking.e_omega,
            "e_p": self.tracking.e_p,
        }
        for k, v in asdict(self.invariants).items():
            out[f"invariants.{k}"] = v
        return out

    def npz_bytes(self) -> bytes:
        """The arrays of :meth:`to_arrays` and the metadata (``meta_json``) as ``.npz`` bytes."""
        meta = {
            "engine": self.engine,
            "scene": self.scene,
            "status": self.status.value,
            "message": self.message,
            "info": self.info,
            "omega_components": list(self.tracking.omega_components),
            "mass_indices": list(self.tracking.mass_indices),
        }
        arrays = self.to_arrays()
        arrays["meta_json"] = np.array(json.dumps(meta, default=str))
        buf = io.BytesIO()
        np.savez(buf, **arrays)  # type: ignore[arg-type]  # numpy's stub: a ** mapping might hold allow_pickle (bool)
        return buf.getvalue()

    def save_npz(self, path: str | Path) -> Path:
        """Write :meth:`npz_bytes` to ``path`` atomically (a new file beside it, then a rename).

        The command line writes through ``validation.runs.atomic`` instead, which also checks the
        written size; this is the dependency-free form for library users.
        """
        path = Path(path)
        data = self.npz_bytes()
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
        try:
            with open(tmp, "xb") as f:  # mode 0o666 & ~umask, like any new file
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except OSError as exc:  # named by the path asked for, not by the temporary file
            tmp.unlink(missing_ok=True)
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        return path
