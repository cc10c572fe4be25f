"""The two plants agree on the paper's scenes: the same comparison code and the same named
thresholds as ``tumble validate``'s reports (validation/compare.py, validation/thresholds.py).

Each paper scene over its full 20 s horizon, as the README's main command runs it (about 15 s
for all four with the compiled controller).
"""

from __future__ import annotations

import pytest

from analytic import load_scene, simulate
from mj_bridge import simulate as mj_simulate
from validation.compare import compare
from validation.scenes import scene_path
from validation.thresholds import thresholds_for

PAPER = [
    "paper_example1",
    "paper_example1_controlled",
    "paper_example2",
    "paper_example2_controlled",
]


def _agree(name: str, t_end: float | None):
    scene = load_scene(scene_path(name))
    ana = simulate(scene, t_end=t_end)
    mj = mj_simulate(scene, t_end=t_end)
    cmp = compare(ana, mj, scene, thresholds_for(scene), t_end=t_end)
    assert cmp.checks, "no check was made"
    assert cmp.passed, [f"{c.label}: {c.value:.3e} > {c.threshold:.1e}" for c in cmp.failed_checks]
    return cmp


@pytest.mark.parametrize("name", PAPER)
def test_plants_agree_over_the_scene_horizon(name):
    _agree(name, None)
