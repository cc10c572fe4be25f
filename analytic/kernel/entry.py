"""Which compiled solve a scene needs, and the entry point that decides at run time.

A compiled caller (the integrator's right-hand side, the MuJoCo stage, ...) embeds one kernel. It
is built once per :class:`Solver` with the solver as a closure constant, so numba prunes the other
branch before compiling: a Gauss scene never compiles the M⁻² solve (:mod:`analytic.kernel.minv2`)
or the identity weighting's (:mod:`analytic.kernel.identity`), and so on. :data:`Solver.ANY` keeps
all three and chooses per call from ``ip`` (for callers that serve every scene with one compiled
function).
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

from analytic.kernel.layout import (
    I_KP,
    I_KW,
    I_WEIGHT,
    STATUS_UNSUPPORTED,
    W_GAUSS,
    W_IDENTITY,
    W_MINV2,
)
from analytic.kernel.weighting import join
from analytic.runtime.jit import inline_always, jit_entry


class Solver(IntEnum):
    """The solve a compiled caller embeds: ``GAUSS`` (:mod:`analytic.kernel.gauss`, also every
    uncontrolled scene), ``MINV2`` (:mod:`analytic.kernel.minv2`), ``IDENTITY``
    (:mod:`analytic.kernel.identity`), or ``ANY`` (all three, chosen per call)."""

    GAUSS = W_GAUSS
    MINV2 = W_MINV2
    IDENTITY = W_IDENTITY
    ANY = -1


def solver_of(ip: np.ndarray) -> Solver:
    """The solve a packed scene needs: its weighting's when it is controlled, else Gauss (an
    uncontrolled scene has no control force to weigh)."""
    controlled = int(ip[I_KW]) + int(ip[I_KP]) > 0
    return Solver(int(ip[I_WEIGHT])) if controlled else Solver.GAUSS


def _make_evaluate(deps: int):
    def evaluate(t, q, qd, fp, ip, out):
        """The kernel of the weighting the scene in ``ip`` needs
        (:func:`analytic.kernel.weighting.join`; all three are compiled with this function)."""
        if deps < 0:  # never true: ties numba's cache key to the kernel's sources
            return STATUS_UNSUPPORTED
        if ip[I_KW] + ip[I_KP] > 0:
            if ip[I_WEIGHT] == W_MINV2:
                return join(W_MINV2, t, q, qd, fp, ip, out)
            if ip[I_WEIGHT] == W_IDENTITY:
                return join(W_IDENTITY, t, q, qd, fp, ip, out)
        return join(W_GAUSS, t, q, qd, fp, ip, out)

    return evaluate


evaluate = jit_entry(_make_evaluate)
"""The kernel for any packed scene: ``[q̈, Q^C, τ, residual]`` into ``out`` (see
:func:`analytic.kernel.weighting.make_evaluate`), status returned."""

_ANY = int(Solver.ANY)


@inline_always
def evaluate_as(solver, t, q, qd, fp, ip, out):
    """The kernel a compiled caller embeds, by ``solver`` (a :class:`Solver` value). Pass a
    constant of the caller (a closure variable of its factory): inlined by numba
    (:func:`analytic.runtime.jit.inline_always`), the other branches are dropped before compiling.
    A single solve is called as its two cached halves by address
    (:func:`analytic.kernel.weighting.join`), so the caller compiles without them; ``Solver.ANY``
    goes through :data:`evaluate`."""
    if solver == _ANY:
        return evaluate(t, q, qd, fp, ip, out)
    return join(solver, t, q, qd, fp, ip, out)
