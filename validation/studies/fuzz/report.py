"""The campaign's report: ``campaign.md``, ``campaign.json`` (schema ``campaign``) and
``campaign.png``.

The figure has one panel per driver (spin rate, mass ratio, stiffness, n): for every judged scene,
its worst check's value over its threshold against the driver; scenes with a disagreement drawn
apart. ``campaign.json`` carries the provenance block of every machine-read file
(:func:`validation.report.provenance.provenance`, kind ``campaign``).
"""

from __future__ import annotations

import dataclasses
import io
import math
from collections import Counter
from pathlib import Path
from typing import Any

from validation.report.provenance import dumps, provenance
from validation.runs.atomic import write_bytes, write_text
from validation.studies.fuzz.records import CampaignResult
from validation.studies.fuzz.space import drivers

FIGURE = "campaign.png"
DRIVERS = (("spin", "spin rate |ω(0)|, rad/s"), ("mass_ratio", "mass ratio"),
           ("stiffness", "stiffness max k/m, 1/s²"), ("n", "masses n"))


def worst_ratio(checks: dict[str, tuple[float, float, str]]) -> float:
    """The largest value/threshold over a scene's checks (``completed`` aside), 1."""
    r = [v / t for k, (v, t, _s) in checks.items() if not k.endswith("completed") and t > 0]
    return max(r) if r else math.nan


def refusals(res: CampaignResult) -> dict[str, dict[str, int]]:
    """Plant (or ``scene``) -> refusal reason -> scenes."""
    out: dict[str, Counter] = {}
    for rec in res.scenes:
        for who, why in rec.outcome.refused.items():
            out.setdefault(who, Counter())[why] += 1
    return {k: dict(v) for k, v in sorted(out.items())}


def timeouts(res: CampaignResult) -> dict[str, list[int]]:
    """Plant -> the indices of the scenes its run was stopped in at its time limit."""
    out: dict[str, list[int]] = {}
    for rec in res.scenes:
        for who in rec.outcome.timeouts:
            out.setdefault(who, []).append(rec.index)
    return dict(sorted(out.items()))


def pass_rates(res: CampaignResult) -> dict[str, dict[str, int]]:
    """Check label -> {"run": scenes judging it, "passed": scenes passing it}."""
    out: dict[str, dict[str, int]] = {}
    for rec in res.scenes:
        for label, (_v, _t, state) in rec.outcome.checks.items():
            row = out.setdefault(label, {"run": 0, "passed": 0})
            row["run"] += 1
            row["passed"] += state == "pass"
    return dict(sorted(out.items()))


def campaign_doc(res: CampaignResult) -> dict[str, Any]:
    """``campaign.json``'s content."""

    per_plant = Counter(p for rec in res.scenes for p in rec.outcome.ran)
    return {
        "provenance": provenance("campaign"),
        "config": res.config.to_dict(),
        "complete": res.complete,
        "wall_s": res.wall_s,
        "scenes": len(res.scenes),
        "scenes_per_plant": {p: per_plant.get(p, 0) for p in res.config.plants},
        "with_disagreement": sum(bool(r.outcome.disagreements) for r in res.scenes),
        "refused": refusals(res),
        "timeouts": timeouts(res),
        "pass_rates": pass_rates(res),
        "counterexamples": [
            {
                "key": ex.disagreement.key,
                "kind": ex.disagreement.kind.value,
                "what": ex.disagreement.what,
                "plant": ex.disagreement.plant,
                "known": ex.known,
                "file": f"counterexamples/{ex.path.name}",
                "found_in": ex.found_in,
                "occurrences": ex.occurrences,
                "evaluations": ex.evaluations,
                "horizon": ex.horizon,
                "drivers": drivers(ex.data).to_dict(),
                "verdicts": list(ex.outcome.verdicts),
                "command": reproduce(ex, res),
                "settlement": _settlement(ex),
            }
            for ex in res.counterexamples
        ],
        "points": [
            {
                "index": r.index,
                "drivers": drivers(r.data).to_dict(),
                "worst_ratio": _finite(worst_ratio(r.outcome.checks)),
                "disagreements": [d.key for d in r.outcome.disagreements],
            }
            for r in res.scenes
        ],
    }


def _settlement(ex: Any) -> dict[str, Any] | None:
    st = ex.settlement
    if st is None:
        return None
    return {
        "cause": st.cause.value,
        "text": st.text,
        "culprit": st.culprit,
        "own_errors": {
            p: {k: _finite(v) for k, v in q.items()} for p, q in st.own_errors.items()
        },
        "settings": {p: list(v) for p, v in st.settings.items()},
        "tightened_verdicts": list(st.tightened.verdicts),
        "tightened_disagreements": [d.key for d in st.tightened.disagreements],
    }


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def reproduce(ex: Any, res: CampaignResult) -> str:
    """The command that reproduces a counterexample, each plant run within the campaign's
    time limit."""
    return (
        f"tumble validate {res.out_dir / 'counterexamples' / ex.path.name} "
        f"--plants {','.join(res.config.plants)} --t-end {ex.horizon:g} "
        f"--time-limit {res.config.time_limit_s:g}"
    )


def cause(e: dict[str, Any]) -> str:
    """A counterexample's settled cause (``campaign.json``'s ``settlement.cause``), else
    ``unsettled``."""
    return e["settlement"]["cause"] if e["settlement"] else "unsettled"


SECTIONS = (
    ("New findings", "not known, and neither tightened settings, a singular or "
     "ill-conditioned motion nor an engine's range explain them",
     lambda e: not e["known"]
     and cause(e) not in ("settings", "scene", "range", "conditioning")),
    ("Numerical limits of the settings", "gone at tightened settings, or within the plants' "
     "own error estimates at their default settings: the settings, not the model",
     lambda e: not e["known"] and cause(e) == "settings"),
    ("Singular motions", "a plant stops, and every other plant stops or stalls at the same "
     "time: the controlled motion itself ends there (or a disagreement with that plant's "
     "run up to its stop)",
     lambda e: not e["known"] and cause(e) == "scene"),
    ("Beyond an engine's range", "a plant stops where the motion passes the largest value it "
     "carries on with (MuJoCo's mjMAXVAL), while every other plant finishes (or a "
     "disagreement with that plant's run up to its stop)",
     lambda e: not e["known"] and cause(e) == "range"),
    ("Ill-conditioned motions", "the motion amplifies a round-off-sized change of its "
     "initial state into a tenth of the disagreement or more, or a plant stops round-off "
     "limited at its default and tightened settings (a one-ulp change of its state moves a "
     "step by its whole tolerance): beyond what double precision can judge, no two engines "
     "can agree closer", lambda e: not e["known"] and cause(e) == "conditioning"),
    ("Known findings", "", lambda e: bool(e["known"])),
)
"""The sections of the counterexamples, in order: title, what they hold, which belong."""


def campaign_markdown(res: CampaignResult, doc: dict[str, Any]) -> str:
    """``campaign.md``."""
    c = res.config
    lines = [
        "# Differential fuzzing campaign",
        "",
        f"Seed {c.seed}, plants {', '.join(c.plants)}, horizon {c.horizon:g} s: "
        f"{len(res.scenes)} scenes in {res.wall_s:.1f} s"
        + ("" if res.complete else " (interrupted: resume with the same --out)") + ".",
        "",
        "| plant | scenes run |",
        "|---|---|",
        *[f"| {p} | {k} |" for p, k in doc["scenes_per_plant"].items()],
        "",
        "## Refused (by reason)",
        "",
    ]
    if doc["refused"]:
        for who, reasons in doc["refused"].items():
            for why, k in reasons.items():
                lines.append(f"- {who}: {k} × {why}")
    else:
        lines.append("none")
    lines += ["", "## Over the time limit (by plant)", ""]
    if doc["timeouts"]:
        limits = sorted({x for r in res.scenes for x in r.outcome.timeouts.values()})
        lines.append(
            f"A run stopped at its wall-time limit ({', '.join(f'{x:g}' for x in limits)} s): whether "
            "it trips depends on this machine's speed and load, so compare two campaigns on the "
            "scenes neither lists here; everything else follows from the seed."
        )
        lines.append("")
        for who, idx in doc["timeouts"].items():
            lines.append(f"- plant {who}: {len(idx)} × over its time limit (scenes "
                         f"{', '.join(str(i) for i in idx)})")
    else:
        lines.append("none")
    lines += ["", "## Pass rate per check", "", "| check | passed / run |", "|---|---|"]
    lines += [f"| `{k}` | {v['passed']} / {v['run']} |" for k, v in doc["pass_rates"].items()]
    for title, what, keep in SECTIONS:
        lines += ["", f"## {title}", ""]
        if what:
            lines += [f"{what[0].upper()}{what[1:]}.", ""]
        rows = [e for e in doc["counterexamples"] if keep(e)]
        if not rows:
            lines.append("none")
        for e in rows:
            outl = [f"{v['quantity']}: {v['verdict']} {v['outlier']}".strip()
                    for v in e["verdicts"] if v["verdict"] != "agree"]
            dr = e["drivers"]
            lines += [
                f"- **{e['key']}**{' (' + e['known'] + ')' if e['known'] else ''}: in "
                f"{e['occurrences']} scene(s); minimal scene `{e['file']}` (n = {dr['n']}, spin "
                f"{dr['spin']:.3g} rad/s, mass ratio {dr['mass_ratio']:.3g}, stiffness "
                f"{dr['stiffness']:.3g} 1/s², horizon {e['horizon']:g} s)",
                f"  - referee: {'; '.join(outl) if outl else 'no outlier'}",
                f"  - cause: {cause(e)}"
                + (f": {e['settlement']['text']}" if e["settlement"] else ""),
                f"  - reproduce: `{e['command']}`",
            ]
    lines += ["", f"![where the disagreements lie]({FIGURE})", ""]
    return "\n".join(lines)


def campaign_png(doc: dict[str, Any]) -> bytes:
    """The figure: worst check ratio against each driver (module docstring)."""
    # deferred: matplotlib costs ~0.3 s to import (python -X importtime), paid only for the figure
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(16, 4), sharey=True)
    for ax, (key, label) in zip(axes, DRIVERS, strict=True):
        for bad, style in ((False, dict(c="tab:blue", marker="o")), (True, dict(c="tab:red", marker="x"))):
            pts = [(p["drivers"][key], p["worst_ratio"]) for p in doc["points"]
                   if p["worst_ratio"] and bool(p["disagreements"]) is bad]
            if pts:
                x, y = zip(*pts, strict=True)
                ax.scatter(x, y, s=12, label="disagreement" if bad else "agree", **style)
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xlabel(label)
        ax.set_yscale("log")
        if key != "n":
            ax.set_xscale("symlog" if key == "stiffness" else "log")
    axes[0].set_ylabel("worst check value / threshold")
    if axes[0].get_legend_handles_labels()[0]:
        axes[0].legend(loc="best")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    plt.close(fig)
    return buf.getvalue()


def write_campaign(res: CampaignResult) -> CampaignResult:
    """Write the three files into the campaign's directory; the result with ``files`` set."""

    doc = campaign_doc(res)
    out = Path(res.out_dir)
    files = {"md": out / "campaign.md", "json": out / "campaign.json", "png": out / FIGURE}
    write_bytes(files["png"], campaign_png(doc))
    write_text(files["md"], campaign_markdown(res, doc))
    write_text(files["json"], dumps(doc))
    return dataclasses.replace(res, files=files)


__all__ = ["SECTIONS", "campaign_doc", "campaign_markdown", "campaign_png", "cause", "pass_rates",
           "refusals", "timeouts", "worst_ratio", "write_campaign"]
