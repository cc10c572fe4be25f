"""``sweep.html``: the sweep for a browser, from the same record as ``sweep.md``
(:class:`validation.studies.sweep.result.SweepResult` and its
:class:`~validation.studies.sweep.config.SweepConfig`), one self-contained file
(:mod:`validation.report.html_page`).

A sweep measures what accuracy costs; it has no thresholds to pass. Its verdict is how its runs
ended: every run ``ok`` (or cut as too slow, or skipped after its series stopped) is a sweep that
measured what it set out to; a run that failed is named first, a diverged or degraded one too
(the banner's colour: failed red, diverged or degraded amber). Then the link to ``sweep.rrd``, the
work-precision figure embedded with its caption, the cheapest setting per accuracy level, every
run (sortable: error, drifts, wall time ...), the stabilisation study and the reference.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from typing import Any

from validation.report.html_page import (
    Banner,
    Column,
    Row,
    Tone,
    figure,
    num,
    page,
    para,
    recording,
    section,
    state,
    table,
    text,
)
from validation.studies.sweep.config import ENGINES, FLOOR_FACTOR, Outcome, SweepConfig
from validation.studies.sweep.markdown import (
    _cheapest_cell,
    figure_caption,
    reference_origin,
    skipped_note,
)
from validation.studies.sweep.result import SweepResult

HTML_NAME = "sweep.html"
RECORDING = "sweep.rrd"

TONES = {
    Outcome.OK: Tone.PASS,
    Outcome.FAILED: Tone.FAIL,
    Outcome.DIVERGED: Tone.STOP,
    Outcome.DEGRADED: Tone.STOP,
    Outcome.TOO_SLOW: Tone.IDLE,
    Outcome.SKIPPED: Tone.IDLE,
}
"""The colour of each way a run ends."""

NOT_OK = (Outcome.FAILED, Outcome.DIVERGED, Outcome.DEGRADED)
"""The endings the banner names run by run."""


def _setting(r: Mapping[str, Any]) -> str:
    return f"{r['engine']} {r['method']} {r['setting_name']} {r['setting']:.3g}"


def banner(res: SweepResult) -> Banner:
    """How many runs are ok, how the others ended, and each failed, diverged or degraded run."""
    counts = Counter(str(r["status"]) for r in res.runs)
    ok = counts.get(Outcome.OK.value, 0)
    rest = ", ".join(f"{k} {s}" for s, k in counts.items() if s != Outcome.OK.value)
    lines = [
        f"{ok} of {len(res.runs)} runs ok" + (f"; {rest}" if rest else "") + ".",
        *(skipped_note(e, why) + "." for e, why in res.skipped_series.items()),
    ]
    bad = [r for r in res.runs if r["status"] in NOT_OK]
    failed = [
        f"#{r['run_id']} {_setting(r)}: {r['status']}" + (f" ({r['note']})" if r["note"] else "")
        for r in bad
    ]
    if any(r["status"] == Outcome.FAILED for r in bad):
        tone, word = Tone.FAIL, "RUNS FAILED"
    elif bad:
        tone, word = Tone.STOP, "MEASURED"  # a diverged run is a measurement, named
    else:
        tone, word = Tone.PASS, "MEASURED"
    return Banner(word, tone, lines, failed)


def reference(res: SweepResult) -> str:
    """The reference: its solver, cost and estimated error, and where it came from."""
    ref = res.reference
    comp = ref.get("error_components", {})
    return section(
        "Reference",
        para(
            f"Analytic engine, DOP853, steps capped at {ref['max_step']:.3g} s: {ref['nfev']} "
            f"evaluations, {ref['wall_time_s']:.3g} s. Estimated error {ref['error_estimate']:.2e} "
            f"(position {comp.get('pos', float('nan')):.2e}, attitude "
            f"{comp.get('att', float('nan')):.2e} rad, rod {comp.get('rod', float('nan')):.2e}); "
            f"runs within {FLOOR_FACTOR:g}x of it are marked 'floor'. "
            + reference_origin(ref.get("cache", {}))
        ),
        section_id="reference",
    )


def cheapest(res: SweepResult, cfg: SweepConfig) -> str:
    """The cheapest setting per accuracy level and plant (the words of ``sweep.md``)."""
    columns = list(res.cheapest) + [e for e in res.skipped_series if e not in res.cheapest]
    est = float(res.reference["error_estimate"])
    out = []
    for lv in cfg.levels:
        cells = [num(lv)]
        for engine in columns:
            rid = res.cheapest.get(engine, {}).get(lv)
            if engine in res.skipped_series:
                cells.append(state("series skipped", Tone.IDLE))
            elif lv <= FLOOR_FACTOR * est:
                cells.append(state("below the reference's resolution", Tone.IDLE))
            elif rid is None:
                cells.append(state("not reached", Tone.IDLE))
            else:
                cells.append(text(_cheapest_cell(res.runs, rid, lv)))
        out.append(cells)
    return section(
        "Cheapest setting per accuracy level",
        para(
            "The ok run of least median wall time whose error reaches the level, with its "
            "timings; named the cheapest only when its timings rank it."
        ),
        table("cheapest", [Column("level", True), *columns], out),
        section_id="cheapest-settings",
    )


RUN_COLUMNS = (
    Column("#", True),
    Column("engine"),
    Column("method"),
    Column("setting"),
    Column("status"),
    Column("error (max)", True),
    Column("error (final)", True),
    Column("max e_u", True),
    Column("L bal.", True),
    Column("E bal.", True),
    Column("track ω (final)", True),
    Column("wall ms", True),
    Column("n", True),
    Column("nfev", True),
    Column("steps", True),
    Column("note"),
)
"""The columns of the table of every run."""


def run_row(r: Mapping[str, Any], stars: list[float]) -> Row:
    """One run: its setting, how it ended, its errors, drifts, wall time and costs."""
    status = Outcome(r["status"])
    wall = r["wall_time_s"]
    note = " ".join(
        x
        for x in (
            ("★ " + ", ".join(f"{lv:.0e}" for lv in stars)) if stars else "",
            "floor" if r["at_reference_floor"] else "",
            str(r["note"] or ""),
        )
        if x
    )
    return Row(
        [
            num(r["run_id"]),
            text(r["engine"]),
            text(r["method"]),
            text(f"{r['setting_name']} {r['setting']:.3g}"),
            state(status.value, TONES[status]),
            num(r["error"]),
            num(r["error_final"]),
            num(r["quat_norm_error_max"]),
            num(r["angular_momentum_balance_rel"]),
            num(r["energy_balance_rel"]),
            num(r["tracking_omega_final"], "rad/s"),
            num(None if wall is None else wall * 1e3, "ms", 3),
            num(r["wall_time_repeats"]),
            num(r["nfev"]),
            num(r["nsteps"]),
            text(note),
        ],
        TONES[status].value if status in NOT_OK else "",
    )


def every_run(res: SweepResult) -> str:
    """Every run of the grid, sortable; ★ the cheapest for the levels listed."""
    marked: dict[int, list[float]] = {int(r["run_id"]): [] for r in res.runs}
    for by_level in res.cheapest.values():
        for lv, rid in by_level.items():
            if rid is not None:
                marked[int(rid)].append(lv)
    rows = [run_row(r, marked[int(r["run_id"])]) for r in res.runs]
    return section(
        "Every run",
        para(
            "★ marks the cheapest run for the levels listed. Drift columns: max |uᵀu − 1| (e_u), "
            "the relative angular-momentum and energy balances. Wall: the median over n "
            "timings. Click a heading to sort; hover a number for its exact value.",
            "note",
        ),
        table("runs", RUN_COLUMNS, rows),
        section_id="every-run",
    )


def stabilisation(res: SweepResult) -> str:
    """The (δ1, δ2) study of the quaternion norm."""
    if not res.stabilization:
        return ""
    cols = [Column(x, True) for x in ("δ1", "δ2", "rtol", "φ(0)", "φ(T)", "max |φ|", "at steps")]
    rows = [
        [
            num(s["delta1"]),
            num(s["delta2"]),
            num(s["rtol"]),
            num(s["initial_norm_error"]),
            num(s["quat_norm_error_final"]),
            num(s["quat_norm_error_max"]),
            num(s["quat_norm_error_at_steps_max"]),
        ]
        for s in res.stabilization
    ]
    return section(
        "Stabilisation (δ1, δ2) and the quaternion norm",
        para("φ = uᵀu − 1 obeys φ̈ + δ1 φ̇ + δ2 φ = 0 (Eq. 58); it decays only when δ1, δ2 > 0."),
        table("stabilisation", cols, rows),
        section_id="stabilisation-study",
    )


def sweep_html(
    res: SweepResult, cfg: SweepConfig, png: bytes | None, recording_file: str | None = RECORDING
) -> str:
    """The text of ``sweep.html`` (``png``: the work-precision figure's bytes, embedded;
    ``recording_file``: the recording beside it, None when there is none)."""
    ran = [e for e in ENGINES if any(r["engine"] == e for r in res.runs)]
    caption = figure_caption(res, cfg).replace("**", "")
    body = [
        recording(recording_file) if recording_file else "",
        section(
            "Work-precision",
            figure("work-precision", png, "png", caption) if png else para(caption),
            section_id="work-precision",
        ),
        cheapest(res, cfg),
        every_run(res),
        stabilisation(res),
        reference(res),
        para(
            f"Horizon {cfg.t_end:g} s; plants {', '.join(ran)}. The cost of each effect is in "
            "sweep.md and sweep.json.",
            "note",
        ),
    ]
    return page(f"What accuracy costs in time: {res.scene}", banner(res), [b for b in body if b])


__all__ = ["HTML_NAME", "RECORDING", "RUN_COLUMNS", "TONES", "banner", "run_row", "sweep_html"]
