"""The Pinocchio plant: a scene integrated in Pinocchio's configuration space with ``pin.aba``, under
the same analytic controller, returning the same :class:`~analytic.trajectory.Trajectory` record as
the analytic and MuJoCo plants (paper coordinates, Eq. 44).

Pinocchio (PyPI ``pin`` >= 4.1) is optional: it is imported when a :class:`PinocchioDynamics` is built.
The plant is one of the plants on scipy's loop (:class:`mj_bridge.scipy_plant.ScipyDynamics`): this
module provides the engine, its state and its accelerations only.

State integrated by scipy (one ``OdeSolver`` step at a time, :func:`analytic.stepping.step_and_sample`,
the analytic plant's loop): the stage state of :mod:`mj_bridge.scipy_stage` itself::

    y = [x (3), qx, qy, qz, qw, p (n) | Ṙ (3), ω (3), ṗ (n) | W, I_L (3), I_P (3)]
        '---------- q_pin ----------'   '-- velocities ---'   '---- quadratures ----'

Pinocchio's configuration as it is (C, the quaternion scalar last, the rod positions), and its
velocity with the linear part in the inertial frame: ``v_pin = [Sᵀ Ṙ, ω, ṗ]`` is formed for ``aba``
at every stage (``S`` the rotation of the normalised quaternion); integrating ``Ṙ`` rather than
Pinocchio's local ``v = Sᵀ Ṙ`` keeps the integration error of C small under a fast spin
(``docs/performance.md``).

``ẏ = [Ṙ, ½ q ⊗ (0, ω), ṗ | S (v̇ + ω × v), ω̇, p̈ | Ẇ, İ_L, İ_P]`` with ``v̇ = aba(q_pin, v_pin, τ)``
(see :mod:`model_xml.coordinates` for the maps). The work and impulse rates are those of
:mod:`analytic.aux_rates` and ride along outside the error control, as in the analytic plant.

Every right-hand side is one compiled call of the shared stage (:mod:`mj_bridge.scipy_stage`: the
map to the paper state, the controller, the force effects, ``τ``, the rates), ``pin.aba``, and a
compiled :func:`_finish` mapping its result into ``ẏ`` and checking it is finite. The generalized
force ``τ`` (n + 6) handed to ``aba``:

* ``τ[:3] = Sᵀ F_C``: a force at C (the ``M^-2`` weighting's ``Q^C_R``, inertial) in body axes;
* ``τ[3:6] = τ_c + τ_g``: the control torque (body axes) and the given torque of Remark 2;
* ``τ[6+i] = F_i + F^S_i``: the rod force of the controller and the spring force
  ``F^S = −∂U_s/∂p`` of Eq. (38).

The controller is the analytic one (Eq. 89), evaluated at the paper state mapped from Pinocchio's
(``u`` = the normalised quaternion, ``u̇ = ¼ Hᵀ ω``): by default the compiled kernel inside the stage
(:mod:`analytic.kernel`), with the numpy model answering where the kernel declines or does not apply
(no numba); ``ControllerSource.ANALYTIC`` uses the numpy model always. Gravity and the masses'
inertia are Pinocchio's model (:mod:`mj_bridge.pinocchio_effects`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from analytic.assemble import N_AUX
from analytic.error_scale import ErrorGroups
from analytic.model import ControlOutput
from analytic.runtime import compile_lock
from analytic.runtime.jit import jit
from analytic.scene import Scene
from analytic.stepping import NonFinite
from analytic.trajectory import Engine, Trajectory
from mj_bridge import scipy_plant
from mj_bridge.pinocchio_model import build_model, import_pinocchio
from mj_bridge.pinocchio_settings import PinocchioSettings, check_pinocchio_size
from mj_bridge.scipy_plant import ScipyDynamics, numba_types
from mj_bridge.scipy_stage import MODE_GIVEN, MODE_KERNEL, MODE_MAP, STATUS_NONFINITE
from mj_bridge.stages import ControllerSource
from model_xml.coordinates import (
    paper_to_pinocchio_plant,
    pinocchio_to_paper_acc,
    pinocchio_to_paper_batch,
)


def _finish(acc, work, ydot):  # pragma: no cover - compiled
    """The accelerations of ``ẏ`` from aba's ``v̇`` (``acc``): ``R̈ = S (v̇ + ω × v)``, ``ω̇``, ``p̈``,
    into ``ydot[nq : nq + nv]``; False when one is a NaN or an infinity."""
    nv = acc.shape[0]
    nq = nv + 1
    o_v = nq
    o_rot = work.shape[0] - 9
    v0, v1, v2 = work[o_v], work[o_v + 1], work[o_v + 2]
    w0, w1, w2 = work[o_v + 3], work[o_v + 4], work[o_v + 5]
    b0 = acc[0] + (w1 * v2 - w2 * v1)
    b1 = acc[1] + (w2 * v0 - w0 * v2)
    b2 = acc[2] + (w0 * v1 - w1 * v0)
    for r in range(3):
        ydot[nq + r] = (
            work[o_rot + 3 * r] * b0 + work[o_rot + 3 * r + 1] * b1 + work[o_rot + 3 * r + 2] * b2
        )
    for i in range(3, nv):
        ydot[nq + i] = acc[i]
    ok = True
    for i in range(nv):
        if not math.isfinite(ydot[nq + i]):
            ok = False
    return ok


finish = jit(_finish)


def error_groups(n: int) -> ErrorGroups:
    """The coupled groups of ``y = [x, q_xyzw, p | Ṙ, ω, ṗ | quadratures]`` (:mod:`analytic.error_scale`):
    positions ``{x, p}``, the quaternion, velocities ``{Ṙ, ṗ}``, ω."""
    nq = n + 7
    return ErrorGroups.of(
        2 * n + 13,
        np.r_[0:3, 7:nq],
        np.arange(3, 7),
        np.r_[nq : nq + 3, nq + 6 : nq + 6 + n],
        np.arange(nq + 3, nq + 6),
    )


class PinocchioDynamics(ScipyDynamics):
    """One scene on Pinocchio, with the analytic controller in every right-hand side
    (:class:`~mj_bridge.scipy_plant.ScipyDynamics`).

    Args:
        scene: a validated scene.
        controller: ``analytic_fast`` (default) or ``analytic`` (see :class:`PinocchioSettings`).

    Attributes:
        pin: the ``pinocchio`` module. model, data: the ``pinocchio.Model``
            (:func:`mj_bridge.pinocchio_model.build_model`) and its ``Data``.
        fallbacks: stages whose control the numpy model gave.
    """

    engine = Engine.PINOCCHIO.value
    lock_name = compile_lock.PINOCCHIO
    settings_type = PinocchioSettings

    def build(self, scene: Scene) -> None:
        check_pinocchio_size(scene)  # before Pinocchio allocates its data (n³)
        self.pin = import_pinocchio()
        self.model = build_model(scene)
        self.data = self.model.createData()

    def setup(self) -> None:
        self._qpin, self._vpin, self._tau = self.view("qpin"), self.view("vpin"), self.view("tau")
        self._q, self._qd = self.view("q"), self.view("qd")
        use_kernel = self.fast.compiled and self.controller is ControllerSource.ANALYTIC_FAST
        self._mode = MODE_KERNEL if (use_kernel and self.controlled) else MODE_GIVEN
        self._numpy_each_stage = self.controlled and not use_kernel
        self._numpy_model_control = self.numpy_control_into(self._q, self._qd)
        self.fallbacks = 0

    groups = staticmethod(error_groups)

    def versions(self) -> dict[str, str]:
        return {"pinocchio_version": self.pin.__version__}

    # -- coordinates ------------------------------------------------------------------------

    def state_from_paper(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The integrated state ``y`` (2n + 20) of a paper state, with zero quadratures:
        ``[q_pin, Ṙ, ω, ṗ, 0]`` (u normalised, ``ω = H(u) u̇``)."""
        return np.concatenate([paper_to_pinocchio_plant(q, qdot), np.zeros(N_AUX)])

    def paper_q(self, y: np.ndarray) -> np.ndarray:
        """The paper's q of a state ``y`` (its progress's state): ``q_pin`` with its quaternion
        w first, as :meth:`to_paper` makes it."""
        q_pin = y[: self.nq]
        return np.concatenate([q_pin[:3], q_pin[6:7], q_pin[3:6], q_pin[7:]])

    def control_state(self) -> tuple[np.ndarray, np.ndarray]:
        return self._q, self._qd

    # -- the right-hand side ----------------------------------------------------------------

    def _numpy_control(self, t: float) -> None:
        """The control from the numpy model at the mapped paper state, into the work array."""
        self.fallbacks += 1
        self._numpy_model_control(t)

    def _stage(self, t: float, y: np.ndarray, ydot: np.ndarray) -> None:
        """Fill ``ydot`` except ``v̇`` and aba's arguments in the work array (any controller path)."""
        fp, ip, work = self.fp, self.ip, self.work
        stage = self._kernel_stage
        if self._numpy_each_stage:
            stage(t, y, fp, ip, work, ydot, MODE_MAP)
            self._numpy_control(t)
            status = stage(t, y, fp, ip, work, ydot, MODE_GIVEN)
        else:
            status = stage(t, y, fp, ip, work, ydot, self._mode)
            if status != 0 and status != STATUS_NONFINITE:  # the kernel declined this stage
                self._numpy_control(t)
                status = stage(t, y, fp, ip, work, ydot, MODE_GIVEN)
        if status == STATUS_NONFINITE:
            raise NonFinite(f"non-finite right-hand side at t = {t:.6g} s")

    def _make_rhs(self) -> Callable[[float, np.ndarray], np.ndarray]:
        """``f(t, y) -> ẏ`` for scipy: one compiled stage, ``pin.aba``, one compiled copy."""
        aba = self.pin.aba
        model, data = self.model, self.data
        qpin, vpin, tau = self._qpin, self._vpin, self._tau
        fp, ip, work = self.fp, self.ip, self.work
        ny = self.ny
        empty = np.empty
        mode = self._mode
        slow = self._stage
        fast_ok = not self._numpy_each_stage
        stage = self._kernel_stage

        def f(t: float, y: np.ndarray) -> np.ndarray:
            self.nfev += 1
            ydot = empty(ny)
            if not (fast_ok and stage(t, y, fp, ip, work, ydot, mode) == 0):
                slow(t, y, ydot)  # declined, non-finite (raises) or the numpy controller
            if not finish(aba(model, data, qpin, vpin, tau), work, ydot):
                raise NonFinite(f"non-finite acceleration at t = {t:.6g} s")
            return ydot

        return f

    def compile(self) -> None:
        """Compile (or load from numba's cache) the compiled stage and copy for the argument types
        :attr:`rhs` passes them, without running them (nothing when the compiled controller is
        not used)."""
        if not self.fast.compiled:
            return
        ydot = np.empty(self.ny)
        if not self._numpy_each_stage:
            args = (0.0, self.initial_state(), self.fp, self.ip, self.work, ydot, self._mode)
            self._kernel_stage.compile(numba_types(*args))
        acc = self.pin.aba(self.model, self.data, self._qpin, self._vpin, self._tau)
        finish.compile(numba_types(acc, self.work, ydot))

    # -- one state, paper coordinates -------------------------------------------------------

    def pinocchio_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q_pin, v_pin)`` handed to ``aba`` at the last state mapped (copies)."""
        return self._qpin.copy(), self._vpin.copy()

    def generalized_force(self, t: float, y: np.ndarray) -> np.ndarray:
        """Pinocchio's ``τ`` (n + 6) at the integrated state ``y``: force at C (body axes), torque
        (body axes), rod + spring forces; a copy."""
        self._stage(float(t), np.ascontiguousarray(y, dtype=float), np.empty(self.ny))
        return self._tau.copy()

    def v_dot(self, t: float, y: np.ndarray) -> np.ndarray:
        """``aba`` at the integrated state ``y`` under the controller, ``v̇`` (n + 6)."""
        self._stage(float(t), np.ascontiguousarray(y, dtype=float), np.empty(self.ny))
        return np.array(self.pin.aba(self.model, self.data, self._qpin, self._vpin, self._tau))

    def acceleration(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, ControlOutput | None]:
        """Pinocchio's ``q̈`` (n + 7, paper coordinates) at a paper state, under the controller.

        Args:
            t: time, s. q, qdot: paper state (n + 7 each); u is normalised for Pinocchio.

        Returns:
            ``(q̈, control)``; control is the analytic controller's output at the mapped state
            (None when the scene is not controlled).
        """
        y = self.state_from_paper(q, qdot)
        a = self.v_dot(t, y)
        return pinocchio_to_paper_acc(self._qpin, self._vpin, a), self.control_output(t)

    # -- the record -------------------------------------------------------------------------

    def sample_size(self) -> int:
        return 2 * self.nv

    def sample(self, t: float, y: np.ndarray) -> np.ndarray:
        """``[v̇ (aba), v_pin]`` at the sample ``y``."""
        a = self.v_dot(t, y)
        return np.concatenate([a, self._vpin])

    def to_paper(self, Y, rows):
        nq, nv = self.nq, self.nv
        return pinocchio_to_paper_batch(Y[:, :nq], rows[:, nv:], rows[:, :nv])


def simulate(
    scene: Scene,
    settings: PinocchioSettings | None = None,
    t_end: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """Integrate ``scene`` on Pinocchio (:func:`mj_bridge.scipy_plant.simulate`): a
    :class:`Trajectory` with ``engine = pinocchio``, the settings' default
    :class:`PinocchioSettings()` (DOP853 at the scene's tolerances, the compiled controller)."""
    return scipy_plant.simulate(PinocchioDynamics, scene, settings, t_end, progress)


__all__ = [
    "NonFinite",
    "PinocchioDynamics",
    "PinocchioSettings",
    "error_groups",
    "simulate",
]
