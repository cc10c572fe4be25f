"""The runaway campaign's goals: what counts as a counterexample reproduced, and (slow) the
campaign itself holding them."""

from __future__ import annotations

import pytest

from validation.studies.fuzz.runaway_goal import _shows, runaway_campaign


def _report(*, referee=(), plants=(), checks=()) -> dict:
    return {"referee": list(referee), "plants": list(plants), "checks": list(checks)}


OK = {"engine": "analytic", "status": "ok", "message": "", "t_reached": 2.0}


def test_an_outlier_is_reproduced_only_when_the_referee_names_that_plant_on_that_quantity():
    """The finding ``outlier:rod_positions:mujoco`` is shown again by a referee verdict naming
    mujoco on rod_positions, not by one naming another plant or another quantity."""
    named = {"quantity": "rod_positions", "verdict": "outlier", "outliers": [{"plant": "mujoco"}]}
    other = {"quantity": "rod_positions", "verdict": "outlier", "outliers": [{"plant": "analytic"}]}
    elsewhere = {"quantity": "attitude", "verdict": "outlier", "outliers": [{"plant": "mujoco"}]}
    key = "outlier:rod_positions:mujoco"
    assert _shows(key, _report(referee=[elsewhere, named], plants=[OK]))[0]
    assert not _shows(key, _report(referee=[other], plants=[OK]))[0]
    assert not _shows(key, _report(referee=[elsewhere], plants=[OK]))[0]


def test_a_stop_and_a_failed_check_are_reproduced_by_the_same_stop_and_failure():
    """A plant that stopped must stop again; a failed check must fail again (a passing one, or one
    the report lacks, does not reproduce it)."""
    stopped = {"engine": "analytic", "status": "failed", "message": "round-off limited at t = 1 s",
               "t_reached": 1.0}
    assert _shows("stopped:failed:analytic", _report(plants=[stopped]))[0]
    assert not _shows("stopped:failed:analytic", _report(plants=[OK]))[0]
    failing = {"subject": "mujoco", "name": "energy", "passed": False, "applicable": True}
    passing = dict(failing, passed=True)
    assert _shows("check:mujoco.energy", _report(plants=[OK], checks=[failing]))[0]
    assert not _shows("check:mujoco.energy", _report(plants=[OK], checks=[passing]))[0]
    assert not _shows("check:mujoco.energy", _report(plants=[OK]))[0]


def test_a_run_over_its_time_limit_never_counts_as_reproduced():
    """A reproduction whose plant passed the campaign's per-run limit shows nothing, whatever the
    referee said."""
    over = {"engine": "pinocchio", "status": "failed",
            "message": "stopped at its time limit of 30 s", "t_reached": 0.2}
    named = {"quantity": "rod_positions", "verdict": "outlier", "outliers": [{"plant": "mujoco"}]}
    ok, why = _shows("outlier:rod_positions:mujoco", _report(referee=[named], plants=[OK, over]))
    assert not ok and "pinocchio" in why


@pytest.mark.slow
def test_the_runaway_campaign_blames_no_model_grinds_no_plant_and_reproduces_its_findings():
    """Seed 7, 40 violent scenes over 2 s, the default plants: no new finding settled as
    ``model``, no run over its time limit, and every counterexample's command shows its finding
    again (its wall is a benchmark goal, not asserted here)."""
    res = runaway_campaign(progress=lambda _m: None)
    assert res.scenes == 40
    assert res.model == (), res.lines()
    assert sum(res.timeouts.values()) == 0, res.timeouts
    assert res.reproductions and all(r.reproduced for r in res.reproductions), res.lines()
