"""A run's progress callback (``analytic.progress``): a callback takes the state when its second
positional parameter is ``q``; one written for ``progress(t)`` alone is still given ``t`` alone,
whatever the plant passes; the analytic plant's states are its trajectory's rows where it reports."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.plant import AnalyticPlant, AnalyticSettings, Plant
from analytic.progress import takes_state, with_state
from analytic.scene import load_scene
from analytic.trajectory import Engine
from tests.support.tolerances import PROGRESS_STATE_REL
from validation.scenes import scene_path


def _t_only(t): ...


def _with_q(t, q): ...


def _q_default(t, q=None): ...


def _args(*a): ...


def _closure(t, i=0, horizon=1.0): ...  # defaults of its own: never handed a state


class _Bar:
    def __call__(self, t): ...


@pytest.mark.parametrize(
    ("callback", "wants"),
    [
        (_t_only, False),
        (_with_q, True),
        (_q_default, True),
        (_args, True),
        (_closure, False),
        (_Bar(), False),
        (functools.partial(_with_q), True),
        ([].append, False),
        (None, False),
    ],
)
def test_a_callback_takes_the_state_by_its_q(callback, wants):
    assert takes_state(callback) is wants
    wrapped = with_state(callback)
    if callback is None:
        assert wrapped is None
        return
    assert (wrapped is callback) is wants
    assert not takes_state(wrapped) or wants


def test_a_time_only_callback_is_given_the_time_only():
    heard = []
    wrapped = with_state(heard.append)
    wrapped(0.5, np.zeros(7))
    wrapped(1.0)
    assert heard == [0.5, 1.0]
    assert with_state(wrapped) is wrapped


class _Reporting(Plant):
    """A plugin-like plant whose run passes its state to every progress call."""

    engine = "reporting"
    label = "Reporting"
    settings_type = AnalyticSettings
    effects = frozenset(Effect)

    def default_settings(self, scene):
        return AnalyticSettings()

    def describe(self, settings):
        return "reporting"

    def _simulate(self, scene, settings, t_end, progress):
        progress(0.25, np.arange(7.0))
        progress(0.5)  # and one without
        raise StopIteration("ran")


def test_a_plant_may_pass_the_state_to_a_callback_written_for_the_time_alone():
    sc = load_scene(scene_path("paper_example1"))
    heard, states = [], []
    with pytest.raises(StopIteration):
        _Reporting().simulate(sc, progress=heard.append)
    assert heard == [0.25, 0.5]
    with pytest.raises(StopIteration):
        _Reporting().simulate(sc, progress=lambda t, q=None: states.append((t, q)))
    assert states[0][0] == 0.25 and np.array_equal(states[0][1], np.arange(7.0))
    assert states[1] == (0.5, None)


@pytest.mark.parametrize("stepper", ["compiled", "scipy"])
def test_the_analytic_plants_states_are_its_rows(stepper):
    """Where the run reports at a sample time (the compiled loop: each whole second; scipy's:
    where a step ends on one), the state it passes is the trajectory's row there; everywhere it
    is the state at the time it reports, in [R, u (w first), p]."""
    sc = load_scene(scene_path("paper_example1_controlled"))
    got: list = []
    settings = AnalyticSettings(sc.solver.method, sc.solver.rtol, sc.solver.atol, stepper=stepper)
    tr = AnalyticPlant().simulate(sc, settings, t_end=2.0, progress=lambda t, q: got.append((t, q)))
    assert tr.engine == Engine.ANALYTIC and got
    ts = np.array([t for t, _ in got])
    assert np.all(np.diff(ts) > 0) and ts[-1] == tr.t[-1]
    for t, q in got:
        assert q.shape == (sc.n + 7,)
        k = int(np.searchsorted(tr.t, t))
        if tr.t[k] == t:  # a sample time: the row itself, to the round-off of its dense output
            row = tr.q[k]
            scale = max(1.0, float(np.max(np.abs(row))))
            assert np.max(np.abs(q - row)) <= PROGRESS_STATE_REL.value * scale, t
        else:  # a step's end inside a sample interval: nearer one of its rows than they are apart
            before, after = tr.q[k - 1], tr.q[k]
            apart = np.max(np.abs(after - before))
            assert min(np.max(np.abs(q - before)), np.max(np.abs(q - after))) <= apart, t
    on = sum(bool(np.any(tr.t == t)) for t, _ in got)
    assert on >= (2 if stepper == "compiled" else 1)  # each whole second; the horizon
