"""The integrator's whole right-hand side in one compiled call: ``ẏ`` for ``y = [q, q̇, W, I_L, I_P]``.

:func:`analytic.simulate._rhs` builds ``ẏ`` in Python from :meth:`FastModel.acceleration_output`
(q̈ and the control outputs) and :func:`analytic.aux_rates.aux_rates` (work and impulse rates): about
20 µs per evaluation, of which the kernel is under 1 µs. This module does the same lines in one
numba function (same kernel, same arithmetic, same order of operations, so the same numbers), so a
right-hand side costs about one kernel call plus numba's dispatch.

``rhs_into(t, y, fp, ip, work, out)`` returns a status: ``fast_kernel.STATUS_OK``; the kernel's
nonzero status (the caller answers that evaluation with the numpy model); or :data:`STATUS_NONFINITE`
when ``ẏ`` has a NaN or an infinity.
"""

from __future__ import annotations

import math

from analytic import aux_rates as _aux
from analytic import fast_kernel as fk

STATUS_NONFINITE = 3


def _make(deps: int):
    """``rhs_into`` closing over ``deps`` (the source fingerprint of the kernel and of
    :mod:`analytic.aux_rates`, which it embeds; see :func:`analytic.fast_kernel.source_fingerprint`)."""

    def rhs_into(t, y, fp, ip, work, out):  # pragma: no cover - compiled
        """Fill ``out`` (2 nq + 7) with ``ẏ``; ``work`` (2 nq + 3 + k) receives the kernel's output.

        Args:
            t: time, s. y: ``[q (nq), q̇ (nq), W, I_L (3), I_P (3)]``.
            fp, ip: packed parameters (:func:`analytic.fast.pack`).
        """
        if deps < 0:  # never true: ties numba's cache key to the sources this embeds
            return fk.STATUS_UNSUPPORTED
        n = ip[fk.I_N]
        kp = ip[fk.I_KP]
        nq = n + 7
        q = y[:nq]
        qd = y[nq : 2 * nq]
        status = fk.evaluate(t, q, qd, fp, ip, work)
        if status != fk.STATUS_OK:
            return status
        for i in range(nq):
            out[i] = qd[i]
            out[nq + i] = work[i]
        tau = work[2 * nq : 2 * nq + 3]  # control torque, then + the given torque (Remark 2)
        if ip[fk.I_TORQ]:
            ct = math.cos(fp[fk.F_TFREQ] * t)
            for r in range(3):
                tau[r] = tau[r] + (fp[fk.F_TC + r] + fp[fk.F_TA + r] * ct)
        # a, d follow m, p_e, k_l, k_n (n + 1 each) and the four mass-track arrays (analytic.fast.pack)
        oa = fk.F_ARR + 4 * n + 2 + 4 * kp
        _aux.aux_rates(
            q,
            qd,
            tau,
            work[nq + 7 : 2 * nq],  # rod forces Q^C_p
            work[nq : nq + 3],  # force at C Q^C_R
            fp[oa : oa + 3],
            fp[oa + 3 : oa + 6],
            fp[fk.F_ARR : fk.F_ARR + n],
            fp[fk.F_MU0],
            fp[fk.F_MBR] + fp[fk.F_MU0],  # m_T = m_BR + μ0, as TumblingModel.m_T
            out[2 * nq :],
        )
        for i in range(out.shape[0]):
            if not math.isfinite(out[i]):
                return STATUS_NONFINITE
        return fk.STATUS_OK

    return rhs_into


DEPS = fk.source_fingerprint(fk, _aux)
rhs_into = fk._jit(_make(DEPS)) if fk.HAVE_NUMBA else None
