"""The fast engine: the controlled dynamics of :class:`~analytic.model.TumblingModel` (``M``, ``Q``,
modeling constraint, control constraints and the fundamental equation, Eqs. 51-53, 59, 80-89, B10)
in one compiled O(n) kernel (:mod:`analytic.fast_kernel`, numba ``njit(cache=True)``).

Usage::

    fm = FastModel(scene)                      # packs the scene's constants once
    qdd, torque, rod_forces, force_at_C, QC = fm.acceleration(t, q, qdot)
    qdd = fm.qddot(t, q, qdot)                 # the same q̈ only (the integrator's right-hand side)
    qdd, ctrl = fm.acceleration_output(t, q, qdot)  # drop-in for TumblingModel.acceleration

The numpy model stays the reference; ``tests/test_fast.py`` checks that both agree to 1e-12
(relative, Euclidean norm) on q̈, ``τ``, the rod forces and ``Q^C``.

What runs where:

* **Gauss weighting (N = M⁻¹, the paper's Eq. 89) and uncontrolled scenes**: the kernel, O(n): the
  tracked-mass rows of ``A_c`` are unit rows, so Gauss's principle fixes those accelerations, the
  free rod rows (``M_pp = s diag(m)``) are eliminated onto the 7x7 body block ``[R, u]`` by a Schur
  complement built from three mass moments, its R block is inverted in closed form, and a 4x4 LDLᵀ
  on u bordered by ``1 + k_ω`` constraint rows finishes the solve.
* **N = M⁻² (Eq. B13)**: the kernel, O(n), with the closed form
  ``Zᵀ M² Z = diag(4|u|² I, I) + |u|² w wᵀ`` (see :mod:`analytic.fast_kernel`) and
  ``M_α⁻¹ M v = v - α y (a_mᵀ v)`` in place of a product with ``M`` followed by a solve (that
  product-then-solve cost about cond(M) in accuracy and kept this path switched off until it was
  replaced). Against a 40-digit solve over 1728 random states the kernel's worst error was 5.9e-10
  where the dense numpy reference's was 7.4e-8.
* **Identity weighting**: not structured here; falls back to the numpy path (the dense
  ``(n+7)²`` solve of :func:`analytic.fundamental.solve`). Counted in ``FastModel.fallbacks``.
* **A Schur complement or the bordered constraint matrix not numerically positive definite** (the
  motion is then not unique, or barely so): falls back to the numpy path, which raises or applies its
  own rank decision. Counted in ``FastModel.fallbacks``.
* **numba not installed**: every call goes to the numpy path (``available()`` is False).

Rank of the control rows: for this model ``A_c`` never loses rank in exact arithmetic, for any
weighting: ``A_c a_m = 0`` (``H(u) u = 0``, and the tracked rows have no u entries), ``A_c`` has full
row rank (``H Hᵀ = 4|u|² I``; distinct unit rows), and the norm-constrained compliance ``K`` is
positive definite on ``a_m⊥`` (its only null direction is ``a_m``), so ``A_c K A_cᵀ``, ``Zᵀ Z`` and
``Zᵀ M² Z`` are all positive definite. The fast path therefore always reports ``rank = k``. The numpy
path's Moore-Penrose cut-off (``fundamental.PINV_RCOND`` = 1e-10 relative eigenvalue) can only drop
a direction when the Gram matrix's condition number exceeds 1e10, i.e. when the reference solution is
itself accurate to no better than ~1e-6; in that case the two paths legitimately differ.

numba's on-disk cache: see :func:`analytic.fast_kernel._jit`. In short, ``NUMBA_CACHE_DIR`` if set,
else ``__pycache__`` beside the source, else the user-wide cache dir (read-only installs); with none
writable the kernel is compiled in memory each process (about a second or two, first call only).
"""

from __future__ import annotations

import numpy as np

from analytic import fast_kernel as fk
from analytic.effects import Effect, Weighting
from analytic.model import ControlOutput, TumblingModel
from analytic.scene import Scene

# bound once: FastModel.qddot runs once per right-hand side; a global + attribute lookup per name
# costs ~20 ns of its ~1.5 µs
_empty = np.empty
_qddot_into = fk.qddot_into


def available() -> bool:
    """True when numba is importable, i.e. the compiled kernel can run."""
    return fk.HAVE_NUMBA


def pack(model: TumblingModel) -> tuple[np.ndarray, np.ndarray]:
    """Pack a model's constants for :func:`analytic.fast_kernel.evaluate`.

    Returns:
        ``(fp, ip)``: float64 array (layout ``fast_kernel.F_*``, then ``m, p_e, k_l, k_n`` and the
        mass-track ``l, λ, α, β``, then ``a``, ``d``) and int64 array (layout ``fast_kernel.I_*``,
        then the per-mass tracked flag (n) and the tracked indices (k_p)).
    """
    sc = model.scene
    n = model.n
    kw = len(model.omega_track.components) if model.omega_track else 0
    kp = len(model.mass_track.indices) if model.mass_track else 0
    head = np.zeros(fk.F_ARR)
    head[fk.F_MBR] = model.m_BR
    head[fk.F_MU0] = model.mu0
    head[fk.F_D1] = model.delta1
    head[fk.F_D2] = model.delta2
    head[fk.F_J : fk.F_J + 9] = model.J.ravel()
    head[fk.F_G : fk.F_G + 3] = model.g
    if sc.has(Effect.EXTERNAL_TORQUE):
        et = sc.external_torque
        head[fk.F_TFREQ] = et.frequency
        head[fk.F_TC : fk.F_TC + 3] = et.constant
        head[fk.F_TA : fk.F_TA + 3] = et.amplitude
    if model.omega_track:
        w = model.omega_track
        head[fk.F_WB : fk.F_WB + 3] = w.b
        head[fk.F_WS : fk.F_WS + 3] = w.sigma
        head[fk.F_GAIN : fk.F_GAIN + kw * kw] = np.asarray(w.gain, float).ravel()
    head[fk.F_TAT : fk.F_TAT + 48] = model.T_a.ravel()
    head[fk.F_TDT : fk.F_TDT + 48] = model.T_d.ravel()
    parts = [head, model.m, model.p_e, model.k_l, model.k_n]
    if model.mass_track:
        mt = model.mass_track
        parts += [mt.l, mt.lam, mt.alpha, mt.beta]
    parts += [model.a, model.d]
    fp = np.ascontiguousarray(np.concatenate([np.asarray(x, float).ravel() for x in parts]))

    ip = np.zeros(fk.I_TRACK + n + kp, dtype=np.int64)
    ip[fk.I_N], ip[fk.I_KW], ip[fk.I_KP] = n, kw, kp
    ip[fk.I_GRAV] = sc.has(Effect.GRAVITY)
    ip[fk.I_SLIN] = sc.has(Effect.SPRINGS_LINEAR)
    ip[fk.I_SCUB] = sc.has(Effect.SPRINGS_CUBIC)
    ip[fk.I_TORQ] = sc.has(Effect.EXTERNAL_TORQUE)
    ip[fk.I_WEIGHT] = {Weighting.M_INV: fk.W_GAUSS, Weighting.M_INV2: fk.W_MINV2}.get(
        model.weighting, -1
    )
    if model.omega_track:
        ip[fk.I_COMP : fk.I_COMP + kw] = model.omega_track.components
    if model.mass_track:
        idx = np.asarray(model.mass_track.indices, dtype=np.int64)
        ip[fk.I_TRACK + idx] = 1
        ip[fk.I_TRACK + n :] = idx
    return fp, ip


class FastModel:
    """The controlled dynamics of one scene through the compiled kernel.

    Args:
        scene: a validated :class:`~analytic.scene.Scene`.
        model: the numpy :class:`TumblingModel` of the same scene (built when not given); used for
            the constants and as the fallback.

    Attributes:
        n, nq, k: masses, coordinates (n + 7) and control rows (k_ω + k_p).
        compiled: True when calls go to the kernel (numba present and the weighting is structured:
            ``M^-1``, ``M^-2``, or no control at all).
        fallbacks: number of calls answered by the numpy path so far.
    """

    def __init__(self, scene: Scene, model: TumblingModel | None = None):
        self.scene = scene
        self.model = model if model is not None else TumblingModel(scene)
        self.n = self.model.n
        self.nq = self.model.nq
        self.k = self.model.k
        self.fp, self.ip = pack(self.model)
        self.compiled = available() and (
            self.k == 0 or self.model.weighting in (Weighting.M_INV, Weighting.M_INV2)
        )
        self.fallbacks = 0
        self._nout = 2 * self.nq + 3 + self.k

    def _raw(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray | None:
        """The kernel's output ``[q̈, Q^C, τ, residual]`` or None when the numpy path must answer."""
        if not self.compiled:
            return None
        out = np.empty(self._nout)
        status = fk.evaluate(float(t), q, qdot, self.fp, self.ip, out)
        return out if status == fk.STATUS_OK else None

    def _numpy(self, t, q, qdot) -> tuple[np.ndarray, ControlOutput]:
        self.fallbacks += 1
        return self.model.acceleration(t, q, qdot)

    def qddot(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """Constrained, controlled acceleration ``q̈`` (Eq. 89), shape (nq,).

        q and qdot must be contiguous float64 arrays of shape (nq,) (no conversion is made here, to
        keep the call cheap; :meth:`acceleration` converts). The result is a new array on every
        call (integrators keep it), written by :func:`analytic.fast_kernel.qddot_into`.
        """
        if self.compiled:
            qdd = _empty(self.nq)  # a fresh array each call: callers (solve_ivp) keep it
            if _qddot_into(float(t), q, qdot, self.fp, self.ip, qdd) == 0:  # fk.STATUS_OK
                return qdd
        return self._numpy(t, np.asarray(q, float), np.asarray(qdot, float))[0]

    def acceleration(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(q̈, τ, rod_forces, force_at_C, Q^C)`` at one state.

        Args:
            t: time, s.
            q, qdot: ``[R, u, p]`` (w-first u) and its rate, shape (nq,).

        Returns:
            q̈ (nq,); body-axis control torque ``τ = ¼ H Q^C_u`` (3,), N·m; rod forces
            ``F_i = Q^C_p,i`` (n,), N; force at C ``Q^C_R`` (3,), inertial, N; ``Q^C`` (nq,) with
            the norm-constraint reaction along ``[0, u, 0]`` included (as ``ControlOutput.QC``).
        """
        q = np.ascontiguousarray(q, dtype=float)
        qdot = np.ascontiguousarray(qdot, dtype=float)
        out = self._raw(t, q, qdot)
        nq = self.nq
        if out is None:
            qdd, c = self._numpy(t, q, qdot)
            return qdd, c.torque, c.rod_forces, c.force_at_C, c.QC
        QC = out[nq : 2 * nq]
        return out[:nq], out[2 * nq : 2 * nq + 3], QC[7:], QC[:3], QC

    def acceleration_output(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, ControlOutput]:
        """Same signature and result as :meth:`TumblingModel.acceleration` (``rank = k`` on the
        compiled path, see the module docstring)."""
        q = np.ascontiguousarray(q, dtype=float)
        qdot = np.ascontiguousarray(qdot, dtype=float)
        out = self._raw(t, q, qdot)
        if out is None:
            return self._numpy(t, q, qdot)
        nq = self.nq
        QC = out[nq : 2 * nq]
        ctrl = ControlOutput(
            QC=QC,
            torque=out[2 * nq : 2 * nq + 3],
            rod_forces=QC[7:],
            force_at_C=QC[:3],
            residual=out[2 * nq + 3 :],
            rank=self.k,
        )
        return out[:nq], ctrl


__all__ = ["FastModel", "available", "pack"]
