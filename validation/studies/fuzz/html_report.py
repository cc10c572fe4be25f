"""``campaign.html``: the fuzzing campaign for a browser, from the same records as ``campaign.md``
(the :class:`~validation.studies.fuzz.records.CampaignResult` and ``campaign.json``'s content,
:func:`validation.studies.fuzz.report.campaign_doc`), one self-contained file
(:mod:`validation.report.html_page`).

The verdict first: FAILED when a finding is new (not known, and neither the settings, the motion
nor an engine's range explain it), each named with the plant the referee blames; PASSED
otherwise; INTERRUPTED (amber) when the campaign stopped before its budget. Then every
counterexample as a sortable table (its section, the plant blamed and why: the referee's
rulings and the settled cause, where it occurred, its drivers, a link to its minimal scene; then
each one's settlement in words and the command that reproduces it), the pass rate of each check, the refusals and time-outs, and the
figure embedded. Every string from a scene or a plant is escaped.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from validation.report.html_page import (
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
    raw,
    relative_link,
    section,
    state,
    table,
    text,
)
from validation.studies.fuzz.records import CampaignResult
from validation.studies.fuzz.report import SECTIONS, cause

HTML_NAME = "campaign.html"
NEW = SECTIONS[0][0]
"""The title of the section whose findings fail the campaign."""


def section_of(e: Mapping[str, Any]) -> str:
    """The title of the section of ``campaign.md`` a counterexample is listed in."""
    return next(title for title, _what, keep in SECTIONS if keep(e))


def referee_words(e: Mapping[str, Any]) -> str:
    """The referee's rulings other than agree (``quantity: outlier mujoco``), or why there are
    none."""
    if not e["verdicts"]:
        return "no ruling (the referee rules on three plants or more)"
    said = [
        f"{v['quantity']}: {v['verdict']} {v['outlier']}".strip()
        for v in e["verdicts"]
        if v["verdict"] != "agree"
    ]
    return "; ".join(said) or "all agree"


def blamed(e: Mapping[str, Any]) -> str:
    """The plants blamed: the referee's outliers, the culprit the settlement named, else the
    plant the disagreement is about."""
    who = [v["outlier"] for v in e["verdicts"] if v["verdict"] != "agree" and v["outlier"]]
    st = e.get("settlement") or {}
    if st.get("culprit"):
        who.append(st["culprit"])
    if not who and e.get("plant"):
        who.append(e["plant"])
    return ", ".join(dict.fromkeys(who)) or "none named"


def banner(res: CampaignResult, doc: Mapping[str, Any]) -> Banner:
    """The verdict, the campaign in one line, how many findings each section holds, and every
    new finding with the plant blamed."""
    c = res.config
    found = [(section_of(e), e) for e in doc["counterexamples"]]
    new = [e for title, e in found if title == NEW]
    per = {title: sum(t == title for t, _ in found) for title, _what, _keep in SECTIONS}
    lines = [
        f"Seed {c.seed}, plants {', '.join(c.plants)}, horizon {c.horizon:g} s: "
        f"{len(res.scenes)} scenes in {res.wall_s:.1f} s, {doc['with_disagreement']} with a "
        "disagreement"
        + ("" if res.complete else " (interrupted: resume with the same --out)")
        + ".",
        "Findings: " + "; ".join(f"{k} {title.lower()}" for title, k in per.items()) + ".",
    ]
    failed = [
        f"{e['key']}: blamed {blamed(e)}; referee: {referee_words(e)}; in {e['occurrences']} "
        f"scene(s); cause {cause(e)}"
        for e in new
    ]
    if new:
        word, tone = "FAILED", Tone.FAIL
    elif not res.complete:
        word, tone = "INTERRUPTED", Tone.STOP
    else:
        word, tone = "PASSED", Tone.PASS
    return Banner(word, tone, lines, failed)


FINDING_COLUMNS = (
    Column("finding"),
    Column("section"),
    Column("blamed"),
    Column("referee"),
    Column("cause"),
    Column("scenes", True),
    Column("n", True),
    Column("spin rad/s", True),
    Column("mass ratio", True),
    Column("stiffness 1/s²", True),
    Column("horizon s", True),
    Column("minimal scene"),
)
"""The columns of the table of counterexamples."""


def finding_row(e: Mapping[str, Any]) -> Row:
    """One counterexample: where it is listed, who is blamed and why, its drivers, its scene."""
    title = section_of(e)
    dr = e["drivers"]
    tone = Tone.FAIL if title == NEW else Tone.IDLE
    known = f" ({e['known']})" if e["known"] else ""
    return Row(
        [
            text(e["key"] + known),
            state(title, tone),
            text(blamed(e)),
            text(referee_words(e)),
            text(cause(e)),
            num(e["occurrences"]),
            num(dr["n"]),
            num(dr["spin"]),
            num(dr["mass_ratio"]),
            num(dr["stiffness"]),
            num(e["horizon"], "s"),
            raw(relative_link(e["file"])),
        ],
        tone.value if title == NEW else "",
    )


def details(doc: Mapping[str, Any]) -> str:
    """Each counterexample's settlement in words and the command that reproduces it."""
    items = []
    for e in doc["counterexamples"]:
        st = e.get("settlement")
        why = f"{cause(e)}: {st['text']}" if st else cause(e)
        items.append(
            f"<li><b>{esc(e['key'])}</b> ({esc(section_of(e))}). Cause {esc(why)}. "
            f"Reproduce: <code>{esc(e['command'])}</code></li>"
        )
    return '<ul class="details">' + "".join(items) + "</ul>" if items else ""


def pass_rates(doc: Mapping[str, Any]) -> str:
    """Each check: the scenes that judged it and passed it, and the rate."""
    rows = []
    for k, v in doc["pass_rates"].items():
        rate = v["passed"] / v["run"] if v["run"] else float("nan")
        tone = Tone.PASS if v["passed"] == v["run"] else Tone.FAIL
        rows.append(
            Row(
                [text(k), num(v["passed"]), num(v["run"]), num(rate)],
                "" if tone is Tone.PASS else tone.value,
            )
        )
    cols = ["check", Column("passed", True), Column("run", True), Column("pass rate", True)]
    return section("Pass rate per check", table("pass-rates", cols, rows), section_id="checks")


def refused_and_timeouts(doc: Mapping[str, Any]) -> str:
    """The refusals by reason, the runs over the time limit by plant."""
    refused = [f"{who}: {k} × {why}" for who, rs in doc["refused"].items() for why, k in rs.items()]
    slow = [
        f"plant {who}: {len(idx)} × over its time limit (scenes {', '.join(map(str, idx))})"
        for who, idx in doc["timeouts"].items()
    ]
    return section(
        "Refused and over the time limit",
        para("Refused (by reason):"),
        bullets(refused) or para("none"),
        para("Over the time limit (machine-dependent):"),
        bullets(slow) or para("none"),
        section_id="refused",
    )


def campaign_html(res: CampaignResult, doc: Mapping[str, Any], png: bytes | None) -> str:
    """The text of ``campaign.html`` (``png``: the figure's bytes, embedded; None: none)."""
    findings = [finding_row(e) for e in doc["counterexamples"]]
    runs = [[text(p), num(k)] for p, k in doc["scenes_per_plant"].items()]
    body = [
        section(
            "Counterexamples",
            para(
                "Each minimal scene the shrinker kept, with the plant the referee blames and the "
                "cause the settlement found (docs/fuzzing.md). Click a heading to sort.",
                "note",
            ),
            table("findings", FINDING_COLUMNS, findings) if findings else para("none"),
            details(doc),
            section_id="counterexamples",
        ),
        pass_rates(doc),
        section("Scenes per plant", table("plants", ["plant", Column("scenes run", True)], runs)),
        refused_and_timeouts(doc),
        section(
            "Where the disagreements lie",
            figure(
                "campaign",
                png,
                "png",
                "Worst check value over its threshold against each "
                "driver; red: a scene with a disagreement.",
            )
            if png
            else "",
            section_id="figure",
        )
        if png
        else "",
    ]
    return page("Differential fuzzing campaign", banner(res, doc), [b for b in body if b])


__all__ = [
    "FINDING_COLUMNS",
    "HTML_NAME",
    "banner",
    "blamed",
    "campaign_html",
    "finding_row",
    "referee_words",
    "section_of",
]
