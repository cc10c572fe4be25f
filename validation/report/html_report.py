"""``report.html``: the validation report for a browser, from the same records as ``report.md``
(:class:`validation.report.markdown.Page`), one self-contained file
(:mod:`validation.report.html_page`).

In order: the verdict banner (PASSED / FAILED / INTERRUPTED, the failure, every failed check, the
stages redone), the link to the recording with the command that opens it, the pointwise check
made before the run (when a plant offered one), the referee's rulings (which plant is the outlier
and why), every check as a sortable table (value with its threshold beside it, their ratio, the
part of the threshold that decided, pass/fail in colour), the summaries over time, the figures
embedded, the thresholds, and the run's metadata. Every string from a scene or an error is escaped.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

from validation.compare.checks import Check, CheckState
from validation.compare.referee import Verdict, rule_text, summary_lines
from validation.compare.summary import check_sentence
from validation.report.figures import FigureFormat
from validation.report.html_page import (
    MIME,
    Banner,
    Column,
    Row,
    Tone,
    bullets,
    esc,
    figure,
    num,
    page,
    para,
    recording,
    relative_link,
    section,
    state,
    table,
    text,
)
from validation.report.markdown import Page, _outliers_explained
from validation.report.md_text import jsonable
from validation.report.records import FigureEntry, RunVerdict, SeriesSummary

HTML_NAME = "report.html"

_TONES = {RunVerdict.PASSED: Tone.PASS, RunVerdict.FAILED: Tone.FAIL}
_CHECK_TONES = {CheckState.PASS: Tone.PASS, CheckState.FAIL: Tone.FAIL}


def scene_name(p: Page) -> str:
    """The scene's name as the report gives it."""
    return str(p.meta.get("scene", {}).get("name", p.cmp.scene if p.cmp else "?"))


def banner(p: Page) -> Banner:
    """The verdict, the failure, the count of checks that pass and each failed check."""
    lines: list[str] = []
    if p.failure:
        lines.append(f"The run {p.verdict.stopped()}: {p.failure}")
    failed: list[str] = []
    if p.cmp is not None:
        total = len(p.cmp.applicable_checks)
        bad = p.cmp.failed_checks
        lines.append(f"{total - len(bad)} of {total} checks pass." + (" Failed:" if bad else ""))
        failed = [check_sentence(c) for c in bad]
    lines += [f"Redone: {x}" for x in p.meta.get("redone", ())]
    return Banner(p.verdict.value, _TONES.get(p.verdict, Tone.STOP), lines, failed)


def pointwise(p: Page) -> str:
    """The pointwise check before the run: each finding, the plants not checked."""
    pw = p.meta.get("pointwise")
    if not pw:
        return ""
    found = [f"{f['plant']}: {f['text']}" for f in pw.get("findings", [])]
    rows = []
    for pl in pw.get("plants", []):
        for c in pl.get("cases", []):
            if not c.get("bounds"):
                continue
            over = any(
                max(m, a) > b
                for m, a, b in zip(c["vs_mujoco"], c["vs_analytic"], c["bounds"], strict=True)
            )
            rows.append(
                Row(
                    [
                        text(pl["plant"]),
                        text(pl["precision"]),
                        text(c["case"]),
                        num(max(c["vs_mujoco"])),
                        num(max(c["vs_analytic"])),
                        num(max(c["mujoco_vs_analytic"])),
                        num(min(c["bounds"])),
                        state("differs" if over else "agrees", Tone.FAIL if over else Tone.PASS),
                    ],
                    Tone.FAIL.value if over else "",
                )
            )
    cols = [
        "plant",
        "precision",
        "case",
        Column("max vs MuJoCo C", True),
        Column("max vs analytic", True),
        Column("MuJoCo C vs analytic", True),
        Column("least bound", True),
        "verdict",
    ]
    return section(
        "Pointwise check before the run",
        para(f"{len(found)} finding(s)." if found else "No finding."),
        bullets([*found, *pw.get("not_checked", [])]),
        table("pointwise", cols, rows) if rows else "",
        section_id="pointwise-check",
    )


def _who(v: Verdict) -> str:
    """The ruling's kind with whom it blames: each outlier and its distance, or the groups."""
    who = v.kind.value
    if v.outliers:
        who += ": " + ", ".join(f"{o.plant} ({o.distance:.2g})" for o in v.outliers)
    elif v.groups:
        who += ": " + " vs ".join(", ".join(g) for g in v.groups)
    return who


def referee(p: Page) -> str:
    """The referee's rulings: who is blamed and why (sentences), then the table per quantity."""
    if p.cmp is None:
        return ""
    note = str(p.meta.get("referee_note", ""))
    if not p.verdicts:
        return section("Referee", para(f"No referee verdict: {note}.")) if note else ""
    parts = []
    plants = p.meta.get("plants", [])
    if plants:
        parts.append(para("Plants: " + "; ".join(str(x.get("settings", "")) for x in plants)))
    if note:
        parts.append(para(f"Note: {note}."))
    parts.append(bullets([*summary_lines(p.verdicts), *_outliers_explained(p.verdicts, p.meta)]))
    pairs = list(dict.fromkeys(k for v in p.verdicts for k in v.values))
    cols = [
        "quantity",
        *(Column(x, True) for x in pairs),
        Column("threshold", True),
        Column("noise floor", True),
        "floor set by",
        "unit",
        "verdict",
        "decided by",
    ]
    rows = []
    for v in p.verdicts:
        agree = v.kind.value == "agree"
        rows.append(
            Row(
                [
                    text(v.quantity),
                    *(num(v.values.get(x, math.nan), v.unit) for x in pairs),
                    num(v.threshold, v.unit),
                    num(v.floor, v.unit),
                    text(v.floor_set_by.value if v.floor_set_by else "–"),
                    text(v.unit),
                    state(_who(v), Tone.PASS if agree else Tone.FAIL),
                    text(v.clause.value if v.clause else "–"),
                ],
                "" if agree else Tone.FAIL.value,
            )
        )
    rule = rule_text().replace("`", "").replace("*", "")  # Markdown's marks, not text here
    parts += [
        table("referee", cols, rows),
        f"<details><summary>The referee's rule</summary>{para(rule, 'note')}</details>",
    ]
    return section("Referee", *parts, section_id="referee-verdicts")


def _decided(c: Check) -> str:
    if not c.applicable or c.relative_part <= 0 or not c.magnitude:
        return ""
    if c.decided_by.value == "relative":
        return f"relative ({c.relative_part / c.magnitude:.3g} × {c.magnitude:.3g})"
    return "absolute"


def check_row(c: Check) -> Row:
    """A check: its label, value and threshold side by side, their ratio, what decided, unit,
    verdict, when."""
    st = c.state
    ratio = c.value / c.threshold if c.applicable and c.threshold else math.nan
    return Row(
        [
            text(c.label),
            num(c.value, c.unit),
            num(c.threshold, c.unit),
            num(ratio),
            text(_decided(c)),
            text(c.unit),
            state(st.value, _CHECK_TONES.get(st, Tone.IDLE)),
            num(c.t_max, "s"),
        ],
        _CHECK_TONES.get(st, Tone.IDLE).value,
    )


CHECK_COLUMNS = (
    Column("check"),
    Column("value", True),
    Column("threshold", True),
    Column("value / threshold", True),
    Column("threshold set by"),
    Column("unit"),
    Column("verdict"),
    Column("at t (s)", True),
)
"""The columns of the checks table, in order."""


def checks(p: Page) -> str:
    """Every check, sortable (a click on a header; ``value / threshold`` finds the closest)."""
    if p.cmp is None:
        return ""
    return section(
        "Checks",
        table("checks", CHECK_COLUMNS, [check_row(c) for c in p.cmp.checks]),
        para(
            "A check passes when its value is at most its threshold. The states' and tracking "
            "laws' thresholds are the absolute part plus rtol × the quantity's largest magnitude "
            "over the run; 'threshold set by' names the larger part. A 'completed' check's value "
            "is the time the plant reached, its threshold the horizon. Click a heading to sort; "
            "hover a number for its exact value.",
            "note",
        ),
        section_id="all-checks",
    )


def summaries(p: Page) -> str:
    """Every series over time: its largest magnitude and when, RMS, final value."""
    if p.cmp is None:
        return ""
    rows = []
    for s in p.cmp.series:
        m = SeriesSummary.of(s)
        rows.append(
            [
                text(s.label),
                text(s.subject.value),
                num(m.max_abs, s.unit),
                num(m.t_max_abs, "s"),
                num(m.rms, s.unit),
                num(m.final, s.unit),
                text(s.unit),
            ]
        )
    cols = [
        "quantity",
        "of",
        Column("max |x|", True),
        Column("t of max |x| (s)", True),
        Column("RMS", True),
        Column("final", True),
        "unit",
    ]
    return section(
        "Summaries over time", table("summaries", cols, rows), section_id="series-summaries"
    )


def shown_file(f: FigureEntry) -> str | None:
    """The file of a figure the page embeds: its PNG, else its SVG; None when it has neither."""
    png = next((x for x in f.files if x.endswith(f".{FigureFormat.PNG.value}")), None)
    return png or next((x for x in f.files if Path(x).suffix[1:] in MIME), None)


def figures(entries: Sequence[FigureEntry], images: Mapping[str, bytes]) -> str:
    """Each figure embedded (its PNG, else its SVG) with its caption; a figure in no embeddable
    format linked; a figure not drawn named with its reason."""
    if not entries:
        return ""
    parts = []
    for f in entries:
        shown = shown_file(f)
        if not f.files:
            parts.append(para(f"No {f.name} figure. {f.caption}", "note"))
        elif shown is not None and shown in images:
            parts.append(figure(f.name, images[shown], Path(shown).suffix[1:], f.caption))
        else:
            parts.append(para(f"{f.name}: {f.caption}"))
        links = [relative_link(x) for x in f.files]
        if links:
            parts.append(f'<p class="note">Files: {", ".join(links)}</p>')
    return section("Figures", *parts, section_id="figures")


def thresholds(p: Page) -> str:
    """Every threshold: value (and its relative part), unit, source, reason."""
    if p.cmp is None or not p.cmp.thresholds:
        return ""
    rows = []
    for th in p.cmp.thresholds.values():
        rel = f"+ {th.rtol:g} × scale" if th.rtol else ("relative" if th.relative else "")
        rows.append(
            [
                text(th.name),
                num(th.value, th.unit),
                text(rel),
                text(th.unit),
                text(th.source),
                text(th.reason),
            ]
        )
    cols = ["name", Column("value", True), "relative part", "unit", "source", "reason"]
    return section("Thresholds", table("thresholds", cols, rows), section_id="threshold-list")


def run_block(p: Page) -> str:
    """The code that ran and the run's metadata (JSON, folded)."""
    meta = {k: v for k, v in p.meta.items() if k != "pointwise"}
    body = json.dumps(jsonable(meta), indent=2)
    return section(
        "Run",
        para(p.code) if p.code else "",
        f"<details><summary>Metadata (JSON)</summary><pre>{esc(body)}</pre></details>",
        section_id="run",
    )


def render_html(
    p: Page, images: Mapping[str, bytes] | None = None, recording_file: str | None = None
) -> str:
    """The text of ``report.html`` for the report ``p``: ``images`` maps a figure's file name to
    its bytes (the figures to embed), ``recording_file`` names the recording beside the report
    (None: there is none)."""
    body = [
        recording(recording_file) if recording_file else "",
        pointwise(p),
        referee(p),
        checks(p),
        summaries(p),
        figures(p.figures, images or {}),
        thresholds(p),
        run_block(p),
    ]
    return page(f"{scene_name(p)}: {p.verdict.value}", banner(p), [b for b in body if b])


def figure_images(directory: Path, entries: Sequence[FigureEntry]) -> dict[str, bytes]:
    """The bytes of each figure file in ``directory`` a page embeds (PNG, SVG), by file name."""
    out = {}
    for f in entries:
        name = shown_file(f)
        if name is not None and Path(name).name == name:  # a file beside the report, no path
            out[name] = (directory / name).read_bytes()
    return out


__all__ = ["CHECK_COLUMNS", "HTML_NAME", "check_row", "figure_images", "render_html", "shown_file"]
