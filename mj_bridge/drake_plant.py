"""The Drake plant: a scene integrated in Drake's state with ``MultibodyPlant.EvalTimeDerivatives``
(continuous time), under the same analytic controller, returning the same
:class:`~analytic.trajectory.Trajectory` record as the other plants (paper coordinates, Eq. 44).

Drake (PyPI ``drake`` >= 1.51) is optional: it is imported when a :class:`DrakeDynamics` is built.
The plant is :class:`mj_bridge.drake_plugin.DrakePlant` (``DrakePlant().simulate(scene)``, which runs
:func:`simulate` here), a plant plugin registered by the project's own entry point
(``pyproject.toml``, group ``tumbling_testbed.plants``: ``drake``); it is not among the default
plants (``default = False``): ``--plants analytic,mujoco,drake`` runs it. It is one of the plants on
scipy's loop (:class:`mj_bridge.scipy_plant.ScipyDynamics`): this module provides the engine, its
state and its accelerations only.

State integrated by scipy (one ``OdeSolver`` step at a time, :func:`analytic.stepping.step_and_sample`,
the analytic and Pinocchio plants' loop)::

    y = [R (3), qw, qx, qy, qz, p (n) | ω_W (3), Ṙ (3), ṗ (n) | W, I_L (3), I_P (3)]
        '---- Drake's q_d, reordered ---'   '---- Drake's v_d ----'   '--- quadratures ---'

Drake's continuous state (:mod:`mj_bridge.drake_model`: the angular velocity ``ω_W`` in inertial
axes), its positions in the paper's order (the quaternion at ``y[3:7]``, w first, as the shared loop
expects). ``ẏ = [Ṙ, ½ u ⊗ (0, ω), ṗ | v̇_d | Ẇ, İ_L, İ_P]`` with ``v̇_d`` the velocity part of
Drake's ``EvalTimeDerivatives`` and ``ω = S(û)ᵀ ω_W`` the body-axis angular velocity. Drake gets
the quaternion normalised (û); the integrated one is never renormalised.

Every derivative evaluation:

1. a compiled map of ``y`` (:func:`_to_stage`) into Drake's ``[q_d, v_d]`` (with û), into the stage
   state of :mod:`mj_bridge.scipy_stage` ``[R, qx, qy, qz, qw, p | Ṙ, ω, ṗ | quadratures]`` and into
   the paper state the controller gets: ``q = [R, u, p]``, ``q̇ = [Ṙ, ½ u ⊗ (0, ω), ṗ]`` with u **as
   integrated** (not normalised), as the analytic plant's controller sees its own state (which
   keeps the closed loop's integration error small under a fast spin, ``docs/performance.md``);
2. the analytic controller (Eq. 89) at that state
   (:meth:`~mj_bridge.scipy_plant.ScipyDynamics.control_into`: the compiled kernel, the numpy model
   where it declines, or with ``ControllerSource.ANALYTIC`` the numpy model);
3. the shared compiled stage (:func:`mj_bridge.scipy_stage.stage_for`, given that control): the
   force effects of :mod:`mj_bridge.scipy_forces` (the springs ``F^S = −∂U_s/∂p`` of Eq. (38), the
   given torque of Remark 2), the quaternion rate and the rates of :mod:`analytic.aux_rates`;
4. a compiled map of the stage's forces into Drake's generalized force (:func:`_drake_force`), fed
   to the plant's applied generalized-force port:

   * ``f[0:3] = S(û) (τ_c + τ_g)``: the control and given torques (body axes) as an inertial torque
     on BR (Drake's angular velocity is inertial: the power ``f·ω_W`` is ``τ·ω``);
   * ``f[3:6] = F_C``: the force at C (the ``M^-2`` weighting's ``Q^C_R``), inertial, at BR's
     origin C;
   * ``f[6+i] = F_i + F^S_i``: the controller's rod force and the spring force on prismatic joint i;

5. ``plant.SetPositionsAndVelocities`` and ``plant.EvalTimeDerivatives`` once each, and a compiled
   copy into ``ẏ`` that checks it is finite (:func:`_finish`). The dynamics (mass matrix,
   gyroscopic and Coriolis terms, gravity, the masses' inertia: :mod:`mj_bridge.drake_effects`) are
   Drake's alone.

scipy's DOP853 at the scene's tolerances on ``EvalTimeDerivatives`` is the fast path (Drake's own
``Simulator`` and what one evaluation costs: ``docs/performance.md``); one evaluation is O(n), so
the plant has no size limit.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from analytic.assemble import N_AUX
from analytic.error_scale import ErrorGroups
from analytic.model import ControlOutput
from analytic.runtime.jit import jit
from analytic.scene import Scene
from analytic.stepping import NonFinite
from analytic.trajectory import Trajectory
from mj_bridge import scipy_plant
from mj_bridge.drake_model import build_model, drake_to_paper_batch, import_drake, paper_to_drake
from mj_bridge.drake_settings import DrakeSettings
from mj_bridge.scipy_plant import ScipyDynamics, numba_types
from mj_bridge.scipy_stage import MODE_GIVEN
from mj_bridge.stages import ControllerSource

ENGINE = "drake"
"""The plant's name in its trajectories: :attr:`mj_bridge.drake_plugin.DrakePlant.engine`."""

COMPILE_LOCK = "drake-stage"
"""The :mod:`analytic.runtime.compile_lock` name held while the maps below and the shared stage
(:mod:`mj_bridge.scipy_stage`) are compiled or loaded from numba's cache."""


# ----------------------------------------------------------------------------------------------
# The compiled maps
# ----------------------------------------------------------------------------------------------


def _to_stage(y, yp, xd, qc, qdc):  # pragma: no cover - compiled
    """The integrated state ``y`` (2n + 20: ``[R, u, p | ω_W, Ṙ, ṗ | quadratures]``) -> the
    stage state ``yp`` (2n + 20: ``[R, qx, qy, qz, qw, p | Ṙ, ω, ṗ | quadratures]``,
    ``ω = S(û)ᵀ ω_W``), Drake's ``xd`` (2n + 13: ``[û, R, p | ω_W, Ṙ, ṗ]``, û the normalised
    quaternion) and the controller's paper state ``qc``, ``qdc`` (n + 7 each: ``[R, u, p]``,
    ``[Ṙ, ½ u ⊗ (0, ω), ṗ]`` with u as integrated, as the analytic plant's controller sees it)."""
    nq = (xd.shape[0] + 1) // 2
    n = nq - 7
    qw, qx, qy, qz = y[3], y[4], y[5], y[6]
    s = 1.0 / math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    u0, u1, u2, u3 = qw * s, qx * s, qy * s, qz * s
    # S(û), Eq. (11)
    s00 = u0 * u0 + u1 * u1 - u2 * u2 - u3 * u3
    s01 = 2.0 * (u1 * u2 - u0 * u3)
    s02 = 2.0 * (u1 * u3 + u0 * u2)
    s10 = 2.0 * (u1 * u2 + u0 * u3)
    s11 = u0 * u0 - u1 * u1 + u2 * u2 - u3 * u3
    s12 = 2.0 * (u2 * u3 - u0 * u1)
    s20 = 2.0 * (u1 * u3 - u0 * u2)
    s21 = 2.0 * (u2 * u3 + u0 * u1)
    s22 = u0 * u0 - u1 * u1 - u2 * u2 + u3 * u3
    a0, a1, a2 = y[nq], y[nq + 1], y[nq + 2]  # ω_W
    w0 = s00 * a0 + s10 * a1 + s20 * a2  # ω = Sᵀ ω_W
    w1 = s01 * a0 + s11 * a1 + s21 * a2
    w2 = s02 * a0 + s12 * a1 + s22 * a2
    xd[0], xd[1], xd[2], xd[3] = u0, u1, u2, u3
    yp[3], yp[4], yp[5], yp[6] = qx, qy, qz, qw
    yp[nq + 3], yp[nq + 4], yp[nq + 5] = w0, w1, w2
    for i in range(3):
        xd[4 + i] = y[i]
        yp[i] = y[i]
        qc[i] = y[i]
        xd[nq + i] = y[nq + i]
        xd[nq + 3 + i] = y[nq + 3 + i]
        yp[nq + i] = y[nq + 3 + i]  # Ṙ
        qdc[i] = y[nq + 3 + i]
    qc[3], qc[4], qc[5], qc[6] = qw, qx, qy, qz
    qdc[3] = 0.5 * (-qx * w0 - qy * w1 - qz * w2)  # ½ u ⊗ (0, ω) = ¼ H(u)ᵀ ω for unit u
    qdc[4] = 0.5 * (qw * w0 - qz * w1 + qy * w2)
    qdc[5] = 0.5 * (qz * w0 + qw * w1 - qx * w2)
    qdc[6] = 0.5 * (-qy * w0 + qx * w1 + qw * w2)
    for i in range(n):
        xd[7 + i] = y[7 + i]
        yp[7 + i] = y[7 + i]
        qc[7 + i] = y[7 + i]
        xd[nq + 6 + i] = y[nq + 6 + i]
        yp[nq + 6 + i] = y[nq + 6 + i]
        qdc[7 + i] = y[nq + 6 + i]
    for i in range(2 * nq - 1, y.shape[0]):
        yp[i] = y[i]


def _drake_force(work, o_tau, o_tt, o_ctl, o_rot, f):  # pragma: no cover - compiled
    """Drake's generalized force ``f`` (n + 6) from the shared stage's work array: ``[S (τ_c +
    τ_g), F_C, F + F^S]`` (see the module docstring); False when one is not finite."""
    t0, t1, t2 = work[o_tt], work[o_tt + 1], work[o_tt + 2]
    for r in range(3):
        f[r] = (
            work[o_rot + 3 * r] * t0 + work[o_rot + 3 * r + 1] * t1 + work[o_rot + 3 * r + 2] * t2
        )
        f[3 + r] = work[o_ctl + 3 + r]
    for i in range(6, f.shape[0]):
        f[i] = work[o_tau + i]
    ok = True
    for i in range(f.shape[0]):
        if not math.isfinite(f[i]):
            ok = False
    return ok


def _finish(xdot, ydp, y, ydot):  # pragma: no cover - compiled
    """``ẏ`` (2n + 20) from Drake's time derivatives ``xdot`` (2n + 13, its ``v̇`` after ``q̇``), the
    stage's ``ydp`` (the raw quaternion's rate, x, y, z, w, and the quadratures' rates)
    and ``y``; False when one is a NaN or an infinity."""
    nv = (xdot.shape[0] - 1) // 2
    nq = nv + 1
    n = nq - 7
    for i in range(3):
        ydot[i] = y[nq + 3 + i]  # Ṙ
    ydot[3], ydot[4], ydot[5], ydot[6] = ydp[6], ydp[3], ydp[4], ydp[5]  # ½ u ⊗ (0, ω)
    for i in range(n):
        ydot[7 + i] = y[nq + 6 + i]  # ṗ
    for i in range(nv):
        ydot[nq + i] = xdot[nq + i]
    for i in range(nq + nv, ydot.shape[0]):
        ydot[i] = ydp[i]
    ok = True
    for i in range(ydot.shape[0]):
        if not math.isfinite(ydot[i]):
            ok = False
    return ok


to_stage = jit(_to_stage)
drake_force = jit(_drake_force)
finish = jit(_finish)


# ----------------------------------------------------------------------------------------------
# The dynamics
# ----------------------------------------------------------------------------------------------


def error_groups(n: int) -> ErrorGroups:
    """The coupled groups of ``y = [R, u, p | ω_W, Ṙ, ṗ | quadratures]`` (:mod:`analytic.error_scale`):
    positions ``{R, p}``, the quaternion, ω_W, velocities ``{Ṙ, ṗ}``."""
    nq = n + 7
    return ErrorGroups.of(
        2 * n + 13,
        np.r_[0:3, 7:nq],
        np.arange(3, 7),
        np.arange(nq, nq + 3),
        np.r_[nq + 3 : nq + 6, nq + 6 : nq + 6 + n],
    )


class DrakeDynamics(ScipyDynamics):
    """One scene on Drake, with the analytic controller in every derivative evaluation
    (:class:`~mj_bridge.scipy_plant.ScipyDynamics`).

    Args:
        scene: a validated scene.
        controller: ``analytic_fast`` (default) or ``analytic`` (see :class:`DrakeSettings`).

    Attributes:
        pydrake: the ``pydrake.all`` module.
        drake: the :class:`~mj_bridge.drake_model.DrakeModel` (plant, context, force port value).
    """

    engine = ENGINE
    lock_name = COMPILE_LOCK
    settings_type = DrakeSettings
    sample_errors = (*ScipyDynamics.sample_errors, RuntimeError)

    def build(self, scene: Scene) -> None:
        self.pydrake = import_drake()
        self.drake = build_model(scene)

    def setup(self) -> None:
        self._o = tuple(self.layout[k][0] for k in ("tau", "tt", "ctl", "rot"))
        self._yp = np.zeros(self.ny)
        self._ydp = np.zeros(self.ny)
        self._xd = np.zeros(self.nq + self.nv)
        self._qc = np.zeros(self.nq)
        self._qdc = np.zeros(self.nq)
        self._f = np.zeros(self.nv)

    groups = staticmethod(error_groups)

    def versions(self) -> dict[str, str]:
        return {"drake_version": _drake_version()}

    @property
    def fallbacks(self) -> int:
        """Evaluations whose control the numpy model gave (all of them with the ``analytic``
        controller)."""
        if self.controller is ControllerSource.ANALYTIC:
            return self.nfev if self.controlled else 0
        return self.fast.fallbacks

    # -- coordinates ------------------------------------------------------------------------

    def state_from_paper(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The integrated state ``y`` (2n + 20) of a paper state, with zero quadratures:
        ``[R, û, p, ω_W, Ṙ, ṗ, 0]`` (:func:`mj_bridge.drake_model.paper_to_drake`: u normalised,
        ``ω_W = S(û) H(u) u̇``)."""
        q_d, v_d = paper_to_drake(np.asarray(q, dtype=float), np.asarray(qdot, dtype=float))
        return np.concatenate([q_d[4:7], q_d[:4], q_d[7:], v_d, np.zeros(N_AUX)])

    def paper_q(self, y: np.ndarray) -> np.ndarray:
        """The paper's q of a state ``y`` (its progress's state): ``[R, u, p]`` as integrated,
        as :meth:`to_paper` makes it."""
        return y[: self.nq].copy()

    def control_state(self) -> tuple[np.ndarray, np.ndarray]:
        return self._qc, self._qdc

    # -- the right-hand side ----------------------------------------------------------------

    def _make_rhs(self) -> Callable[[float, np.ndarray], np.ndarray]:
        """``f(t, y) -> ẏ`` for scipy (see the module docstring for its steps)."""
        plant, context = self.drake.plant, self.drake.context
        force = self.drake.force
        set_state = plant.SetPositionsAndVelocities
        derivatives = plant.EvalTimeDerivatives
        yp, ydp, xd, fgen, work = self._yp, self._ydp, self._xd, self._f, self.work
        qc, qdc = self._qc, self._qdc
        o_tau, o_tt, o_ctl, o_rot = self._o
        fp, ip = self.fp, self.ip
        ny = self.ny
        empty = np.empty
        stage = self._kernel_stage
        control = self.control_into(qc, qdc)

        def f(t: float, y: np.ndarray) -> np.ndarray:
            self.nfev += 1
            to_stage(y, yp, xd, qc, qdc)
            control(t)
            if stage(t, yp, fp, ip, work, ydp, MODE_GIVEN) != 0:
                raise NonFinite(f"non-finite right-hand side at t = {t:.6g} s")
            if not drake_force(work, o_tau, o_tt, o_ctl, o_rot, fgen):
                raise NonFinite(f"non-finite generalized force at t = {t:.6g} s")
            force.GetMutableData().get_mutable_value().SetFromVector(fgen)
            set_state(context, xd)
            ydot = empty(ny)
            if not finish(derivatives(context).get_vector().CopyToVector(), ydp, y, ydot):
                raise NonFinite(f"non-finite acceleration at t = {t:.6g} s")
            return ydot

        return f

    def compile(self) -> None:
        """Compile (or load from numba's cache) the maps and the shared stage for the argument
        types :attr:`rhs` passes them, without running them."""
        y = self.initial_state()
        to_stage.compile(numba_types(y, self._yp, self._xd, self._qc, self._qdc))
        drake_force.compile(numba_types(self.work, *self._o, self._f))
        xdot = np.zeros(self.nq + self.nv)
        finish.compile(numba_types(xdot, self._ydp, y, np.empty(self.ny)))
        args = (0.0, self._yp, self.fp, self.ip, self.work, self._ydp, MODE_GIVEN)
        self._kernel_stage.compile(numba_types(*args))

    # -- one state, paper coordinates -------------------------------------------------------

    def generalized_force(self, t: float, y: np.ndarray) -> np.ndarray:
        """Drake's applied generalized force (n + 6) at the integrated state ``y``: inertial torque
        on BR, force at C, rod + spring forces; a copy."""
        self.rhs(float(t), np.ascontiguousarray(y, dtype=float))
        return self._f.copy()

    def acceleration(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, ControlOutput | None]:
        """Drake's ``q̈`` (n + 7, paper coordinates) at a paper state, under the controller.

        Args:
            t: time, s. q, qdot: paper state (n + 7 each); u is normalised for Drake.

        Returns:
            ``(q̈, control)``; control is the analytic controller's output at the mapped state
            (None when the scene is not controlled).
        """
        y = self.state_from_paper(q, qdot)
        ydot = self.rhs(float(t), y)
        nq, nv = self.nq, self.nv
        qdd = drake_to_paper_batch(_drake_q(y[:nq]), y[nq : nq + nv], ydot[nq : nq + nv])[2]
        return qdd[0], self.control_output(t)

    # -- the record -------------------------------------------------------------------------

    def sample_size(self) -> int:
        return self.nv

    def sample(self, t: float, y: np.ndarray) -> np.ndarray:
        """Drake's ``v̇`` at the sample ``y``."""
        nq, nv = self.nq, self.nv
        return self.rhs(t, np.ascontiguousarray(y))[nq : nq + nv]

    def to_paper(self, Y, rows):
        nq, nv = self.nq, self.nv
        return drake_to_paper_batch(_drake_q(Y[:, :nq]), Y[:, nq : nq + nv], rows)


def simulate(
    scene: Scene,
    settings: DrakeSettings | None = None,
    t_end: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """Integrate ``scene`` on Drake (:func:`mj_bridge.scipy_plant.simulate`): a :class:`Trajectory`
    with ``engine = drake``, the settings' default :class:`DrakeSettings()` (DOP853 at the scene's
    tolerances, the compiled controller)."""
    return scipy_plant.simulate(DrakeDynamics, scene, settings, t_end, progress)


def _drake_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("drake")
    except PackageNotFoundError:  # pragma: no cover - a source build
        return "unknown"


def _drake_q(x: np.ndarray) -> np.ndarray:
    """Drake's positions ``[u, R, p]`` of the integrated ones ``[R, u, p]`` ((n+7,) or (N, n+7))."""
    x = np.asarray(x)
    return np.concatenate([x[..., 3:7], x[..., :3], x[..., 7:]], axis=-1)


__all__ = [
    "COMPILE_LOCK",
    "ENGINE",
    "DrakeDynamics",
    "DrakeSettings",
    "NonFinite",
    "simulate",
]
