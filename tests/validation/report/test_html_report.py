"""``report.html``: from the records ``report.md`` is written from; the verdict and every failed
check before the tables, every check in the sortable table with its threshold beside it, the
referee's outlier named, the figures embedded, the recording linked, every scene string text."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.support.html_checks import assert_report_page, headers, parse, rows
from validation.compare.checks import Check, Comparison, Group, Series
from validation.compare.referee import Clause, Outlier, Verdict, VerdictKind
from validation.compare.subject import Subject
from validation.report.html_report import CHECK_COLUMNS, render_html
from validation.report.markdown import Page
from validation.report.records import FigureEntry, RunVerdict
from validation.report.report import write_report

HOSTILE = "<script>alert(1)</script>"
PNG = b"\x89PNG\r\n\x1a\n" + b"\0" * 16
PAIR = Subject.pair("analytic", "mujoco")


def _comparison() -> Comparison:
    t = np.linspace(0.0, 1.0, 5)
    checks = (
        Check("position_C", PAIR, 5e-5, 1.2e-6, "m", False, "a reason " + HOSTILE, t_max=0.8),
        Check("attitude", PAIR, 2.6e-13, 1e-6, "rad", True, "r", t_max=0.4),
        Check("control_torque", PAIR, math.nan, 1e-6, "1", True, "no torque", applicable=False),
        Check("energy", Subject("mujoco"), 8.2e-11, 1e-8, "1", True, "r", t_max=1.0),
    )
    series = (
        Series("diff.position_C", "position of C " + HOSTILE, "m", Group.DIFFERENCE, PAIR, t, t),
    )
    return Comparison("s", t, series, checks, notes=("a note",))


def _verdict() -> Verdict:
    return Verdict(
        "position_C",
        VerdictKind.OUTLIER,
        "mujoco",
        "mujoco is the outlier on position_C (" + HOSTILE + ")",
        values={"analytic vs mujoco": 5e-5, "analytic vs pinocchio": 1e-12},
        unit="m",
        threshold=1.2e-6,
        clause=Clause.SEPARATED,
        floor=1e-8,
        outliers=(Outlier("mujoco", 5e-5),),
    )


def _page(**kw) -> Page:
    meta = {"scene": {"name": HOSTILE}, "plants": [{"settings": "mujoco " + HOSTILE}]}
    figures = [
        FigureEntry("errors", "the errors " + HOSTILE, ("errors.png", "errors.pdf")),
        FigureEntry("control", "No control: " + HOSTILE),
    ]
    args = dict(
        cmp=_comparison(),
        verdict=RunVerdict.FAILED,
        failure="",
        figures=figures,
        meta=meta,
        verdicts=(_verdict(),),
        code="code " + HOSTILE,
    )
    return Page(**(args | kw))


def test_the_verdict_and_the_failed_check_come_before_every_table():
    doc = assert_report_page(render_html(_page(), {"errors.png": PNG}, "run.rrd"))
    banner = doc.find(id="verdict")[0]
    assert banner.attrs["class"] == "banner fail"
    said = banner.text()
    assert said.startswith("FAILED") and "2 of 3 checks pass" in said and "position_C" in said


def test_every_check_is_in_the_table_with_its_threshold_beside_it():
    p = _page()
    doc = parse(render_html(p, {}, None))
    assert headers(doc, "checks") == [c.name for c in CHECK_COLUMNS]
    got = rows(doc, "checks")
    assert [r[0] for r in got] == [c.label for c in p.cmp.checks]
    by = {r[0]: r for r in got}
    assert by["position_C"][1:4] == ["5.0e-05", "1.2e-06", "41.7"]
    assert by["position_C"][6] == "FAIL" and by["attitude"][6] == "pass"
    assert by["control_torque"][6] == "not applicable" and by["control_torque"][1] == "–"
    [table] = doc.find("table", id="checks")
    tr = table.find("tbody")[0].find("tr")
    assert [r.attrs.get("class") for r in tr] == ["fail", "pass", "idle", "pass"]
    value = tr[1].find("td")[1]
    assert float(value.attrs["data-v"]) == 2.6e-13 and value.attrs["title"] == "2.6e-13 rad"


def test_the_referee_names_the_plant_it_blames_and_why():
    doc = parse(render_html(_page(), {}, None))
    section = doc.find(id="referee-verdicts")[0]
    assert "mujoco is the outlier on position_C (" + HOSTILE + ")" in section.text()
    [row] = rows(doc, "referee")
    assert row[0] == "position_C" and "outlier: mujoco" in row[-2] and row[-1] == "separated"


def test_figures_are_embedded_and_the_recording_linked():
    doc = parse(render_html(_page(), {"errors.png": PNG}, "run.rrd"))
    [img] = doc.find("img")
    assert img.attrs["src"].startswith("data:image/png;base64,")
    hrefs = [a.attrs["href"] for a in doc.find("a")]
    assert hrefs == ["run.rrd", "errors.png", "errors.pdf"]
    assert "rerun run.rrd" in doc.text()
    assert "No control figure. No control: " + HOSTILE in doc.text()
    no_recording = parse(render_html(_page(), {}, None))
    assert "run.rrd" not in [a.attrs["href"] for a in no_recording.find("a")]


def test_every_scene_string_is_text():
    markup = render_html(_page(), {"errors.png": PNG}, "run.rrd")
    doc = parse(markup)
    assert len(doc.find("script")) == 1 and HOSTILE not in markup
    assert doc.find("h1")[0].text() == f"{HOSTILE}: FAILED"
    [pre] = doc.find("pre")
    assert json.loads(pre.text())["scene"]["name"] == HOSTILE


@pytest.mark.parametrize("verdict", [RunVerdict.PASSED, RunVerdict.INTERRUPTED])
def test_a_run_without_a_comparison_says_what_it_has(verdict):
    p = _page(cmp=None, verdict=verdict, failure="stopped " + HOSTILE, verdicts=())
    doc = assert_report_page(render_html(p, {}, None))
    banner = doc.find(id="verdict")[0]
    assert banner.text().startswith(verdict.value) and HOSTILE in banner.text()
    assert doc.find("table", id="checks") == []


def test_write_report_writes_report_html_beside_report_md(tmp_path):
    files = write_report(tmp_path, None, [], {"scene": {"name": HOSTILE}}, failure="no run")
    assert files.html == tmp_path / "report.html"
    doc = assert_report_page(files.html.read_text(encoding="utf-8"))
    assert doc.find(id="verdict")[0].text().startswith("FAILED")
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # atomic: no temp left
