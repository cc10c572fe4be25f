"""The compiled backend and the numpy reference integrate the same trajectory.

Pointwise agreement is covered by tests/analytic/test_fast.py; this checks a whole controlled run, where
the two right-hand sides (equal to ~1e-13) must give trajectories equal to the integration
tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic import fast
from analytic.scene import load_scene
from analytic.simulate import simulate
from validation.compare.differences import attitude_angle
from validation.scenes import scene_path

# Two integrations of right-hand sides equal to ~1e-13 at rtol 1e-12 over 1 s: the step sequences
# may differ, so the samples differ by the local error level times the sensitivity (~1e-10 m).
AGREE_M = 1e-9
AGREE_RAD = 1e-10


@pytest.mark.skipif(not fast.available(), reason="numba not installed")
@pytest.mark.parametrize("name", ["paper_example1_controlled", "paper_example2_controlled"])
def test_backends_give_the_same_trajectory(name):
    sc = load_scene(scene_path(name))
    a = simulate(sc, t_end=1.0, backend="numpy")
    b = simulate(sc, t_end=1.0, backend="numba")
    assert a.info["backend"] == "numpy" and b.info["backend"] == "numba"
    assert np.max(np.abs(a.R - b.R)) < AGREE_M
    assert np.max(np.abs(a.p - b.p)) < AGREE_M
    assert np.max(attitude_angle(a.u, b.u)) < AGREE_RAD
    scale = np.max(np.abs(a.torque))
    assert np.max(np.abs(a.torque - b.torque)) < 1e-9 * scale


def test_an_interrupted_runs_record_ends_where_a_caller_that_discards_it_says_so():
    """The record of an interrupted run calls ``progress`` again (at the time reached) after every
    ASSEMBLY_REPORT_SAMPLES samples; a ``progress`` that raises ``KeyboardInterrupt`` (a caller
    that discards an interrupted run) ends the record there, still interrupted, instead of every
    sample being made (a 3000 s reference run took 6 s to stop); ``simulate`` never raises it. A
    run that finished makes its whole record without calling ``progress``."""
    from analytic.effects import Backend
    from analytic.model import TumblingModel
    from analytic.simulate import ASSEMBLY_REPORT_SAMPLES, _assemble, evaluator
    from analytic.trajectory import RunStatus

    sc = load_scene(scene_path("paper_example1"))
    model = TumblingModel(sc)
    accel = evaluator(model, Backend.NUMPY)
    n = 2 * ASSEMBLY_REPORT_SAMPLES + 1
    y = np.concatenate([sc.initial.q0(), sc.initial.qdot0(), np.zeros(7)])
    t, Y = np.linspace(0.0, 1.0, n), np.tile(y, (n, 1))
    calls: list[float] = []

    def progress(at: float) -> None:
        calls.append(at)
        if len(calls) == 2:
            raise KeyboardInterrupt

    tr = _assemble(model, accel, t, Y, RunStatus.INTERRUPTED, "interrupted", {}, progress)
    assert calls == [1.0, 1.0]
    assert tr.status is RunStatus.INTERRUPTED and len(tr.t) == 2 * ASSEMBLY_REPORT_SAMPLES
    np.testing.assert_array_equal(tr.q, Y[: 2 * ASSEMBLY_REPORT_SAMPLES, : model.nq])
    calls.clear()
    whole = _assemble(model, accel, t, Y, RunStatus.OK, "", {}, progress)
    assert calls == [] and len(whole.t) == n
