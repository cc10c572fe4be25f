"""Shared fixture of the trajectory-file tests: one short controlled run of the analytic plant."""

from __future__ import annotations

import pytest

from analytic.scene import load_scene


@pytest.fixture(scope="module")
def controlled_run():
    """``(scene, trajectory)``: the analytic plant on paper_example1_controlled for 0.2 s
    (21 samples at 100 Hz), the scene's horizon set to match."""
    from mj_bridge.plants import plant

    scene = load_scene("paper_example1_controlled")
    scene = scene.replace(output=scene.output.with_t_end(0.2))
    return scene, plant("analytic").simulate(scene)
