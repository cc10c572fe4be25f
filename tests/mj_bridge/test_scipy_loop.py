"""The Pinocchio and Drake plants' groups of coupled components (analytic.error_scale): each group
is the components of one physical block of the plant's own state layout, and an O(1) run is the
run of the fixed atol.

References: the plants' own maps from a paper state with a distinct value in every component
(``state_from_paper``), so the groups are checked against the layout, not against themselves.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.kinematics import H
from analytic.trajectory import RunStatus
from validation.scenes import resolve_scene


def _plants():
    out = []
    try:
        import pinocchio  # noqa: F401

        from mj_bridge.pinocchio_plant import PinocchioDynamics

        out.append(pytest.param(PinocchioDynamics, id="pinocchio"))
    except ImportError:
        pass
    try:
        import pydrake  # noqa: F401

        from mj_bridge.drake_plant import DrakeDynamics

        out.append(pytest.param(DrakeDynamics, id="drake"))
    except ImportError:
        pass
    return out or [pytest.param(None, marks=pytest.mark.skip(reason="no engine plant installed"))]


SCENE = "paper_example2_controlled"


@pytest.mark.parametrize("dynamics", _plants())
def test_groups_are_the_blocks_of_the_plant_state(dynamics):
    """Positions {R, p}, the quaternion, the translational velocities {Ṙ, ṗ}, and the three
    rotational rates: found in y by their values, each group exactly one block."""
    sc = resolve_scene(SCENE)
    d = dynamics(sc)
    n = sc.n
    R = np.array([11.0, 12.0, 13.0])
    u = np.array([0.5, 0.5, 0.5, 0.5])
    p = 20.0 + np.arange(n)
    Rd = np.array([31.0, 32.0, 33.0])
    pd = 40.0 + np.arange(n)
    udot = 0.25 * H(u).T @ np.array([0.1, 0.2, 0.3])  # ω = (0.1, 0.2, 0.3) rad/s
    y = d.state_from_paper(np.r_[R, u, p], np.r_[Rd, udot, pd])
    g = d.error_groups
    assert g.n_motion == d.nq + d.nv and len(g.groups) == 4
    sets = [set(np.round(y[i], 9)) for i in g.groups]
    assert set(np.r_[R, p]) in sets
    assert set(np.r_[Rd, pd]) in sets
    quat = [s for s in sets if s == set(np.round(u, 9))]
    assert len(quat) == 1
    covered = np.sort(np.concatenate(g.groups))
    np.testing.assert_array_equal(covered, np.arange(d.nq + d.nv))  # every motion component


@pytest.mark.parametrize("dynamics", _plants())
def test_an_o1_run_is_the_run_of_the_fixed_atol(dynamics):
    """Example 2 controlled over 1 s stays O(1): the scaled error control gives the same run."""
    from mj_bridge.scipy_loop import integrate
    from mj_bridge.scipy_loop_settings import ScipyLoopSettings

    sc = resolve_scene(SCENE)
    runs = []
    for scaled in (True, False):
        d = dynamics(sc)
        if not scaled:
            d.error_groups = None
        run, _ = integrate(d, ScipyLoopSettings(), sc, 1.0, None)
        assert run.status is RunStatus.OK and run.rescales == 0
        runs.append(run)
    np.testing.assert_array_equal(runs[0].y, runs[1].y)
    assert runs[0].nsteps == runs[1].nsteps
