"""Where every number lives: the packed parameter arrays ``fp`` (float64) and ``ip`` (int64) that
:func:`analytic.fast.pack` writes and the kernel reads, the kernel's output array, and the slots of
its stack workspace. Defined here once; the packer, the kernel stages and the compiled callers
(:mod:`analytic.fast_rhs`, :mod:`mj_bridge.fast_stage`, :mod:`mj_bridge.native`,
:mod:`mj_bridge.pinocchio_plant`) all read these names.

Pure constants, one record type and plain functions; no numba here (``pack`` imports it without
compiling).

``fp``: a fixed head (``F_*``, ``F_ARR`` slots) then, for n masses and k_p tracked masses, the
tail of :func:`tail_offsets` (:class:`FpTail`): ``m (n), p_e (n)``, each spring law's coefficients
(n+1 each, :data:`LAW_INDEX`), the mass
track ``l, λ, α, β`` (k_p each, Eq. 75, 78) and the rod geometry ``a (3), d (3)`` (body axes).

``ip``: a fixed head (``I_*``, ``I_TRACK`` slots), then the per-mass tracked flag (n) at
``I_TRACK`` and the tracked indices (k_p, 0-based) at ``I_TRACK + n``.

Adding a parameter is a change here plus the stage that reads it (and the packer that writes it):
a tail block is a field of :class:`FpTail` and a line of :func:`tail_offsets`; a head slot or flag
is a new ``F_*`` / ``I_*`` constant, with ``F_ARR`` / ``I_TRACK`` (the head's length) moved past it.
Every reader names the slots it reads, so no other reader changes.

The kernel's output ``out`` (:func:`output_length`): ``[q̈ (nq), Q^C (nq), τ (3), A_c q̈ - b_c (k)]``
with ``nq = n + 7``; an ``out`` of length ``nq`` asks for ``q̈`` only (Gauss weighting).
"""

from __future__ import annotations

from typing import NamedTuple

from analytic.effects import Effect
from analytic.effects.registry import SPRING_LAWS

# ----------------------------------------------------------------------------------------------
# fp head
# ----------------------------------------------------------------------------------------------
F_MBR = 0  # m_BR, kg
F_MU0 = 1  # μ0 = Σ m_i, kg
F_D1 = 2  # δ1 of Eq. (58)
F_D2 = 3  # δ2 of Eq. (58)
F_TFREQ = 4  # given torque frequency, rad/s (Remark 2)
F_J = 5  # 9: J, row-major, body axes, kg·m²
F_G = 14  # 3: gravity, inertial, m/s²
F_TC = 17  # 3: given torque, constant part, body axes, N·m
F_TA = 20  # 3: given torque, amplitude of cos(freq t), body axes, N·m
F_WB = 23  # 3: ω amplitudes b (Eq. 76), rad/s
F_WS = 26  # 3: ω frequencies σ (Eq. 76), rad/s
F_GAIN = 29  # k_ω x k_ω gain P (Eq. B6), row-major (9 slots)
F_TAT = 38  # 48: T_a (3, 4, 4) row-major, L_a(u) = T_a @ u (Eq. 29; kinematics.kinematic_terms)
F_TDT = 86  # 48: T_d, L_d(u) = T_d @ u (Eq. 34)
F_ARR = 134  # the head's length: the start of the tail (tail_offsets)

# ----------------------------------------------------------------------------------------------
# The spring laws (analytic.effects.registry.SPRING_LAWS): one on/off flag each in ip, one block of
# n + 1 coefficients each in fp's tail, in the laws' order; a law declared later needs no change here
# ----------------------------------------------------------------------------------------------
N_LAWS = len(SPRING_LAWS)
LAW_INDEX: dict[Effect, int] = {law.effect: j for j, law in enumerate(SPRING_LAWS)}
"""``effect -> j``: its flag is ``ip[I_LAWS + j]``, its coefficients ``fp[o.laws + j (n + 1) :]``."""

# ----------------------------------------------------------------------------------------------
# ip head
# ----------------------------------------------------------------------------------------------
I_N = 0  # n, number of masses
I_KW = 1  # k_ω, tracked ω components
I_KP = 2  # k_p, tracked masses
I_GRAV = 3  # 1: gravity on
I_TORQ = 4  # 1: given torque on (Remark 2)
I_WEIGHT = 5  # W_GAUSS, W_MINV2 or W_IDENTITY
I_COMP = 6  # 3 slots: the tracked ω components (0-based)
I_FN_SYSTEM = 9  # address of the compiled stages 1-6 in this process (analytic.kernel.halves)
I_FN_SOLVE = 10  # address of the compiled solve of this scene's weighting, in this process
I_LAWS = 11  # N_LAWS slots: 1 where a spring law is on, in the order of SPRING_LAWS
I_TRACK = I_LAWS + N_LAWS  # the head's length: n flags (1 for a tracked mass), then the k_p tracked indices

W_GAUSS = 0  # N = M⁻¹, the paper's Eq. (89)
W_MINV2 = 1  # N = M⁻² (Eq. B13)
W_IDENTITY = 2  # N = I (the Euclidean norm of the control force, Eq. B10 with W = I)

IDENTITY_RANK_TOL = 1e-5
"""The identity weighting's rank decision (:mod:`analytic.kernel.identity`): the kernel declines
(the numpy path answers, with its own Moore-Penrose rank decision) when a column of ``Z = K A_cᵀ``,
scaled to unit length, lies within this distance of the span of the others. It is
``sqrt(analytic.fundamental.PINV_RCOND)``: that cut-off is on eigenvalues of the Jacobi-scaled Gram
matrix ``ZᵀZ``, whose eigenvalues are squares of the singular values of the scaled ``Z``."""

IX = 0x7FFFFFFF
"""Mask for sizes and indices read from ``ip`` inside the kernel. The values are small and
non-negative, so the mask changes nothing; it lets LLVM prove every array index non-negative and
drop numba's negative-index wrap-around code, which otherwise dominates the cost of the O(n) loops
(``docs/performance.md``)."""

STATUS_OK = 0
STATUS_NOT_PD = 1  # a Schur complement or the bordered Gram matrix is not numerically PD
STATUS_UNSUPPORTED = 2  # not this solve's scene, output too short, or halves not bound


class FpTail(NamedTuple):
    """Offsets in ``fp`` of the tail's blocks (each block's length in its comment) and ``end``,
    the length of ``fp``. Read by name (``tail_offsets(n, kp).p_e``), never unpacked: a block added
    to the tail is one field here and one line in :func:`tail_offsets` (and its length in
    ``tests/analytic/kernel/test_layout.py``), and no reader changes. numba compiles the record as
    a tuple of ints (no per-call cost once inlined)."""

    m: int  # (n) masses m_i, kg
    p_e: int  # (n) spring equilibria p_e,i, m
    laws: int  # (N_LAWS (n + 1)) each spring law's coefficients, in the laws' order (LAW_INDEX)
    l: int  # (k_p) mass track amplitudes l (Eq. 75)
    lam: int  # (k_p) mass track frequencies λ (Eq. 75)
    alpha: int  # (k_p) mass track gains α (Eq. 78)
    beta: int  # (k_p) mass track gains β (Eq. 78)
    a: int  # (3) rod axis a, body axes
    d: int  # (3) rod offset d, body axes, m
    end: int  # the length of fp


def tail_offsets(n: int, kp: int) -> FpTail:
    """Where each block of ``fp``'s tail starts, for n masses and k_p tracked masses.

    Plain arithmetic; compiled code calls it as :data:`analytic.kernel.calls.tail` (the same
    function, compiled inline).
    """
    o_m = F_ARR
    o_pe = o_m + n
    o_laws = o_pe + n
    o_l = o_laws + N_LAWS * (n + 1)
    o_lam = o_l + kp
    o_alpha = o_lam + kp
    o_beta = o_alpha + kp
    o_a = o_beta + kp
    o_d = o_a + 3
    return FpTail(o_m, o_pe, o_laws, o_l, o_lam, o_alpha, o_beta, o_a, o_d, o_d + 3)


def law_offset(o: FpTail, n: int, j: int) -> int:
    """Where spring law ``j``'s n + 1 coefficients start in ``fp`` (``j = LAW_INDEX[effect]``)."""
    return o.laws + j * (n + 1)


def ip_length(n: int, kp: int) -> int:
    """Length of ``ip``: the head, the n tracked flags and the k_p tracked indices."""
    return I_TRACK + n + kp


def fp_length(n: int, kp: int) -> int:
    """Length of ``fp``: the head and the tail (:func:`tail_offsets`)."""
    return tail_offsets(n, kp).end


def output_length(n: int, k: int) -> int:
    """Length of the kernel's full output ``[q̈, Q^C, τ, residual]``: ``2 (n + 7) + 3 + k``."""
    return 2 * (n + 7) + 3 + k


# ----------------------------------------------------------------------------------------------
# Workspace: one float64 array on the stack per evaluation (analytic.runtime.jit.workspace), carved
# by these offsets, instead of ~30 small np.empty/np.zeros (each a heap allocation plus reference
# counting). The stages hand each other their results through these slots.
# ----------------------------------------------------------------------------------------------
WS_MB = 0  # 49: body block M_bb of M (Eq. 51), row-major 7x7, both triangles
WS_S4 = 49  # 4x4 (row stride 4, lower triangle): S_4, the Schur complement on the u block
WS_BF = 65  # 3x4: B_F, the R-u block of S_F
WS_HT = 77  # 4: h = B_Fᵀ Sa
WS_R4 = 81  # 4: right-hand side on the u block
WS_C1 = 85  # 7: c1 = [Sa; L_dᵀSa]
WS_C2 = 92  # 7: c2 = [0; L_aᵀSa]
WS_RB = 99  # 7: body right-hand side r_b
WS_Z = 106  # 4 x 4: Z = L⁻¹ Cᵀ (u rows), column j at WS_Z + 4 j
WS_GC = 122  # 4x4 (row stride 4): G = C S_4⁻¹ Cᵀ, then its LDLᵀ factors
WS_GI = 138  # 4: 1 / pivots of that factorisation
WS_NU = 142  # 4: right-hand side, then ν = [λ, μ_ω]
WS_H = 146  # 12: H(u), row-major (3, 4) (Eq. 13)
WS_LA = 158  # 12: L_a(u) (Eq. 29)
WS_LD = 170  # 12: L_d(u) (Eq. 34)
WS_JH = 182  # 12: J H(u)
WS_PM = 194  # 12: μ2 L_a + μ1 L_d (first 4 slots reused at the end for H_wᵀ μ_ω)
WS_OM = 206  # 3: ω = H(u) u̇ (Eq. 12)
WS_EW = 209  # 3: ω tracking error
WS_QB = 212  # 7: body rows of Q_α (the rod rows of Q go into out, see forces.rod_pass)
WS_BW = 219  # 3: b_c of the ω rows (those of the tracked masses go into out)
WS_SA = 222  # 3: S(u) a, inertial
WS_LAU = 225  # 3: L_a(u) u̇
WS_LAD = 228  # 3: L̇_a u̇ = L_a(u̇) u̇
WS_LDD = 231  # 3: L̇_d u̇ = L_d(u̇) u̇
WS_JW = 234  # 3: J ω
WS_XR = 237  # 3: A⁻¹ r_R (Gauss, schur.schur_complement)
# scalars
WS_S = 240  # s = (Sa)ᵀSa (Eq. 51, M_pp = s diag(m))
WS_SLAU = 241  # (Sa)ᵀ L_a u̇
WS_SLAD = 242  # (Sa)ᵀ L̇_a u̇
WS_SLDD = 243  # (Sa)ᵀ L̇_d u̇
WS_MU1 = 244  # μ1 = Σ m_i p_i (all masses)
WS_MU2 = 245  # μ2 = Σ m_i p_i²
WS_MPD = 246  # Σ m_i ṗ_i
WS_MPPD = 247  # Σ m_i p_i ṗ_i
WS_N0 = 248  # Σ_F m_i (free masses)
WS_N1 = 249  # Σ_F m_i p_i
WS_N2 = 250  # Σ_F m_i p_i²
WS_NT0 = 251  # Σ_T m_i (tracked masses)
WS_NT1 = 252  # Σ_T m_i p_i
WS_SQ = 253  # Σ_F Q_i
WS_SPQ = 254  # Σ_F p_i Q_i
WS_UU = 255  # |u|²
WS_BM = 256  # b_m of Eq. (59)
WS_ALPHA = 257  # α = tr(M) / nq of M_α = M + α a_m a_mᵀ
WS_T0 = 258  # Σ_T m_i b_i
WS_T1 = 259  # Σ_T m_i p_i b_i
WS_GAM = 260  # γ of the closed-form R block inverse (Gauss)
WS_KT = 261  # 1 / m_T
WS_LEN = 262
