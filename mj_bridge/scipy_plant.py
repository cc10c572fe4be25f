"""The base of the engine plants stepped by scipy's loop (Pinocchio, Drake, the next one): what they
share around their engine's dynamics.

An engine's plant subclasses :class:`ScipyDynamics` and provides its engine only:

* :meth:`~ScipyDynamics.build`: the engine's model of the scene (the effects the engine implements
  itself are its own table, e.g. ``mj_bridge.pinocchio_effects.EFFECTS``);
* its state: :meth:`~ScipyDynamics.state_from_paper`, :meth:`~ScipyDynamics.groups` (the coupled
  groups of the error control), :meth:`~ScipyDynamics.to_paper` (its samples in the paper's
  coordinates);
* its right-hand side :meth:`~ScipyDynamics._make_rhs` (the engine's accelerations: its mass matrix
  and dynamics), :meth:`~ScipyDynamics.compile` and :meth:`~ScipyDynamics.sample`.
* optionally ``paper_q(y)``: the paper's q of a state, which its progress then carries
  (:mod:`analytic.progress`; without it the progress carries the time only).

The base holds the rest: the scene's analytic and compiled models, the work array of the shared
compiled stage (:mod:`mj_bridge.scipy_stage`: the map to the paper state, the controller, the force
effects of :mod:`mj_bridge.scipy_forces`, the quaternion and quadrature rates), the controller's
coupling (:meth:`~ScipyDynamics.control_into`, :meth:`~ScipyDynamics.control_output`), the stepping
(:func:`simulate`: :func:`mj_bridge.scipy_loop.integrate` under the engine's compile lock) and the
record (:meth:`~ScipyDynamics.record`: :func:`analytic.assemble.assemble` of the samples).
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from analytic.assemble import N_AUX, assemble
from analytic.error_scale import ErrorGroups
from analytic.fast import FastModel
from analytic.model import ControlOutput, TumblingModel
from analytic.runtime import compile_lock
from analytic.scene import Scene
from analytic.stepping import NonFinite
from analytic.trajectory import RunStatus, Trajectory
from mj_bridge.scipy_loop import check_t_end, integrate
from mj_bridge.scipy_loop_settings import ScipyLoopSettings
from mj_bridge.scipy_stage import stage_for, work_layout
from mj_bridge.stages import ControllerSource


class ScipyDynamics(abc.ABC):
    """One scene on an engine, with the analytic controller in every right-hand side.

    Args:
        scene: a validated scene.
        controller: ``analytic_fast`` (default) or ``analytic`` (:class:`ScipyLoopSettings`).

    Class attributes a subclass sets:
        engine: the name of its trajectories. lock_name: the :mod:`analytic.runtime.compile_lock`
        name held while it is built and compiled. settings_type: its settings record.
        sample_errors: what :meth:`sample` may raise at a sample it cannot evaluate (NaN there).

    Attributes:
        scene, controller. n, nq (= n + 7), nv (= n + 6), ny (= 2n + 20): sizes.
        analytic: the numpy :class:`~analytic.model.TumblingModel` (constants, numpy controller).
        fast: the :class:`~analytic.fast.FastModel` (packed constants ``fp``, ``ip``, compiled
            controller). k: the control's rank; controlled: ``k > 0``.
        layout, work: the compiled stage's work array and its slices
            (:func:`mj_bridge.scipy_stage.work_layout`). nfev: right-hand sides evaluated.
        error_groups: the coupled groups whose ``atol`` follows their magnitude (:meth:`groups`).
    """

    engine: ClassVar[str]
    lock_name: ClassVar[str]
    settings_type: ClassVar[type[ScipyLoopSettings]] = ScipyLoopSettings
    sample_errors: ClassVar[tuple[type[BaseException], ...]] = (
        NonFinite,
        np.linalg.LinAlgError,
        ValueError,
    )

    def __init__(
        self, scene: Scene, controller: ControllerSource | str = ControllerSource.ANALYTIC_FAST
    ):
        self.scene = scene
        self.build(scene)
        self.controller = self.settings_type(controller=controller).controller
        self.analytic = TumblingModel(scene)
        self.fast = FastModel(scene, self.analytic)
        self.n = n = scene.n
        self.nq, self.nv = n + 7, n + 6
        self.ny = 2 * n + 13 + N_AUX
        self.error_groups = self.groups(n)
        self.k = self.analytic.k
        self.controlled = self.k > 0
        self.fp, self.ip = self.fast.fp, self.fast.ip
        self._kernel_stage = stage_for(self.ip)
        self.layout = work_layout(n, self.k)
        self.work = np.zeros(max(stop for _, stop in self.layout.values()))
        self.nfev = 0
        self.setup()
        self.rhs = self._make_rhs()

    # -- what an engine provides ------------------------------------------------------------

    @abc.abstractmethod
    def build(self, scene: Scene) -> None:
        """Build the engine's model of ``scene`` (before anything else is set up)."""

    @abc.abstractmethod
    def setup(self) -> None:
        """The engine's own arrays and views of the work array, after the base's."""

    @staticmethod
    @abc.abstractmethod
    def groups(n: int) -> ErrorGroups:
        """The coupled groups of the engine's integrated state (:mod:`analytic.error_scale`)."""

    @abc.abstractmethod
    def state_from_paper(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The integrated state ``y`` (2n + 20) of a paper state, with zero quadratures."""

    @abc.abstractmethod
    def _make_rhs(self) -> Callable[[float, np.ndarray], np.ndarray]:
        """``f(t, y) -> ẏ`` for scipy: the stage, the engine's accelerations, ``ẏ``; raises
        :class:`~analytic.stepping.NonFinite` for a non-finite one."""

    @abc.abstractmethod
    def compile(self) -> None:
        """Compile (or load from numba's cache) the compiled functions :attr:`rhs` calls, for the
        argument types it passes them, without running them."""

    @abc.abstractmethod
    def control_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The paper state ``(q, q̇)`` the controller got at the last state mapped (the arrays)."""

    @abc.abstractmethod
    def sample(self, t: float, y: np.ndarray) -> np.ndarray:
        """What :meth:`to_paper` needs of the engine at one sample ``y`` (a row), under the
        controller; raises one of :attr:`sample_errors` where it cannot be evaluated."""

    @abc.abstractmethod
    def sample_size(self) -> int:
        """The length of a :meth:`sample` row."""

    @abc.abstractmethod
    def to_paper(
        self, Y: np.ndarray, rows: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The paper's ``(q, q̇, q̈, ω)`` of the samples ``Y`` (N, ny) and their :meth:`sample`
        rows (NaN where not evaluated); the integrated quaternion as it is (not renormalised)."""

    def versions(self) -> dict[str, str]:
        """The engine's version, for the trajectory's ``info``."""
        return {}

    # -- the shared parts -------------------------------------------------------------------

    def initial_state(self) -> np.ndarray:
        """``y(0)`` from the scene's ``[initial]`` table."""
        return self.state_from_paper(self.scene.initial.q0(), self.scene.initial.qdot0())

    def view(self, name: str) -> np.ndarray:
        """The slice ``name`` of the work array (:func:`~mj_bridge.scipy_stage.work_layout`)."""
        a, b = self.layout[name]
        return self.work[a:b]

    def control_into(self, q: np.ndarray, qd: np.ndarray) -> Callable[[float], None]:
        """``control(t)``: the controller at the paper state held in ``q``, ``qd`` (read at the
        call), into the stage's control slots ``[τ_c, F_C, F]`` (``MODE_GIVEN``); nothing for an
        uncontrolled scene. The numpy model with the ``analytic`` controller, else the compiled
        kernel (the numpy model where it declines)."""
        if not self.controlled:
            return lambda t: None
        if self.controller is ControllerSource.ANALYTIC:
            return self.numpy_control_into(q, qd)
        ctl = self.view("ctl")
        forces = self.fast.qddot_and_forces

        def control(t: float) -> None:
            _, torque, rod, force_at_c, _ = forces(t, q, qd)
            ctl[0:3], ctl[3:6], ctl[6:] = torque, force_at_c, rod

        return control

    def numpy_control_into(self, q: np.ndarray, qd: np.ndarray) -> Callable[[float], None]:
        """``control(t)``: the numpy model's control at the paper state held in ``q``, ``qd``
        (read at the call), into the stage's control slots ``[τ_c, F_C, F]``."""
        ctl = self.view("ctl")
        numpy_model = self.analytic.acceleration

        def control(t: float) -> None:
            c = numpy_model(t, q.copy(), qd.copy())[1]
            ctl[0:3], ctl[3:6], ctl[6:] = c.torque, c.force_at_C, c.rod_forces

        return control

    def control_output(self, t: float) -> ControlOutput | None:
        """The controller's full output at the paper state last mapped (None uncontrolled)."""
        if not self.controlled:
            return None
        q, qd = (a.copy() for a in self.control_state())
        if self.controller is ControllerSource.ANALYTIC:
            return self.analytic.acceleration(t, q, qd)[1]
        return self.fast.acceleration(t, q, qd)[1]

    def record(
        self, t: np.ndarray, Y: np.ndarray, status: RunStatus, message: str, info: dict
    ) -> Trajectory:
        """The trajectory of the samples ``Y`` (N, ny): the engine's :meth:`sample` and the
        controller's output at each sample (NaN and none where they cannot be evaluated), in
        paper coordinates (:meth:`to_paper`), then :func:`analytic.assemble.assemble`."""
        N, nq, nv = len(t), self.nq, self.nv
        rows = np.full((N, self.sample_size()), np.nan)
        controls: list[ControlOutput | None] = [None] * N
        for i in range(N):
            try:
                rows[i] = self.sample(float(t[i]), Y[i])
                controls[i] = self.control_output(float(t[i]))
            except self.sample_errors:
                continue
        q, qd, qdd, omega = self.to_paper(Y, rows)
        return assemble(
            self.analytic,
            self.engine,
            t,
            q,
            qd,
            qdd,
            controls,
            Y[:, nq + nv :],
            status,
            message,
            info,
            omega=omega,
        )


def simulate(
    dynamics: type[ScipyDynamics],
    scene: Scene,
    settings: ScipyLoopSettings | None = None,
    t_end: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """Integrate ``scene`` on the engine of ``dynamics``; samples at the scene's output rate,
    paper coordinates.

    Args:
        dynamics: the engine's :class:`ScipyDynamics`.
        scene: a validated scene.
        settings: solver, tolerances and controller (default ``dynamics.settings_type()``: DOP853
            at the scene's tolerances, the compiled controller).
        t_end: horizon, s (default ``scene.output.t_end``).
        progress: called with the simulated time reached after each step that passes a sample, s.

    Returns:
        a :class:`Trajectory` named ``dynamics.engine``; a run that fails (solver failure,
        non-finite state) returns the samples reached with ``status = failed``, one interrupted
        (KeyboardInterrupt) with ``status = interrupted``.
    """
    settings = settings or dynamics.settings_type()
    check_t_end(t_end)
    with compile_lock.compiling(dynamics.lock_name):  # a first run's helper may be at it
        plant = dynamics(scene, settings.controller)
        plant.compile()
    run, info = integrate(plant, settings, scene, t_end, progress)
    info.update(plant.versions())
    return plant.record(run.t, run.y, run.status, run.message, info)


def numba_types(*args: Any) -> tuple:
    """numba's types of ``args`` (a signature to compile for)."""
    import numba

    return tuple(numba.typeof(a) for a in args)


__all__ = ["ScipyDynamics", "numba_types", "simulate"]
