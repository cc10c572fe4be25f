"""Faults the fuzzer's judging and settling must not turn into a model finding against a plant
(docs/verdicts.md, the fault table's last section)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from validation.studies.fuzz.judge import (
    NON_FINITE,
    Disagreement,
    Kind,
    PlantRun,
    outcome_of,
    prepare,
)
from validation.studies.fuzz.settle import Cause, settle
from validation.studies.fuzz.space import draw_scene_dict

PLANTS = ("analytic", "mujoco", "pinocchio")


def test_a_plant_that_reports_a_non_finite_run_finished_is_stopped_not_a_model_outlier():
    """A plant returns a run it says finished with a NaN coordinate -> the fuzzer's judge records
    that plant stopped (non-finite, with a message saying so), and the referee's outliers on that
    run are settled unsettled, never a model finding."""
    data = draw_scene_dict(0, 0, 0.1)
    scene, _refused, chosen = prepare(data, ["analytic"], 0.1)
    tr = chosen[0][1].simulate(scene, None, t_end=0.1)
    q = np.array(tr.q)
    q[-1, 0] = np.nan
    runs = [PlantRun("analytic", tr, 0.0),
            PlantRun("mujoco", dataclasses.replace(tr, q=q, engine="mujoco"), 0.0),
            PlantRun("pinocchio", dataclasses.replace(tr, engine="pinocchio"), 0.0)]
    out = outcome_of(scene, 0.1, {}, runs)
    assert Disagreement(Kind.STOPPED, NON_FINITE, "mujoco") in out.disagreements
    assert "non-finite" in out.messages["mujoco"]
    outliers = [d for d in out.disagreements if d.kind is Kind.OUTLIER and d.plant == "mujoco"]
    assert outliers  # the referee names it, at an infinite distance
    task = {
        "own_errors": {p: {"position_C": 0.0, "rod_positions": 0.0} for p in ("analytic",
                                                                           "pinocchio")},
        "settings": {p: [f"{p} default", f"{p} tight"] for p in PLANTS},
        "untightened": {},
        "tightened": out.to_dict(),
        "default_runs": {"analytic": {"status": "ok", "reached": 0.1,
                                      "largest": {"coordinate": 1.0}},
                         "pinocchio": {"status": "ok", "reached": 0.1,
                                       "largest": {"coordinate": 1.0}},
                         "mujoco": {"status": "stopped", "reached": 0.1}},
        "bounds": {"analytic": math.inf, "mujoco": 1e10, "pinocchio": math.inf},
        "interval": 0.01,
        "sensitivity": {},
    }
    for d in outliers:
        st = settle(d, out, task, PLANTS)
        assert st.cause is Cause.UNSETTLED and "cut short" in st.text, st.text
