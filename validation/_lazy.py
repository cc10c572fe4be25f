"""Lazy re-exports for a package's public face: ``import validation.x`` stays cheap.

A wing's ``__init__`` names its public objects and the module each lives in; the module is
imported the first time one of its names is read (PEP 562 ``__getattr__``), as
``validation/__init__.py`` does for the package's top-level names. This matters because the pytest
plugin and the command line import the package before anything heavy (numpy, MuJoCo, numba,
Rerun) is needed, and the command line installs its signal handlers first.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(
    package: str, table: Mapping[str, str], namespace: dict[str, Any]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package`` whose public ``name`` lives in ``table[name]``.

    ``table`` maps each public name to the dotted module that defines it; a name once read is
    cached in ``namespace`` (the package's ``globals()``), so the lookup runs once per name.
    """

    def __getattr__(name: str) -> Any:
        if name in table:
            value = getattr(importlib.import_module(table[name]), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted({*namespace, *table})

    return __getattr__, __dir__
