"""The kernel's two halves as compiled C callbacks, each compiled once and cached on its own.

* stages 1-6 (:func:`analytic.kernel.system.make_build_system`), the same for every weighting;
* the solve of the scene's weighting (:func:`analytic.kernel.gauss.make_solve_gauss`, also every
  uncontrolled scene; :func:`analytic.kernel.minv2.make_solve_minv2`).

Each is a ``numba.cfunc(sig, cache=True)`` with a C signature of :mod:`analytic.kernel.abi`, made
the first time a process asks (:func:`callback`: compiled, or loaded from numba's disk cache);
:func:`addresses` gives the two addresses a scene's callers read from ``ip`` (written by
:class:`analytic.fast.FastModel`). Two processes can compile the two halves at the same time
(:mod:`validation.runs.warmup`); the callers do not need either to compile.

The stages are ordinary numba functions (:func:`analytic.kernel.jit.inner`) that numba compiles
into each half; the halves index their C pointers directly (numba lowers a pointer index as one
address and one load)."""

from __future__ import annotations

import functools
import threading
from enum import StrEnum

from analytic.kernel import gauss, minv2, system
from analytic.kernel.abi import SOLVE_SIG, SYSTEM_SIG
from analytic.kernel.jit import HAVE_NUMBA, KERNEL_SOURCES, cfunc, source_fingerprint


class KernelHalf(StrEnum):
    """The two halves of the kernel, each compiled and cached on its own."""

    SYSTEM = "system"
    """Stages 1-6 (:func:`analytic.kernel.system.make_build_system`), the same for every weighting."""
    SOLVE = "solve"
    """The scene's solve: Gauss (also uncontrolled scenes) or M⁻²."""


_DEPS = source_fingerprint(*KERNEL_SOURCES)
"""The fingerprint every half closes over (an edit of any kernel file compiles them again)."""

_MAKERS = {
    (KernelHalf.SYSTEM, False): (system.make_build_system, SYSTEM_SIG),
    (KernelHalf.SYSTEM, True): (system.make_build_system, SYSTEM_SIG),
    (KernelHalf.SOLVE, False): (gauss.make_solve_gauss, SOLVE_SIG),
    (KernelHalf.SOLVE, True): (minv2.make_solve_minv2, SOLVE_SIG),
}
"""``(half, minv2_solve)`` -> (the factory of its body, its C signature): stages 1-6
``void(t, q*, qd*, fp*, ip*, out*, len_out, full, w*)``, the same for every weighting; the Gauss or
the M⁻² solve ``int64(q*, fp*, ip*, out*, len_out, w*, full)`` -> status (the M⁻² solve needs
``full`` = 1: this weighting needs ``Q^C``)."""

_lock = threading.Lock()


@functools.cache
def _compile(make, sig):
    return cfunc(sig, make(_DEPS))


def callback(half: KernelHalf | str, minv2_solve: bool = False):
    """The compiled ``cfunc`` of ``half`` (for a solve, the M⁻² one when ``minv2_solve``),
    compiled in this process or loaded from numba's disk cache on the first call."""
    if not HAVE_NUMBA:  # pragma: no cover - without numba the numpy model answers
        raise RuntimeError("the compiled kernel needs numba")
    make, sig = _MAKERS[KernelHalf(half), bool(minv2_solve)]
    with _lock:
        return _compile(make, sig)


def compiled(half: KernelHalf | str, minv2_solve: bool = False) -> int:
    """Compile ``half`` in this process (or load it from numba's disk cache) if not done yet;
    returns its address."""
    return callback(half, minv2_solve).address


def addresses(minv2_solve: bool) -> tuple[int, int]:
    """``(stages 1-6, solve)``: the addresses a scene's callers read from ``ip``, compiling (or
    loading) both halves as needed."""
    return compiled(KernelHalf.SYSTEM), compiled(KernelHalf.SOLVE, minv2_solve)


__all__ = [
    "KernelHalf",
    "addresses",
    "callback",
    "compiled",
]
