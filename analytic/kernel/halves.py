"""The kernel's two halves as compiled C callbacks, each compiled once and cached on its own.

* :data:`SYSTEM`: stages 1-6 (:func:`analytic.kernel.system.make_build_system`), the same for
  every weighting;
* :data:`SOLVE_GAUSS` / :data:`SOLVE_MINV2`: the solve of the scene's weighting
  (:func:`analytic.kernel.gauss.make_solve_gauss`, also every uncontrolled scene;
  :func:`analytic.kernel.minv2.make_solve_minv2`).

Each is a numba ``cfunc`` with a C signature of :mod:`analytic.kernel.abi`, created here without
being compiled; :func:`compiled` compiles it (or loads it from numba's disk cache) the first time a
process asks, and :func:`addresses` gives the two addresses a scene's callers read from ``ip``
(written by :class:`analytic.fast.FastModel`). Two processes can compile the two halves at the same
time (:mod:`validation.warmup`, a first run); the callers do not need either to compile.

Each body rebuilds the arrays behind its pointers (:func:`analytic.kernel.abi.arrays`) and calls
its stages. numba compiles each half from source in which the stages are already pasted
(:func:`analytic.kernel.paste.flatten`): numba's own inlining re-ran its front end and deep-copied
the stages' code at every call site, about a third of a first compile.
"""

from __future__ import annotations

import threading
import warnings
from enum import StrEnum

from analytic.kernel import gauss, minv2, system
from analytic.kernel.abi import SOLVE_SIG, SYSTEM_SIG
from analytic.kernel.jit import (
    HAVE_NUMBA,
    KERNEL_SOURCES,
    CacheFallbackWarning,
    LeanCompiler,
    source_fingerprint,
)
from analytic.kernel.paste import flatten


class KernelHalf(StrEnum):
    """The two halves of the kernel, each compiled and cached on its own."""

    SYSTEM = "system"
    """Stages 1-6 (:func:`analytic.kernel.system.make_build_system`), the same for every weighting."""
    SOLVE = "solve"
    """The scene's solve: Gauss (also uncontrolled scenes) or M⁻²."""


def _callback(pyfunc, sig):
    """A ``cfunc`` of ``pyfunc`` with disk caching, not compiled yet (:func:`compiled` does)."""
    from numba.core import sigutils
    from numba.core.ccallback import CFunc

    cf = CFunc(
        pyfunc,
        sigutils.normalize_signature(sig),
        locals={},
        options={},
        pipeline_class=LeanCompiler,
    )
    try:
        cf.enable_caching()
    except RuntimeError:  # no usable cache directory: compiled in memory (as jit.jit says once)
        warnings.warn(
            "no writable cache directory for numba; the kernel is compiled in memory in every "
            "process",
            CacheFallbackWarning,
            stacklevel=2,
        )
    return cf


if HAVE_NUMBA:
    _DEPS = source_fingerprint(*KERNEL_SOURCES)
    SYSTEM = _callback(flatten(system.make_build_system(_DEPS)), SYSTEM_SIG)
    """Stages 1-6: ``void(t, q*, qd*, fp*, ip*, out*, len_out, full, w*)``."""
    SOLVE_GAUSS = _callback(flatten(gauss.make_solve_gauss(_DEPS)), SOLVE_SIG)
    """The Gauss solve: ``int64(q*, fp*, ip*, out*, len_out, w*, full)`` -> status."""
    SOLVE_MINV2 = _callback(flatten(minv2.make_solve_minv2(_DEPS)), SOLVE_SIG)
    """The M⁻² solve, same signature (``full`` must be 1: this weighting needs ``Q^C``)."""
else:  # pragma: no cover - without numba the numpy model answers
    SYSTEM = SOLVE_GAUSS = SOLVE_MINV2 = None

_lock = threading.Lock()


def callback(half: KernelHalf | str, minv2_solve: bool = False):
    """The ``cfunc`` object of ``half`` (for a solve, the M⁻² one when ``minv2_solve``)."""
    if KernelHalf(half) is KernelHalf.SYSTEM:
        return SYSTEM
    return SOLVE_MINV2 if minv2_solve else SOLVE_GAUSS


def compiled(half: KernelHalf | str, minv2_solve: bool = False) -> int:
    """Compile ``half`` in this process (or load it from numba's disk cache) if not done yet;
    returns its address."""
    cf = callback(half, minv2_solve)
    with _lock:
        if cf.address is None:
            cf.compile()
    return cf.address


def addresses(minv2_solve: bool) -> tuple[int, int]:
    """``(stages 1-6, solve)``: the addresses a scene's callers read from ``ip``, compiling (or
    loading) both halves as needed."""
    return compiled(KernelHalf.SYSTEM), compiled(KernelHalf.SOLVE, minv2_solve)


__all__ = [
    "SOLVE_GAUSS",
    "SOLVE_MINV2",
    "SYSTEM",
    "KernelHalf",
    "addresses",
    "callback",
    "compiled",
]
