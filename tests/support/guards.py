"""Guards the tests put around the code under test (imported as ``tests.support.guards``)."""

from __future__ import annotations

import sys


def forbid_plant_runs(monkeypatch) -> None:
    """Every plant's engine entry point raises ``AssertionError("a plant ran")`` if called: a test
    of bad input uses it to prove the refusal came before any plant started."""
    import analytic.simulate  # noqa: F401  (the modules, not the functions of the same name)
    import mj_bridge
    import mj_bridge.simulate

    def boom(*a, **k):
        raise AssertionError("a plant ran")

    for module in ("analytic.simulate", "mj_bridge.simulate"):
        monkeypatch.setattr(sys.modules[module], "simulate", boom)
    monkeypatch.setattr(mj_bridge, "simulate", boom)
