"""The Pinocchio plant: a scene integrated in Pinocchio's configuration space with ``pin.aba``, under
the same analytic controller, returning the same :class:`~analytic.trajectory.Trajectory` record as
the analytic and MuJoCo plants (paper coordinates, Eq. 44).

Pinocchio (PyPI ``pin`` >= 4.1) is optional: it is imported when a :class:`PinocchioDynamics` is built.

State integrated by scipy (one ``OdeSolver`` step at a time, :func:`analytic.stepping.step_and_sample`,
the analytic plant's loop)::

    y = [x (3), qx, qy, qz, qw, p (n) | Ṙ (3), ω (3), ṗ (n) | W, I_L (3), I_P (3)]
        '---------- q_pin ----------'   '-- velocities ---'   '---- quadratures ----'

Pinocchio's configuration as it is (C, the quaternion scalar last, the rod positions), and its
velocity with the linear part in the inertial frame: ``v_pin = [Sᵀ Ṙ, ω, ṗ]`` is formed for ``aba``
at every stage (``S`` the rotation of the normalised quaternion). Integrating Pinocchio's local
``v = Sᵀ Ṙ`` instead works too, but under the controlled Example 1's fast spin (|ω| up to ~20 rad/s)
``v`` turns with the body, and DOP853 at rtol 1e-12 then errs more in the position of C over 20 s:
9.2e-9 m with local ``v``, 5.8e-9 m with ``Ṙ`` (the analytic plant: 2.6e-9 m), each against its own
rtol-1e-14 run (C falls ~1.6 km: these are ~4e-12 relative).

``ẏ = [Ṙ, ½ q ⊗ (0, ω), ṗ | S (v̇ + ω × v), ω̇, p̈ | Ẇ, İ_L, İ_P]`` with ``v̇ = aba(q_pin, v_pin, τ)``
(see :mod:`model_xml.coordinates` for the maps). The work and impulse rates are those of
:mod:`analytic.aux_rates` and ride along outside the error control, as in the analytic plant.

The generalized force ``τ`` (n + 6) handed to ``aba`` at every right-hand side (so at every stage of
the integrator, at that stage's state):

* ``τ[:3] = Sᵀ F_C``: a force at C (the ``M^-2`` weighting's ``Q^C_R``, inertial) in body axes;
* ``τ[3:6] = τ_c + τ_g``: the control torque (body axes) and the given torque of Remark 2;
* ``τ[6+i] = F_i + F^S_i``: the rod force of the controller and the spring force
  ``F^S = −∂U_s/∂p`` of Eq. (38) (linear and cubic terms only when their effects are on).

The controller is the analytic one (Eq. 89), evaluated at the paper state mapped from Pinocchio's
(``u`` = the normalised quaternion, ``u̇ = ¼ Hᵀ ω``): by default the compiled kernel
(:mod:`analytic.kernel`), with the numpy model answering where the kernel declines
or does not apply (no numba); ``ControllerSource.ANALYTIC`` uses the numpy model
always. The mapping, the controller, the springs, the given torque, the quaternion and position
rates and the quadratures are one compiled call (:func:`_make_stage`); ``pin.aba`` is a second call,
and a third compiled call (:func:`_finish`) maps its result into ``ẏ`` and checks it is finite. The
maps written out there for numba are those of :mod:`model_xml.coordinates`
(:func:`~model_xml.coordinates.pinocchio_plant_to_pinocchio`,
:func:`~model_xml.coordinates.pinocchio_plant_to_paper`), and tested against them.

The run is stepped by :func:`analytic.stepping.step_and_sample` and its record built by
:func:`analytic.assemble.assemble`, as the analytic plant's.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from analytic import aux_rates as _aux
from analytic.assemble import N_AUX, assemble
from analytic.aux_rates import rates
from analytic.effects import Effect
from analytic.error_scale import ErrorGroups
from analytic.fast import FastModel
from analytic.kernel.calls import tail
from analytic.kernel.entry import Solver, evaluate_as, solver_of
from analytic.kernel.kinematics import rotation
from analytic.kernel.layout import (
    F_MBR,
    F_MU0,
    F_TA,
    F_TC,
    F_TFREQ,
    I_KP,
    I_KW,
    I_N,
    I_SCUB,
    I_SLIN,
    I_TORQ,
    STATUS_OK,
    STATUS_UNSUPPORTED,
)
from analytic.model import ControlOutput, TumblingModel
from analytic.runtime import compile_lock
from analytic.runtime.jit import KERNEL_SOURCES, jit, source_fingerprint
from analytic.scene import Scene
from analytic.stepping import NonFinite
from analytic.trajectory import Engine, RunStatus, Trajectory
from mj_bridge.pinocchio_model import build_model, import_pinocchio
from mj_bridge.pinocchio_settings import PinocchioSettings, check_pinocchio_size
from mj_bridge.scipy_loop import check_t_end, integrate
from mj_bridge.stages import ControllerSource
from model_xml.coordinates import (
    paper_to_pinocchio_plant,
    pinocchio_to_paper_acc,
    pinocchio_to_paper_batch,
)

# Modes of the compiled stage
MODE_GIVEN = 0  # use the control already in the work array
MODE_KERNEL = 1  # evaluate the control with the compiled kernel
MODE_MAP = 2  # only map y to the paper's (q, q̇) in the work array, then return
STATUS_NONFINITE = 3  # as analytic.fast_rhs.STATUS_NONFINITE

SUPPORTED_EFFECTS = frozenset(Effect)
"""Every effect of :class:`analytic.effects.Effect` (all are forces this plant applies)."""


# ----------------------------------------------------------------------------------------------
# The compiled stage
# ----------------------------------------------------------------------------------------------


def work_layout(n: int, k: int) -> dict[str, tuple[int, int]]:
    """Slices ``name -> (start, stop)`` of the work array (float64) shared with the compiled stage.

    ``qpin`` (n+7), ``vpin`` (n+6), ``tau`` (n+6): the arguments of ``aba``; ``q``, ``qd`` (n+7):
    the mapped paper state; ``ctl`` = ``[τ_c (3), F_C (3), F (n)]`` the control; ``tt`` (3) the total
    body torque ``τ_c + τ_g``; ``kout`` (2(n+7) + 3 + k) the kernel's output; ``rot`` (9) the
    rotation ``S`` (body -> inertial, row-major) of the normalised quaternion.
    """
    nq, nv = n + 7, n + 6
    sizes = [
        ("qpin", nq),
        ("vpin", nv),
        ("tau", nv),
        ("q", nq),
        ("qd", nq),
        ("ctl", n + 6),
        ("tt", 3),
        ("kout", 2 * nq + 3 + k),
        ("rot", 9),
    ]
    out, o = {}, 0
    for name, size in sizes:
        out[name] = (o, o + size)
        o += size
    return out


def _make_stage(deps: int, solver: int):
    """The stage closing over ``deps`` (the source fingerprint of the kernel and of
    :mod:`analytic.aux_rates`, which it calls; see :func:`analytic.runtime.jit.jit_entry`) and the
    solve it embeds (``solver``, a :class:`Solver`; numba drops the other branches)."""

    def stage(t, y, fp, ip, work, ydot, mode):  # pragma: no cover - compiled
        """Everything of ``ẏ`` but ``v̇``, and ``aba``'s arguments (see the module docstring).

        Args:
            t: time, s. y (2n + 20): the integrated state. fp, ip: :func:`analytic.fast.pack`.
            work: the work array (:func:`work_layout`). ydot (2n + 20): receives ``ẏ`` except
                ``ydot[n+7 : 2n+13]`` (``v̇``, from ``aba``). mode: ``MODE_*``.

        Returns:
            status: 0; the kernel's nonzero status (the caller supplies the control and calls again
            with ``MODE_GIVEN``); :data:`STATUS_NONFINITE` for a non-finite ``ẏ`` or ``τ``.
        """
        if deps < 0:  # never true: ties numba's cache key to the sources this embeds
            return STATUS_UNSUPPORTED
        n = ip[I_N]
        kp = ip[I_KP]
        k = ip[I_KW] + kp
        nq = n + 7
        nv = n + 6
        o_v = nq
        o_tau = o_v + nv
        o_q = o_tau + nv
        o_qd = o_q + nq
        o_ctl = o_qd + nq
        o_tt = o_ctl + n + 6
        o_k = o_tt + 3
        o_rot = o_k + 2 * nq + 3 + k
        # quaternion (x, y, z, w in y), normalised
        qx, qy, qz, qw = y[3], y[4], y[5], y[6]
        s = 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        u0, u1, u2, u3 = qw * s, qx * s, qy * s, qz * s
        s00, s01, s02, s10, s11, s12, s20, s21, s22 = rotation(u0, u1, u2, u3)  # S(u), Eq. 11
        work[o_rot], work[o_rot + 1], work[o_rot + 2] = s00, s01, s02
        work[o_rot + 3], work[o_rot + 4], work[o_rot + 5] = s10, s11, s12
        work[o_rot + 6], work[o_rot + 7], work[o_rot + 8] = s20, s21, s22
        Rd0, Rd1, Rd2 = y[nq], y[nq + 1], y[nq + 2]
        w0, w1, w2 = y[nq + 3], y[nq + 4], y[nq + 5]
        # aba's q and v; the paper's q, q̇ (u̇ = ¼ Hᵀ ω, Eq. 12 inverted)
        for i in range(3):
            work[i] = y[i]
            work[o_q + i] = y[i]
        work[3], work[4], work[5], work[6] = u1, u2, u3, u0
        work[o_q + 3], work[o_q + 4], work[o_q + 5], work[o_q + 6] = u0, u1, u2, u3
        for i in range(n):
            work[7 + i] = y[7 + i]
            work[o_q + 7 + i] = y[7 + i]
        # Pinocchio's local linear velocity v = Sᵀ Ṙ
        work[o_v] = s00 * Rd0 + s10 * Rd1 + s20 * Rd2
        work[o_v + 1] = s01 * Rd0 + s11 * Rd1 + s21 * Rd2
        work[o_v + 2] = s02 * Rd0 + s12 * Rd1 + s22 * Rd2
        for i in range(3, nv):
            work[o_v + i] = y[nq + i]
        work[o_qd], work[o_qd + 1], work[o_qd + 2] = Rd0, Rd1, Rd2
        work[o_qd + 3] = 0.5 * (-u1 * w0 - u2 * w1 - u3 * w2)
        work[o_qd + 4] = 0.5 * (u0 * w0 - u3 * w1 + u2 * w2)
        work[o_qd + 5] = 0.5 * (u3 * w0 + u0 * w1 - u1 * w2)
        work[o_qd + 6] = 0.5 * (-u2 * w0 + u1 * w1 + u0 * w2)
        for i in range(n):
            work[o_qd + 7 + i] = y[nq + 6 + i]
        if mode == MODE_MAP:
            return STATUS_OK
        # the control at this state
        if mode == MODE_KERNEL and k > 0:
            kout = work[o_k : o_k + 2 * nq + 3 + k]
            qk, qdk = work[o_q : o_q + nq], work[o_qd : o_qd + nq]
            status = evaluate_as(solver, t, qk, qdk, fp, ip, kout)  # only this solve compiled in
            if status != STATUS_OK:
                return status
            for r in range(3):
                work[o_ctl + r] = kout[2 * nq + r]  # τ_c, body axes
                work[o_ctl + 3 + r] = kout[nq + r]  # F_C = Q^C_R, inertial
            for i in range(n):
                work[o_ctl + 6 + i] = kout[nq + 7 + i]  # F_i = Q^C_p,i
        tt0, tt1, tt2 = work[o_ctl], work[o_ctl + 1], work[o_ctl + 2]
        if ip[I_TORQ]:  # the given torque of Remark 2
            ct = math.cos(fp[F_TFREQ] * t)
            tt0 += fp[F_TC] + fp[F_TA] * ct
            tt1 += fp[F_TC + 1] + fp[F_TA + 1] * ct
            tt2 += fp[F_TC + 2] + fp[F_TA + 2] * ct
        work[o_tt], work[o_tt + 1], work[o_tt + 2] = tt0, tt1, tt2
        f0, f1, f2 = work[o_ctl + 3], work[o_ctl + 4], work[o_ctl + 5]
        # τ: force at C in body axes (Sᵀ F_C), torque, rod forces + springs
        work[o_tau] = s00 * f0 + s10 * f1 + s20 * f2
        work[o_tau + 1] = s01 * f0 + s11 * f1 + s21 * f2
        work[o_tau + 2] = s02 * f0 + s12 * f1 + s22 * f2
        work[o_tau + 3], work[o_tau + 4], work[o_tau + 5] = tt0, tt1, tt2
        for i in range(n):
            work[o_tau + 6 + i] = work[o_ctl + 6 + i]
        lin = ip[I_SLIN] != 0
        cub = ip[I_SCUB] != 0
        if n > 0 and (lin or cub):
            # F^S = -∂U_s/∂p, Eq. (38): spring j (0..n) has extension x_j - x_{j-1}, x = p - p_e,
            # x_{-1} = x_n = 0, force f_j = k_l e + k_n e³; mass i gets f_{i+1} - f_i
            o = tail(n, kp)
            o_pe, o_kl, o_kn = o.p_e, o.k_l, o.k_n
            x_prev = 0.0
            for j in range(n + 1):
                x_j = y[7 + j] - fp[o_pe + j] if j < n else 0.0
                e = x_j - x_prev
                f = 0.0
                if lin:
                    f += fp[o_kl + j] * e
                if cub:
                    f += fp[o_kn + j] * e * e * e
                if j < n:
                    work[o_tau + 6 + j] -= f
                if j > 0:
                    work[o_tau + 5 + j] += f
                x_prev = x_j
        # ẏ except the accelerations: Ṙ, quaternion rate ½ q ⊗ (0, ω) of the integrated (raw) quaternion, ṗ
        ydot[0], ydot[1], ydot[2] = Rd0, Rd1, Rd2
        ydot[3] = 0.5 * (qw * w0 + qy * w2 - qz * w1)
        ydot[4] = 0.5 * (qw * w1 + qz * w0 - qx * w2)
        ydot[5] = 0.5 * (qw * w2 + qx * w1 - qy * w0)
        ydot[6] = -0.5 * (qx * w0 + qy * w1 + qz * w2)
        for i in range(n):
            ydot[7 + i] = y[nq + 6 + i]
        # work and impulses (analytic.aux_rates; a, d follow the mass-track arrays in fp)
        o = tail(n, kp)
        rates(
            work[o_q : o_q + nq],
            work[o_qd : o_qd + nq],
            work[o_tt : o_tt + 3],
            work[o_ctl + 6 : o_ctl + 6 + n],
            work[o_ctl + 3 : o_ctl + 6],
            fp[o.a : o.a + 3],
            fp[o.d : o.d + 3],
            fp[o.m : o.m + n],
            fp[F_MU0],
            fp[F_MBR] + fp[F_MU0],
            ydot[nq + nv :],
        )
        for i in range(nq):
            if not math.isfinite(ydot[i]):
                return STATUS_NONFINITE
        for i in range(nq + nv, ydot.shape[0]):
            if not math.isfinite(ydot[i]):
                return STATUS_NONFINITE
        for i in range(nv):
            if not math.isfinite(work[o_tau + i]):
                return STATUS_NONFINITE
        return STATUS_OK

    return stage


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


DEPS = source_fingerprint(*KERNEL_SOURCES, _aux)
stage_gauss = jit(_make_stage(DEPS, int(Solver.GAUSS)))
stage_minv2 = jit(_make_stage(DEPS, int(Solver.MINV2)))
stage_identity = jit(_make_stage(DEPS, int(Solver.IDENTITY)))
stage = jit(_make_stage(DEPS, int(Solver.ANY)))  # any scene: every solve compiled in


def stage_for(ip: np.ndarray):
    """The compiled stage embedding only the solve the packed scene ``ip`` needs."""
    solver = solver_of(ip)
    return {Solver.MINV2: stage_minv2, Solver.IDENTITY: stage_identity}.get(solver, stage_gauss)


finish = jit(_finish)


# ----------------------------------------------------------------------------------------------
# The plant
# ----------------------------------------------------------------------------------------------


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


class PinocchioDynamics:
    """One scene on Pinocchio, with the analytic controller in every right-hand side.

    Args:
        scene: a validated scene.
        controller: ``analytic_fast`` (default) or ``analytic`` (see :class:`PinocchioSettings`).

    Attributes:
        model, data: the ``pinocchio.Model`` (:func:`mj_bridge.pinocchio_model.build_model`) and
            its ``Data``.
        n, nq (= n + 7, also Pinocchio's), nv (= n + 6), ny (= 2n + 20): sizes.
        analytic: the numpy :class:`~analytic.model.TumblingModel` (constants, numpy controller).
        fast: the :class:`~analytic.fast.FastModel` (packed constants, compiled controller).
        nfev: right-hand sides evaluated; fallbacks: stages whose control the numpy model gave.
        error_groups: the coupled groups whose ``atol`` follows their magnitude (:func:`error_groups`).
    """

    def __init__(
        self, scene: Scene, controller: ControllerSource | str = ControllerSource.ANALYTIC_FAST
    ):
        check_pinocchio_size(scene)  # before Pinocchio allocates its data (n³)
        self.pin = import_pinocchio()
        self.scene = scene
        self.controller = PinocchioSettings(controller=controller).controller
        self.model = build_model(scene)
        self.data = self.model.createData()
        self.analytic = TumblingModel(scene)
        self.fast = FastModel(scene, self.analytic)
        self.n = n = scene.n
        self.nq, self.nv = n + 7, n + 6
        self.ny = 2 * n + 13 + N_AUX
        self.error_groups = error_groups(n)
        self.k = self.analytic.k
        self.controlled = self.k > 0
        self.fp, self.ip = self.fast.fp, self.fast.ip
        self._kernel_stage = stage_for(self.ip)
        self.layout = work_layout(n, self.k)
        self.work = np.zeros(max(stop for _, stop in self.layout.values()))
        w = self.work
        v = {name: w[a:b] for name, (a, b) in self.layout.items()}
        self._qpin, self._vpin, self._tau = v["qpin"], v["vpin"], v["tau"]
        self._q, self._qd, self._ctl = v["q"], v["qd"], v["ctl"]
        self._tt = v["tt"]
        use_kernel = self.fast.compiled and self.controller is ControllerSource.ANALYTIC_FAST
        self._mode = MODE_KERNEL if (use_kernel and self.controlled) else MODE_GIVEN
        self._numpy_each_stage = self.controlled and not use_kernel
        self.nfev = 0
        self.fallbacks = 0
        self.rhs = self._make_rhs()

    # -- coordinates ------------------------------------------------------------------------

    def state_from_paper(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The integrated state ``y`` (2n + 20) of a paper state, with zero quadratures:
        ``[q_pin, Ṙ, ω, ṗ, 0]`` (u normalised, ``ω = H(u) u̇``)."""
        return np.concatenate([paper_to_pinocchio_plant(q, qdot), np.zeros(N_AUX)])

    def initial_state(self) -> np.ndarray:
        """``y(0)`` from the scene's ``[initial]`` table."""
        return self.state_from_paper(self.scene.initial.q0(), self.scene.initial.qdot0())

    # -- the right-hand side ----------------------------------------------------------------

    def _numpy_control(self, t: float) -> None:
        """The control from the numpy model at the mapped paper state, into the work array."""
        self.fallbacks += 1
        _, c = self.analytic.acceleration(t, self._q.copy(), self._qd.copy())
        ctl = self._ctl
        ctl[0:3] = c.torque
        ctl[3:6] = c.force_at_C
        ctl[6:] = c.rod_forces

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
        import numba

        ydot = np.empty(self.ny)
        if not self._numpy_each_stage:
            args = (0.0, self.initial_state(), self.fp, self.ip, self.work, ydot, self._mode)
            self._kernel_stage.compile(tuple(numba.typeof(a) for a in args))
        acc = self.pin.aba(self.model, self.data, self._qpin, self._vpin, self._tau)
        finish.compile(tuple(numba.typeof(a) for a in (acc, self.work, ydot)))

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

    def control_output(self, t: float) -> ControlOutput | None:
        """The controller's full output at the paper state last mapped into the work array."""
        if not self.controlled:
            return None
        q, qd = self._q.copy(), self._qd.copy()
        if self.controller is ControllerSource.ANALYTIC:
            return self.analytic.acceleration(t, q, qd)[1]
        return self.fast.acceleration(t, q, qd)[1]


# ----------------------------------------------------------------------------------------------
# simulate
# ----------------------------------------------------------------------------------------------


def simulate(
    scene: Scene,
    settings: PinocchioSettings | None = None,
    t_end: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """Integrate ``scene`` on Pinocchio; samples at the scene's output rate, paper coordinates.

    Args:
        scene: a validated scene.
        settings: solver, tolerances and controller (default :class:`PinocchioSettings()`: DOP853
            at the scene's tolerances, the compiled controller).
        t_end: horizon, s (default ``scene.output.t_end``).
        progress: called with the simulated time reached after each step that passes a sample, s.

    Returns:
        a :class:`Trajectory` with ``engine = pinocchio``; a run that fails (solver failure,
        non-finite state) returns the samples reached with ``status = failed``, one interrupted
        (KeyboardInterrupt) with ``status = interrupted``.
    """
    settings = settings or PinocchioSettings()
    check_t_end(t_end)
    with compile_lock.compiling(compile_lock.PINOCCHIO):  # a first run's helper may be at it
        plant = PinocchioDynamics(scene, settings.controller)
        plant.compile()
    run, info = integrate(plant, settings, scene, t_end, progress)
    info["pinocchio_version"] = plant.pin.__version__
    return _assemble(plant, run.t, run.y, run.status, run.message, info)


def _assemble(
    plant: PinocchioDynamics,
    t: np.ndarray,
    Y: np.ndarray,
    status: RunStatus,
    message: str,
    info: dict,
) -> Trajectory:
    """The record of the samples ``Y`` (N, ny): Pinocchio's ``v̇`` and the controller's output at
    each sample (NaN and none where they cannot be evaluated), mapped to paper coordinates, then
    :func:`analytic.assemble.assemble`."""
    N, nq, nv = len(t), plant.nq, plant.nv
    a_pin = np.full((N, nv), np.nan)
    v_pin = np.full((N, nv), np.nan)
    controls: list[ControlOutput | None] = [None] * N
    for i in range(N):
        try:
            a_pin[i] = plant.v_dot(float(t[i]), Y[i])
            v_pin[i] = plant._vpin
            controls[i] = plant.control_output(float(t[i]))
        except (NonFinite, np.linalg.LinAlgError, ValueError):
            continue
    # the integrated quaternion as it is (not renormalised: its norm error is the run's)
    q, qd, qdd, omega = pinocchio_to_paper_batch(Y[:, :nq], v_pin, a_pin)
    return assemble(
        plant.analytic,
        Engine.PINOCCHIO,
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


__all__ = [
    "SUPPORTED_EFFECTS",
    "NonFinite",
    "PinocchioDynamics",
    "PinocchioSettings",
    "simulate",
    "work_layout",
]
