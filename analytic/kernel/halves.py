"""The kernel's two halves as compiled C callbacks, each compiled once and cached on its own.

* stages 1-6 (:func:`analytic.kernel.system.make_build_system`), the same for every weighting;
* the solve of the scene's weighting (:func:`analytic.kernel.gauss.make_solve_gauss`, also every
  uncontrolled scene; :func:`analytic.kernel.minv2.make_solve_minv2`;
  :func:`analytic.kernel.identity.make_solve_identity`).

Each is a ``numba.cfunc(sig, cache=True)`` with a C signature of :mod:`analytic.runtime.abi`, made
the first time a process asks (:func:`callback`: compiled, or loaded from numba's disk cache);
:func:`addresses` gives the two addresses a scene's callers read from ``ip`` (written by
:class:`analytic.fast.FastModel`). Two processes can compile the two halves at the same time
(:mod:`validation.runs.warmup`); the callers do not need either to compile.

The stages are ordinary numba functions (:func:`analytic.runtime.jit.inner`) that numba compiles
into each half; the halves index their C pointers directly (numba lowers a pointer index as one
address and one load)."""

from __future__ import annotations

import functools
import threading
from enum import StrEnum

from analytic.kernel import gauss, identity, minv2, system
from analytic.kernel.entry import Solver
from analytic.runtime.abi import SOLVE_SIG, SYSTEM_SIG
from analytic.runtime.jit import HAVE_NUMBA, KERNEL_SOURCES, cfunc, source_fingerprint


class KernelHalf(StrEnum):
    """The two halves of the kernel, each compiled and cached on its own."""

    SYSTEM = "system"
    """Stages 1-6 (:func:`analytic.kernel.system.make_build_system`), the same for every weighting."""
    SOLVE = "solve"
    """The scene's solve: Gauss (also uncontrolled scenes), M⁻² or identity."""


_DEPS = source_fingerprint(*KERNEL_SOURCES)
"""The fingerprint every half closes over (an edit of any kernel file compiles them again)."""

_SOLVES = {
    Solver.GAUSS: gauss.make_solve_gauss,
    Solver.MINV2: minv2.make_solve_minv2,
    Solver.IDENTITY: identity.make_solve_identity,
}
"""The factory of each solve's body, C signature ``int64(q*, fp*, ip*, out*, len_out, w*, full)``
-> status (the M⁻² and identity solves need ``full`` = 1: those weightings need ``Q^C``). Stages
1-6 are ``void(t, q*, qd*, fp*, ip*, out*, len_out, full, w*)``, the same for every weighting."""

_lock = threading.Lock()


@functools.cache
def _compile(make, sig):
    return cfunc(sig, make(_DEPS))


def _maker(half: KernelHalf, solver: Solver):
    """(the factory of ``half``'s body, its C signature); ``solver`` picks the solve."""
    if half is KernelHalf.SYSTEM:
        return system.make_build_system, SYSTEM_SIG
    if solver not in _SOLVES:
        raise ValueError(f"solver: a solve is compiled for one weighting (got {solver!r})")
    return _SOLVES[solver], SOLVE_SIG


def callback(half: KernelHalf | str, solver: Solver | int = Solver.GAUSS):
    """The compiled ``cfunc`` of ``half`` (for a solve, the one of ``solver``, a
    :class:`~analytic.kernel.entry.Solver` value other than ``ANY``), compiled in this process or
    loaded from numba's disk cache on the first call."""
    if not HAVE_NUMBA:  # pragma: no cover - without numba the numpy model answers
        raise RuntimeError("the compiled kernel needs numba")
    make, sig = _maker(KernelHalf(half), Solver(int(solver)))
    with _lock:
        return _compile(make, sig)


def compiled(half: KernelHalf | str, solver: Solver | int = Solver.GAUSS) -> int:
    """Compile ``half`` in this process (or load it from numba's disk cache) if not done yet;
    returns its address."""
    return callback(half, solver).address


def addresses(solver: Solver | int) -> tuple[int, int]:
    """``(stages 1-6, solve)``: the addresses a scene's callers read from ``ip`` (``solver``: the
    scene's, :func:`analytic.kernel.entry.solver_of`), compiling (or loading) both as needed."""
    return compiled(KernelHalf.SYSTEM), compiled(KernelHalf.SOLVE, solver)


__all__ = [
    "KernelHalf",
    "addresses",
    "callback",
    "compiled",
]
