"""Where numba caches the compiled kernel, decided without importing numba (the process that starts
the plants asks, and only the plants import numba): ``$NUMBA_CACHE_DIR`` when set, else
``__pycache__`` beside the kernel's sources when writable, else the user's cache directory
(:func:`user_cache_dir`), which :mod:`analytic.runtime.jit` then points numba at."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

APP_NAME = "tumbling-testbed"
RUNTIME_DIR = Path(__file__).resolve().parent
KERNEL_DIR = RUNTIME_DIR.parent / "kernel"
"""The kernel package's directory (by path: this package imports nothing of the rest of
``analytic``); numba's ``__pycache__`` beside the kernel's sources is tried first."""
EFFECTS_DIR = RUNTIME_DIR.parent / "effects"
"""The effects' declarations (by path): the kernel compiles their spring laws' shapes in."""


def writable(path: Path) -> bool:
    """Whether files can be created in ``path`` (made if missing), tested as numba tests it."""
    try:
        os.makedirs(path, exist_ok=True)
        tempfile.TemporaryFile(dir=path).close()
    except OSError:
        return False
    return True


def user_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/tumbling-testbed/numba``, or ``~/.cache/tumbling-testbed/numba``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / APP_NAME / "numba"


def kernel_cache_dir() -> Path | None:
    """The directory numba keeps the kernel's compiled code in (for ``$NUMBA_CACHE_DIR`` and the
    user directory, numba adds subdirectories below it), or None when none is writable."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        return Path(env)
    for path in (KERNEL_DIR / "__pycache__", user_cache_dir()):
        if writable(path):
            return path
    return None


__all__ = [
    "APP_NAME",
    "KERNEL_DIR",
    "RUNTIME_DIR",
    "kernel_cache_dir",
    "user_cache_dir",
    "writable",
]
