"""Compiled O(n) kernel of the controlled dynamics (Eqs. 51-53, 59, 80-89, B10): the numba side of
:mod:`analytic.fast`.

Everything the kernel needs is packed by :func:`analytic.fast.pack` into one float array ``fp`` and
one int array ``ip`` (layout constants below), so a call unboxes six arguments only.
:func:`evaluate` writes ``[q̈ (nq), Q^C (nq), τ (3), residual (k)]`` into ``out`` and returns a status
(0 = done); :func:`qddot_into` (the integrator's right-hand side, ``FastModel.qddot``) writes the same
``q̈`` only.

Structure used (coordinates ``q = [R (3), u (4), p (n)]``, body block ``b = [R, u]`` of size 7):

* ``M_pp = s diag(m)`` with ``s = (Sa)ᵀSa`` (Eq. 51), and column i of ``M_bp`` is
  ``m_i (c1 + p_i c2)`` with ``c1 = [Sa; L_dᵀSa]``, ``c2 = [0; L_aᵀSa]`` (7-vectors). Eliminating any
  set F of rod rows onto the body block gives the 7x7 Schur complement
  ``M_bb - (1/s) Σ_F m_i (c1 + p_i c2)(c1 + p_i c2)ᵀ``, i.e. three moments ``Σ_F m_i p_iʲ``.
* Gauss weighting (N = M⁻¹, Eq. 89): the control is the KKT system of Gauss's principle
  ``M_α q̈ = Q_α + a_m λ + A_cᵀ μ``, ``a_mᵀq̈ = b_m``, ``A_c q̈ = b_c``. Tracked-mass rows of ``A_c`` are
  unit rows, so ``q̈_p,i = b_c,i`` for a tracked mass, the free rod rows are eliminated by the Schur
  complement, and what is left is a 7x7 body system bordered by ``1 + k_ω`` rows (≤ 4). Its R block
  is ``m_T I - (Σ_F m_i / s) Sa Saᵀ`` (``c2`` and ``a_m`` vanish on R), inverted in closed form
  (Sherman-Morrison), so R is eliminated too and a 4x4 system on u (LDLᵀ) bordered by those rows
  remains. ``μ_i`` of a tracked mass is its row of ``M_α q̈ - Q_α``. Cost O(n), no (n+7)² matrix is
  formed.
* N = M⁻² (Eq. B13): with ``Z = K A_cᵀ`` (``K`` the norm-constrained compliance) one has
  ``M Z = A_cᵀ - a_m wᵀ``, ``w = A_c y / s_m``, and since ``H(u) u = 0``,
  ``Zᵀ M² Z = A_c A_cᵀ + |u|² w wᵀ = diag(4|u|² I_kω, I_kp) + |u|² w wᵀ`` (Sherman-Morrison); the rest
  are structured solves with ``M_α``, one product with ``M`` (for ``Q^C``) and
  ``M_α⁻¹ M v = v - α y (a_mᵀ v)`` (``y = M_α⁻¹ a_m``). Cost O(n).

The identity weighting is not in this kernel (:mod:`analytic.fast` uses the numpy path for it).

Cost notes (one evaluation is ~0.5 µs at small n, so constant factors matter): no heap allocation on
the Gauss path (one stack workspace, :func:`_workspace`, carved by the ``_MB``... offsets; the rod rows
of ``Q`` and ``b_c`` live in ``out``); closed forms for ``L_a(u)``, ``L̇_a u̇`` and ``H(u)ᵀx`` instead of
the (3, 4, 4) tensor contractions; no square roots (LDLᵀ, Gauss path); cos and sin of one argument in one block
(one ``sincos`` call) and reused while the mass-track λ repeats; indices read from ``ip`` masked (see
``_IX``).
"""

from __future__ import annotations

import math
import os

import numpy as np

try:  # numba is optional: without it analytic.fast falls back to the numpy model
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None
    HAVE_NUMBA = False


def _jit(fn):
    """``numba.njit(cache=True)``, or without the on-disk cache when no cache directory is usable.

    numba looks for a writable cache directory in this order: ``$NUMBA_CACHE_DIR`` (when set),
    ``__pycache__`` beside this file, then the user-wide cache dir (``~/.cache/numba/...`` on Linux;
    the route taken when the package is installed in a read-only site-packages). If none of them is
    writable, ``njit(cache=True)`` raises ``RuntimeError`` at decoration time; the kernel is then
    compiled in memory on every process start instead (slower first call, same results).
    """
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    try:
        return numba.njit(cache=True, fastmath=False, nogil=True)(fn)
    except RuntimeError:  # no usable cache locator
        return numba.njit(cache=False, fastmath=False, nogil=True)(fn)


def source_fingerprint(*modules) -> int:
    """A 60-bit integer from the SHA-256 of the given modules' source files.

    numba's on-disk cache checks only the source file of the function being cached, yet a cached
    function also contains the code of every function it calls. A compiled function in another file
    that calls this kernel (:mod:`mj_bridge.fast_stage`, :mod:`mj_bridge.native`) therefore closes
    over this fingerprint: numba hashes closure variables into its cache key, so editing or upgrading
    the kernel's file makes those callers recompile instead of running a stale copy of the kernel.
    """
    import hashlib
    import inspect

    h = hashlib.sha256()
    for mod in modules:
        with open(inspect.getfile(mod), "rb") as f:
            h.update(f.read())
    return int(h.hexdigest()[:15], 16)


# ----------------------------------------------------------------------------------------------
# Packed-parameter layout (shared with analytic.fast.pack)
# ----------------------------------------------------------------------------------------------
F_MBR, F_MU0, F_D1, F_D2, F_TFREQ = 0, 1, 2, 3, 4
F_J = 5  # 9, row-major, body axes
F_G = 14  # 3, inertial
F_TC = 17  # 3, external torque constant, body
F_TA = 20  # 3, external torque amplitude, body
F_WB = 23  # 3, omega amplitudes b
F_WS = 26  # 3, omega frequencies sigma
F_GAIN = 29  # kw*kw row-major (9 slots)
F_TAT = 38  # 48: T_a (3, 4, 4) row-major, L_a(u) = T_a @ u (Eq. 29; the kernel uses _Lw)
F_TDT = 86  # 48: T_d, L_d(u) = T_d @ u (Eq. 34)
F_ARR = 134  # then m (n), p_e (n), k_l (n+1), k_n (n+1), l, lam, alpha, beta (kp each)

I_N, I_KW, I_KP, I_GRAV, I_SLIN, I_SCUB, I_TORQ, I_WEIGHT = 0, 1, 2, 3, 4, 5, 6, 7
I_COMP = 8  # 3 slots: omega components
I_TRACK = 11  # n: 1 for a tracked mass, then the kp tracked indices

W_GAUSS, W_MINV2 = 0, 1
# Sizes and indices read from ip are masked to 31 bits (values are small and non-negative, so the
# mask changes nothing): it lets LLVM prove every array index non-negative and drop numba's
# negative-index wrap-around code, which otherwise tripled the cost of the O(n) loops.
_IX = 0x7FFFFFFF
STATUS_OK, STATUS_NOT_PD, STATUS_UNSUPPORTED = 0, 1, 2


# ----------------------------------------------------------------------------------------------
# Workspace: one float64 array on the stack per call (_workspace), carved by these offsets, instead
# of ~30 small np.empty/np.zeros (each a heap allocation plus reference counting, ~20 ns)
# ----------------------------------------------------------------------------------------------
_MB = 0  # 49: body block M_bb of M (Eq. 51), row-major 7x7, both triangles
_S4 = 49  # 4x4 (row stride 4, lower triangle): S_4, the Schur complement on the u block
_BF = 65  # 3x4: B_F, the R-u block of S_F
_HT = 77  # 4: h = B_Fᵀ Sa
_R4 = 81  # 4: right-hand side on the u block
_C1 = 85  # 7: c1 = [Sa; L_dᵀSa]
_C2 = 92  # 7: c2 = [0; L_aᵀSa]
_RB = 99  # 7: body right-hand side r_b
_Z = 106  # 4 x 4: Z = L⁻¹ Cᵀ (u rows), column j at _Z + 4 j
_GC = 122  # 4x4 (row stride 4): G = C S_4⁻¹ Cᵀ, then its LDLᵀ factors
_GI = 138  # 4: 1 / pivots of that factorisation
_NU = 142  # 4: right-hand side, then ν = [λ, μ_ω]
_H = 146  # 12: H(u), row-major (3, 4)
_LA = 158  # 12: L_a(u)
_LD = 170  # 12: L_d(u)
_JH = 182  # 12: J H(u)
_PM = 194  # 12: μ2 L_a + μ1 L_d (first 4 slots reused at the end for H_wᵀ μ_ω)
_OM = 206  # 3: ω
_EW = 209  # 3: ω tracking error
_QB = 212  # 7: body rows of Q_α (the rod rows of Q go into out, see _core)
_BW = 219  # 3: b_c of the ω rows (those of the tracked masses go into out)
_NW = 222


if HAVE_NUMBA and not numba.config.DISABLE_JIT:
    from numba.core import cgutils, types
    from numba.extending import intrinsic
    from numba.np.arrayobj import populate_array

    @intrinsic
    def _workspace(typingctx):
        """A float64 array of ``_NW`` uninitialised slots on the calling function's stack.

        An intrinsic, so its code is emitted inside the caller: the memory lives as long as the
        caller's frame (never return it or a view of it). Unlike ``np.empty`` there is no heap
        allocation, no reference count, and LLVM may keep constant-index slots in registers.
        """
        arrty = types.Array(types.float64, 1, "C")

        def codegen(context, builder, sig, args):
            f64 = context.get_value_type(types.float64)
            data = cgutils.alloca_once(builder, f64, size=_NW)
            ary = context.make_array(arrty)(context, builder)
            intp = context.get_value_type(types.intp)
            populate_array(
                ary,
                data=data,
                shape=[intp(_NW)],
                strides=[intp(8)],
                itemsize=intp(8),
                meminfo=None,
            )
            return ary._getvalue()

        return arrty(), codegen

else:  # pragma: no cover - plain Python (no numba, or NUMBA_DISABLE_JIT=1)

    def _workspace():
        return np.empty(_NW)


# ----------------------------------------------------------------------------------------------
# Small dense helpers (fixed tiny sizes; no LAPACK call overhead)
# ----------------------------------------------------------------------------------------------


@_jit
def _chol(A, k):
    """In-place lower Cholesky of the leading k x k block of A. Returns False if not PD."""
    for j in range(k):
        d = A[j, j]
        for c in range(j):
            d -= A[j, c] * A[j, c]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        A[j, j] = d
        for i in range(j + 1, k):
            v = A[i, j]
            for c in range(j):
                v -= A[i, c] * A[j, c]
            A[i, j] = v / d
    return True


@_jit
def _chol_solve(L, k, b):
    """Solve (L Lᵀ) x = b in place (b of length >= k)."""
    for i in range(k):
        v = b[i]
        for c in range(i):
            v -= L[i, c] * b[c]
        b[i] = v / L[i, i]
    for i in range(k - 1, -1, -1):
        v = b[i]
        for c in range(i + 1, k):
            v -= L[c, i] * b[c]
        b[i] = v / L[i, i]


@_jit
def _ldl_w(w, o, ld, oi, k):
    """In-place ``A = L D Lᵀ`` (L unit lower, stored below the diagonal) of the k x k matrix at
    ``w[o + ld i + j]`` (lower triangle read); ``w[oi + j] = 1 / D_j``. Returns False if a pivot is
    not positive (A not numerically positive definite)."""
    for j in range(k):
        rj = o + ld * j
        for c in range(j):  # row j <- L_jc D_c
            rc = o + ld * c
            v = w[rj + c]
            for e in range(c):
                v -= w[rj + e] * w[rc + e]
            w[rj + c] = v
        d = w[rj + j]
        for c in range(j):  # row j <- L_jc
            lc = w[rj + c] * w[oi + c]
            d -= lc * w[rj + c]
            w[rj + c] = lc
        if not d > 0.0:
            return False
        w[oi + j] = 1.0 / d
    return True


@_jit
def _ldl_solve_w(w, o, ld, oi, k, ox):
    """``x <- (L D Lᵀ)⁻¹ x`` for ``x = w[ox:ox+k]``, with the factors of :func:`_ldl_w`."""
    for i in range(k):
        v = w[ox + i]
        for c in range(i):
            v -= w[o + ld * i + c] * w[ox + c]
        w[ox + i] = v
    for i in range(k):
        w[ox + i] *= w[oi + i]
    for i in range(k - 1, -1, -1):
        v = w[ox + i]
        for c in range(i + 1, k):
            v -= w[o + ld * c + i] * w[ox + c]
        w[ox + i] = v


@_jit
def _Hmat(u, Hm):
    """H(u) of Eq. (13), shape (3, 4)."""
    u0, u1, u2, u3 = u[0], u[1], u[2], u[3]
    Hm[0, 0] = -2 * u1
    Hm[0, 1] = 2 * u0
    Hm[0, 2] = 2 * u3
    Hm[0, 3] = -2 * u2
    Hm[1, 0] = -2 * u2
    Hm[1, 1] = -2 * u3
    Hm[1, 2] = 2 * u0
    Hm[1, 3] = 2 * u1
    Hm[2, 0] = -2 * u3
    Hm[2, 1] = 2 * u2
    Hm[2, 2] = -2 * u1
    Hm[2, 3] = 2 * u0


@_jit
def _Ht(u0, u1, u2, u3, x0, x1, x2):
    """``H(u)ᵀ x`` (Eq. 13) for a 3-vector x, as a 4-tuple."""
    return (
        -2.0 * (u1 * x0 + u2 * x1 + u3 * x2),
        2.0 * (u0 * x0 - u3 * x1 + u2 * x2),
        2.0 * (u3 * x0 + u0 * x1 - u1 * x2),
        2.0 * (-u2 * x0 + u1 * x1 + u0 * x2),
    )


@_jit
def _Lw(x0, x1, x2, u0, u1, u2, u3, w, o):
    """``L_x(u) = Σ x_i L_i(u)`` (Eqs. 23-29, 34), row-major (3, 4) at ``w[o:o+12]``: the closed
    form of ``T_x @ u`` (each entry has at most three of the 48 terms)."""
    w[o] = 4.0 * x0 * u0 - 2.0 * x1 * u3 + 2.0 * x2 * u2
    w[o + 1] = 4.0 * x0 * u1 + 2.0 * x1 * u2 + 2.0 * x2 * u3
    w[o + 2] = 2.0 * x1 * u1 + 2.0 * x2 * u0
    w[o + 3] = -2.0 * x1 * u0 + 2.0 * x2 * u1
    w[o + 4] = 2.0 * x0 * u3 + 4.0 * x1 * u0 - 2.0 * x2 * u1
    w[o + 5] = 2.0 * x0 * u2 - 2.0 * x2 * u0
    w[o + 6] = 2.0 * x0 * u1 + 4.0 * x1 * u2 + 2.0 * x2 * u3
    w[o + 7] = 2.0 * x0 * u0 + 2.0 * x2 * u2
    w[o + 8] = -2.0 * x0 * u2 + 2.0 * x1 * u1 + 4.0 * x2 * u0
    w[o + 9] = 2.0 * x0 * u3 + 2.0 * x1 * u0
    w[o + 10] = -2.0 * x0 * u0 + 2.0 * x1 * u3
    w[o + 11] = 2.0 * x0 * u1 + 2.0 * x1 * u2 + 4.0 * x2 * u3


# ----------------------------------------------------------------------------------------------
# The kernel
# ----------------------------------------------------------------------------------------------


@_jit
def evaluate(t, q, qd, fp, ip, out):
    """One evaluation of the controlled dynamics; see the module docstring.

    Args:
        t: time, s.
        q, qd: state ``[R, u, p]`` and its rate, shape (nq,).
        fp, ip: packed parameters (:func:`analytic.fast.pack`).
        out: float array of length ``2 nq + 3 + k``; receives ``[q̈, Q^C, τ, A_c q̈ - b_c]``.

    Returns:
        status: 0 done; 1 a Schur complement was not numerically positive definite (the caller
        falls back); 2 weighting not supported by this kernel. With a nonzero status the content
        of ``out`` is unspecified (it may hold intermediate values).
    """
    return _core(t, q, qd, fp, ip, out)


@_jit
def qddot_into(t, q, qd, fp, ip, qdd):
    """:func:`evaluate` reduced to ``q̈``: writes ``q̈`` (the same numbers) into ``qdd``, shape
    (nq,), and skips ``Q^C``, ``τ`` and the residual. Same arguments otherwise, same status."""
    n = ip[I_N]
    k = ip[I_KW] + ip[I_KP]
    if k > 0 and ip[I_WEIGHT] == W_MINV2:  # that path needs the full output
        nq = n + 7
        out = np.empty(2 * nq + 3 + k)
        status = _core(t, q, qd, fp, ip, out)
        if status == STATUS_OK:
            qdd[:] = out[:nq]
        return status
    return _core(t, q, qd, fp, ip, qdd)


@_jit
def _core(t, q, qd, fp, ip, out):
    """:func:`evaluate`, or only its ``q̈`` when ``out`` is shorter than the full output (length
    nq; Gauss weighting or k = 0 only). One compiled body for both (a literal flag argument would
    compile it twice)."""
    n = ip[I_N] & _IX
    kw = ip[I_KW] & _IX
    kp = ip[I_KP] & _IX
    k = kw + kp
    nq = n + 7
    wt = ip[I_WEIGHT]
    if k > 0 and wt != W_GAUSS and wt != W_MINV2:
        return STATUS_UNSUPPORTED
    full = out.shape[0] >= 2 * nq + 3 + k  # else: q̈ only
    om = F_ARR
    ope = om + n
    okl = ope + n
    okn = okl + n + 1
    oml = okn + n + 1
    omlam = oml + kp
    omal = omlam + kp
    ombe = omal + kp
    oa = ombe + kp  # a (3), d (3) appended after the mass-track arrays
    itr = I_TRACK
    iidx = I_TRACK + n

    w = _workspace()
    oq = _QB  # (Q_α)_b
    ob = _BW  # b_c of the ω rows

    m_BR = fp[F_MBR]
    mu0 = fp[F_MU0]
    m_T = m_BR + mu0

    # --- kinematics (Eqs. 11-13, 29, 34) ---
    u0, u1, u2, u3 = q[3], q[4], q[5], q[6]
    v0, v1, v2, v3 = qd[3], qd[4], qd[5], qd[6]  # u̇
    s00 = 2 * u0 * u0 - 1 + 2 * u1 * u1
    s01 = 2 * u1 * u2 - 2 * u0 * u3
    s02 = 2 * u1 * u3 + 2 * u0 * u2
    s10 = 2 * u1 * u2 + 2 * u0 * u3
    s11 = 2 * u0 * u0 - 1 + 2 * u2 * u2
    s12 = 2 * u2 * u3 - 2 * u0 * u1
    s20 = 2 * u1 * u3 - 2 * u0 * u2
    s21 = 2 * u2 * u3 + 2 * u0 * u1
    s22 = 2 * u0 * u0 - 1 + 2 * u3 * u3
    a0, a1, a2 = fp[oa], fp[oa + 1], fp[oa + 2]
    d0, d1, d2 = fp[oa + 3], fp[oa + 4], fp[oa + 5]
    Sa0 = s00 * a0 + s01 * a1 + s02 * a2
    Sa1 = s10 * a0 + s11 * a1 + s12 * a2
    Sa2 = s20 * a0 + s21 * a1 + s22 * a2
    s = Sa0 * Sa0 + Sa1 * Sa1 + Sa2 * Sa2
    w[_H] = -2 * u1
    w[_H + 1] = 2 * u0
    w[_H + 2] = 2 * u3
    w[_H + 3] = -2 * u2
    w[_H + 4] = -2 * u2
    w[_H + 5] = -2 * u3
    w[_H + 6] = 2 * u0
    w[_H + 7] = 2 * u1
    w[_H + 8] = -2 * u3
    w[_H + 9] = 2 * u2
    w[_H + 10] = -2 * u1
    w[_H + 11] = 2 * u0
    _Lw(a0, a1, a2, u0, u1, u2, u3, w, _LA)
    _Lw(d0, d1, d2, u0, u1, u2, u3, w, _LD)
    # L̇_a u̇ = L_a(u̇) u̇ = 2 (S(u̇) + I) a: L_a(u) is the Jacobian of the quadratic form S(u) a
    # (Eqs. 23-29), so L_a(v) v is twice that form at v; same for d
    r00 = 2 * v0 * v0 + 2 * v1 * v1
    r01 = 2 * v1 * v2 - 2 * v0 * v3
    r02 = 2 * v1 * v3 + 2 * v0 * v2
    r10 = 2 * v1 * v2 + 2 * v0 * v3
    r11 = 2 * v0 * v0 + 2 * v2 * v2
    r12 = 2 * v2 * v3 - 2 * v0 * v1
    r20 = 2 * v1 * v3 - 2 * v0 * v2
    r21 = 2 * v2 * v3 + 2 * v0 * v1
    r22 = 2 * v0 * v0 + 2 * v3 * v3
    Lad0 = 2.0 * (r00 * a0 + r01 * a1 + r02 * a2)
    Lad1 = 2.0 * (r10 * a0 + r11 * a1 + r12 * a2)
    Lad2 = 2.0 * (r20 * a0 + r21 * a1 + r22 * a2)
    Ldd0 = 2.0 * (r00 * d0 + r01 * d1 + r02 * d2)
    Ldd1 = 2.0 * (r10 * d0 + r11 * d1 + r12 * d2)
    Ldd2 = 2.0 * (r20 * d0 + r21 * d1 + r22 * d2)
    Lau0 = w[_LA] * v0 + w[_LA + 1] * v1 + w[_LA + 2] * v2 + w[_LA + 3] * v3
    Lau1 = w[_LA + 4] * v0 + w[_LA + 5] * v1 + w[_LA + 6] * v2 + w[_LA + 7] * v3
    Lau2 = w[_LA + 8] * v0 + w[_LA + 9] * v1 + w[_LA + 10] * v2 + w[_LA + 11] * v3
    sLau = Sa0 * Lau0 + Sa1 * Lau1 + Sa2 * Lau2
    sLad = Sa0 * Lad0 + Sa1 * Lad1 + Sa2 * Lad2
    sLdd = Sa0 * Ldd0 + Sa1 * Ldd1 + Sa2 * Ldd2
    om0 = 2.0 * (-u1 * v0 + u0 * v1 + u3 * v2 - u2 * v3)  # ω = H(u) u̇, Eq. (12)
    om1 = 2.0 * (-u2 * v0 - u3 * v1 + u0 * v2 + u1 * v3)
    om2 = 2.0 * (-u3 * v0 + u2 * v1 - u1 * v2 + u0 * v3)
    w[_OM] = om0
    w[_OM + 1] = om1
    w[_OM + 2] = om2
    Jw0 = fp[F_J] * om0 + fp[F_J + 1] * om1 + fp[F_J + 2] * om2
    Jw1 = fp[F_J + 3] * om0 + fp[F_J + 4] * om1 + fp[F_J + 5] * om2
    Jw2 = fp[F_J + 6] * om0 + fp[F_J + 7] * om1 + fp[F_J + 8] * om2

    grav = ip[I_GRAV] != 0
    g0, g1, g2 = fp[F_G], fp[F_G + 1], fp[F_G + 2]
    sg = Sa0 * g0 + Sa1 * g1 + Sa2 * g2
    lin = ip[I_SLIN] != 0
    cub = ip[I_SCUB] != 0
    springs = n > 0 and (lin or cub)

    # --- one pass over the masses: moments Σ m_i p_iʲ (all, free and tracked rods), Q_p (Eq. 52,
    # springs Eq. 38) and the free rods' Σ Q_i, Σ p_i Q_i. Q_i goes straight into out: the q̈_i slot
    # of a free mass, the Q^C_i slot of a tracked one (full output only; else it is not needed) ---
    mu1 = 0.0
    mu2 = 0.0
    mpd = 0.0
    mppd = 0.0
    n0 = 0.0
    n1 = 0.0
    n2 = 0.0
    nt0 = 0.0  # Σ_T m_i, Σ_T m_i p_i (tracked)
    nt1 = 0.0
    sq = 0.0
    spq = 0.0
    sl2 = 2.0 * sLau
    # spring forces F^S = -∂U_s/∂p (Eq. 38; docs/errata.md item 2): spring j joins x_{j-1} and x_j
    # (x = p - p_e, x_{-1} = x_n = 0) with force f_j; Q_p,i += f_{i+1} - f_i
    x = 0.0
    f_prev = 0.0
    if springs:
        x = q[7] - fp[ope]
        if lin:
            f_prev += fp[okl] * x
        if cub:
            f_prev += fp[okn] * (x * x * x)
    for i in range(n):
        mi = fp[om + i]
        pi = q[7 + i]
        pdi = qd[7 + i]
        mp = mi * pi
        mu1 += mp
        mu2 += mp * pi
        mpd += mi * pdi
        mppd += mp * pdi
        Qi = -mi * (sl2 * pdi + sLad * pi + sLdd)
        if grav:
            Qi += sg * mi
        if springs:
            xn = q[8 + i] - fp[ope + i + 1] if i + 1 < n else 0.0
            e = xn - x
            f = 0.0
            if lin:
                f += fp[okl + i + 1] * e
            if cub:
                f += fp[okn + i + 1] * (e * e * e)
            Qi += f - f_prev
            f_prev = f
            x = xn
        if ip[itr + i] == 0:
            out[7 + i] = Qi  # q̈_i is computed from it in place
            n0 += mi
            n1 += mp
            n2 += mp * pi
            sq += Qi
            spq += pi * Qi
        else:
            if full:
                out[nq + 7 + i] = Qi  # μ_i (Q^C_i) is computed from it in place
            nt0 += mi
            nt1 += mp

    # --- M body block (Eq. 51): [[m_T I, B], [Bᵀ, HᵀJH + L_aᵀ(μ2 L_a + μ1 L_d) + L_dᵀ B]],
    # B = μ1 L_a + μ0 L_d ---
    for r in range(3):
        for c in range(3):
            w[_MB + 7 * r + c] = m_T if r == c else 0.0
        for c in range(4):
            la = w[_LA + 4 * r + c]
            ld = w[_LD + 4 * r + c]
            b = mu1 * la + mu0 * ld
            w[_MB + 7 * r + 3 + c] = b
            w[_MB + 7 * (3 + c) + r] = b
            w[_PM + 4 * r + c] = mu2 * la + mu1 * ld
            w[_JH + 4 * r + c] = (
                fp[F_J + 3 * r] * w[_H + c]
                + fp[F_J + 3 * r + 1] * w[_H + 4 + c]
                + fp[F_J + 3 * r + 2] * w[_H + 8 + c]
            )
    for i in range(4):
        for j in range(i, 4):
            v = 0.0
            for r in range(3):
                v += (
                    w[_H + 4 * r + i] * w[_JH + 4 * r + j]
                    + w[_LA + 4 * r + i] * w[_PM + 4 * r + j]
                    + w[_LD + 4 * r + i] * w[_MB + 7 * r + 3 + j]
                )
            w[_MB + 7 * (3 + i) + 3 + j] = v
            w[_MB + 7 * (3 + j) + 3 + i] = v
    w[_C1] = Sa0
    w[_C1 + 1] = Sa1
    w[_C1 + 2] = Sa2
    w[_C2] = 0.0
    w[_C2 + 1] = 0.0
    w[_C2 + 2] = 0.0
    for c in range(4):
        w[_C1 + 3 + c] = w[_LD + c] * Sa0 + w[_LD + 4 + c] * Sa1 + w[_LD + 8 + c] * Sa2
        w[_C2 + 3 + c] = w[_LA + c] * Sa0 + w[_LA + 4 + c] * Sa1 + w[_LA + 8 + c] * Sa2

    # --- Q body rows (Eq. 52 with the effect-gated terms):
    # Q_R = -Σm κ (+ m_T g), Q_u = -2 H(u̇)ᵀ J ω - L_aᵀ Σmp κ - L_dᵀ Σm κ (+ Bᵀ g) (+ Hᵀ τ_e) ---
    smk0 = 2.0 * mpd * Lau0 + mu1 * Lad0 + mu0 * Ldd0
    smk1 = 2.0 * mpd * Lau1 + mu1 * Lad1 + mu0 * Ldd1
    smk2 = 2.0 * mpd * Lau2 + mu1 * Lad2 + mu0 * Ldd2
    xa0 = -(2.0 * mppd * Lau0 + mu2 * Lad0 + mu1 * Ldd0)
    xa1 = -(2.0 * mppd * Lau1 + mu2 * Lad1 + mu1 * Ldd1)
    xa2 = -(2.0 * mppd * Lau2 + mu2 * Lad2 + mu1 * Ldd2)
    xd0 = -smk0
    xd1 = -smk1
    xd2 = -smk2
    w[oq] = -smk0
    w[oq + 1] = -smk1
    w[oq + 2] = -smk2
    if grav:
        w[oq] += m_T * g0
        w[oq + 1] += m_T * g1
        w[oq + 2] += m_T * g2
        xa0 += mu1 * g0
        xa1 += mu1 * g1
        xa2 += mu1 * g2
        xd0 += mu0 * g0
        xd1 += mu0 * g1
        xd2 += mu0 * g2
    h0, h1, h2, h3 = _Ht(v0, v1, v2, v3, -2.0 * Jw0, -2.0 * Jw1, -2.0 * Jw2)
    if ip[I_TORQ]:
        ct = math.cos(fp[F_TFREQ] * t)
        e0, e1, e2, e3 = _Ht(
            u0,
            u1,
            u2,
            u3,
            fp[F_TC] + fp[F_TA] * ct,
            fp[F_TC + 1] + fp[F_TA + 1] * ct,
            fp[F_TC + 2] + fp[F_TA + 2] * ct,
        )
        h0 += e0
        h1 += e1
        h2 += e2
        h3 += e3
    w[oq + 3] = h0
    w[oq + 4] = h1
    w[oq + 5] = h2
    w[oq + 6] = h3
    for c in range(4):
        w[oq + 3 + c] += (
            w[_LA + c] * xa0
            + w[_LA + 4 + c] * xa1
            + w[_LA + 8 + c] * xa2
            + w[_LD + c] * xd0
            + w[_LD + 4 + c] * xd1
            + w[_LD + 8 + c] * xd2
        )

    # --- modeling constraint (Eq. 59) and M_α = M + α a_m a_mᵀ (fundamental.py) ---
    uu = u0 * u0 + u1 * u1 + u2 * u2 + u3 * u3
    uud = u0 * v0 + u1 * v1 + u2 * v2 + u3 * v3
    udud = v0 * v0 + v1 * v1 + v2 * v2 + v3 * v3
    b_m = -fp[F_D1] * uud - 0.5 * fp[F_D2] * (uu - 1.0) - udud
    trM = 3.0 * m_T + s * mu0
    for c in range(4):
        trM += w[_MB + 8 * (3 + c)]
    alpha = trM / nq
    for c in range(4):  # Q_α = Q + α b_m a_m (a_m = [0, u, 0])
        w[oq + 3 + c] += alpha * b_m * q[3 + c]

    # --- control requirements (Eqs. 75-76, 81, 84) ---
    for j in range(kw):  # (cos and sin of one argument in one block: a single sincos call)
        comp = ip[I_COMP + j] & _IX
        arg = fp[F_WS + comp] * t
        cs = math.cos(arg)
        sn = math.sin(arg)
        w[_EW + j] = w[_OM + comp] - fp[F_WB + comp] * cs
        w[ob + j] = -fp[F_WB + comp] * fp[F_WS + comp] * sn
    for j in range(kw):
        v = w[ob + j]
        for c in range(kw):
            v -= fp[F_GAIN + kw * j + c] * w[_EW + c]
        w[ob + j] = v
    t0 = 0.0  # Σ_T m_i b_i
    t1 = 0.0  # Σ_T m_i p_i b_i
    lam_prev = math.nan  # cos, sin of λ t are reused while λ repeats (often one λ for all masses)
    cs = 0.0
    sn = 0.0
    for j in range(kp):
        i = ip[iidx + j] & _IX
        lam = fp[omlam + j]
        li = fp[oml + j]
        if lam != lam_prev:
            cs = math.cos(lam * t)
            sn = math.sin(lam * t)
            lam_prev = lam
        pbar = fp[ope + i] + li * cs
        pbar_d = -li * lam * sn
        pbar_dd = -li * lam * lam * cs
        b = pbar_dd - fp[omal + j] * (qd[7 + i] - pbar_d) - fp[ombe + j] * (q[7 + i] - pbar)
        out[7 + i] = b  # q̈_i = b_i for a tracked mass
        mi = fp[om + i]
        t0 += mi * b
        t1 += mi * q[7 + i] * b

    if wt != W_GAUSS and k > 0:
        return _minv2(q, fp, ip, out, w, n, kw, kp, s, mu0, mu1, mu2, alpha, b_m, uu)

    # ---- Gauss: KKT of Gauss's principle, tracked rod rows fixed, free rod rows eliminated ----
    # S_F = (M_α)_bb - (1/s) Σ_F m_i (c1 + p_i c2)(c1 + p_i c2)ᵀ, and
    # r_b = (Q_α)_b - (1/s) Σ_F Q_i (c1 + p_i c2) - Σ_T m_i b_i (c1 + p_i c2).
    # Since c2 and a_m vanish on the R rows, S_F = [[A, B_F], [B_Fᵀ, D]] with
    # A = m_T I - (n0/s) Sa Saᵀ, B_F = B - Sa g_uᵀ (g = (n0 c1 + n1 c2)/s), and
    # A⁻¹ = (I + γ Sa Saᵀ)/m_T, γ = n0 / (s (m_T - n0)) (Sherman-Morrison; m_T - n0 = m_BR + Σ_T m_i
    # ≥ m_BR). R is eliminated in closed form: S_4 = D - B_Fᵀ A⁻¹ B_F = D - (B_FᵀB_F + γ h hᵀ)/m_T with
    # h = B_Fᵀ Sa = Σ_T m_i (c1 + p_i c2)_u, then an LDLᵀ of S_4 bordered by C = [a_bᵀ; H_w], which
    # acts on the u rows only. (Cholesky of the 7x7 S_F took 7 dependent sqrt + division steps.)
    inv_s = 1.0 / s
    m_Tt = m_BR + nt0
    rs = 0.0  # 1/s in S_F: no rod term when s = 0 (as in the dense S_F)
    gam = 0.0
    if s > 0.0:
        if not m_Tt > 0.0:
            return STATUS_NOT_PD
        rs = inv_s
        gam = n0 * inv_s / m_Tt
    if not m_T > 0.0:
        return STATUS_NOT_PD
    kT = 1.0 / m_T
    for i in range(7):  # r_b
        c1i = w[_C1 + i]
        c2i = w[_C2 + i]
        w[_RB + i] = w[oq + i] - (c1i * sq + c2i * spq) * inv_s - c1i * t0 - c2i * t1
    rR0 = w[_RB]
    rR1 = w[_RB + 1]
    rR2 = w[_RB + 2]
    sr = gam * (Sa0 * rR0 + Sa1 * rR1 + Sa2 * rR2)
    xr0 = (rR0 + sr * Sa0) * kT  # A⁻¹ r_R
    xr1 = (rR1 + sr * Sa1) * kT
    xr2 = (rR2 + sr * Sa2) * kT
    for c in range(4):
        c1c = w[_C1 + 3 + c]
        c2c = w[_C2 + 3 + c]
        gc = (n0 * c1c + n1 * c2c) * rs
        b0 = w[_MB + 3 + c] - Sa0 * gc  # B_F column c
        b1 = w[_MB + 10 + c] - Sa1 * gc
        b2 = w[_MB + 17 + c] - Sa2 * gc
        w[_BF + c] = b0
        w[_BF + 4 + c] = b1
        w[_BF + 8 + c] = b2
        w[_HT + c] = nt0 * c1c + nt1 * c2c  # h
        w[_R4 + c] = w[_RB + 3 + c] - (b0 * xr0 + b1 * xr1 + b2 * xr2)
    for i in range(4):
        c1i = w[_C1 + 3 + i]
        c2i = w[_C2 + 3 + i]
        g1 = (n0 * c1i + n1 * c2i) * rs
        g2 = (n1 * c1i + n2 * c2i) * rs
        ai = alpha * q[3 + i]  # α a_m a_mᵀ, a_m = u on these rows
        gh = gam * w[_HT + i]
        for j in range(i + 1):
            v = w[_MB + 7 * (3 + i) + 3 + j] + ai * q[3 + j]
            v -= g1 * w[_C1 + 3 + j] + g2 * w[_C2 + 3 + j]
            bb = (
                w[_BF + i] * w[_BF + j]
                + w[_BF + 4 + i] * w[_BF + 4 + j]
                + w[_BF + 8 + i] * w[_BF + 8 + j]
            )
            w[_S4 + 4 * i + j] = v - (bb + gh * w[_HT + j]) * kT
    # S_4 = L D Lᵀ, L unit lower (unrolled: S_4 is 4x4)
    a00 = w[_S4]
    if not a00 > 0.0:
        return STATUS_NOT_PD
    iv0 = 1.0 / a00
    a10 = w[_S4 + 4]
    a20 = w[_S4 + 8]
    a30 = w[_S4 + 12]
    l10 = a10 * iv0
    l20 = a20 * iv0
    l30 = a30 * iv0
    d1 = w[_S4 + 5] - l10 * a10
    if not d1 > 0.0:
        return STATUS_NOT_PD
    iv1 = 1.0 / d1
    t21 = w[_S4 + 9] - l20 * a10  # L_21 d_1
    t31 = w[_S4 + 13] - l30 * a10
    l21 = t21 * iv1
    l31 = t31 * iv1
    d2 = w[_S4 + 10] - l20 * a20 - l21 * t21
    if not d2 > 0.0:
        return STATUS_NOT_PD
    iv2 = 1.0 / d2
    t32 = w[_S4 + 14] - l30 * a20 - l31 * t21
    l32 = t32 * iv2
    d3 = w[_S4 + 15] - l30 * a30 - l31 * t31 - l32 * t32
    if not d3 > 0.0:
        return STATUS_NOT_PD
    iv3 = 1.0 / d3
    # Z = L⁻¹ Cᵀ, z = L⁻¹ r_4: G = C S_4⁻¹ Cᵀ = Zᵀ D⁻¹ Z, ν = G⁻¹ (b - Zᵀ D⁻¹ z)
    z0 = w[_R4]
    z1 = w[_R4 + 1] - l10 * z0
    z2 = w[_R4 + 2] - l20 * z0 - l21 * z1
    z3 = w[_R4 + 3] - l30 * z0 - l31 * z1 - l32 * z2
    z0 *= iv0  # D⁻¹ z
    z1 *= iv1
    z2 *= iv2
    z3 *= iv3
    nc = 1 + kw
    for j in range(nc):
        if j == 0:
            x0, x1, x2, x3 = u0, u1, u2, u3
            bj = b_m
        else:
            oh = _H + 4 * (ip[I_COMP + j - 1] & _IX)
            x0, x1, x2, x3 = w[oh], w[oh + 1], w[oh + 2], w[oh + 3]
            bj = w[ob + j - 1]
        y0 = x0
        y1 = x1 - l10 * y0
        y2 = x2 - l20 * y0 - l21 * y1
        y3 = x3 - l30 * y0 - l31 * y1 - l32 * y2
        oz = _Z + 4 * j
        w[oz] = y0
        w[oz + 1] = y1
        w[oz + 2] = y2
        w[oz + 3] = y3
        w[_NU + j] = bj - (y0 * z0 + y1 * z1 + y2 * z2 + y3 * z3)
        y0 *= iv0
        y1 *= iv1
        y2 *= iv2
        y3 *= iv3
        for c in range(j + 1):
            oc = _Z + 4 * c
            w[_GC + 4 * j + c] = y0 * w[oc] + y1 * w[oc + 1] + y2 * w[oc + 2] + y3 * w[oc + 3]
    if not _ldl_w(w, _GC, 4, _GI, nc):
        return STATUS_NOT_PD
    _ldl_solve_w(w, _GC, 4, _GI, nc, _NU)  # ν = [λ, μ_ω]
    for j in range(nc):  # D⁻¹ (z + Z ν)
        oz = _Z + 4 * j
        nu = w[_NU + j]
        z0 += w[oz] * nu * iv0
        z1 += w[oz + 1] * nu * iv1
        z2 += w[oz + 2] * nu * iv2
        z3 += w[oz + 3] * nu * iv3
    x3 = z3  # q̈_u = L⁻ᵀ D⁻¹ (z + Z ν)
    x2 = z2 - l32 * x3
    x1 = z1 - l21 * x2 - l31 * x3
    x0 = z0 - l10 * x1 - l20 * x2 - l30 * x3
    out[3] = x0
    out[4] = x1
    out[5] = x2
    out[6] = x3
    # q̈_R = A⁻¹ (r_R - B_F q̈_u) = A⁻¹ r_R - (B_F q̈_u + γ Sa (h·q̈_u)) / m_T
    sh = gam * (w[_HT] * x0 + w[_HT + 1] * x1 + w[_HT + 2] * x2 + w[_HT + 3] * x3)
    out[0] = (
        xr0 - (w[_BF] * x0 + w[_BF + 1] * x1 + w[_BF + 2] * x2 + w[_BF + 3] * x3 + sh * Sa0) * kT
    )
    out[1] = (
        xr1
        - (w[_BF + 4] * x0 + w[_BF + 5] * x1 + w[_BF + 6] * x2 + w[_BF + 7] * x3 + sh * Sa1) * kT
    )
    out[2] = (
        xr2
        - (w[_BF + 8] * x0 + w[_BF + 9] * x1 + w[_BF + 10] * x2 + w[_BF + 11] * x3 + sh * Sa2) * kT
    )
    # rod rows: (c1 + p_i c2)ᵀ q̈_b = e1 + p_i e2
    e1 = 0.0
    e2 = 0.0
    for r in range(7):
        e1 += w[_C1 + r] * out[r]
        e2 += w[_C2 + r] * out[r]
    for i in range(n):
        if ip[itr + i] == 0:
            out[7 + i] = (out[7 + i] / fp[om + i] - (e1 + q[7 + i] * e2)) * inv_s
            if full:
                out[nq + 7 + i] = 0.0
    if not full:
        return STATUS_OK
    for j in range(kp):  # μ_i: the tracked row of M_α q̈ - Q_α (q̈_i = b_i, Q_i stored in Q^C_i)
        i = ip[iidx + j] & _IX
        out[nq + 7 + i] = fp[om + i] * (s * out[7 + i] + (e1 + q[7 + i] * e2)) - out[nq + 7 + i]
    oc = nq  # Q^C
    out[oc] = 0.0
    out[oc + 1] = 0.0
    out[oc + 2] = 0.0
    lam_m = w[_NU]
    for c in range(4):
        v = 0.0  # applied control torque part H_wᵀ μ_ω
        for j in range(kw):
            v += w[_H + 4 * (ip[I_COMP + j] & _IX) + c] * w[_NU + 1 + j]
        w[_PM + c] = v
        out[oc + 3 + c] = v + q[3 + c] * lam_m
    # torque τ = ¼ H Q^C_u of the applied control force (docs/errata.md C4), residual A_c q̈ - b_c
    ot = 2 * nq
    for r in range(3):
        v = 0.0
        for c in range(4):
            v += w[_H + 4 * r + c] * w[_PM + c]
        out[ot + r] = 0.25 * v
    ores = ot + 3
    for j in range(kw):
        comp = ip[I_COMP + j] & _IX
        v = 0.0
        for c in range(4):
            v += w[_H + 4 * comp + c] * out[3 + c]
        out[ores + j] = v - w[ob + j]
    for j in range(kp):
        i = ip[iidx + j] & _IX
        out[ores + kw + j] = out[7 + i] - out[7 + i]  # q̈_i - b_i, b_i stored as q̈_i
    return STATUS_OK


@_jit
def _minv2(q, fp, ip, out, w, n, kw, kp, s, mu0, mu1, mu2, alpha, b_m, uu):
    """The N = M⁻² path (Eq. B13) of :func:`evaluate`, mirroring fundamental.solve with the closed
    forms of the module docstring; ``w`` is the workspace filled by :func:`_core`."""
    nq = n + 7
    k = kw + kp
    om = F_ARR
    iidx = I_TRACK + n
    itr = I_TRACK
    p = q[7:]
    u = q[3:7]
    Mbb = np.empty((7, 7))
    for i in range(7):
        for j in range(7):
            Mbb[i, j] = w[_MB + 7 * i + j]
    c1 = w[_C1 : _C1 + 7].copy()
    c2 = w[_C2 : _C2 + 7].copy()
    Qa = np.empty(nq)  # Q_α: body rows in w, rod rows in out (see _core)
    for i in range(7):
        Qa[i] = w[_QB + i]
    for i in range(n):
        Qa[7 + i] = out[nq + 7 + i] if ip[itr + i] else out[7 + i]
    bc = np.empty(k)
    for j in range(kw):
        bc[j] = w[_BW + j]
    for j in range(kp):
        bc[kw + j] = out[7 + ip[iidx + j]]
    Hm = np.empty((3, 4))
    _Hmat(u, Hm)
    Hw = np.empty((kw, 4))
    for j in range(kw):
        for c in range(4):
            Hw[j, c] = Hm[ip[I_COMP + j], c]
    qdd = out[:nq]
    QC = out[nq : 2 * nq]
    tau = out[2 * nq : 2 * nq + 3]
    res = out[2 * nq + 3 : 2 * nq + 3 + k]

    SB = Mbb.copy()  # body block of M_α, then its Schur complement over all rods
    for i in range(4):
        for j in range(4):
            SB[3 + i, 3 + j] += alpha * u[i] * u[j]
    if s > 0.0:
        for i in range(7):
            for j in range(7):
                SB[i, j] -= (
                    mu0 * c1[i] * c1[j]
                    + mu1 * (c1[i] * c2[j] + c2[i] * c1[j])
                    + mu2 * c2[i] * c2[j]
                ) / s
    if not _chol(SB, 7):
        return STATUS_NOT_PD
    a0 = Qa.copy()
    _ma_solve(SB, c1, c2, s, fp, om, p, n, a0)
    y = np.zeros(nq)
    for c in range(4):
        y[3 + c] = u[c]
    _ma_solve(SB, c1, c2, s, fp, om, p, n, y)
    sm = 0.0
    am_a0 = 0.0
    for c in range(4):
        sm += u[c] * y[3 + c]
        am_a0 += u[c] * a0[3 + c]
    lam_m = (b_m - am_a0) / sm
    acc = a0 + lam_m * y
    # r = b_c - A acc; w = A y / s_m; G = diag(4|u|², 1) + |u|² w wᵀ
    r = np.empty(k)
    wv = np.empty(k)
    dg = np.empty(k)
    for j in range(kw):
        va = 0.0
        vy = 0.0
        for c in range(4):
            va += Hw[j, c] * acc[3 + c]
            vy += Hw[j, c] * y[3 + c]
        r[j] = bc[j] - va
        wv[j] = vy / sm
        dg[j] = 4.0 * uu
    for j in range(kp):
        i = ip[iidx + j]
        r[kw + j] = bc[kw + j] - acc[7 + i]
        wv[kw + j] = y[7 + i] / sm
        dg[kw + j] = 1.0
    wDr = 0.0
    wDw = 0.0
    for j in range(k):
        wDr += wv[j] * r[j] / dg[j]
        wDw += wv[j] * wv[j] / dg[j]
    f = uu * wDr / (1.0 + uu * wDw)
    mu = np.empty(k)
    wmu = 0.0
    for j in range(k):
        mu[j] = (r[j] - wv[j] * f) / dg[j]
        wmu += wv[j] * mu[j]
    # v = A_cᵀ μ - a_m (w·μ) (= M Z μ); Q_c = M v
    v = np.zeros(nq)
    for j in range(kw):
        for c in range(4):
            v[3 + c] += Hw[j, c] * mu[j]
    for c in range(4):
        v[3 + c] -= u[c] * wmu
    for j in range(kp):
        v[7 + ip[iidx + j]] = mu[kw + j]
    Qc = np.zeros(nq)
    _m_mul(Mbb, c1, c2, s, fp, om, p, n, v, Qc)
    # v2 = M_α⁻¹ Q_c = M_α⁻¹ M v = v - α y (a_mᵀ v) exactly (M = M_α - α a_m a_mᵀ, y = M_α⁻¹ a_m):
    # no product with M followed by a solve, which would cost about cond(M) in accuracy
    am_v = 0.0
    for c in range(4):
        am_v += u[c] * v[3 + c]
    v2 = np.empty(nq)
    for i in range(nq):
        v2[i] = v[i] - alpha * am_v * y[i]
    am_v2 = 0.0
    yQc = 0.0
    for c in range(4):
        am_v2 += u[c] * v2[3 + c]
    for i in range(nq):
        yQc += y[i] * Qc[i]
    for i in range(nq):
        qdd[i] = acc[i] + v2[i] - y[i] * (am_v2 / sm)
    corr = lam_m - yQc / sm
    for i in range(nq):
        QC[i] = Qc[i]
    for c in range(4):
        QC[3 + c] += u[c] * corr
    # torque τ = ¼ H Q^C_u of the applied control force (docs/errata.md C4), residual A_c q̈ - b_c
    for rr in range(3):
        vv = 0.0
        for c in range(4):
            vv += Hm[rr, c] * Qc[3 + c]
        tau[rr] = 0.25 * vv
    for j in range(kw):
        vv = 0.0
        for c in range(4):
            vv += Hw[j, c] * qdd[3 + c]
        res[j] = vv - bc[j]
    for j in range(kp):
        res[kw + j] = qdd[7 + ip[iidx + j]] - bc[kw + j]
    return STATUS_OK


@_jit
def _ma_solve(SB, c1, c2, s, fp, om, p, n, x):
    """In place x <- M_α⁻¹ x by the Schur complement SB (Cholesky factor) on the body block."""
    s0 = 0.0
    s1 = 0.0
    for i in range(n):
        s0 += x[7 + i]
        s1 += p[i] * x[7 + i]
    xb = np.empty(7)
    for r in range(7):
        xb[r] = x[r] - (c1[r] * s0 + c2[r] * s1) / s
    _chol_solve(SB, 7, xb)
    for r in range(7):
        x[r] = xb[r]
    for i in range(n):
        v = 0.0
        for r in range(7):
            v += (c1[r] + p[i] * c2[r]) * xb[r]
        x[7 + i] = (x[7 + i] / fp[om + i] - v) / s


@_jit
def _m_mul(Mbb, c1, c2, s, fp, om, p, n, v, out):
    """out = M v (M without the α term) using M_bp columns m_i (c1 + p_i c2), M_pp = s diag(m)."""
    t0 = 0.0
    t1 = 0.0
    for i in range(n):
        mv = fp[om + i] * v[7 + i]
        t0 += mv
        t1 += mv * p[i]
    for r in range(7):
        acc = c1[r] * t0 + c2[r] * t1
        for c in range(7):
            acc += Mbb[r, c] * v[c]
        out[r] = acc
    for i in range(n):
        acc = 0.0
        for r in range(7):
            acc += (c1[r] + p[i] * c2[r]) * v[r]
        out[7 + i] = fp[om + i] * (acc + s * v[7 + i])


def cache_dir_note() -> str:
    """Where numba caches this kernel in this process (for messages)."""
    if not HAVE_NUMBA:
        return "numba not installed"
    env = os.environ.get("NUMBA_CACHE_DIR")
    return f"NUMBA_CACHE_DIR={env}" if env else "__pycache__ beside analytic/ or the user cache dir"
