"""analytic.error_scale: the adaptive plants' atol follows the magnitude of each group of coupled
components, and a run whose steps are set by round-off stops with that reason.

References: a two-component system whose small component is computed from a growing one (its
round-off is that of the large one, as a velocity's is that of the forces on every mass), closed
forms, and Galilean invariance of a fuzz scene; steps are counted, not seconds.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic.effects import SolverMethod
from analytic.error_scale import (
    GROUP_UNIT,
    PROBE_STEPS,
    PROBES_IN_A_ROW,
    ErrorGroups,
    RoundoffWatch,
    atol_vector,
    follow_scales,
    group_scales,
)
from analytic.plant import AnalyticPlant, AnalyticSettings
from analytic.scene import scene_from_dict
from analytic.simulate import simulate
from analytic.stepping import step_and_sample
from analytic.trajectory import RunStatus
from validation.scenes import resolve_scene
from validation.studies.fuzz.space import draw_scene_dict

K = 12.0  # growth rate of the large component, 1/s: a reaches 2.6e10 over 2 s


def _runaway(t, y):
    """``a = e^{K t}`` and ``b' = cos t`` computed as ``(a + cos t) - a``: ``b``
    stays O(1) while its derivative carries the round-off of ``a``."""
    out = np.zeros_like(y)
    out[0] = K * y[0]
    out[1] = (y[0] + np.cos(t)) - y[0]
    return out


def _runaway_run(groups):
    t = np.linspace(0.0, 2.0, 21)
    kw = dict(method=SolverMethod.DOP853, rtol=1e-12, atol=1e-13, n_motion=2)
    return t, step_and_sample(_runaway, t, np.array([1.0, 0.0, 0.0]), groups=groups, **kw)


def test_a_small_component_coupled_to_a_runaway_one_costs_bounded_steps():
    """With the group's atol following ``a``, the run takes the steps the exponential needs (a few
    hundred) and ``b`` is right to the group's floor."""
    t, run = _runaway_run(ErrorGroups.of(2, [0, 1]))
    assert run.status is RunStatus.OK and run.rescales >= 1
    assert run.nsteps <= 1000
    np.testing.assert_allclose(run.y[:, 0], np.exp(K * t), rtol=1e-10)
    floor = 1e-13 * np.exp(K * t[-1]) / GROUP_UNIT
    assert np.max(np.abs(run.y[:, 1] - np.sin(t))) <= 10 * floor


@pytest.mark.slow
def test_a_fixed_atol_grinds_on_the_same_system():
    """The fixed atol on the same system: the round-off of ``a`` in ``b'`` drives the steps down
    to tens of thousands (what the scaling removes)."""
    _, scaled = _runaway_run(ErrorGroups.of(2, [0, 1]))
    _, fixed = _runaway_run(None)
    assert fixed.nsteps >= 20 * scaled.nsteps


def test_scales_are_powers_of_two_above_the_group_unit_and_fall_with_hysteresis():
    """s_g = 1 up to 2 GROUP_UNIT; it follows growth at once and falls only at a quarter."""
    g = ErrorGroups.of(4, [0, 1], [2, 3])
    y = np.array([1.5 * GROUP_UNIT, -3.0, 0.0, 1e-3])
    np.testing.assert_array_equal(group_scales(y, g), [1.0, 1.0])
    y[0] = -5.0 * GROUP_UNIT
    np.testing.assert_array_equal(group_scales(y, g), [4.0, 1.0])
    s = group_scales(y, g)
    y[0] = 2.5 * GROUP_UNIT  # down to 2: within a quarter, kept
    assert follow_scales(s, y, g) is s
    y[0] = 0.5 * GROUP_UNIT  # down to 1: a quarter, followed
    np.testing.assert_array_equal(follow_scales(s, y, g), [1.0, 1.0])
    y[0] = np.nan
    np.testing.assert_array_equal(group_scales(y, g), [1.0, 1.0])


def test_tightened_settings_tighten_the_scaled_floor_too():
    """Plant.tightened divides atol by 100: every component's scaled atol falls by 100."""
    g = ErrorGroups.of(4, [0, 1], [2, 3])
    y = np.array([1e6, 1.0, 0.5, 0.5, 0.0])
    scales = group_scales(y, g)
    sc = resolve_scene("paper_example1_controlled")
    plant = AnalyticPlant()
    base = plant.default_settings(sc)
    tight = plant.tightened(sc, base)
    loose = atol_vector(base.atol, 5, 4, g, scales)
    np.testing.assert_allclose(atol_vector(tight.atol, 5, 4, g, scales)[:4], loose[:4] / 100)
    assert loose[0] > base.atol  # the large group's floor is raised
    assert loose[2] == base.atol  # the O(1) group keeps the fixed atol


@pytest.mark.parametrize("stepper", ["compiled", "scipy"])
def test_an_o1_scene_is_unchanged(stepper):
    """The controlled Example 2 over 2 s stays within a few hundred SI units: the scaled error
    control gives exactly the run of the fixed atol."""
    sc = resolve_scene("paper_example2_controlled")
    on = simulate(sc, t_end=2.0, stepper=stepper, method="DOP853")
    off = simulate(sc, t_end=2.0, stepper=stepper, method="DOP853", scale_atol=False)
    assert on.status is RunStatus.OK and "atol_rescales" not in on.info
    np.testing.assert_array_equal(on.q, off.q)
    np.testing.assert_array_equal(on.qdot, off.qdot)
    assert on.info["nsteps"] == off.info["nsteps"]


def _fuzz_scene(index: int, **initial):
    data = draw_scene_dict(7, index, 2.0)
    data["initial"].update(initial)
    return scene_from_dict(data)


def test_a_large_well_conditioned_motion_is_galilean_and_not_stopped():
    """Fuzz scene 9 moved 1e6 m away at 1e5 m/s (Galilean invariance): it runs to the end, is
    the same motion in the moved frame, and takes about the steps of the unmoved one."""
    t_end = 0.5
    base = _fuzz_scene(9)
    shift = np.array([1e6, -2e6, 3e5])
    vel = np.array([1e5, 2e4, -5e4])
    moved = _fuzz_scene(
        9,
        R=list(np.asarray(base.initial.q0()[:3]) + shift),
        Rdot=list(np.asarray(base.initial.qdot0()[:3]) + vel),
    )
    a = simulate(base, t_end=t_end)
    b = simulate(moved, t_end=t_end)
    assert a.status is RunStatus.OK and b.status is RunStatus.OK
    R_back = b.q[:, :3] - shift - np.outer(b.t, vel)
    pos_scale = np.max(np.abs(b.q[:, :3]))
    assert np.max(np.abs(R_back - a.q[:, :3])) <= 1e-9 * pos_scale
    np.testing.assert_allclose(b.q[:, 3:], a.q[:, 3:], atol=1e-7)
    assert b.info["nsteps"] <= 3 * a.info["nsteps"]


@pytest.mark.parametrize("stepper", ["compiled", "scipy"])
def test_a_runaway_scene_stops_round_off_limited_within_bounded_steps(stepper):
    """Fuzz scene 9 of seed 7 (masses flung ~1e5 m out along the rod; it took the plants past the
    30 s limit): the run stops failed, naming round-off, within a probe's worth of steps of the
    probes in a row that find it; and at
    its last sample the accelerations do follow a one-ulp change of the state far above round-off
    (checked here with the model, independently of the probe)."""
    sc = _fuzz_scene(9)
    settings = AnalyticSettings(stepper=stepper)
    tr = AnalyticPlant().simulate(sc, settings, t_end=2.0)
    assert tr.status is RunStatus.FAILED and "round-off limited" in tr.message
    assert tr.info["nsteps"] <= (PROBES_IN_A_ROW + 1) * PROBE_STEPS + 200
    assert 0.5 < tr.t[-1] < 2.0
    from analytic.model import TumblingModel

    model = TumblingModel(sc)
    q, qd = tr.q[-1].copy(), tr.qdot[-1].copy()
    a0 = model.acceleration(float(tr.t[-1]), q, qd)[0]
    eps = np.finfo(float).eps
    signs = np.where(np.arange(q.size) % 2 == 0, eps, -eps)
    a1 = model.acceleration(float(tr.t[-1]), q * (1 + signs), qd * (1 - signs))[0]
    assert np.max(np.abs(a1 - a0)) / np.max(np.abs(a0)) > 1e4 * eps



def _sensitive(t, y):
    """``ẏ = 1e6 y``: a one-ulp change of y moves ẏ by 1e6 ε |y|, past rtol 1e-12 in steps of 1e-2."""
    return 1e6 * y


@pytest.mark.parametrize(
    ("advance", "stops"),
    [(20.0, False), (2e-3, True)],
    ids=["steady pace: finishes", "steps shrunk a thousandfold: stops"],
)
def test_a_round_off_limited_run_stops_only_while_it_grinds(advance, stops):
    """Probes that find round-off at every call stop the run only when its steps have shrunk
    against its average (or the horizon is out of reach at their pace), never at the first."""
    y = np.array([1.0, 0.0])
    atol = atol_vector(1e-13, 2, 1)
    watch = RoundoffWatch(_sensitive, 1e-12, 1, 0.0, 1000.0)
    t, n, answers = 0.0, 0, []
    for k in range(4):
        pace = 0.01 if k < 2 else advance / PROBE_STEPS  # s per step over the next probe's steps
        t, n = t + pace * PROBE_STEPS, n + PROBE_STEPS
        answers.append(watch.check(t, y, 0.01, atol, n))
    assert answers[0] == ""  # never at the first probe
    assert (answers[-1] != "") is stops
    if stops:
        assert "round-off limited" in answers[-1] and "probes in a row" in answers[-1]


def test_a_run_that_slows_down_just_before_its_horizon_finishes():
    """Steps shrunk a thousandfold, round-off limited at every probe, but the horizon 1000 steps
    away at that pace (fewer than the steps between two probes): the run is not stopped, since
    finishing costs less than it spent since the last probe; the same run with its horizon far
    away stops."""
    y = np.array([1.0, 0.0])
    atol = atol_vector(1e-13, 2, 1)

    def answers(t_end: float) -> list[str]:
        watch = RoundoffWatch(_sensitive, 1e-12, 1, 0.0, t_end)
        t, n, out = 0.0, 0, []
        for k in range(3):
            pace = 0.01 if k < 2 else 1e-6  # s per step
            t, n = t + pace * PROBE_STEPS, n + PROBE_STEPS
            out.append(watch.check(t, y, 0.01, atol, n))
        return out

    near = 2 * 0.01 * PROBE_STEPS + 1e-6 * PROBE_STEPS + 1000 * 1e-6
    assert answers(near) == ["", "", ""]
    assert answers(1000.0)[-1].startswith("round-off limited")
