"""How the Drake plant integrates (its settings record) and whether Drake is installed, apart from the
plant: constructing or checking the settings imports neither Drake nor scipy's integrators."""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass

from mj_bridge.scipy_loop_settings import ScipyLoopSettings

DRAKE_MISSING = (
    "the Drake plant needs the 'drake' package (>= 1.51): pip install 'drake>=1.51' "
    "(the [drake] extra)"
)
"""What :func:`drake_unavailable` says when ``pydrake`` cannot be imported."""


def drake_unavailable() -> str:
    """Why the Drake plant cannot run here (:data:`DRAKE_MISSING`), or "" when ``pydrake`` is
    installed (found without importing it)."""
    return DRAKE_MISSING if importlib.util.find_spec("pydrake") is None else ""


@dataclass(frozen=True)
class DrakeSettings(ScipyLoopSettings):
    """How the Drake plant integrates (:class:`~mj_bridge.scipy_loop_settings.ScipyLoopSettings`:
    scipy's methods, not Drake's own integrators, ``docs/performance.md``)."""


__all__ = ["DRAKE_MISSING", "DrakeSettings", "drake_unavailable"]
