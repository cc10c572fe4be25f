"""numba plumbing of the compiled kernel: where its cache lives, how functions are compiled, and
what a cached function's key covers.

**Four kinds of compiled function.**

* :func:`inline` (``njit(inline="always")``, no disk cache): the kernel's stages and the small
  kinematic helpers; numba pastes their code into the caller.
* the kernel's two halves (:mod:`analytic.kernel.halves`): C callbacks (``cfunc``) into which the
  stages are pasted, compiled once and cached on their own; every compiled caller calls them by
  address (:mod:`analytic.kernel.abi`).
* :func:`jit_entry` (``njit(cache=True)``, key tied to the sources, see below): entry points (what
  Python or another package calls: ``gauss.evaluate``, ``minv2.evaluate``, ``fast_rhs.rhs_into``
  ...), which join the halves.
* :func:`jit` (``njit(cache=True)``, keyed on its own file by numba): only for functions that call
  nothing from another file (the M⁻² dense helpers).

**Why the tie.** numba's disk cache checks only the source file of the function being cached
(numba's caching notes: "Cache invalidation fails to recognize changes in symbols defined in another
file"), yet a cached entry point contains the code of every stage it calls. numba does hash a
function's closure variables into the cache key, so an entry point built by a factory that closes
over :func:`source_fingerprint` of the kernel package (and of any other file it embeds) is
recompiled whenever one of those files changes, instead of running a stale copy.

**Where the cache lives.** numba writes ``__pycache__`` beside the sources, else its user-wide cache
directory. When this package's own ``__pycache__`` cannot be written (a read-only site-packages)
and ``NUMBA_CACHE_DIR`` is not set, this module sets ``NUMBA_CACHE_DIR`` (numba's documented
setting) to ``$XDG_CACHE_HOME/tumbling-testbed/numba`` (``~/.cache/...`` without XDG_CACHE_HOME)
before numba is imported, and says so once (:class:`CacheFallbackWarning`). When no directory at
all can be written, entry points are compiled in memory in each process (same results, slower
first call), also said once.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import os
import sys
import warnings
from pathlib import Path
from types import ModuleType

import numpy as np

from analytic.kernel import cache_check
from analytic.kernel.cache_dir import APP_NAME, PACKAGE_DIR, kernel_cache_dir
from analytic.kernel.layout import WS_LEN
from analytic.kernel.paste import flatten


class CacheFallbackWarning(UserWarning):
    """numba's cache beside the package is not writable: another directory (or none) is used."""


def _configure_cache_dir() -> str | None:
    """Point numba at a writable cache directory when the in-tree one is not; returns the note
    for :func:`cache_dir_note` (None: numba's defaults apply)."""
    fallback = kernel_cache_dir()
    if os.environ.get("NUMBA_CACHE_DIR") or fallback in (None, PACKAGE_DIR / "__pycache__"):
        return None  # none writable: numba's own user-wide directory is tried next (see jit())
    os.environ["NUMBA_CACHE_DIR"] = str(fallback)
    numba_config = sys.modules.get("numba.core.config")
    if numba_config is not None:  # numba imported before this module: it read the environment
        numba_config.CACHE_DIR = str(fallback)
    warnings.warn(
        f"{APP_NAME}: {PACKAGE_DIR / '__pycache__'} is not writable; numba caches the compiled "
        f"kernel in {fallback}",
        CacheFallbackWarning,
        stacklevel=2,
    )
    return f"NUMBA_CACHE_DIR={fallback} (the package's __pycache__ is not writable)"


_CACHE_NOTE = _configure_cache_dir()
cache_check.ensure_checked()  # numba's cache files against their hashes, before any kernel exists

try:  # numba is optional: without it analytic.fast falls back to the numpy model
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None
    HAVE_NUMBA = False

_in_memory_said = False

if HAVE_NUMBA:
    from numba.core import typed_passes, untyped_passes
    from numba.core.compiler import CompilerBase, DefaultPassBuilder
    from numba.core.compiler_machinery import PassManager

    LEAN_DROPPED = (
        untyped_passes.WithLifting,
        untyped_passes.InlineClosureLikes,
        untyped_passes.MakeFunctionToJitFunction,
        untyped_passes.FindLiterallyCalls,
        untyped_passes.LiteralUnroll,
        typed_passes.PreLowerStripPhis,
        typed_passes.NopythonRewrites,
        typed_passes.IRLegalization,
    )
    """numba passes the compiled code of this project has no use for: ``with`` contexts, closures
    and comprehensions, ``literally``/``literal_unroll``, SSA's phi nodes (no SSA, below), the
    rewrites into fused array expressions, and a check of features it does not use."""

    try:  # where numba resolves the signature of a call to a typed function (numba 0.68)
        from numba.core.types.functions import BaseFunction as _BaseFunction

        _RESOLVE = _BaseFunction.get_call_type
    except (ImportError, AttributeError):  # pragma: no cover - another numba: no memo
        _BaseFunction = _RESOLVE = None

    _SCALAR_TYPES = (numba.types.Number, numba.types.Boolean)
    _scalar_calls: dict = {}
    _compiles_open = 0

    def _remembered_call_type(self, context, args, kws):
        """``BaseFunction.get_call_type`` remembering what it found for scalar arguments."""
        if kws or not all(isinstance(a, _SCALAR_TYPES) for a in args):
            return _RESOLVE(self, context, args, kws)
        key = (self, id(context), tuple(args))
        sig = _scalar_calls.get(key)
        if sig is None:
            sig = _RESOLVE(self, context, args, kws)
            if sig is not None:
                _scalar_calls[key] = sig
        return sig

    @contextlib.contextmanager
    def scalar_call_types_remembered():
        """Inside the block (a compile, which holds numba's global compiler lock), numba's
        resolution of a call to a typed function (an operator, ``math.sqrt``...) whose arguments
        are all scalars is looked up once per function type and argument types, and remembered
        until the outermost such block ends.

        Why: numba resolves the signature of every scalar operation by trying each template that
        may apply (numpy's ufunc rules first, which reject scalars only after matching a ufunc
        loop), once while typing each statement, again for each typing round, and once more
        while lowering it. On the kernel's halves that was a quarter of the Python work of a
        first compile (numba 0.68). For scalar arguments the answer depends only on the
        function type and the argument types (literal values included, they are part of a
        literal type), so remembering it changes no signature; the signature found first is
        the one numba would find again, with the same implementation key recorded."""
        global _compiles_open
        if _RESOLVE is None:
            yield
            return
        _compiles_open += 1
        if _compiles_open == 1:
            _BaseFunction.get_call_type = _remembered_call_type
        try:
            yield
        finally:
            _compiles_open -= 1
            if _compiles_open == 0:
                _BaseFunction.get_call_type = _RESOLVE
                _scalar_calls.clear()

    class LeanCompiler(CompilerBase):
        """numba's nopython pipeline (``DefaultPassBuilder``) without :data:`LEAN_DROPPED` and
        without SSA reconstruction, passed as numba's documented ``pipeline_class``.

        Why: numba's compile time grows with the statements of a function, and these passes
        each walk all of them; on the kernel's two halves they were a third to a half of a
        first compile (measured with numba 0.68). What is left types, lowers and optimises the
        same statements, so the machine code does the same arithmetic in the same order
        (``tests/test_fast.py`` compiles the halves with numba's default pipeline too and
        compares every output bit for bit).

        Without SSA a variable has one type in a function: code compiled this way must not reuse
        a name for values of two types (numba says so at compile time, never silently).

        Each compile runs inside :func:`scalar_call_types_remembered` (numba's resolution of
        scalar operations looked up once per compile instead of at every statement)."""

        def define_pipelines(self):
            self.state.flags.enable_ssa = False
            default = DefaultPassBuilder.define_nopython_pipeline(self.state)
            pm = PassManager("lean")
            for pass_class, description in default.passes:
                if pass_class not in LEAN_DROPPED:
                    pm.add_pass(pass_class, description)
            pm.finalize()
            return [pm]

        def _compile_core(self):
            with scalar_call_types_remembered():
                return super()._compile_core()

else:  # pragma: no cover
    LeanCompiler = None


def jit(fn):
    """``numba.njit(cache=True)``, or in memory when no cache directory is usable (said once).

    numba raises ``RuntimeError`` at decoration when none of ``$NUMBA_CACHE_DIR``, ``__pycache__``
    beside the source and its user-wide directory can be written.
    """
    global _in_memory_said
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    try:
        return numba.njit(cache=True, fastmath=False, nogil=True, pipeline_class=LeanCompiler)(fn)
    except RuntimeError:  # no usable cache locator
        if not _in_memory_said:
            _in_memory_said = True
            warnings.warn(
                f"{APP_NAME}: no writable cache directory for numba; the kernel is compiled in "
                "memory in every process",
                CacheFallbackWarning,
                stacklevel=2,
            )
        return numba.njit(cache=False, fastmath=False, nogil=True, pipeline_class=LeanCompiler)(fn)


def inline(fn):
    """A kernel stage or helper: ``numba.njit(inline="always")``, pasted into its callers' code
    (never cached on its own; plain Python without numba)."""
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    return numba.njit(inline="always", fastmath=False)(fn)


def source_fingerprint(*sources: ModuleType | str | Path) -> int:
    """A 60-bit integer from the SHA-256 of the given modules' (or files') sources, in order."""
    h = hashlib.sha256()
    for src in sources:
        path = inspect.getfile(src) if isinstance(src, ModuleType) else src
        with open(path, "rb") as f:
            h.update(f.read())
    return int(h.hexdigest()[:15], 16)


KERNEL_SOURCES: tuple[Path, ...] = tuple(sorted(PACKAGE_DIR.glob("*.py")))
"""Every source file of the kernel package: an entry point embeds some of them, and a cached entry
point is refused when any of them changes (one fingerprint keeps the rule simple)."""


def jit_entry(factory, *also: ModuleType | str | Path):
    """Compile ``factory(fingerprint)`` with :func:`jit`: an entry point whose cache key covers the
    kernel package's sources and ``also`` (the other files whose code it embeds).

    ``factory`` returns the function to compile, which must refer to the fingerprint (e.g.
    ``if deps < 0: return STATUS_UNSUPPORTED``, a test that is never true) so that it is a closure
    variable, which numba hashes into the cache key.
    """
    return jit(flatten(factory(source_fingerprint(*KERNEL_SOURCES, *also))))


def cache_dir_note() -> str:
    """Where numba caches the kernel in this process (for messages)."""
    if not HAVE_NUMBA:
        return "numba not installed"
    if _CACHE_NOTE:
        return _CACHE_NOTE
    env = os.environ.get("NUMBA_CACHE_DIR")
    return (
        f"NUMBA_CACHE_DIR={env}" if env else "__pycache__ beside the sources, or numba's user dir"
    )


if HAVE_NUMBA and not numba.config.DISABLE_JIT:
    from numba.core import cgutils, types
    from numba.extending import intrinsic
    from numba.np.arrayobj import populate_array

    @intrinsic
    def workspace(typingctx):
        """A float64 array of ``WS_LEN`` uninitialised slots on the calling function's stack
        (slots: :mod:`analytic.kernel.layout` ``WS_*``).

        An intrinsic, so its code is emitted inside the caller: the memory lives as long as the
        caller's frame (never return it or a view of it). Unlike ``np.empty`` there is no heap
        allocation, no reference count, and LLVM may keep constant-index slots in registers.
        """
        arrty = types.Array(types.float64, 1, "C")

        def codegen(context, builder, sig, args):
            f64 = context.get_value_type(types.float64)
            data = cgutils.alloca_once(builder, f64, size=WS_LEN)
            ary = context.make_array(arrty)(context, builder)
            intp = context.get_value_type(types.intp)
            populate_array(
                ary,
                data=data,
                shape=[intp(WS_LEN)],
                strides=[intp(8)],
                itemsize=intp(8),
                meminfo=None,
            )
            return ary._getvalue()

        return arrty(), codegen

else:  # pragma: no cover - plain Python (no numba, or NUMBA_DISABLE_JIT=1)

    def workspace():
        return np.empty(WS_LEN)
