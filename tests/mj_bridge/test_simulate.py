"""MuJoCo's run (``mj_bridge.simulate``) and the engine plants on scipy's loop, as their progress
sees them: the state each progress call carries is the run's own at that time, in the
trajectory's coordinates: MuJoCo's every sample, scipy's loop at the end of its steps (the last
at the horizon)."""

from __future__ import annotations

import numpy as np
import pytest

from analytic.scene import load_scene
from mj_bridge.plants import plant
from tests.support.tolerances import PROGRESS_STATE_REL
from validation.scenes import scene_path

T_END = 0.5


def _run(name: str):
    pl = plant(name)
    why = pl.unavailable()
    if why:
        pytest.skip(why)
    sc = load_scene(scene_path("paper_example1_controlled"))
    got: list = []
    tr = pl.simulate(sc, t_end=T_END, progress=lambda t, q: got.append((t, q)))
    assert got and tr.t[-1] == T_END
    ts = np.array([t for t, _ in got])
    assert np.all(np.diff(ts) > 0) and ts[-1] == T_END
    assert all(q.shape == (sc.n + 7,) for _, q in got)
    return tr, got


def _row_error(tr, t: float, q: np.ndarray) -> float:
    row = tr.q[np.flatnonzero(tr.t == t)[0]]
    return float(np.max(np.abs(q - row))) / max(1.0, float(np.max(np.abs(row))))


def test_mujoco_passes_each_sample_it_records():
    tr, got = _run("mujoco")
    assert [t for t, _ in got] == list(tr.t[1:])  # every sample after the initial state
    assert max(_row_error(tr, t, q) for t, q in got) == 0.0  # the sample itself


@pytest.mark.parametrize("name", ["pinocchio", "drake"])
def test_a_scipy_loop_plant_passes_its_state_in_paper_coordinates(name):
    """At the horizon the state is the last row (the step's end against its dense output there);
    before it, each state lies between the rows around its time (a step's end inside a sample
    interval of a smooth motion is nearer one of its ends than they are to each other): the
    trajectory's coordinates, the attitude w first (x, y, z, w would be off by the quaternion)."""
    tr, got = _run(name)
    t, q = got[-1]
    assert _row_error(tr, t, q) <= PROGRESS_STATE_REL.value
    for t, q in got[:-1]:
        k = int(np.searchsorted(tr.t, t))
        before, after = tr.q[k - 1], tr.q[k]
        apart = np.max(np.abs(after - before))
        assert min(np.max(np.abs(q - before)), np.max(np.abs(q - after))) <= apart, t
