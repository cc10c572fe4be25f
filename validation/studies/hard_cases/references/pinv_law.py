"""Redundant and conflicting requirements: the Moore-Penrose law with requirement rows duplicated.

The scene format cannot state such requirements (tracked masses are distinct, and the ω rows of
distinct axes are independent), so they are built here from a scene's own constraint rows: one
mass's row appended again unchanged (redundant), and one ω component's row appended again with its
right-hand side shifted by δ (conflicting). The Moore-Penrose solution of Eq. (89) attains the
projection of ``b`` onto ``range(A_c)``: a redundant pair is met exactly (the same ``q̈`` as without
the duplicate, zero residual); a conflicting pair is met at the mean of its two demands, leaving
the unattainable ``(+δ/2, -δ/2)`` on its rows and every other requirement met. Integrated, the
conflicting component's error then follows ``e(t) = e0 e^{-γt} + δ/(2γ)(1 - e^{-γt})``.

The analytic side is :func:`analytic.fundamental.solve` on the model's ``M``, ``Q`` and rows with the
duplicates appended (:func:`duplicated_acceleration`); each engine's side is the textbook law
``a0 + M⁻¹Aᵀ (A M⁻¹ Aᵀ)⁺ (b - A a0)`` (:func:`pinv_law`) from that engine's own mass matrix and
forces (MuJoCo: ``mj_fullM``, ``qfrc_passive - qfrc_bias``; Pinocchio: ``crba``, the plant's spring
forces - ``nle``) on the same rows.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

import mj_bridge
from analytic import fundamental
from analytic.effects import CONTROL_EFFECTS, SolverMethod
from analytic.kinematics import omega_of
from analytic.model import TumblingModel
from analytic.scene import Scene
from analytic.stepping import Stepped, step_and_sample
from analytic.trajectory import Engine, RunStatus, Trajectory
from mj_bridge.pinocchio_model import pinocchio_to_paper_acc
from mj_bridge.pinocchio_plant import PinocchioDynamics
from model_xml.coordinates import mujoco_to_paper_acc
from validation.runs.interrupts import checkpoint

N_STATES = 6
"""States at which the pointwise properties are evaluated, spread evenly over a short run."""

STATE_RUN_S = 1.0
"""Length of the analytic plant's run that gives those states realistic values, s."""

RTOL, ATOL = 1e-11, 1e-12
"""DOP853 tolerances of the integrated conflicting run: three decades below the bound on its error
law (1e-8 relative)."""


def duplicated_rows(
    model: TumblingModel, t: float, q: np.ndarray, qdot: np.ndarray, rows: Sequence[int], shifts
) -> tuple[np.ndarray, np.ndarray]:
    """``A_c`` and ``b_c`` (Eqs. 80, 85) with the 0-based ``rows`` appended again, their
    right-hand sides shifted by ``shifts`` (rad/s² or m/s²); shapes (k + r, nq), (k + r,)."""
    A, b = model.control_constraints(t, q, qdot)
    rows = np.asarray(rows, int)
    return np.vstack([A, A[rows]]), np.concatenate([b, b[rows] + np.asarray(shifts, float)])


def duplicated_acceleration(
    model: TumblingModel, t: float, q: np.ndarray, qdot: np.ndarray, rows: Sequence[int], shifts
) -> tuple[np.ndarray, np.ndarray]:
    """``(q̈, residual)`` of the fundamental equation (:func:`analytic.fundamental.solve`) with the
    rows of :func:`duplicated_rows`; residual = ``A q̈ - b``, shape (k + r,)."""
    q, qdot = np.asarray(q, float), np.asarray(qdot, float)
    M = model.mass_matrix(q)
    Q = model.generalized_force(t, q, qdot)
    a_m, b_m = model.modeling_constraint(q, qdot)
    A, b = duplicated_rows(model, t, q, qdot, rows, shifts)
    sol = fundamental.solve(M, Q, a_m, b_m, A, b, model.weighting)
    return sol.qddot, sol.residual


def pinv_law(M: np.ndarray, F: np.ndarray, A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The Moore-Penrose Gauss law ``a0 + M⁻¹Aᵀ (A M⁻¹ Aᵀ)⁺ (b - A a0)``, ``a0 = M⁻¹ F`` (numpy's
    pseudo-inverse at the model's cut-off ``PINV_RCOND``, so both sides decide the same rank)."""
    a0 = np.linalg.solve(M, F)
    MinvAt = np.linalg.solve(M, A.T)
    G = A @ MinvAt
    return a0 + MinvAt @ (
        np.linalg.pinv(G, rcond=fundamental.PINV_RCOND, hermitian=True) @ (b - A @ a0)
    )


Row = tuple[str, int]
"""A requirement row in the paper's terms: ``("omega", axis)`` or ``("mass", i)``, 0-based."""


def mujoco_law(tw: Any, t: float, q, qd, rows: list[Row], b: np.ndarray) -> np.ndarray:
    """:func:`pinv_law` from MuJoCo's own ``M`` and forces at a paper state (``tw`` a
    :class:`mj_bridge.Twin`); returns the paper ``q̈``."""
    tw.set_state(t, q, qd)
    m, d = tw.m, tw.d
    d.ctrl[:] = 0.0
    d.xfrc_applied[:] = 0.0
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    F = d.qfrc_passive - d.qfrc_bias + d.qfrc_actuator
    A = np.zeros((len(rows), m.nv))
    for j, (kind, i) in enumerate(rows):
        if kind == "omega":
            A[j, 3:6] = tw.R_I.T[i]
        else:
            A[j, 6 + i] = 1.0
    qacc = pinv_law(M, F, A, b)
    return mujoco_to_paper_acc(d.qpos, d.qvel, qacc, tw.ipos, tw.iquat)


def pinocchio_law(dyn: Any, t: float, q, qd, rows: list[Row], b: np.ndarray) -> np.ndarray:
    """:func:`pinv_law` from Pinocchio's own ``M`` (``crba``) and forces (the plant's generalized
    forces without control, i.e. springs and given torque, minus ``nle``: gravity is the model's).
    ``dyn``: a ``PinocchioDynamics`` of the scene without its control effects. Pinocchio's body
    frame is BR's principal axes, so an ``("omega", axis)`` row is ``ω̇_axis``; returns the paper
    ``q̈``."""
    pin = dyn.pin
    y = dyn.state_from_paper(q, qd)
    tau = dyn.generalized_force(t, y)
    q_pin, v_pin = dyn.pinocchio_state()
    M = np.array(pin.crba(dyn.model, dyn.data, q_pin))
    M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
    F = tau - np.array(pin.nle(dyn.model, dyn.data, q_pin, v_pin))
    A = np.zeros((len(rows), dyn.nv))
    for j, (kind, i) in enumerate(rows):
        A[j, 3 + i if kind == "omega" else 6 + i] = 1.0
    return pinocchio_to_paper_acc(q_pin, v_pin, pinv_law(M, F, A, b))


ENGINE_LAW_PLANTS = frozenset({Engine.MUJOCO.value, Engine.PINOCCHIO.value})
"""The plants :func:`engine_laws` gives a law for (from their own engine's matrices); the measure
``engine_law`` is made on these only."""


def engine_laws(
    scene: Scene, plants: Sequence[str], rows: list[Row]
) -> dict[str, Callable[[float, Any, Any, np.ndarray], np.ndarray]]:
    """plant -> ``law(t, q, q̇, b)``: the law from that engine's own matrices on ``rows``, for
    each engine plant of ``plants``."""
    laws: dict[str, Callable[[float, Any, Any, np.ndarray], np.ndarray]] = {}
    if Engine.MUJOCO.value in plants:
        tw = mj_bridge.Twin(scene)
        laws[Engine.MUJOCO.value] = lambda t, q, qd, b: mujoco_law(tw, t, q, qd, rows, b)
    if Engine.PINOCCHIO.value in plants:
        dyn = PinocchioDynamics(scene.with_effects(scene.effects - CONTROL_EFFECTS))
        laws[Engine.PINOCCHIO.value] = lambda t, q, qd, b: pinocchio_law(dyn, t, q, qd, rows, b)
    return laws


@dataclass(frozen=True)
class PinvFindings:
    """What the duplicated rows give (the measures of ``against = "pinv_law"``, all relative).

    Attributes:
        redundant_acceleration, redundant_residual, conflict_residual, other_residuals: maxima
            over the sampled states (see :data:`validation.studies.hard_cases.catalogue.MEASURES`).
        conflict_tracking: of the integrated conflicting run.
        engine_law: plant -> the law from its own matrices against the analytic ``q̈``.
        residual_norm: ``|residual|`` of the conflicting rows at the last state (δ/√2 exactly).
        run: the integrated conflicting run (its status and samples).
        t_end: its horizon, s.
    """

    redundant_acceleration: float
    redundant_residual: float
    conflict_residual: float
    other_residuals: float
    conflict_tracking: float
    engine_law: dict[str, float] = field(default_factory=dict)
    residual_norm: float = math.nan
    run: Stepped | None = None
    t_end: float = math.nan


def evaluate(
    scene: Scene,
    states: Trajectory,
    plants: Sequence[str],
    duplicate_mass: int,
    conflict_axis: int,
    delta: float,
) -> PinvFindings:
    """The pointwise properties at :data:`N_STATES` states of ``states`` (a short run of the plain
    scene), each engine's law on the same rows, and the conflicting model integrated over the
    scene's output grid.

    Args:
        duplicate_mass: 0-based tracked mass whose row is duplicated (redundant).
        conflict_axis: 0-based tracked ω component whose row is duplicated, shifted by ``delta``
            (rad/s²).
    """
    model = TumblingModel(scene)
    comps = list(scene.control.omega.components)
    k_w = len(comps)
    w_row = comps.index(conflict_axis)
    m_row = k_w + list(scene.control.masses.indices).index(duplicate_mass)
    rows: list[Row] = [("omega", c) for c in comps] + [
        ("mass", i) for i in scene.control.masses.indices
    ]
    laws = engine_laws(scene, plants, [*rows, rows[w_row]])
    law_err = dict.fromkeys(laws, 0.0)
    red_err = res_red = con_res_err = other_err = 0.0
    res_norm = math.nan
    other = [j for j in range(model.k) if j != w_row]
    expected = np.zeros(model.k + 1)
    expected[w_row], expected[-1] = delta / 2, -delta / 2
    for i in np.linspace(0, len(states.t) - 1, N_STATES).astype(int):
        t, q, qd = float(states.t[i]), states.q[i], states.qdot[i]
        qdd0, _ = model.acceleration(t, q, qd)
        qdd_r, r_r = duplicated_acceleration(model, t, q, qd, [m_row], [0.0])
        qdd_c, r_c = duplicated_acceleration(model, t, q, qd, [w_row], [delta])
        red_err = max(red_err, float(np.linalg.norm(qdd_r - qdd0) / np.linalg.norm(qdd0)))
        res_red = max(res_red, float(np.max(np.abs(r_r)) / max(1.0, np.max(np.abs(qdd0)))))
        con_res_err = max(con_res_err, float(np.max(np.abs(r_c - expected)) / delta))
        other_err = max(other_err, float(np.max(np.abs(r_c[other]))) / delta)
        res_norm = float(np.linalg.norm(r_c))
        _, b = duplicated_rows(model, t, q, qd, [w_row], [delta])
        for who, law in laws.items():
            qdd_e = law(t, q, qd, b)
            err = float(np.linalg.norm(qdd_e - qdd_c) / np.linalg.norm(qdd_c))
            law_err[who] = max(law_err[who], err)
    run, traj_err = _integrate_conflict(scene, model, w_row, conflict_axis, delta)
    return PinvFindings(
        redundant_acceleration=red_err,
        redundant_residual=res_red,
        conflict_residual=con_res_err,
        other_residuals=other_err,
        conflict_tracking=traj_err,
        engine_law=law_err,
        residual_norm=res_norm,
        run=run,
        t_end=float(scene.output.times()[-1]),
    )


def _integrate_conflict(
    scene: Scene, model: TumblingModel, w_row: int, axis: int, delta: float
) -> tuple[Stepped, float]:
    """The conflicting model over the scene's output grid (the project's stepping loop, DOP853 at
    :data:`RTOL`, :data:`ATOL`) and ``max |e - e_closed form| / max |e|`` of the conflicting ω
    component (``e0 e^{-γt} + δ/(2γ)(1 - e^{-γt})``, γ its diagonal gain)."""
    nq = model.nq

    def f(t: float, y: np.ndarray) -> np.ndarray:
        qdd, _ = duplicated_acceleration(model, t, y[:nq], y[nq:], [w_row], [delta])
        return np.concatenate([y[nq:], qdd])

    run = step_and_sample(
        f,
        scene.output.times(),
        np.concatenate([scene.initial.q0(), scene.initial.qdot0()]),
        method=SolverMethod.DOP853,
        rtol=RTOL,
        atol=ATOL,
        n_motion=2 * nq,
        progress=checkpoint,  # a signal compiled code swallowed stops the run at its next report
    )
    if run.status is RunStatus.INTERRUPTED:  # the loop keeps what it reached: the suite stops
        raise KeyboardInterrupt(run.message)
    t, q, qd = run.t, run.y[:, :nq], run.y[:, nq:]
    w = omega_of(q[:, 3:7], qd[:, 3:7])
    omega = scene.control.omega
    gamma = float(omega.gain[w_row, w_row])
    e = w[:, axis] - omega.b[axis] * np.cos(omega.sigma[axis] * t)
    ref = e[0] * np.exp(-gamma * t) + delta / (2 * gamma) * (1 - np.exp(-gamma * t))
    return run, float(np.max(np.abs(e - ref)) / max(np.max(np.abs(e)), 1e-300))


__all__ = [
    "ATOL",
    "ENGINE_LAW_PLANTS",
    "N_STATES",
    "RTOL",
    "STATE_RUN_S",
    "PinvFindings",
    "duplicated_acceleration",
    "duplicated_rows",
    "engine_laws",
    "evaluate",
    "mujoco_law",
    "pinocchio_law",
    "pinv_law",
]
