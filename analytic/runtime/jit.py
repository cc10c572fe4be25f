"""numba plumbing of the compiled kernel: where its cache lives, how functions are compiled, and
what a cached function's key covers. Only numba's documented API is used (``numba.njit``,
``numba.cfunc``, ``numba.types``, ``numba.carray``, ``numba.extending.intrinsic``,
``cache=True``, ``NUMBA_CACHE_DIR``).

**Four kinds of compiled function.**

* :func:`inner` (``numba.njit``, no disk cache): the kernel's stages and the small kinematic
  helpers. numba compiles each once per process and links it into its callers, where LLVM
  inlines it; a cached caller carries their code, so a later process loads the caller alone.
* :func:`inline_always` (``numba.njit(inline="always")``, numba's documented inlining): only the
  small functions that choose the solve from a ``solver`` argument
  (:func:`analytic.kernel.entry.evaluate_as`, :func:`analytic.fast_rhs.rhs_body`). Inlined into a
  caller that passes a constant (a closure variable of its factory), numba drops the branches of
  the other solves before compiling, so a Gauss caller compiles no M⁻² code.
* the kernel's two halves (:mod:`analytic.kernel.halves`) and the other C callbacks: ``numba.
  cfunc(..., cache=True)``; every compiled caller calls the halves by address
  (:mod:`analytic.runtime.abi`).
* :func:`jit_entry` (``numba.njit(cache=True)``, key tied to the sources, see below): entry points
  (what Python or another package calls: ``gauss.evaluate``, ``minv2.evaluate``,
  ``fast_rhs.rhs_into`` ...); :func:`jit` for functions that call nothing from another file.

**Why the tie.** numba's disk cache checks only the source file of the function being cached
(numba's caching notes: "Cache invalidation fails to recognize changes in symbols defined in another
file"), yet a cached function contains the code of every stage it calls. Each cached function is
therefore built by a factory that closes over :func:`source_fingerprint` of the kernel and runtime
packages (:data:`KERNEL_SOURCES`, and of any other file it embeds), and refers to it (``if deps < 0: return``, never true): numba's cache
key covers the function's closure variables, so an edit of any of those files compiles it again
instead of loading a stale copy.

**Where the cache lives.** numba writes ``__pycache__`` beside the sources, else its user-wide cache
directory. When the kernel package's ``__pycache__`` cannot be written (a read-only site-packages)
and ``NUMBA_CACHE_DIR`` is not set, this module sets ``NUMBA_CACHE_DIR`` (numba's documented
setting) to ``$XDG_CACHE_HOME/tumbling-testbed/numba`` (``~/.cache/...`` without XDG_CACHE_HOME)
before numba is imported, and says so once (:class:`CacheFallbackWarning`). When no directory at
all can be written, functions are compiled in memory in each process (same results, slower first
call), also said once.
"""

from __future__ import annotations

import hashlib
import inspect
import os
import sys
import warnings
from pathlib import Path
from types import ModuleType

from analytic.runtime import cache_check
from analytic.runtime.cache_dir import (
    APP_NAME,
    EFFECTS_DIR,
    KERNEL_DIR,
    RUNTIME_DIR,
    kernel_cache_dir,
)


class CacheFallbackWarning(UserWarning):
    """numba's cache beside the package is not writable: another directory (or none) is used."""


def _configure_cache_dir() -> str | None:
    """Point numba at a writable cache directory when the in-tree one is not; returns the note
    for :func:`cache_dir_note` (None: numba's defaults apply)."""
    fallback = kernel_cache_dir()
    if os.environ.get("NUMBA_CACHE_DIR") or fallback in (None, KERNEL_DIR / "__pycache__"):
        return None  # none writable: numba's own user-wide directory is tried next (see jit())
    os.environ["NUMBA_CACHE_DIR"] = str(fallback)
    if "numba" in sys.modules:  # imported before this module: it read the environment already
        sys.modules["numba"].config.CACHE_DIR = str(fallback)
    warnings.warn(
        f"{APP_NAME}: {KERNEL_DIR / '__pycache__'} is not writable; numba caches the compiled "
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


def _say_in_memory() -> None:
    global _in_memory_said
    if not _in_memory_said:
        _in_memory_said = True
        warnings.warn(
            f"{APP_NAME}: no writable cache directory for numba; the kernel is compiled in "
            "memory in every process",
            CacheFallbackWarning,
            stacklevel=3,
        )


def cached(decorator, fn):
    """``decorator(cache=True)(fn)``, or ``decorator()(fn)`` when numba has no usable cache
    directory (said once). ``decorator`` is a ``functools.partial`` of ``numba.njit`` or
    ``numba.cfunc``: numba raises ``RuntimeError`` at decoration when none of
    ``$NUMBA_CACHE_DIR``, ``__pycache__`` beside the source and its user-wide directory can be
    written."""
    try:
        return decorator(cache=True)(fn)
    except RuntimeError:  # no usable cache locator
        _say_in_memory()
        return decorator()(fn)


def jit(fn):
    """``numba.njit(cache=True)``, or in memory when no cache directory is usable (said once)."""
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    return cached(lambda **kw: numba.njit(fastmath=False, nogil=True, **kw), fn)


def cfunc(sig, fn):
    """``numba.cfunc(sig, cache=True)`` (compiled now, or loaded from numba's cache), or in memory
    when no cache directory is usable (said once)."""
    return cached(lambda **kw: numba.cfunc(sig, nopython=True, **kw), fn)


def inner(fn):
    """A kernel stage or helper: ``numba.njit`` without a disk cache of its own (compiled into,
    and cached with, its callers; plain Python without numba)."""
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    return numba.njit(fastmath=False, nogil=True)(fn)


def inline_always(fn):
    """``numba.njit(inline="always")``: inlined by numba into each caller, where a constant
    ``solver`` argument prunes the other solves' branches (plain Python without numba)."""
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


KERNEL_SOURCES: tuple[Path, ...] = (
    tuple(sorted(KERNEL_DIR.glob("*.py")))
    + tuple(sorted(RUNTIME_DIR.glob("*.py")))
    + tuple(sorted(EFFECTS_DIR.glob("*.py")))
)
"""Every source file of the kernel package, of this runtime package (whose intrinsics emit code
into the kernel's callers) and of the effects' declarations (whose spring laws' shapes the kernel
compiles in): a cached function embeds some of them, and its cache entry is refused when any of
them changes (one fingerprint keeps the rule simple)."""


def jit_entry(factory, *also: ModuleType | str | Path):
    """Compile ``factory(fingerprint)`` with :func:`jit`: an entry point whose cache key covers the
    kernel package's sources and ``also`` (the other files whose code it embeds).

    ``factory`` returns the function to compile, which must refer to the fingerprint (e.g.
    ``if deps < 0: return STATUS_UNSUPPORTED``, a test that is never true) so that it is a closure
    variable, which numba covers in the cache key.
    """
    return jit(factory(source_fingerprint(*KERNEL_SOURCES, *also)))


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


JIT_ENABLED = HAVE_NUMBA and not numba.config.DISABLE_JIT
"""numba compiles (False: plain Python, without numba or with ``NUMBA_DISABLE_JIT=1``)."""
