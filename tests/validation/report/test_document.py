"""``report.json``'s fields from a run without a comparison: every field present, the failure
stated, long per-sample engine info left out with its length."""

from __future__ import annotations

import dataclasses

import numpy as np

from analytic.simulate import simulate
from analytic.trajectory import Engine, RunStatus
from validation.report.document import report_document
from validation.report.records import FigureEntry, RunVerdict
from validation.scenes import resolve_scene


def test_a_run_without_a_comparison_has_every_field():
    fig = FigureEntry("control", "No plant produced a sample.")
    doc = report_document(None, [], {"scene": {"name": "s"}}, "no plant ran", [], [fig],
                          RunVerdict.FAILED)  # fmt: skip
    assert doc["verdict"] == "FAILED" and doc["passed"] is False
    assert doc["failure"] == "no plant ran" and doc["checks"] == [] and doc["summaries"] == {}
    assert doc["figures"] == [] and doc["captions"] == {"control": "No plant produced a sample."}
    assert doc["thresholds"] == {} and doc["pairwise"] == {} and doc["referee"] == []
    assert doc["run"] == {"scene": {"name": "s"}}


def test_long_engine_info_is_left_out_with_its_length():
    t = np.linspace(0.0, 1.0, 3)
    tr = _trajectory(t, {"steps": list(range(50)), "nfev": 7})
    doc = report_document(None, [tr], {}, "", [], [], RunVerdict.FAILED)
    (plant,) = doc["plants"]
    assert plant["info"] == {"steps_length": 50, "nfev": 7}
    assert plant["samples"] == 3 and plant["t_reached"] == 1.0
    assert plant["engine"] == Engine.ANALYTIC and plant["status"] == RunStatus.OK.value


def _trajectory(t, info):
    """A short analytic run cut to ``t``'s samples, with ``info`` as its engine info."""
    tr = simulate(resolve_scene("paper_example1"), t_end=0.02, rtol=1e-8)
    return dataclasses.replace(tr, t=t, q=tr.q[: len(t)], info=info)
