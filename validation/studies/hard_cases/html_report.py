"""``hard_cases.html``: the hard-case table for a browser, from the same record as
``hard_cases.md`` (:class:`validation.studies.hard_cases.table.HardCaseTable`), one
self-contained file (:mod:`validation.report.html_page`).

In order: the verdict banner (PASSED / FAILED, INCOMPLETE with why when the suite stopped early;
every case that did not pass with its failed checks or its error), the cases (a plant's verdict
per column, sortable), every check of every case (value beside its bound, their ratio, pass / FAIL
/ not judgeable in colour, sortable), then each case's reported figures and notes. Every string
from a scene file or an error is escaped.
"""

from __future__ import annotations

import math
from pathlib import Path

from validation.report.html_page import (
    Banner,
    Column,
    Row,
    Tone,
    bullets,
    esc,
    num,
    page,
    para,
    section,
    state,
    table,
    text,
)
from validation.runs.atomic import write_text
from validation.studies.hard_cases.measures import label
from validation.studies.hard_cases.table import (
    HardCaseRow,
    HardCaseTable,
    Verdict,
    _cell_verdict,
    owner,
    write_table,
)

HTML_NAME = "hard_cases.html"

TONES = {
    Verdict.PASS: Tone.PASS,
    Verdict.FAIL: Tone.FAIL,
    Verdict.ERROR: Tone.FAIL,
    Verdict.NA: Tone.IDLE,
    Verdict.NOT_JUDGEABLE: Tone.IDLE,
}
"""The colour of each verdict."""


def banner(tb: HardCaseTable) -> Banner:
    """PASSED or FAILED, how many cases passed, the plants, and each case that did not pass."""
    passed = sum(r.passed for r in tb.rows)
    lines = [
        f"{passed} of {len(tb.rows)} cases passed"
        + ("" if tb.complete else f"; INCOMPLETE: {tb.message}")
        + ".",
        "Plants: "
        + ", ".join(label(e) for e in tb.plants)
        + "."
        + "".join(
            f" {label(e)} was not run: not installed ({why})."
            for e, why in tb.not_installed.items()
        ),
    ]
    failed = []
    for r in tb.rows:
        if r.passed:
            continue
        what = r.error or "; ".join(
            f"{c.label} = {c.value:.3e} {c.unit} > {c.threshold:.1e}" for c in r.failed_checks()
        )
        failed.append(f"{r.case}: {r.verdict.value}" + (f": {what}" if what else ""))
    tone = Tone.PASS if tb.passed else Tone.FAIL
    if not tb.complete and all(r.passed for r in tb.rows):
        tone = Tone.STOP  # stopped early, nothing failed
    return Banner("PASSED" if tb.passed else "FAILED", tone, lines, failed)


def cases_table(tb: HardCaseTable) -> str:
    """One row per case: its criterion, each plant's verdict, the case's verdict, its wall time."""
    cols = [
        "case",
        "criterion",
        *(label(e) for e in tb.plants),
        "verdict",
        Column("wall s", True),
    ]
    out = []
    for r in tb.rows:
        cells = []
        for e in tb.plants:
            v = r.plant_verdict(e)
            if v is Verdict.NA:
                cells.append(state(f"n/a: {r.not_applicable[e]}", Tone.IDLE))
            elif r.verdict is Verdict.ERROR:
                cells.append(state(v.value, Tone.FAIL))
            else:
                cells.append(state(_cell_verdict(r, e, v), TONES[v]))
        out.append(
            Row(
                [
                    text(r.case),
                    text(r.criterion),
                    *cells,
                    state(r.verdict.value, TONES[r.verdict]),
                    num(r.wall_time_s, "s"),
                ],
                TONES[r.verdict].value,
            )
        )
    return table("cases", cols, out)


CHECK_COLUMNS = (
    Column("case"),
    Column("plant"),
    Column("check"),
    Column("value", True),
    Column("bound", True),
    Column("value / bound", True),
    Column("bound name"),
    Column("unit"),
    Column("verdict"),
)
"""The columns of the table of every check."""


def check_rows(r: HardCaseRow) -> list[Row]:
    """The case's checks: a check below its plant's round-off is ``not judgeable at float32``."""
    unjudged = {x.check: x for x in r.not_judgeable}
    out = []
    for c in r.checks:
        if c.label in unjudged:
            word, tone = f"not judgeable at {unjudged[c.label].precision.value}", Tone.IDLE
        else:
            word, tone = ("ok", Tone.PASS) if c.passed else ("FAIL", Tone.FAIL)
        completed = c.name.startswith("completed")
        ratio = c.value / c.threshold if c.threshold and not completed else math.nan
        out.append(
            Row(
                [
                    text(r.case),
                    text(label(owner(c))),
                    text(c.label),
                    num(c.value, c.unit),
                    num(c.threshold, c.unit),
                    num(ratio),
                    text("horizon" if completed else (c.bound or "must be 0")),
                    text(c.unit),
                    state(word, tone),
                ],
                tone.value,
            )
        )
    return out


def notes(tb: HardCaseTable) -> str:
    """Per case: its error, where it does not apply, its reported figures and its notes."""
    parts = []
    for r in tb.rows:
        items = [f"error: {r.error}"] if r.error else []
        items += [f"{label(e)}: not applicable: {why}" for e, why in r.not_applicable.items()]
        items += [x.reason for x in r.not_judgeable]
        items += [
            f"reported: {x.plant}.{x.name} = {x.value:.3e} {x.unit} ({x.why})" for x in r.reported
        ]
        items += [f"note: {n}" for n in r.notes]
        if items:
            parts += [f"<h3>{esc(r.case)}</h3>", bullets(items)]
    return section("Notes per case", *parts, section_id="case-notes") if parts else ""


def hard_cases_html(tb: HardCaseTable) -> str:
    """The text of ``hard_cases.html``."""
    every = [row for r in tb.rows for row in check_rows(r)]
    body = [
        section("Cases", cases_table(tb), section_id="case-list"),
        section(
            "Checks",
            table("checks", CHECK_COLUMNS, every),
            para(
                "A check passes when its value is at most its bound ('must be 0': a count of "
                "events that must not happen; 'horizon': the run reached it). A bound below the "
                "plant's floating-point round-off for the quantity is not judgeable at that "
                "precision: neither a pass nor a FAIL (docs/hard_cases.md). Click a heading to "
                "sort; hover a number for its exact value.",
                "note",
            ),
            section_id="all-checks",
        ),
        notes(tb),
    ]
    word = "PASSED" if tb.passed else "FAILED"
    return page(f"Hard cases: {word}", banner(tb), [b for b in body if b])


def write_html(tb: HardCaseTable, out_dir: str | Path) -> Path:
    """``hard_cases.html`` in ``out_dir``, atomically."""
    return write_text(Path(out_dir) / HTML_NAME, hard_cases_html(tb))


def write_all(tb: HardCaseTable, out_dir: str | Path) -> None:
    """``hard_cases.md``, ``hard_cases.json`` (:func:`~validation.studies.hard_cases.table.write_table`)
    and ``hard_cases.html``, each atomically."""
    write_table(tb, out_dir)
    write_html(tb, out_dir)


__all__ = [
    "CHECK_COLUMNS",
    "HTML_NAME",
    "TONES",
    "banner",
    "check_rows",
    "hard_cases_html",
    "write_all",
    "write_html",
]
