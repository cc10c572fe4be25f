"""The controlled system at one state, as both weightings need it: stages 1-6 of the kernel.

``M`` (Eq. 51) and ``Q`` (Eq. 52) in structured form, the modeling constraint (Eq. 59) with the
augmentation ``M_α``, and the control right-hand sides ``b_c`` (Eqs. 81, 86), into the workspace
``w`` and (rod rows) ``out``; see :mod:`analytic.kernel.layout` for where each lands. The solve that
follows is the weighting's: :mod:`analytic.kernel.gauss` or :mod:`analytic.kernel.minv2`.
"""

from __future__ import annotations

from analytic.kernel.constraints import control_rows, modeling_row
from analytic.kernel.forces import body_forces, rod_pass
from analytic.kernel.jit import inline, jit_entry
from analytic.kernel.kinematics import kinematic_terms
from analytic.kernel.layout import I_KP, I_KW, I_N, IX, tail_offsets
from analytic.kernel.mass_matrix import body_block

tail = inline(tail_offsets)
""":func:`analytic.kernel.layout.tail_offsets` for compiled callers (the kernel, the compiled
right-hand sides and stages): the offsets of ``fp``'s tail, computed where they are read."""


def _make_build_system(deps: int):
    """:func:`build_system` closing over the kernel's source fingerprint (see
    :func:`analytic.kernel.jit.jit_entry`)."""

    def build_system(t, q, qd, fp, ip, out, full, w):
        """Stages 1-6 (kinematics Eqs. 11-34; Q rod rows Eq. 52 and springs Eq. 38; M Eq. 51; Q body
        rows Eq. 52, 61; b_m and M_α Eq. 59; b_c Eqs. 81, 86). ``full``: whether ``out`` holds the whole
        output (a tracked mass's ``Q_i`` then goes to its ``Q^C_i`` slot).

        Compiled once and cached on its own (not pasted into its callers): both weightings' kernels
        call it, so a process that needs both compiles these stages once.
        """
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return
        n = ip[I_N] & IX
        kw = ip[I_KW] & IX
        kp = ip[I_KP] & IX
        o_m, o_pe, o_kl, o_kn, o_l, o_lam, o_alpha, o_beta, o_a, _o_d, _end = tail(n, kp)
        kinematic_terms(q, qd, fp, o_a, w)
        rod_pass(q, qd, fp, ip, n, o_m, o_pe, o_kl, o_kn, out, full, w)
        body_block(fp, w)
        body_forces(t, q, qd, fp, ip, w)
        modeling_row(q, qd, fp, n + 7, w)
        control_rows(t, q, qd, fp, ip, n, kw, kp, o_m, o_pe, o_l, o_lam, o_alpha, o_beta, out, w)

    return build_system


build_system = jit_entry(_make_build_system)
