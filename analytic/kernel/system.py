"""The controlled system at one state, as both weightings need it: stages 1-6 of the kernel.

``M`` (Eq. 51) and ``Q`` (Eq. 52) in structured form, the modeling constraint (Eq. 59) with the
augmentation ``M_α``, and the control right-hand sides ``b_c`` (Eqs. 81, 86), into the workspace
``w`` and (rod rows) ``out``; see :mod:`analytic.kernel.layout` for where each lands. The solve that
follows is the weighting's: :mod:`analytic.kernel.gauss` or :mod:`analytic.kernel.minv2`.
"""

from __future__ import annotations

from analytic.kernel.calls import tail
from analytic.kernel.constraints import control_rows, modeling_row
from analytic.kernel.forces import body_forces, rod_pass
from analytic.kernel.kinematics import kinematic_terms
from analytic.kernel.layout import I_KP, I_KW, I_N, IX
from analytic.kernel.mass_matrix import body_block


def make_build_system(deps: int):
    """The C callback body of stages 1-6 (:data:`analytic.runtime.abi.SYSTEM_SIG`), closing over
    the kernel's source fingerprint ``deps`` (numba hashes closure variables into its cache key, so
    an edit of any kernel file recompiles it). :mod:`analytic.kernel.halves` compiles it once."""

    def build_system(t, q, qd, fp, ip, out, len_out, full, w):
        """Stages 1-6 (kinematics Eqs. 11-34; Q rod rows Eq. 52 and springs Eq. 38; M Eq. 51; Q
        body rows Eq. 52, 61; b_m and M_α Eq. 59; b_c Eqs. 81, 86) into ``w`` and the rod rows of
        ``out``. ``full`` (0/1): whether ``out`` holds the whole output (a tracked mass's ``Q_i``
        then goes to its ``Q^C_i`` slot).

        The stages index the C pointers themselves (no array is built around them): numba compiles a pointer's index as one address and one
        load, an array's with its checks and wraparound, several times the compile work."""
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return
        on = full != 0
        n = ip[I_N] & IX
        kw = ip[I_KW] & IX
        kp = ip[I_KP] & IX
        o = tail(n, kp)  # the offsets of fp's tail, read by name by the stages that need them
        kinematic_terms(q, qd, fp, o.a, w)
        rod_pass(q, qd, fp, ip, n, o, out, on, w)
        body_block(fp, w)
        body_forces(t, q, qd, fp, ip, w)
        modeling_row(q, qd, fp, n + 7, w)
        control_rows(t, q, qd, fp, ip, n, kw, kp, o, out, w)

    return build_system


__all__ = ["make_build_system"]
