"""The figures' test fixtures: a planted run of a controlled and of an uncontrolled scene
(:mod:`tests.support.figure_runs`), every figure drawn for it, and a run with the masses controlled
and ω not."""

from __future__ import annotations

import pytest

from tests.support.figure_runs import SCENES, drawn_figures, masses_only_run, planted_run


@pytest.fixture(scope="package", params=SCENES)
def run(request):
    """(scene, plants, comparison, meta) of a controlled and of an uncontrolled scene."""
    return planted_run(request.param)


@pytest.fixture(scope="package")
def drawn(run):
    """Every figure drawn for the run (as its PNG is: Agg at the figure's dpi), with the renderer
    that drew it."""
    return drawn_figures(run)


@pytest.fixture(scope="package")
def masses_only():
    """(scene, plants, comparison) of Example 1 with the masses controlled and ω not."""
    return masses_only_run()
