"""The text of ``report.md``: one function per section, in the order of :data:`SECTIONS`.

The verdict comes first (after the scene's name), with the reason of a failure or an interruption;
then the pointwise check made before the run, when a plant offered one; then, when there is a
comparison, the count of checks that pass, the referee, the checks, the
summaries over time; then the figures with their captions (a figure that was not drawn is named
with the reason), the thresholds and the run's metadata. Every string a scene or an error message
brings is escaped to literal text on one line (:func:`validation.report.md_text.md_literal`).

A new section is a function ``(page: Page) -> list[str]`` (its lines, each blank line included;
none when it has nothing to say) and one entry of :data:`SECTIONS`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from analytic.threshold import BoundPart
from validation.compare.checks import Check, CheckState, Comparison
from validation.compare.referee import Verdict, rule_text, summary_lines
from validation.compare.summary import check_sentence
from validation.report.figures import FigureFormat
from validation.report.md_text import fenced_json, fmt_number, md_cell, md_literal
from validation.report.records import FigureEntry, RunVerdict, SeriesSummary


@dataclass(frozen=True)
class Page:
    """What ``report.md`` is written from (:func:`render_markdown`'s arguments).

    Attributes:
        cmp: the comparison, or None when the run failed before one could be made.
        verdict: the run's verdict.
        failure: why the run failed or stopped ("" when it did not).
        figures: every figure's entry, drawn or not.
        meta: the run's metadata (scene, plants, referee note, redone stages ...).
        verdicts: the referee's rulings.
        code: the sentence naming the code that ran ("" when unknown).
    """

    cmp: Comparison | None
    verdict: RunVerdict
    failure: str
    figures: Sequence[FigureEntry]
    meta: Mapping[str, Any]
    verdicts: Sequence[Verdict] = ()
    code: str = ""


def _bound_cell(c: Check) -> str:
    """Which part of a check's threshold decided: ``absolute``, ``relative (1e-07 × 1.6e+03)``
    (rtol × the quantity's scale, in the check's unit), or "" for a threshold without a relative
    part."""
    if not c.applicable or c.relative_part <= 0 or not c.magnitude:
        return ""
    if c.decided_by is BoundPart.RELATIVE:
        return f"relative ({c.relative_part / c.magnitude:.3g} × {c.magnitude:.3g})"
    return "absolute"


def _state_cell(c: Check) -> str:
    """A check's verdict cell: ``pass``, ``**FAIL**`` or ``not applicable``."""
    state = c.state
    return "**FAIL**" if state is CheckState.FAIL else state.value


def heading(page: Page) -> list[str]:
    """``# scene: VERDICT``, then the failure and every stage redone."""
    cmp, meta = page.cmp, page.meta
    scene = meta.get("scene", {}).get("name", cmp.scene if cmp else "?")
    lines = [f"# {md_literal(scene)}: {page.verdict.value}", ""]
    if page.failure:
        lines += [f"**The run {page.verdict.stopped()}:** {md_literal(page.failure)}", ""]
    for again in meta.get("redone", ()):
        lines += [f"**Redone:** {md_literal(again)}", ""]
    return lines


def pointwise(page: Page) -> list[str]:
    """The pointwise check made before the run (``meta["pointwise"]``, when a plant offered one):
    each finding's sentence, the plants not checked, then each plant's largest differences per
    case against their bounds."""
    pw = page.meta.get("pointwise")
    if not pw:
        return []
    lines = ["## Pointwise check before the run", ""]
    findings = pw.get("findings", [])
    lines.append(
        f"q̈ of each plant that offers it, at the initial state and {pw.get('states', 1) - 1} "
        f"random states (seed {pw.get('seed', 0)}), against MuJoCo C's and the analytic "
        "model's (float64), the bound that of the plant's precision: "
        + (f"{len(findings)} finding(s)." if findings else "no finding.")
    )
    lines.append("")
    lines += [f"- **{md_literal(f['plant'])}:** {md_literal(f['text'])}" for f in findings]
    lines += [f"- {md_literal(x)}" for x in pw.get("not_checked", [])]
    if findings or pw.get("not_checked"):
        lines.append("")
    rows = [(p, c) for p in pw.get("plants", []) for c in p.get("cases", []) if c.get("bounds")]
    if rows:
        lines += [
            "| plant | precision | case | max vs MuJoCo C | max vs analytic | "
            "MuJoCo C vs analytic | least bound | verdict |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for p, c in rows:
            over = any(
                max(m, a) > b
                for m, a, b in zip(c["vs_mujoco"], c["vs_analytic"], c["bounds"], strict=True)
            )
            lines.append(
                f"| {md_cell(p['plant'])} | {md_cell(p['precision'])} | {md_cell(c['case'])} | "
                f"{fmt_number(max(c['vs_mujoco']))} | {fmt_number(max(c['vs_analytic']))} | "
                f"{fmt_number(max(c['mujoco_vs_analytic']))} | {fmt_number(min(c['bounds']))} | "
                f"{'**differs**' if over else 'agrees'} |"
            )
        lines += [
            "",
            "Relative differences: max |q̈_a − q̈_b| / max |q̈_b| at a state, over its "
            "coordinates [R, u, p]. A state's bound is its precision's least bound, raised "
            "where MuJoCo C and the analytic model differ by more than that at float64 "
            "(POINTWISE_MARGIN); no integration has happened, so a difference is one of model.",
            "",
        ]
    return lines


def outcome(page: Page) -> list[str]:
    """How many checks pass (and why the others do not apply), every failed check, the notes."""
    cmp = page.cmp
    if cmp is None:
        return []
    lines = []
    bad = cmp.failed_checks
    total = len(cmp.applicable_checks)
    idle: dict[str, list[str]] = {}  # why -> the checks that do not apply for that reason
    for c in cmp.checks:
        if not c.applicable:
            idle.setdefault(c.reason, []).append(c.label)
    also = (
        " Not applicable: "
        + "; ".join(
            f"{', '.join(map(md_literal, who))} ({md_literal(why)})" for why, who in idle.items()
        )
        + "."
        if idle
        else ""
    )
    lines.append(f"{total - len(bad)} of {total} checks pass." + also + (" Failed:" if bad else ""))
    for c in bad:
        lines.append(f"- {md_cell(check_sentence(c))}")
    lines.append("")
    for n in cmp.notes:
        lines.append(f"> {md_literal(n)}")
    if cmp.notes:
        lines.append("")
    return lines


def _outliers_explained(verdicts: Sequence[Verdict], meta: Mapping[str, Any]) -> list[str]:
    """For each outlier that the pointwise check compared before the run, one sentence tying the
    two together: its model differed (and where, when found), or its model agreed and the
    difference grew in the integration (in its precision's arithmetic when that is not float64)."""
    pw = meta.get("pointwise") or {}
    found: dict[str, Mapping[str, Any]] = {}
    for f in pw.get("findings", []):
        if f.get("vs_mujoco", 0.0) > f.get("bound", 0.0):  # a departure from MuJoCo C itself
            found.setdefault(f["plant"], f)
    checked = {p["plant"]: p for p in pw.get("plants", [])}
    counts: dict[str, int] = {}
    for v in verdicts:
        for o in v.outliers:
            counts[o.plant] = counts.get(o.plant, 0) + 1
    out = []
    for plant, k in counts.items():
        head = f"why {plant} is the outlier ({k} quantit{'y' if k == 1 else 'ies'}): its q̈ "
        f = found.get(plant)
        if f is not None:
            where = f"; the difference is in {f['cause']}" if f.get("cause") else ""
            out.append(
                f"{head}already differed from MuJoCo C's by {f['vs_mujoco']:.1e} relative at "
                f"{f['state']} before the run (the pointwise check): the models differ, not "
                f"the integration{where}"
            )
        elif plant in checked and not any(x["plant"] == plant for x in pw.get("findings", [])):
            p = checked[plant]
            worst = max(
                (max(c["vs_mujoco"]) for c in p.get("cases", []) if c.get("vs_mujoco")),
                default=0.0,
            )
            how = (
                "its step and scheme"
                if p["precision"] == "float64"
                else f"its {p['precision']} arithmetic, its step and scheme"
            )
            out.append(
                f"{head}agreed with MuJoCo C's to {worst:.1e} relative at every state before the "
                f"run (the pointwise check, bound {p['threshold']:.1e} in {p['precision']}): the "
                f"models agree; the difference grew in the integration ({how})"
            )
    return out


def referee_lines(verdicts: Sequence[Verdict], meta: Mapping[str, Any]) -> list[str]:
    """The referee's section: one sentence per quantity, then the pairwise table."""
    if not verdicts:
        note = meta.get("referee_note", "")
        return ["## Referee", "", f"No referee verdict: {md_literal(note)}.", ""] if note else []
    lines = ["## Referee", ""]
    plants = meta.get("plants", [])
    if plants:
        lines += ["Plants: " + "; ".join(md_literal(p["settings"]) for p in plants) + ".", ""]
    if meta.get("referee_note"):  # a plant of the run's set left out (it refused the scene)
        lines += [f"Note: {md_literal(meta['referee_note'])}.", ""]
    lines += [f"- {md_literal(t)}" for t in summary_lines(verdicts)]
    lines += [f"- {md_literal(t)}" for t in _outliers_explained(verdicts, meta)]
    pairs = list(dict.fromkeys(p for v in verdicts for p in v.values))
    lines += [
        "",
        "| quantity | "
        + " | ".join(md_cell(p) for p in pairs)
        + " | threshold | noise floor | floor set by | unit | verdict | decided by |",
        "|---|" + "---|" * (len(pairs) + 6),
    ]
    for v in verdicts:
        cells = " | ".join(fmt_number(v.values.get(p, math.nan)) for p in pairs)
        who = v.kind.value
        if v.outliers:  # each outlier with its distance to the group
            who += ": " + ", ".join(f"{o.plant} ({fmt_number(o.distance)})" for o in v.outliers)
        elif v.groups:
            who += ": " + " vs ".join(", ".join(g) for g in v.groups)
        by = v.clause.value if v.clause else "–"
        set_by = v.floor_set_by.value if v.floor_set_by else "–"
        lines.append(
            f"| {md_cell(v.quantity)} | {cells} | {fmt_number(v.threshold)} | "
            f"{fmt_number(v.floor)} | {md_cell(set_by)} | {md_cell(v.unit)} | {md_cell(who)} | "
            f"{md_cell(by)} |"
        )
    lines += ["", rule_text(), ""]
    return lines


def referee(page: Page) -> list[str]:
    """The referee's rulings (:func:`referee_lines`), when there is a comparison."""
    return referee_lines(page.verdicts, page.meta) if page.cmp is not None else []


def checks(page: Page) -> list[str]:
    """Every check: value, threshold, which part of it decided, unit, verdict, when."""
    cmp = page.cmp
    if cmp is None:
        return []
    lines = [
        "## Checks",
        "",
        "| check | value | threshold | threshold set by | unit | verdict | at t (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in cmp.checks:
        lines.append(
            f"| {md_cell(c.label)} | {fmt_number(c.value)} | {fmt_number(c.threshold)} | "
            f"{_bound_cell(c)} | {md_cell(c.unit)} | {_state_cell(c)} | {fmt_number(c.t_max)} |"
        )
    lines += [
        "",
        "Relative checks are divided by the scale of the signal (see report.json). The "
        "states' and tracking laws' thresholds are the absolute part plus rtol × the "
        "quantity's largest magnitude over the run across the compared plants; *threshold set "
        "by* names the larger part (empty without a relative part). A "
        "`completed` check's value is the time the plant reached, its threshold the horizon.",
        "",
    ]
    return lines


def series_summaries(page: Page) -> list[str]:
    """Every series over time: its largest magnitude and when, RMS, final value."""
    cmp = page.cmp
    if cmp is None:
        return []
    lines = [
        "## Summaries over time",
        "",
        "| quantity | of | max \\|x\\| | t of max \\|x\\| (s) | RMS | final | unit |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in cmp.series:
        m = SeriesSummary.of(s)
        lines.append(
            f"| {md_cell(s.label)} | {s.subject.value} | {fmt_number(m.max_abs)} | "
            f"{fmt_number(m.t_max_abs)} | {fmt_number(m.rms)} | {fmt_number(m.final)} | "
            f"{md_cell(s.unit)} |"
        )
    lines += [
        "",
        "max |x| is the largest magnitude over time: of a signed quantity (a rod force) its "
        "largest absolute value; the vector quantities (|R_a − R_m|, |τ|, ...) are Euclidean "
        "norms ‖·‖₂, so max |τ| is max ‖τ‖₂. final is the last value, with its sign.",
        "",
    ]
    return lines


def figure_entries(page: Page) -> list[str]:
    """The Figures section: each drawn figure embedded (PNG if written, else its first file) with
    its numbered caption below; each figure not drawn named with its reason."""
    if not page.figures:
        return []
    lines = ["## Figures", ""]
    number = 0
    for f in page.figures:
        if not f.files:
            lines += [
                f"*No {md_literal(f.name)} figure.* {md_literal(f.caption)}",
                "",
            ]
            continue
        number += 1
        shown = next((x for x in f.files if x.endswith(f".{FigureFormat.PNG.value}")), f.files[0])
        also = [x for x in f.files if x != shown]
        lines += [
            f"![Figure {number}: {f.name}]({shown})",
            "",
            f"*Figure {number} (`{shown}`).* {md_literal(f.caption)}"
            + (f" Also as {', '.join(f'[{x}]({x})' for x in also)}." if also else ""),
            "",
        ]
    return lines


def thresholds(page: Page) -> list[str]:
    """Every threshold: value (and its relative part), unit, source, reason."""
    cmp = page.cmp
    lines = ["## Thresholds", ""]
    if cmp is not None:
        lines += ["| name | value | unit | source | reason |", "|---|---|---|---|---|"]
        for th in cmp.thresholds.values():
            kind = " (relative)" if th.relative else ""
            if th.rtol:
                kind = f" + {th.rtol:g} × scale"
            lines.append(
                f"| {md_cell(th.name)} | {th.value:g}{kind} | {md_cell(th.unit)} | "
                f"{md_cell(th.source)} | {md_cell(th.reason)} |"
            )
        lines.append("")
    return lines


def run(page: Page) -> list[str]:
    """The code that ran, then the run's metadata as a fenced JSON block."""
    lines = ["## Run", ""]
    if page.code:
        lines += [md_literal(page.code), ""]
    meta = {k: v for k, v in page.meta.items() if k != "pointwise"}  # its own section
    lines += ["```json", fenced_json(meta), "```", ""]
    return lines


SECTIONS: tuple[Callable[[Page], list[str]], ...] = (
    heading,
    pointwise,
    outcome,
    referee,
    checks,
    series_summaries,
    figure_entries,
    thresholds,
    run,
)
"""The sections of ``report.md``, in order."""


def render_markdown(
    cmp: Comparison | None,
    verdict: RunVerdict | str,
    failure: str,
    figures: Sequence[FigureEntry],
    meta: Mapping[str, Any],
    verdicts: Sequence[Verdict] = (),
    code: str = "",
) -> str:
    """The text of ``report.md``: every section of :data:`SECTIONS` in turn (after ``code``, the
    sentence naming the code that ran, :meth:`validation.report.provenance.CodeOrigin.sentence`)."""
    verdict = RunVerdict(getattr(verdict, "value", verdict))
    page = Page(cmp, verdict, failure, figures, meta, verdicts, code)
    return "\n".join(line for section in SECTIONS for line in section(page))


__all__ = ["SECTIONS", "Page", "referee_lines", "render_markdown"]
