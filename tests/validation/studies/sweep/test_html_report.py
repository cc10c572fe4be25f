"""``sweep.html``: how the runs ended first (a failed run named, coloured), the figure embedded,
every run in the sortable table, the recording linked, every string text."""

from __future__ import annotations

from pathlib import Path

from tests.support.html_checks import assert_report_page, parse, rows
from validation.studies.sweep import timing
from validation.studies.sweep.config import SweepConfig
from validation.studies.sweep.html_report import RUN_COLUMNS, sweep_html
from validation.studies.sweep.result import SweepResult
from validation.studies.sweep.rows import blank_row

HOSTILE = "<script>alert(1)</script>"
PNG = b"\x89PNG\r\n\x1a\n" + b"\0" * 16


def _row(engine, method, setting, status, error=None, walls=(), note="", rid=0):
    row = blank_row(engine, method, setting, SweepConfig.quick())
    row.update(run_id=rid, status=status, error=error, note=note)
    row.update(timing.summary(list(walls)), at_reference_floor=False, horizon_s=20.0)
    return row


def result(failed: bool = True) -> SweepResult:
    """A sweep's record with an ok, a diverged and (``failed``) a failed run."""
    runs = [
        _row("analytic", "DOP853", 1e-4, "ok", 1e-3, [0.02, 0.01, 0.03], rid=0),
        _row("analytic", "DOP853", 1e-6, "ok", 2.6e-13, [0.05], rid=1),
        _row("mujoco", "Euler", 1e-2, "diverged", 1e3, [0.2], note="error above 1", rid=2),
    ]
    if failed:
        runs.append(_row("mujoco", "implicit", 5e-3, "failed", note="MuJoCo " + HOSTILE, rid=3))
    reference = {
        "max_step": 0.01,
        "nfev": 1000,
        "wall_time_s": 1.5,
        "error_estimate": 1e-13,
        "error_components": {"pos": 1e-13, "att": 1e-14, "rod": 1e-13},
        "cache": {"status": "cached"},
        "R_scale": 1.0,
        "p_scale": 1.0,
    }
    stab = {
        "delta1": 1.0,
        "delta2": 2.0,
        "rtol": 1e-10,
        "initial_norm_error": 1e-3,
        "quat_norm_error_final": 1e-9,
        "quat_norm_error_max": 1e-3,
        "quat_norm_error_at_steps_max": 1e-3,
    }
    return SweepResult(
        scene="scene " + HOSTILE,
        out_dir=Path("."),
        config={},
        reference=reference,
        runs=tuple(runs),
        cheapest={"analytic": {1e-3: 0, 1e-5: 1}, "mujoco": {1e-3: None, 1e-5: None}},
        stabilization=(stab,),
        effects=(),
    )


def test_a_failed_run_is_named_first_and_every_run_is_in_the_table():
    res = result()
    markup = sweep_html(res, SweepConfig.quick(), PNG)
    assert HOSTILE not in markup
    doc = assert_report_page(markup)
    banner = doc.find(id="verdict")[0]
    assert banner.attrs["class"] == "banner fail"
    said = banner.text()
    assert said.startswith("RUNS FAILED") and "2 of 4 runs ok" in said
    assert f"#3 mujoco implicit dt 0.005: failed (MuJoCo {HOSTILE})" in said
    got = rows(doc, "runs")
    assert [int(r[0]) for r in got] == [r["run_id"] for r in res.runs]
    assert len(got[0]) == len(RUN_COLUMNS)
    assert got[1][5] == "2.6e-13" and got[0][-1].startswith("★ 1e-03")
    assert [tr.attrs.get("class") for tr in doc.find("table", id="runs")[0].find("tr")[1:]] == [
        None,
        None,
        "stop",
        "fail",
    ]


def test_the_figure_is_embedded_and_the_recording_linked():
    doc = parse(sweep_html(result(), SweepConfig.quick(), PNG))
    [img] = doc.find("img")
    assert img.attrs["src"].startswith("data:image/png;base64,")
    assert [a.attrs["href"] for a in doc.find("a")] == ["sweep.rrd"]
    assert "rerun sweep.rrd" in doc.text()
    cheapest = rows(doc, "cheapest")
    assert cheapest[0][1].startswith("#0 DOP853 rtol 0.0001") and cheapest[0][2] == "not reached"


def test_a_sweep_without_a_failed_run_is_measured():
    doc = parse(sweep_html(result(failed=False), SweepConfig.quick(), None, None))
    banner = doc.find(id="verdict")[0]
    assert banner.text().startswith("MEASURED") and banner.attrs["class"] == "banner stop"
    assert doc.find("a") == [] and doc.find("img") == []
