"""The demo's test fixtures: the steps' scenes (no simulation), the steps run once and the demo
written once, short (0.2 s per step), with the MuJoCo ghost."""

from __future__ import annotations

import pytest

from validation.studies.demo import STEPS, run_steps, step_scene, write_demo


@pytest.fixture(scope="package")
def scenes():
    return {s.prefix: step_scene(s) for s in STEPS}


@pytest.fixture(scope="package")
def demo_dir(tmp_path_factory):
    """The demo written once, short (0.2 s per step), with the MuJoCo ghost."""
    return write_demo(tmp_path_factory.mktemp("demo"), t_end=0.2)


@pytest.fixture(scope="package")
def step_runs():
    return run_steps(t_end=0.2)[0]
