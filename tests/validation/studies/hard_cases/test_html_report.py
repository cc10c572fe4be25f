"""``hard_cases.html``: the verdict and every failing case before the tables, each plant's verdict
per case, every check with its bound beside it, scene strings as text, written beside
``hard_cases.md`` by the suite's writer."""

from __future__ import annotations

from tests.support.html_checks import assert_report_page, parse, rows
from validation.compare.checks import Subject, judge
from validation.studies.hard_cases.html_report import (
    CHECK_COLUMNS,
    HTML_NAME,
    hard_cases_html,
    write_all,
)
from validation.studies.hard_cases.table import HardCaseRow, HardCaseTable, Verdict

HOSTILE = "<script>alert(1)</script>"


def _table(complete: bool = True) -> HardCaseTable:
    checks = (
        judge("invariants", Subject.ANALYTIC, 1e-12, 1e-10, "1", "r", bound="hard_invariant_rel"),
        judge("invariants", Subject.MUJOCO, 1e-9, 1e-10, "1", "r", bound="hard_invariant_rel"),
        judge("position_C", Subject.BOTH, 1e-9, 1e-6, "m", "r", bound="hard_agreement_abs"),
    )
    failing = HardCaseRow(
        case="stiff" + HOSTILE,
        criterion="criterion " + HOSTILE,
        plants=("analytic", "mujoco", "pinocchio"),
        figures={"analytic": {"invariants": 1e-12}, "mujoco": {"invariants": 1e-9}},
        not_applicable={"pinocchio": "Pinocchio cannot " + HOSTILE},
        checks=checks,
        verdict=Verdict.FAIL,
        wall_time_s=1.5,
        notes=("a note " + HOSTILE,),
    )
    passing = HardCaseRow(
        case="calm",
        criterion="c",
        plants=("analytic", "mujoco", "pinocchio"),
        figures={},
        checks=checks[:1],
        verdict=Verdict.PASS,
        wall_time_s=0.2,
        not_applicable={"mujoco": "n", "pinocchio": "n"},
    )
    return HardCaseTable(
        (failing, passing),
        complete,
        "" if complete else "1 case still to run",
        ("analytic", "mujoco", "pinocchio"),
    )


def test_the_verdict_and_the_failing_case_come_first():
    doc = assert_report_page(hard_cases_html(_table()))
    banner = doc.find(id="verdict")[0]
    assert banner.attrs["class"] == "banner fail"
    said = banner.text()
    assert said.startswith("FAILED") and "1 of 2 cases passed" in said
    assert f"stiff{HOSTILE}: FAIL: mujoco.invariants = 1.000e-09 1 > 1.0e-10" in said


def test_every_check_of_every_case_is_in_the_table():
    tb = _table()
    doc = parse(hard_cases_html(tb))
    got = rows(doc, "checks")
    assert [(r[0], r[2]) for r in got] == [(x.case, c.label) for x in tb.rows for c in x.checks]
    assert len(got[0]) == len(CHECK_COLUMNS)
    by = {(r[0], r[2]): r for r in got}
    bad = by[(f"stiff{HOSTILE}", "mujoco.invariants")]
    assert bad[3:6] == ["1.0e-09", "1.0e-10", "10"] and bad[-1] == "FAIL"
    cases = {r[0]: r for r in rows(doc, "cases")}
    assert cases[f"stiff{HOSTILE}"][2:6] == [
        "PASS",
        "FAIL",
        f"n/a: Pinocchio cannot {HOSTILE}",
        "FAIL",
    ]


def test_an_incomplete_suite_says_so_and_scene_strings_are_text():
    markup = hard_cases_html(_table(complete=False))
    assert HOSTILE not in markup
    doc = assert_report_page(markup)
    assert "INCOMPLETE: 1 case still to run" in doc.find(id="verdict")[0].text()
    assert len(doc.find("script")) == 1
    assert f"note: a note {HOSTILE}" in doc.find(id="case-notes")[0].text()


def test_the_writer_puts_the_page_beside_the_markdown(tmp_path):
    write_all(_table(), tmp_path)
    assert {p.name for p in tmp_path.iterdir()} == {"hard_cases.md", "hard_cases.json", HTML_NAME}
    assert_report_page((tmp_path / HTML_NAME).read_text(encoding="utf-8"))
