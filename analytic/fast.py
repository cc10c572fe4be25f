"""The fast engine: the controlled dynamics of :class:`~analytic.model.TumblingModel` (``M``, ``Q``,
modeling constraint, control constraints and the fundamental equation, Eqs. 51-53, 59, 80-89, B10)
in one compiled O(n) kernel (:mod:`analytic.kernel`, numba ``njit(cache=True)``).

Usage::

    fm = FastModel(scene)                      # packs the scene's constants once
    qdd, ctrl = fm.acceleration(t, q, qdot)    # q̈ and the control, as TumblingModel.acceleration
    qdd = fm.qddot(t, q, qdot)                 # the same q̈ only (the integrator's right-hand side)
    qdd, torque, rod_forces, force_at_C, QC = fm.qddot_and_forces(t, q, qdot)  # views, no record

The numpy model stays the reference; ``tests/analytic/test_fast.py`` checks that both agree to 1e-12
(relative, Euclidean norm) on q̈, ``τ``, the rod forces and ``Q^C``.

What runs where:

* **Gauss weighting (N = M⁻¹, the paper's Eq. 89) and uncontrolled scenes**: the kernel, O(n): the
  tracked-mass rows of ``A_c`` are unit rows, so Gauss's principle fixes those accelerations, the
  free rod rows (``M_pp = s diag(m)``) are eliminated onto the 7x7 body block ``[R, u]`` by a Schur
  complement built from three mass moments, its R block is inverted in closed form, and a 4x4 LDLᵀ
  on u bordered by ``1 + k_ω`` constraint rows finishes the solve.
* **N = M⁻² (Eq. B13)**: the kernel, O(n), with the closed form
  ``Zᵀ M² Z = diag(4|u|² I, I) + |u|² w wᵀ`` (see :mod:`analytic.kernel.minv2`) and
  ``M_α⁻¹ M v = v - α y (a_mᵀ v)`` in place of a product with ``M`` followed by a solve (which
  costs about cond(M) in accuracy; its accuracy against a 40-digit solve: ``docs/performance.md``).
  Compiled only when a scene asks for this weighting.
* **Identity weighting (N = I)**: the kernel, ``O(n k²)``: ``Q_c = Z (ZᵀZ)⁻¹ r`` from a Householder
  QR of ``Z = K A_cᵀ`` with unit columns, never forming ``ZᵀZ`` (which squares the conditioning;
  see :mod:`analytic.kernel.identity`). Compiled only when a scene asks for this weighting.
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
itself accurate to no better than ~1e-6; in that case the two paths legitimately differ (the
identity weighting's kernel declines such a state instead, :data:`analytic.kernel.layout.
IDENTITY_RANK_TOL`, and the numpy path answers it).

numba's on-disk cache: see :mod:`analytic.runtime.jit`. In short, ``NUMBA_CACHE_DIR`` if set,
else ``__pycache__`` beside the source, else (a read-only install) ``tumbling-testbed/numba`` in the
user's cache directory, said once; with none writable the kernel is compiled in memory each process.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from analytic.effects import Effect, Weighting
from analytic.effects.registry import SPRING_LAWS
from analytic.kernel import gauss, halves, identity, minv2
from analytic.kernel import layout as L
from analytic.kernel.entry import Solver, solver_of
from analytic.kernel.halves import KernelHalf
from analytic.model import ControlOutput, TumblingModel
from analytic.runtime.jit import HAVE_NUMBA
from analytic.scene import Scene

# bound once: FastModel.qddot runs once per right-hand side, where a global + attribute lookup per
# name is a visible share of the call
_empty = np.empty


def available() -> bool:
    """True when numba is importable, i.e. the compiled kernel can run."""
    return HAVE_NUMBA


def _not_compiled(*args: object) -> int:
    """The kernel's place where numba is absent; never called (``FastModel.compiled`` is False)."""
    raise RuntimeError("the compiled kernel needs numba, which is not installed")


def pack(model: TumblingModel) -> tuple[np.ndarray, np.ndarray]:
    """Pack a model's constants for the kernel (:mod:`analytic.kernel`).

    Returns:
        ``(fp, ip)``: float64 array (the ``F_*`` head of :mod:`analytic.kernel.layout`, then the
        tail of ``layout.tail_offsets`` (``layout.FpTail``): ``m, p_e``, the spring laws'
        coefficients, the mass-track ``l, λ, α, β``,
        ``a``, ``d``) and int64 array (the ``I_*`` head, then the per-mass tracked flag (n) and
        the tracked indices (k_p)). The head's two addresses of the compiled halves
        (``I_FN_SYSTEM``, ``I_FN_SOLVE``) are left 0: they belong to one process, and
        :class:`FastModel` writes them.
    """
    sc = model.scene
    n = model.n
    kw = len(model.omega_track.components) if model.omega_track else 0
    kp = len(model.mass_track.indices) if model.mass_track else 0
    o = L.tail_offsets(n, kp)
    fp = np.zeros(o.end)
    fp[L.F_MBR] = model.m_BR
    fp[L.F_MU0] = model.mu0
    fp[L.F_D1] = model.delta1
    fp[L.F_D2] = model.delta2
    fp[L.F_J : L.F_J + 9] = model.J.ravel()
    fp[L.F_G : L.F_G + 3] = model.g
    if sc.has(Effect.EXTERNAL_TORQUE):
        et = sc.external_torque
        assert et is not None  # the loader requires its table with the effect
        fp[L.F_TFREQ] = et.frequency
        fp[L.F_TC : L.F_TC + 3] = et.constant
        fp[L.F_TA : L.F_TA + 3] = et.amplitude
    if model.omega_track:
        w = model.omega_track
        fp[L.F_WB : L.F_WB + 3] = w.b
        fp[L.F_WS : L.F_WS + 3] = w.sigma
        fp[L.F_GAIN : L.F_GAIN + kw * kw] = np.asarray(w.gain, float).ravel()
    fp[L.F_TAT : L.F_TAT + 48] = model.T_a.ravel()
    fp[L.F_TDT : L.F_TDT + 48] = model.T_d.ravel()
    fp[o.m : o.m + n] = model.m
    fp[o.p_e : o.p_e + n] = model.p_e
    for law in SPRING_LAWS:  # each law's coefficients and flag (layout.LAW_INDEX)
        j = L.LAW_INDEX[law.effect]
        at = L.law_offset(o, n, j)
        fp[at : at + n + 1] = model.spring_coefficients[law.effect]
    if model.mass_track:
        mt = model.mass_track
        fp[o.l : o.l + kp] = mt.l
        fp[o.lam : o.lam + kp] = mt.lam
        fp[o.alpha : o.alpha + kp] = mt.alpha
        fp[o.beta : o.beta + kp] = mt.beta
    fp[o.a : o.a + 3] = model.a
    fp[o.d : o.d + 3] = model.d

    ip = np.zeros(L.ip_length(n, kp), dtype=np.int64)
    ip[L.I_N], ip[L.I_KW], ip[L.I_KP] = n, kw, kp
    ip[L.I_GRAV] = sc.has(Effect.GRAVITY)
    for law in SPRING_LAWS:
        ip[L.I_LAWS + L.LAW_INDEX[law.effect]] = sc.has(law.effect)
    ip[L.I_TORQ] = sc.has(Effect.EXTERNAL_TORQUE)
    ip[L.I_WEIGHT] = {
        Weighting.M_INV: L.W_GAUSS,
        Weighting.M_INV2: L.W_MINV2,
        Weighting.IDENTITY: L.W_IDENTITY,
    }[model.weighting]
    if model.omega_track:
        ip[L.I_COMP : L.I_COMP + kw] = model.omega_track.components
    if model.mass_track:
        idx = np.asarray(model.mass_track.indices, dtype=np.int64)
        ip[L.I_TRACK + idx] = 1
        ip[L.I_TRACK + n :] = idx
    return fp, ip


class FastModel:
    """The controlled dynamics of one scene through the compiled kernel.

    Args:
        scene: a validated :class:`~analytic.scene.Scene`.
        model: the numpy :class:`TumblingModel` of the same scene (built when not given); used for
            the constants and as the fallback.

    Attributes:
        n, nq, k: masses, coordinates (n + 7) and control rows (k_ω + k_p).
        compiled: True when calls go to the kernel (numba present; every weighting is compiled).
        solver: the compiled solve this scene uses (:class:`analytic.kernel.entry.Solver`; only
            that one is compiled).
        fallbacks: number of calls answered by the numpy path so far.
    """

    def __init__(self, scene: Scene, model: TumblingModel | None = None):
        self.scene = scene
        self.model = model if model is not None else TumblingModel(scene)
        self.n = self.model.n
        self.nq = self.model.nq
        self.k = self.model.k
        self.fp, self._ip = pack(self.model)
        self._bound = False  # ip's addresses of the compiled halves not written yet
        self.compiled = available()
        self.fallbacks = 0
        self._nout = L.output_length(self.n, self.k)
        self.solver = solver_of(self._ip)
        # the kernel's entry points: (t, q, qdot, fp, ip, out) -> status
        self._evaluate: Callable[..., int]
        self._qddot_into: Callable[..., int]
        if not available():
            self._evaluate = self._qddot_into = _not_compiled
        elif self.solver is Solver.MINV2:
            self._evaluate, self._qddot_into = minv2.evaluate, minv2.qddot_into
        elif self.solver is Solver.IDENTITY:
            self._evaluate, self._qddot_into = identity.evaluate, identity.qddot_into
        else:  # the Gauss kernel writes q̈ alone when given an array of length nq
            self._evaluate = self._qddot_into = gauss.evaluate

    @property
    def ip(self) -> np.ndarray:
        """The packed integers (:func:`pack`) with the addresses of the kernel's two compiled
        halves in this process (:mod:`analytic.kernel.halves`), which are compiled, or loaded
        from numba's cache, on the first access; what every compiled caller is given."""
        if not self._bound:
            if self.compiled:
                self._ip[L.I_FN_SYSTEM], self._ip[L.I_FN_SOLVE] = halves.addresses(self.solver)
            self._bound = True
        return self._ip

    def __getstate__(self) -> dict:
        """Pickled without this process's addresses: another process binds its own."""
        state = dict(self.__dict__)
        state["_ip"] = self._ip.copy()
        state["_ip"][[L.I_FN_SYSTEM, L.I_FN_SOLVE]] = 0
        state["_bound"] = False
        return state

    def _raw(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray | None:
        """The kernel's output ``[q̈, Q^C, τ, residual]`` or None when the numpy path must answer."""
        if not self.compiled:
            return None
        out = np.empty(self._nout)
        status = self._evaluate(float(t), q, qdot, self.fp, self.ip, out)
        return out if status == L.STATUS_OK else None

    def _numpy(self, t: float, q: np.ndarray, qdot: np.ndarray) -> tuple[np.ndarray, ControlOutput]:
        self.fallbacks += 1
        return self.model.acceleration(t, q, qdot)

    def qddot(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """Constrained, controlled acceleration ``q̈`` (Eq. 89), shape (nq,).

        q and qdot must be contiguous float64 arrays of shape (nq,) (no conversion is made here, to
        keep the call cheap; :meth:`acceleration` converts). The result is a new array on every
        call (integrators keep it), written by the kernel's q̈-only path.
        """
        if self.compiled:
            qdd = _empty(self.nq)  # a fresh array each call: callers (solve_ivp) keep it
            if self._qddot_into(float(t), q, qdot, self.fp, self.ip, qdd) == 0:  # STATUS_OK
                return qdd
        return self._numpy(t, np.asarray(q, float), np.asarray(qdot, float))[0]

    def qddot_and_forces(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(q̈, τ, rod_forces, force_at_C, Q^C)`` at one state, as arrays (views of the kernel's
        output on the compiled path; :meth:`acceleration` wraps the same in a ControlOutput).

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

    def acceleration(
        self, t: float, q: np.ndarray, qdot: np.ndarray
    ) -> tuple[np.ndarray, ControlOutput]:
        """``(q̈, control)``: same signature and result as :meth:`TumblingModel.acceleration`
        (``rank = k`` on the compiled path, see the module docstring)."""
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


def compile_half(scene: Scene, half: KernelHalf | str) -> bool:
    """Compile one half of the kernel ``scene`` evaluates (or load it from numba's disk cache),
    without running it (:mod:`analytic.kernel.halves`).

    The kernel's callers call the two halves by address, so two processes can compile one half
    each at the same time (:mod:`validation.runs.warmup`, a first run), and the callers compile without
    either. Returns False when there is nothing to compile (numba absent).
    """
    fm = FastModel(scene)  # its ip (and so the other half) is not touched
    if not fm.compiled:
        return False
    halves.compiled(half, fm.solver)
    return True


__all__ = ["FastModel", "KernelHalf", "available", "compile_half", "pack"]
