"""A weighting's kernel built in one place: how a caller reaches the two compiled halves, and the
entry points Python calls.

Every weighting's kernel is the same two halves called by address (:mod:`analytic.runtime.abi`):
stages 1-6, then the weighting's solve. What differs between weightings here is one constant, the
weighting ``W_*`` of :mod:`analytic.kernel.layout`, and what follows from it:

* Gauss (``W_GAUSS``, also every uncontrolled scene) answers ``q̈`` alone when ``out`` has length
  ``nq``, and any weighting's scene without control;
* M⁻² and identity need ``Q^C`` on the way to ``q̈``: a controlled scene of that weighting and the
  full output ``[q̈, Q^C, τ, residual]``, else ``STATUS_UNSUPPORTED``.

:func:`join` is that choice (inlined into each caller with the weighting a constant);
:func:`make_evaluate` and :func:`make_qddot_into` build a weighting's cached entry points. Each
weighting's module (:mod:`analytic.kernel.gauss`, :mod:`~analytic.kernel.minv2`,
:mod:`~analytic.kernel.identity`) keeps only its own solve and names its entry points with these.
"""

from __future__ import annotations

import numpy as np

from analytic.kernel.calls import call_halves
from analytic.kernel.layout import (
    I_KP,
    I_KW,
    I_N,
    I_WEIGHT,
    IX,
    STATUS_OK,
    STATUS_UNSUPPORTED,
    W_GAUSS,
    W_IDENTITY,
    W_MINV2,
)
from analytic.runtime.jit import inline_always, jit_entry

NAMES = {W_GAUSS: "gauss", W_MINV2: "minv2", W_IDENTITY: "identity"}
"""Each weighting's short name: its module's, and the name of its cached entry points (numba
names a cached function's files by it, so each weighting's are its own)."""


@inline_always
def join(weight, t, q, qd, fp, ip, out):
    """The kernel of weighting ``weight`` (a ``W_*`` constant of the caller: inlined, the other
    weightings' branches drop out): the two compiled halves called by the addresses in ``ip``
    (:mod:`analytic.kernel.calls`; ``STATUS_UNSUPPORTED`` when they are not set, i.e. ``ip`` did
    not come from a :class:`analytic.fast.FastModel`), or ``STATUS_UNSUPPORTED`` when the scene in
    ``ip`` is not this weighting's (module docstring)."""
    n = ip[I_N] & IX
    kw = ip[I_KW] & IX
    kp = ip[I_KP] & IX
    controlled = kw + kp > 0
    if weight == W_GAUSS:
        if controlled and ip[I_WEIGHT] != W_GAUSS:
            return STATUS_UNSUPPORTED
    elif not controlled or ip[I_WEIGHT] != weight:
        return STATUS_UNSUPPORTED
    full = out.shape[0] >= 2 * (n + 7) + 3 + kw + kp  # else: q̈ only
    if weight != W_GAUSS and not full:  # this weighting needs Q^C on the way to q̈
        return STATUS_UNSUPPORTED
    return call_halves(t, q, qd, fp, ip, out, full)


def make_evaluate(weight: int):
    """The cached entry point ``evaluate(t, q, qd, fp, ip, out) -> status`` of weighting
    ``weight``: one evaluation of the controlled dynamics (:func:`join`).

    Its arguments: ``t`` time, s; ``q``, ``qd`` the state ``[R, u, p]`` and its rate, shape (nq,);
    ``fp``, ``ip`` the packed parameters (:func:`analytic.fast.pack`, addresses bound by
    :class:`analytic.fast.FastModel`); ``out`` ``[q̈, Q^C, τ, A_c q̈ - b_c]`` (length
    ``2 nq + 3 + k``), or for Gauss ``q̈`` only (length nq).

    Its status: 0 done; 1 (``STATUS_NOT_PD``) the solve declined (a Schur complement or Gram matrix
    not numerically positive definite, or for the identity weighting ``Z`` numerically rank
    deficient: the caller falls back); 2 (``STATUS_UNSUPPORTED``) not this weighting's scene, an
    ``out`` too short, or ``ip`` without the addresses. With a nonzero status ``out`` is
    unspecified.
    """
    name = NAMES[weight]

    def factory(deps: int):
        def evaluate(t, q, qd, fp, ip, out):
            if deps < 0:  # never true: ties numba's cache key to the kernel's sources
                return STATUS_UNSUPPORTED
            return join(weight, t, q, qd, fp, ip, out)

        evaluate.__qualname__ = evaluate.__name__ = f"evaluate_{name}"
        return evaluate

    return jit_entry(factory)


def make_qddot_into(weight: int):
    """The cached entry point ``qddot_into(t, q, qd, fp, ip, qdd) -> status`` of weighting
    ``weight``: :func:`make_evaluate`'s evaluation reduced to ``q̈`` (written into ``qdd``, shape
    (nq,)), computed through the full output (the same numbers: M⁻² and identity need ``Q^C``
    on the way)."""
    name = NAMES[weight]

    def factory(deps: int):
        def qddot_into(t, q, qd, fp, ip, qdd):
            if deps < 0:  # never true: ties numba's cache key to the kernel's sources
                return STATUS_UNSUPPORTED
            nq = (ip[I_N] & IX) + 7
            out = np.empty(2 * nq + 3 + (ip[I_KW] & IX) + (ip[I_KP] & IX))
            status = join(weight, t, q, qd, fp, ip, out)
            if status == STATUS_OK:
                qdd[:] = out[:nq]
            return status

        qddot_into.__qualname__ = qddot_into.__name__ = f"qddot_into_{name}"
        return qddot_into

    return jit_entry(factory)


__all__ = ["NAMES", "join", "make_evaluate", "make_qddot_into"]
