"""A package's public names imported on first use (PEP 562), so that importing the package costs
only what its eagerly bound names need: the command line starts its work sooner, and a process that
only chooses and checks (the one that starts the plants) does not import the engines. Used by
``analytic`` and ``mj_bridge``.

A package's ``__init__`` names its public objects and the module each lives in, and binds
``__getattr__, __dir__ = lazy_exports(__name__, table, globals())``. (``validation`` has the same
helper in ``validation/_lazy.py``: importing this module runs ``analytic/__init__.py``, which
imports numpy, and ``import validation`` must not.)
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
    bound in ``namespace`` (the package's ``globals()``) like an ordinary attribute, so the lookup
    runs once per name.
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


__all__ = ["lazy_exports"]
