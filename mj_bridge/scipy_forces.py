"""The generalized forces the plants on scipy's loop apply in the paper's coordinates, one function
per effect, found by the effect's name (:data:`FORCES`).

A scene's springs and given torque act on the coordinates every engine shares (the rod positions
``p``, the body-axis torque), so the plants stepped by scipy (Pinocchio, Drake, the next one) apply
them through this one table; what an engine builds into its model itself (gravity, the masses'
inertia) is its own table (``mj_bridge.pinocchio_effects``, ``mj_bridge.drake_effects``). Adding
such an effect is one function here, registered with :func:`force`.

Every function has the signature ``force(t, q, qd, fp, ip, off, tt, ten)`` and is plain Python that
numba compiles (:mod:`mj_bridge.scipy_stage` compiles them into the stage, in the table's order, each
called only when its ``ip`` flag is set):

* ``t``: time, s; ``q``, ``qd`` (n + 7 each): the paper state ``[R, u, p]``, ``[Ṙ, u̇, ṗ]``;
* ``fp``, ``ip``: the packed scene (:func:`analytic.fast.pack`); ``off``: the offsets of its tail
  (:class:`analytic.kernel.layout.FpTail`, read by name: ``off.p_e``, ``off.laws``, …; a spring
  law's coefficients start at ``off.laws + LAW_INDEX[effect] (n + 1)``);
* ``tt`` (3): the body-axis torque on BR, holding the control torque: add to it;
* ``ten`` (n + 1): the tension ``f_j`` of each spring of the chain, zero on entry: add to it.
  Spring ``j`` joins mass ``j - 1`` and mass ``j`` (``x = p - p_e``, ``x_{-1} = x_n = 0``, extension
  ``e_j = x_j - x_{j-1}``); the stage applies ``f_{j+1} - f_j`` to mass ``j`` (``F^S = −∂U_s/∂p``,
  Eq. 38).

Light on purpose (numpy-free, numba-free): the plants' classes read :data:`FORCE_EFFECTS` when the
plants are listed.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from analytic.effects import Effect
from analytic.kernel.layout import F_TA, F_TC, F_TFREQ, I_LAWS, I_N, I_TORQ, LAW_INDEX

ForceFn = Callable[..., None]
"""``force(t, q, qd, fp, ip, off, tt, ten) -> None`` (module docstring)."""

FORCES: dict[Effect, tuple[int, ForceFn]] = {}
"""Each force effect: the ``ip`` slot of its on/off flag and its function, in the order the stage
adds them (the order of the registrations below)."""


def force(effect: Effect, flag: int) -> Callable[[ForceFn], ForceFn]:
    """Register the decorated function as ``effect``'s force, applied when ``ip[flag]`` is set."""

    def register(fn: ForceFn) -> ForceFn:
        if effect in FORCES:
            raise ValueError(f"{effect.value}: a force is registered for it already")
        FORCES[effect] = (flag, fn)
        return fn

    return register


@force(Effect.EXTERNAL_TORQUE, I_TORQ)
def external_torque(t, q, qd, fp, ip, off, tt, ten):  # pragma: no cover - compiled
    """The given torque of Remark 2, ``τ_g = c + A cos(ω_g t)`` (body axes), added to ``tt``."""
    ct = math.cos(fp[F_TFREQ] * t)
    for r in range(3):
        tt[r] += fp[F_TC + r] + fp[F_TA + r] * ct


LINEAR = LAW_INDEX[Effect.SPRINGS_LINEAR]
CUBIC = LAW_INDEX[Effect.SPRINGS_CUBIC]


@force(Effect.SPRINGS_LINEAR, I_LAWS + LINEAR)
def springs_linear(t, q, qd, fp, ip, off, tt, ten):  # pragma: no cover - compiled
    """The linear springs of Eq. (38): ``f_j += k_l,j e_j``."""
    n = ip[I_N]
    o_pe, o_kl = off.p_e, off.laws + LINEAR * (n + 1)
    x_prev = 0.0
    for j in range(n + 1):
        x_j = q[7 + j] - fp[o_pe + j] if j < n else 0.0
        ten[j] += fp[o_kl + j] * (x_j - x_prev)
        x_prev = x_j


@force(Effect.SPRINGS_CUBIC, I_LAWS + CUBIC)
def springs_cubic(t, q, qd, fp, ip, off, tt, ten):  # pragma: no cover - compiled
    """The cubic springs of Eq. (38): ``f_j += k_n,j e_j³``."""
    n = ip[I_N]
    o_pe, o_kn = off.p_e, off.laws + CUBIC * (n + 1)
    x_prev = 0.0
    for j in range(n + 1):
        x_j = q[7 + j] - fp[o_pe + j] if j < n else 0.0
        e = x_j - x_prev
        ten[j] += fp[o_kn + j] * e * e * e
        x_prev = x_j


DAMPING = LAW_INDEX[Effect.SPRINGS_DAMPING]


@force(Effect.SPRINGS_DAMPING, I_LAWS + DAMPING)
def springs_damping(t, q, qd, fp, ip, off, tt, ten):  # pragma: no cover - compiled
    """The springs' viscous damping: ``f_j += c_j ė_j``, ``ė_j = ṗ_j - ṗ_{j-1}``."""
    n = ip[I_N]
    o_c = off.laws + DAMPING * (n + 1)
    v_prev = 0.0
    for j in range(n + 1):
        v_j = qd[7 + j] if j < n else 0.0
        ten[j] += fp[o_c + j] * (v_j - v_prev)
        v_prev = v_j


FORCE_EFFECTS = frozenset(FORCES)
"""The effects :data:`FORCES` applies."""


__all__ = ["FORCES", "FORCE_EFFECTS", "ForceFn", "force"]
