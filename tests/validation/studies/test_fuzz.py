"""tumble fuzz: the scene space, judging, shrinking against a planted wrong plant, the minimal
scene files, resume, determinism across executors, the report and its schema, the CLI."""

from __future__ import annotations

import json
import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from analytic.plant import AnalyticPlant
from analytic.scene import load_scene, scene_from_dict
from tests.support.fuzz_plants import (
    SLEEP_S,
    STALL_T,
    CoarsePlant,
    ShiftedPlant,
    SleepyPlant,
    StallingPlant,
)
from tests.support.plugins import install_project
from validation.studies.fuzz import campaign as campaign_mod
from validation.studies.fuzz.campaign import SerialExecutor, fuzz
from validation.studies.fuzz.judge import Disagreement, Kind, Outcome, judge_scene
from validation.studies.fuzz.known import recognise
from validation.studies.fuzz.settle import SETTLE_MARGIN, Cause, settle
from validation.studies.fuzz.shrink import MIN_HORIZON_S, round_sig
from validation.studies.fuzz.space import draw_scene_dict, drivers
from validation.studies.sweep.running import executor_for

PLANTS = ("analytic", ShiftedPlant())
TARGET = Disagreement(Kind.CHECK, "position_C")


def test_space_is_seeded_per_scene_and_valid():
    a = [draw_scene_dict(7, i, 0.5) for i in range(60)]
    assert a[3] == draw_scene_dict(7, 3, 0.5)  # the same scene whatever was drawn before
    assert draw_scene_dict(8, 3, 0.5) != a[3]
    for d in a:
        scene_from_dict(d)  # every draw is a valid scene file
    dr = [drivers(d) for d in a]
    assert any(x.n == 0 for x in dr) and any(x.n > 10 for x in dr)
    assert any(x.offset == 0.0 for x in dr)
    assert any(d["initial"]["attitude"]["quaternion"][0] < 0 for d in a)
    assert any("gravity" in d for d in a) and any("gravity" not in d for d in a)
    assert any("control" in d for d in a) and any("external_torque" in d for d in a)
    assert max(x.mass_ratio for x in dr) > 1e4  # mass ratios over several decades


def test_round_sig():
    assert round_sig(0.123456) == 0.1 and round_sig(-2870.0) == -3000.0 and round_sig(0.0) == 0.0


def test_planted_wrong_plant_shrinks_to_the_simplest_scene(tmp_path):
    res = fuzz(tmp_path, budget=2, seed=0, plants=PLANTS, executor=SerialExecutor())
    keys = {e.disagreement.key: e for e in res.counterexamples}
    assert TARGET.key in keys
    ex = keys[TARGET.key]
    # a displaced C shows on every scene: the shrinker must reach the simplest one
    assert drivers(ex.data).n == 0
    assert ex.data["scene"]["effects"] == []
    assert ex.horizon < 2 * MIN_HORIZON_S
    assert ex.data["rod"]["offset"] == [0.0, 0.0, 0.0]
    assert sorted(abs(x) for x in ex.data["rod"]["axis"]) == [0.0, 0.0, 1.0]
    assert ex.data["initial"]["attitude"]["quaternion"] == [1.0, 0.0, 0.0, 0.0]
    assert ex.outcome.shows(TARGET)
    # the minimal scene file reproduces it, read back as a file
    out = judge_scene(_file_dict(ex.path), PLANTS, ex.horizon)
    assert out.shows(TARGET)
    assert recognise(draw_scene_dict(0, ex.found_in, 0.5), ex.data, TARGET) == ""  # a new finding


def _file_dict(path):
    import tomllib

    return tomllib.loads(path.read_text())


def _reproduce_limit(command: str) -> float:
    """The ``--time-limit`` a ``tumble validate`` command gives (its only one)."""
    import shlex

    words = shlex.split(command)
    assert words[:2] == ["tumble", "validate"] and words.count("--time-limit") == 1, command
    return float(words[words.index("--time-limit") + 1])


def test_minimal_scene_is_accepted_by_validate_plugin_and_hard_case_runner(tmp_path):
    """... and its reproduce command, in the file and in campaign.json, runs each plant within
    the campaign's own per-run time limit (not the default's)."""
    res = fuzz(tmp_path, budget=1, seed=0, plants=PLANTS, executor=SerialExecutor(),
               time_limit_s=45.5)
    path = res.counterexamples[0].path
    text = path.read_text()
    assert text.startswith("# Minimal counterexample")
    (line,) = [x for x in text.splitlines() if x.startswith("# Reproduce: ")]
    assert _reproduce_limit(line.removeprefix("# Reproduce: ")) == 45.5
    doc = json.loads(res.files["json"].read_text())
    assert [_reproduce_limit(c["command"]) for c in doc["counterexamples"]] == [45.5]
    load_scene(path)  # tumble validate and the plugin read it through the loader
    from validation.studies.hard_cases.runner import load_case

    case = load_case(path)
    assert case.criterion.checks
    from validation.testing.pytest_plugin import _SCENE_TABLE

    assert _SCENE_TABLE.search(path.read_bytes())  # the plugin sees a scene file


def _strip(outcome_dict):
    return {k: v for k, v in outcome_dict.items() if k != "walls"}


def test_same_verdicts_on_every_executor(tmp_path):
    a = fuzz(tmp_path / "a", budget=3, seed=1, plants=["analytic", ShiftedPlant()],
             executor=SerialExecutor(), report=False)
    with ThreadPoolExecutor(2) as pool:
        b = fuzz(tmp_path / "b", budget=3, seed=1, plants=["analytic", ShiftedPlant()],
                 executor=pool, report=False)
    assert [_strip(r.outcome.to_dict()) for r in a.scenes] == [
        _strip(r.outcome.to_dict()) for r in b.scenes
    ]
    assert [e.data for e in a.counterexamples] == [e.data for e in b.counterexamples]


def test_resume_keeps_what_was_found(tmp_path, monkeypatch):
    fuzz(tmp_path, budget=2, seed=0, plants=PLANTS, executor=SerialExecutor(), report=False)
    calls = []
    real = campaign_mod.scene_plant_task
    monkeypatch.setattr(
        campaign_mod, "scene_plant_task", lambda *a: calls.append(a[1]) or real(*a)
    )
    res = fuzz(tmp_path, budget=3, seed=0, plants=PLANTS, executor=SerialExecutor())
    assert set(calls) == {2}  # scenes 0 and 1 were read back, only scene 2's plants ran
    assert len(res.scenes) == 3 and res.complete
    with pytest.raises(ValueError, match=r"^out: "):
        fuzz(tmp_path, budget=1, seed=5, plants=PLANTS, executor=SerialExecutor())


def test_report_matches_its_schema(tmp_path):
    from tests.validation.report.test_provenance import validator

    res = fuzz(tmp_path, budget=2, seed=0, plants=PLANTS, executor=SerialExecutor())
    doc = json.loads(res.files["json"].read_text())
    validator("campaign").validate(doc)
    assert doc["scenes"] == 2 and doc["counterexamples"][0]["command"].startswith("tumble validate")
    assert res.files["png"].read_bytes()[:4] == b"\x89PNG"
    assert "## New findings" in res.files["md"].read_text()


def test_known_findings_are_recognised():
    import copy

    found = draw_scene_dict(0, 0, 0.5)
    found["rod"]["offset"] = [1.5, 0.0, 0.0]
    data = copy.deepcopy(found)
    data["rod"]["offset"] = [0.0, 0.0, 0.0]
    pin = Disagreement(Kind.OUTLIER, "rod_positions", "pinocchio")
    assert recognise(data, data, pin) == "rod_through_C"
    assert recognise(data, data, Disagreement(Kind.OUTLIER, "rod_positions", "mujoco")) == ""
    # found with the rod off C, shrunk with the offset zeroed: not the known finding
    assert recognise(found, data, pin) == ""
    data["initial"]["omega"] = [0.0, 200.0, 0.0]
    fast = Disagreement(Kind.OUTLIER, "attitude", "analytic")
    assert recognise(data, data, fast) == "fast_spin_analytic"
    found["initial"]["omega"] = [0.0, 20.0, 0.0]
    assert recognise(found, data, fast) == ""


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"budget": 0}, "budget"),
        ({"minutes": -1.0}, "minutes"),
        ({"horizon": 0.0}, "horizon"),
        ({"seed": -1}, "seed"),
        ({"plants": ["analytic"]}, "plants"),
        ({"plants": ["analytic", "nope"]}, "plants"),
    ],
)
def test_bad_input_names_the_field(tmp_path, kwargs, field):
    with pytest.raises(ValueError, match=f"^{field}: "):
        fuzz(tmp_path, executor=SerialExecutor(), **kwargs)


def test_cli_bad_plant_is_one_line(tmp_path, capsys):
    from validation.cli import main

    rc = main(["fuzz", "--budget", "1", "--plants", "analytic,nope", "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc != 0 and len(err) == 1 and "plants" in err[0]



def test_cli_time_limit_reaches_the_campaign_and_is_checked(tmp_path, monkeypatch, capsys):
    from validation.cli import main

    seen = {}

    def fake_fuzz(out, **kwargs):
        seen.update(kwargs)
        raise SystemExit(0)

    monkeypatch.setattr(campaign_mod, "fuzz", fake_fuzz)
    with pytest.raises(SystemExit):
        main(["fuzz", "--budget", "1", "--time-limit", "2.5", "--out", str(tmp_path)])
    assert seen["time_limit_s"] == 2.5
    with pytest.raises(SystemExit) as exc:
        main(["fuzz", "--time-limit", "0", "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and "--time-limit" in err[-1]

DASK_PLANTS = ("analytic", "pinocchio")


def test_dask_local_cluster_gives_the_serial_verdicts(tmp_path):
    """dask is in [test]: the distributed path runs on every submission."""
    pytest.importorskip("distributed")
    kw = dict(budget=3, seed=3, plants=DASK_PLANTS, horizon=0.1, report=False, shrink_evaluations=5)
    serial = fuzz(tmp_path / "serial", executor=SerialExecutor(), **kw)
    dask = fuzz(tmp_path / "dask", dask_workers=2, **kw)
    assert [_strip(r.outcome.to_dict()) for r in serial.scenes] == [
        _strip(r.outcome.to_dict()) for r in dask.scenes
    ]


def test_dashboard_served_on_the_loopback_and_its_link_logged_once(caplog):
    """--dashboard: the local cluster serves Dask's dashboard on 127.0.0.1, the link logged once
    at INFO; the page answers there."""
    pytest.importorskip("distributed")
    pytest.importorskip("bokeh")
    import logging
    import urllib.request

    with caplog.at_level(logging.INFO, logger="tumbling_testbed"):
        with executor_for(None, None, 1, dashboard=True) as (ex, width):
            ours = [r for r in caplog.records if r.name.startswith("tumbling_testbed.")]
            links = [r.getMessage() for r in ours if "dashboard" in r.getMessage()]
            assert len(links) == 1, links
            link = links[0].split(": ", 1)[1]
            assert link.startswith("http://127.0.0.1:"), link
            with urllib.request.urlopen(link, timeout=30) as page:
                assert page.status == 200
            assert ex.submit(sum, (1, 2)).result() == 3 and width == 1


def test_executor_for_refuses_both_and_bad_counts():
    with pytest.raises(ValueError, match=r"^scheduler: "), executor_for(None, "tcp://x:1", 2):
        pass
    with pytest.raises(ValueError, match=r"^dask_workers: "), executor_for(None, None, 0):
        pass


TIME_LIMIT_S = 2.0
STOP_MARGIN_S = 0.25 * SLEEP_S - TIME_LIMIT_S
"""Fork, SIGTERM, the 0.5 s grace before SIGKILL (workers.STOP_GRACE_S), reaping: a run stopped at
its limit ends within a quarter of SLEEP_S, which a run that was not stopped (SLEEP_S) cannot; on
a 2-core machine running the suite in two workers a stopped run took 2.1-5.2 s (this is not a
timing goal, only the line between stopped and not stopped)."""


def test_a_plant_that_hangs_is_stopped_at_its_limit_and_the_campaign_goes_on(tmp_path):
    """The default executor (a process pool: single-threaded workers, so each run forks)."""
    import os
    import time

    pids = tmp_path / "pids"
    pids.mkdir()
    t0 = time.perf_counter()
    res = fuzz(tmp_path / "out", budget=2, seed=0, plants=["analytic", SleepyPlant(pids)],
               horizon=0.1, time_limit_s=TIME_LIMIT_S)
    wall = time.perf_counter() - t0
    assert res.complete and [r.index for r in res.scenes] == [0, 1]  # on to the next scene
    assert wall < 0.5 * SLEEP_S
    for r in res.scenes:
        assert r.outcome.timeouts == {"pinocchio": TIME_LIMIT_S}
        assert r.outcome.ran == ("analytic",) and not r.outcome.disagreements
        assert "pinocchio" not in r.outcome.refused
        assert TIME_LIMIT_S <= r.outcome.walls["pinocchio"] < TIME_LIMIT_S + STOP_MARGIN_S
    assert len(list(pids.iterdir())) == 2  # each run started in its own process ...
    for p in pids.iterdir():  # ... which is gone (killed, not left sleeping)
        with pytest.raises(ProcessLookupError):
            os.kill(int(p.stem), 0)
    doc = json.loads(res.files["json"].read_text())
    assert doc["timeouts"] == {"pinocchio": [0, 1]}
    md = res.files["md"].read_text()
    assert "plant pinocchio: 2 × over its time limit (scenes 0, 1)" in md


def test_time_limit_must_be_positive(tmp_path):
    with pytest.raises(ValueError, match=r"^time_limit_s: "):
        fuzz(tmp_path, executor=SerialExecutor(), time_limit_s=0.0)


PLANTED = Path(__file__).parents[2] / "support" / "planted_plugin"
PLANTED_SEED = 21
"""A seed whose first scene shows the planted slip: 10 masses, spin 41 rad/s, both over the
slip's bounds, so the shrinker has masses to remove and a spin it must keep."""


def test_a_planted_wrong_plant_is_found_through_the_plugin_mechanism_and_shrunk_to_three_masses(
    tmp_path,
):
    """The planted plant (``tests/support/planted_plugin``: the analytic plant with its body
    inertia 1e-6 relative too large, only with at least three masses and |ω(0)| > 5 rad/s),
    installed as a plugin and named on ``tumble fuzz``'s command line: the campaign finds it, and
    the minimal scene has exactly three masses (two cannot show the slip), a spin over 5 rad/s, and
    names the planted plant the outlier, reproduced by ``tumble validate`` on the file."""
    import os
    import subprocess
    import sys

    site = install_project(PLANTED, tmp_path / "site")
    sys.path.insert(0, str(site))
    try:
        from tumble_planted_plant import MIN_MASSES, MIN_SPIN
    finally:
        sys.path.remove(str(site))
    env = dict(os.environ, PYTHONPATH=str(site))
    out = tmp_path / "campaign"
    cmd = [sys.executable, "-m", "validation", "fuzz", "--plants", "analytic,pinocchio,planted",
           "--seed", str(PLANTED_SEED), "--budget", "1", "--out", str(out)]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 1, res.stdout + res.stderr  # 1: a new finding
    doc = json.loads((out / "campaign.json").read_text())
    assert doc["scenes_per_plant"]["planted"] == 1
    found = [c for c in doc["counterexamples"] if c["plant"] == "planted"]
    assert found and {c["kind"] for c in found} == {Kind.OUTLIER.value}
    first = drivers(draw_scene_dict(PLANTED_SEED, 0, campaign_mod.DEFAULT_HORIZON_S))
    assert first.n > MIN_MASSES  # the scene found had masses to remove
    for c in found:
        assert c["known"] == ""  # a new finding
        # not the settings: it stays at tightened settings, far beyond every plant's own error
        assert c["settlement"]["cause"] == "model", c["settlement"]["text"]
        data = _file_dict(out / c["file"])
        assert drivers(data).n == MIN_MASSES  # exactly three masses
        assert drivers(data).spin > MIN_SPIN
        for v in c["verdicts"]:  # every outlier the minimal scene shows is the planted plant
            assert v["verdict"] != "outlier" or v["outlier"] == "planted"
        # the file, read by tumble validate as it is, reproduces the verdict
        report = tmp_path / "validate"
        rerun = subprocess.run(
            [sys.executable, "-m", "validation", "validate", str(out / c["file"]), "--plants",
             "analytic,pinocchio,planted", "--t-end", str(c["horizon"]), "--out", str(report)],
            env=env, capture_output=True, text=True, timeout=600,
        )
        # exit 0 or 1: the checks' verdict (the planted slip sits near their bounds); the
        # referee's is the one asked for
        assert rerun.returncode in (0, 1), rerun.stdout + rerun.stderr
        verdicts = json.loads((report / "report.json").read_text())["referee"]
        outliers = [v for v in verdicts if v["verdict"] == "outlier"]
        assert outliers and {v["outlier"] for v in outliers} == {"planted"}
        assert all("Planted DOP853 rtol 1e-12 is the outlier" in v["text"] for v in outliers)


def test_a_right_model_at_coarse_settings_is_settled_as_a_limit_of_its_settings(tmp_path):
    """The coarse plant is the outlier (its error at rtol 1e-5 is far above the others' at
    1e-12); settling names it, as a numerical limit of its settings, not a model difference:
    its own error estimate (rtol 1e-5 against 1e-7) is of the size of its distance. A campaign
    with only such findings exits 0."""
    res = fuzz(tmp_path, budget=2, seed=0, plants=("analytic", "pinocchio", CoarsePlant()),
               executor=SerialExecutor())
    assert any(e.disagreement.kind is Kind.OUTLIER for e in res.counterexamples)
    for e in res.counterexamples:  # every one: the coarse plant's model is the analytic one
        st = e.settlement
        assert st.cause is Cause.SETTINGS and st.culprit == "mujoco", st.text
        assert not e.counts_against
        assert "rtol 1e-05" in st.settings["mujoco"][0] and "rtol 1e-07" in st.settings["mujoco"][1]
    doc = json.loads(res.files["json"].read_text())
    assert {c["settlement"]["cause"] for c in doc["counterexamples"]} == {"settings"}
    assert "## Numerical limits of the settings" in res.files["md"].read_text()


def _task(own, tightened_disagreements=(), untightened=None, plants=("a", "b", "c")):
    tight = Outcome(ran=tuple(plants), disagreements=tuple(tightened_disagreements))
    return {
        "own_errors": own,
        "settings": {p: [f"{p} default", f"{p} tight"] for p in plants},
        "untightened": untightened or {},
        "tightened": tight.to_dict(),
    }


def _outlier_outcome(dist):
    d = Disagreement(Kind.OUTLIER, "attitude", "c")
    v = {"quantity": "attitude", "verdict": "outlier", "outlier": "c", "group": ["a", "b"],
         "outliers": [{"plant": "c", "distance": dist}]}
    return d, Outcome(ran=("a", "b", "c"), verdicts=(v,), disagreements=(d,))


def test_settle_rules():
    """The rules of validation.studies.fuzz.settle on hand-made outcomes."""
    d, out = _outlier_outcome(1e-6)
    own = {p: {"attitude": 1e-12} for p in "abc"}
    # persists, far beyond the own errors: the model
    assert settle(d, out, _task(own, [d]), "abc").cause is Cause.MODEL
    # gone at tightened settings: the settings, the largest own error named
    own_b = {**own, "b": {"attitude": 3e-7}}
    st = settle(d, out, _task(own_b, []), "abc")
    assert st.cause is Cause.SETTINGS and st.culprit == "b"
    # persists, but the group's own error is within the margin of the distance: the settings
    within = {**own, "a": {"attitude": 1e-6 / SETTLE_MARGIN}}
    st = settle(d, out, _task(within, [d]), "abc")
    assert st.cause is Cause.SETTINGS and st.culprit == "a"
    # a plant that cannot tighten: unsettled
    st = settle(d, out, _task(own, [d], {"c": "the c plant cannot tighten its settings"}), "abc")
    assert st.cause is Cause.UNSETTLED
    # a plant stopping at its default settings and finishing at tightened ones: the settings
    stop = Disagreement(Kind.STOPPED, "diverged", "c")
    st = settle(stop, Outcome(ran=("a", "b", "c"), disagreements=(stop,)), _task(own, []), "abc")
    assert st.cause is Cause.SETTINGS and st.culprit == "c"
    st = settle(stop, Outcome(ran=("a", "b", "c"), disagreements=(stop,)), _task(own, [stop]), "abc")
    assert st.cause is Cause.MODEL


@pytest.mark.parametrize("where", ["here", "thread"])
def test_a_run_stopped_at_its_limit_says_where_it_was(where):
    """The simulated time a stalled run had reached comes back with its timeout, from a forked
    worker or one of the fork server's (under a thread: a multi-threaded caller)."""
    from validation.studies.fuzz.judge import OverTime, run_limited

    scene = scene_from_dict(draw_scene_dict(0, 2, 0.5))

    def run():
        with pytest.raises(OverTime) as exc:
            run_limited("pinocchio", StallingPlant(), scene, 0.5, TIME_LIMIT_S)
        return exc.value

    if where == "here":
        err = run()
    else:
        with ThreadPoolExecutor(1) as pool:
            err = pool.submit(run).result()
    assert err.reached_s == STALL_T
    assert f"at t = {STALL_T:g} s" in str(err)


def test_settle_scene_rule():
    """A plant stopping at its tightened settings too, while every other plant stops or stalls
    within two output samples of the same time: the scene's own singular motion, which does not
    fail a campaign; stalls far apart: the plant's model."""
    stop = Disagreement(Kind.STOPPED, "failed", "c")
    out = Outcome(ran=("a", "b", "c"), disagreements=(stop,))
    task = _task({}, [stop])
    task["interval"] = 0.01
    task["default_runs"] = {
        "a": {"status": "timeout", "reached": 0.3926},
        "b": {"status": "timeout", "reached": 0.3900},
        "c": {"status": "stopped", "reached": 0.39},
    }
    st = settle(stop, out, task, "abc")
    assert st.cause is Cause.SCENE, st.text
    task["default_runs"]["b"] = {"status": "ok", "reached": 0.5}
    assert settle(stop, out, task, "abc").cause is Cause.MODEL
    task["default_runs"]["b"] = {"status": "timeout", "reached": 0.2}
    assert settle(stop, out, task, "abc").cause is Cause.MODEL


def test_settle_range_rule():
    """A plant stopping at its tightened settings too, while another plant finishes a run that
    reaches an acceleration beyond the stopped plant's value_bound: the motion left that
    engine's range (MuJoCo's mjMAXVAL), which does not fail a campaign; within the bound, or with
    no finished plant to show it: the plant's model."""
    stop = Disagreement(Kind.STOPPED, "failed", "c")
    out = Outcome(ran=("a", "b", "c"), disagreements=(stop,))
    task = _task({}, [stop])
    task["interval"] = 0.01
    task["bounds"] = {"a": math.inf, "b": math.inf, "c": 1e10}
    big = {"coordinate": 2e7, "velocity": 5e8, "acceleration": 1.05e10}
    task["default_runs"] = {
        "a": {"status": "timeout", "reached": 0.457},
        "b": {"status": "ok", "reached": 0.5, "largest": big},
        "c": {"status": "stopped", "reached": 0.49},
    }
    st = settle(stop, out, task, "abc")
    assert st.cause is Cause.RANGE and "acceleration 1.05e+10" in st.text, st.text
    task["default_runs"]["b"]["largest"] = {**big, "acceleration": 9e9}
    assert settle(stop, out, task, "abc").cause is Cause.MODEL
    task["default_runs"]["b"] = {"status": "timeout", "reached": 0.45}
    assert settle(stop, out, task, "abc").cause is Cause.MODEL


def test_mujoco_states_its_range():
    import mujoco

    from mj_bridge.plants import MujocoPlant

    assert MujocoPlant.value_bound == mujoco.mjMAXVAL
    assert math.isinf(AnalyticPlant.value_bound)


def test_a_failed_pair_check_names_no_known_culprit():
    data = draw_scene_dict(0, 0, 0.5)
    data["rod"]["offset"] = [0.0, 0.0, 0.0]
    pair = Disagreement(Kind.CHECK, "mujoco_vs_pinocchio.rod_velocities")
    assert recognise(data, data, pair) == ""
    own = Disagreement(Kind.CHECK, "pinocchio.energy")
    assert recognise(data, data, own) == "rod_through_C"


def test_settle_conditioning_rule():
    """A failed check whose value the first plant's own run reproduces to a tenth or more from an
    initial state moved at round-off level: the scene's conditioning, which no settings remove
    and which does not fail a campaign; a perturbation that moves the run far less: not."""
    d = Disagreement(Kind.CHECK, "analytic_vs_mujoco.velocity_C")
    out = Outcome(ran=("a", "b", "c"), checks={d.what: (164.6, 0.07, "FAIL")}, disagreements=(d,))
    task = _task({}, [d], {"a": "plant a over its time limit (30 s)"})
    task["sensitivity"] = {"a": {"velocity_C": 40.0}}
    st = settle(d, out, task, "abc")
    assert st.cause is Cause.CONDITIONING, st.text
    task["sensitivity"] = {"a": {"velocity_C": 1e-6}}
    assert settle(d, out, task, "abc").cause is not Cause.CONDITIONING


def test_perturbed_moves_the_initial_state_at_round_off_level():
    from validation.studies.fuzz.settle import PERTURBATION, perturbed

    data = draw_scene_dict(0, 0, 0.5)
    moved = perturbed(data)
    for key in ("omega", "p", "pdot"):
        a, b = np.array(data["initial"][key]), np.array(moved["initial"][key])
        assert np.all(b - a != 0.0)
        assert np.all(np.abs(b - a) <= 2 * PERTURBATION * np.maximum(1.0, np.abs(a)))
    assert data != moved and scene_from_dict(moved)
