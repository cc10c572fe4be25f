"""``sweep.md``: the reference, the plants, the cheapest setting per level, every run, the
stabilisation study, the cost of each effect, and the work-precision figure with its caption.

:func:`sweep_markdown` with ``image=None`` is the same text for the recording, where the figure is
a view of the recording itself, not a link to a PNG file the viewer cannot open.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from validation.studies.effects_cost import effects_markdown
from validation.studies.sweep.accelerated import floors, floors_markdown, grid_words
from validation.studies.sweep.config import (
    ANALYTIC,
    ENGINES,
    FLOOR_FACTOR,
    MJWARP,
    MJX,
    MUJOCO,
    PINOCCHIO,
    REFERENCE_ATOL,
    REFERENCE_RTOL,
    Outcome,
    SweepConfig,
)
from validation.studies.sweep.metrics import ERROR_MEASURE
from validation.studies.sweep.result import SweepResult
from validation.studies.sweep.selection import ranking

FIGURE_FILE = "work_precision.png"
VIEW_NAME = "work-precision"
"""Name of the work-precision view in ``sweep.rrd`` (the text of the recording refers to it)."""


def fmt(v: Any, spec: str = ".3g") -> str:
    """A table cell: ``–`` for None, yes/blank for booleans, floats by ``spec``."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else ""
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return format(v, spec)
    return str(v)


def skipped_note(engine: str, reason: str) -> str:
    """The sentence ``sweep.md`` gives for a plant whose series were skipped."""
    if engine == PINOCCHIO:
        return f"Pinocchio series skipped: pin is not installed ({reason})"
    return f"{engine} series skipped: {reason}"


def _scipy_grid(cfg: SweepConfig) -> str:
    rtols = ", ".join(f"{r:.0e}" for r in cfg.rtols)
    return f"scipy {', '.join(cfg.solvers)} over rtol {rtols} (atol = {cfg.atol_ratio:g} rtol)"


def _mujoco_grid(cfg: SweepConfig) -> str:
    dts = ", ".join(f"{d:.3g}" for d in cfg.dts) + " s" if cfg.dts else "none"
    return f"{', '.join(cfg.integrators)} over dt {dts}"


def _settings_words(cfg: SweepConfig) -> dict[str, str]:
    return {
        MJX: grid_words(cfg, MJX),
        MJWARP: grid_words(cfg, MJWARP),
        ANALYTIC: f"the paper's model, {_scipy_grid(cfg)}",
        MUJOCO: f"the MJCF twin, {_mujoco_grid(cfg)}",
        PINOCCHIO: "the same body in Pinocchio (`pin.aba`), the same scipy solvers and rtol grid "
        "as the analytic engine, through the plant protocol",
    }


def _timing_words(cfg: SweepConfig, workers: int | None) -> str:
    where = (
        f"in the sweep's {workers} worker processes, {workers} runs at a time"
        if workers
        else "in the executor the sweep was given"
    )
    if cfg.repeats > 1:
        how = (
            "the first timing of a setting is its accuracy run, and a setting is timed again "
            f"while it has fewer than {cfg.repeats} timings and they add up to less than "
            f"{cfg.repeat_budget_s:g} s; the median is reported, with the fastest and slowest"
        )
    else:
        how = (
            "each setting is timed once, by its accuracy run (no repeats: the timings' spread is "
            "not measured)"
        )
    return (
        "Wall time: the integration only, as the engine measures it, after an untimed warm-up run "
        f"of each series; {how}. Runs are timed {where}."
    )


def reference_origin(cache: Mapping[str, Any]) -> str:
    """Where the reference came from, in one sentence (``cache``: the reference's cache record,
    whose ``status`` is ``cached`` or says why it was computed)."""
    status = str(cache.get("status", ""))
    if status == "cached":
        return "Read from the cache (computed by an earlier sweep of the same scene, horizon and code)."
    why = status.removeprefix("computed").strip().strip("()").strip()
    return f"Computed by this sweep ({why or 'not cached'})."


def _count_words(mine: Sequence[Mapping[str, Any]]) -> str:
    """``20/20 runs ok`` and, when any, how many were degraded."""
    ok = sum(r["status"] == Outcome.OK for r in mine)
    degraded = sum(r["status"] == Outcome.DEGRADED for r in mine)
    words = f"{ok}/{len(mine)} runs ok"
    if degraded:
        words += f", {degraded} degraded (MuJoCo dropped a control for a step; see the note)"
    return words


def _plants(cfg: SweepConfig, runs: Sequence[Mapping[str, Any]], skipped: Mapping[str, str]):
    """One bullet per plant: its series, or why they were skipped."""
    what = _settings_words(cfg)
    out = []
    for e in ENGINES:
        if e in skipped:
            out.append(f"- **{e}**: {skipped_note(e, skipped[e])}.")
            continue
        mine = [r for r in runs if r["engine"] == e]
        if not mine:
            continue
        out.append(f"- **{e}**: {what[e]}; {_count_words(mine)}.")
    out += [
        "",
        "Every plant is measured against the same reference (the analytic engine's), with the same "
        f"error measure, the same timing rules and the same budget per run ({cfg.max_run_wall_s:g} "
        "s: a run over it is stopped, one predicted to pass it is not started, and the rest of its "
        "series is skipped). A series also ends at its first run at the reference's floor.",
    ]
    return out


def _pinocchio_vs_analytic(runs: Sequence[Mapping[str, Any]]) -> list[str]:
    """The two scipy plants side by side at each solver and rtol they both ran."""
    a = {(r["method"], r["rtol"]): r for r in runs if r["engine"] == ANALYTIC}
    pairs = [
        (a[(r["method"], r["rtol"])], r)
        for r in runs
        if r["engine"] == PINOCCHIO and (r["method"], r["rtol"]) in a
    ]
    if not pairs:
        return []
    L = [
        "",
        "## Pinocchio and the analytic engine at the same setting",
        "",
        "Same solver, rtol and atol; errors against the same reference.",
        "",
        "| method | rtol | analytic error | Pinocchio error | analytic ms | Pinocchio ms | "
        "wall ratio | analytic nfev | Pinocchio nfev |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for ra, rp in pairs:
        wa, wp = ra["wall_time_s"], rp["wall_time_s"]
        ratio = wp / wa if wa and wp and ra["status"] == rp["status"] == Outcome.OK else None
        L.append(
            f"| {rp['method']} | {rp['rtol']:.0e} | "
            f"{fmt(ra['error'], '.2e') if ra['status'] == Outcome.OK else ra['status']} | "
            f"{fmt(rp['error'], '.2e') if rp['status'] == Outcome.OK else rp['status']} | "
            f"{fmt(None if wa is None else wa * 1e3, '.3g')} | "
            f"{fmt(None if wp is None else wp * 1e3, '.3g')} | {fmt(ratio, '.2f')} | "
            f"{fmt(ra['nfev'])} | {fmt(rp['nfev'])} |"
        )
    return L


def _ms_span(r: Mapping[str, Any]) -> str:
    """``15.4 ms (14.9–16.0 ms, 3 timings)``, or ``15.4 ms (1 timing)``."""
    n = int(r.get("wall_time_repeats") or 1)
    w = r["wall_time_s"] * 1e3
    if n < 2 or r.get("wall_time_min_s") is None:
        return f"{w:.3g} ms (1 timing)"
    return (
        f"{w:.3g} ms ({r['wall_time_min_s'] * 1e3:.3g}–{r['wall_time_max_s'] * 1e3:.3g} ms, "
        f"{n} timings)"
    )


def _cheapest_cell(runs: Sequence[Mapping[str, Any]], rid: int, level: float) -> str:
    """The pick for one plant and level, its timings, and whether they rank it."""
    r = runs[rid]
    rank = ranking(runs, rid, level)
    cell = (
        f"#{rid} {r['method']} {r['setting_name']} {r['setting']:.3g}: {_ms_span(r)}, "
        f"error {r['error']:.2g}"
    )
    if rank.rivals:
        others = ", ".join(f"#{i}" for i in rank.rivals)
        cell += f"; not ranked: its timings overlap those of {others}"
    elif rank.timings < 2:
        cell += "; not ranked: a single timing"
    return cell


def figure_caption(res: SweepResult, cfg: SweepConfig) -> str:
    """What the work-precision figure draws, with the solver settings and the horizon."""
    ran = [e for e in ENGINES if any(r["engine"] == e for r in res.runs)]
    est = res.reference["error_estimate"]
    scipy_plants = " and the Pinocchio plant" if PINOCCHIO in ran else ""
    return (
        f"**Figure: work-precision of {', '.join(ran)} on {res.scene}, horizon 0–{cfg.t_end:g} s.** "
        "Each point is one setting: x is its wall time per simulated second (the run's wall time "
        "over its horizon, s/s, log axis; the integration only, "
        + (
            f"median of up to {cfg.repeats} timings, bar from the fastest to the slowest timing, "
            "hollow: a single timing"
            if cfg.repeats > 1
            else "a single timing, drawn hollow: no spread measured"
        )
        + f"), y its error (log axis): the {ERROR_MEASURE}. "
        "Lines join the settings of one plant (line style and marker: analytic solid ○, MuJoCo "
        "dashed □, Pinocchio dotted △, MJX dash-dotted ◇, MuJoCo Warp dashed ▽) and one solver, "
        "integrator or precision (colour), loose to tight. "
        f"Settings: analytic engine{scipy_plants}: {_scipy_grid(cfg)}; "
        f"MuJoCo: {_mujoco_grid(cfg)}. "
        + "".join(
            f"{'MJX' if e == MJX else 'MuJoCo Warp'}: {grid_words(cfg, e)}. "
            for e in (MJX, MJWARP)
            if e in ran
        )
        + "".join(
            f"Ringed: the {f.precision} floor of {f.engine} (dt {f.dt:.3g} s), the smallest step "
            f"beyond which a smaller one stopped lowering the error ({f.kind.value if f.kind else ''}: "
            "told by a float64 series of the same twin at the next step). "
            for f in floors(res.runs)
            if f.dt is not None
        )
        + f"▷ marks where a series was cut as too slow (a run over the {cfg.max_run_wall_s:g} s "
        "budget, at its measured or predicted wall time); ✕ a failed or diverged run (error above "
        f"{cfg.diverge_error:g} or not finite), on the top edge; ✚ a degraded run (MuJoCo "
        "dropped a control for a step), where it is; each mark is labelled. Two series of one "
        "plant that draw the same errors are both shown, the second dotted with large hollow ◇, "
        "and the legend says they coincide. The grey "
        f"dotted line is the reference's floor, {FLOOR_FACTOR:g}x its estimated error "
        f"{est:.2e}."
    )


def sweep_markdown(res: SweepResult, cfg: SweepConfig, *, image: str | None = FIGURE_FILE) -> str:
    """The text of ``sweep.md`` (``image``: the figure's file, linked; None: refer to the
    recording's view instead)."""
    ref = res.reference
    runs = res.runs
    cheapest = res.cheapest
    skipped = res.skipped_series
    columns = list(cheapest) + [e for e in skipped if e not in cheapest]
    marked: dict[int, list[float]] = {rid: [] for rid in range(len(runs))}
    for by_level in cheapest.values():
        for lv, rid in by_level.items():
            if rid is not None:
                marked[rid].append(lv)
    origin = reference_origin(ref.get("cache", {}))
    L = [
        f"# What accuracy costs in time: {res.scene}",
        "",
        f"Horizon {cfg.t_end:g} s. Error = the largest over the trajectory of: position of C "
        f"relative to its largest displacement ({ref['R_scale']:.4g} m), attitude angle (rad), rod "
        f"positions relative to the largest |p| ({ref['p_scale']:.4g} m), against the reference. "
        + _timing_words(cfg, res.workers),
        "",
        "## Reference",
        "",
        f"Analytic engine, DOP853, rtol {REFERENCE_RTOL:g}, atol {REFERENCE_ATOL:g}, steps capped "
        f"at {ref['max_step']:.3g} s (half the mean step uncapped): {ref['nfev']} evaluations, "
        f"{ref['wall_time_s']:.3g} s. **Estimated error {ref['error_estimate']:.2e}** "
        f"(self-convergence: difference to the uncapped run; position "
        f"{ref['error_components']['pos']:.2e}, attitude {ref['error_components']['att']:.2e} "
        f"rad, rod {ref['error_components']['rod']:.2e}). Runs within {FLOOR_FACTOR:g}x of it are "
        f"marked 'floor': their error is not resolved. {origin}",
        "",
        "## Plants",
        "",
    ]
    L += _plants(cfg, runs, skipped)
    L += ["", "## Work-precision", ""]
    if image is not None:
        L += [f"![work-precision]({image})", ""]
    else:
        L += [
            f"The figure is the view '{VIEW_NAME}' of this recording (x: log10 of the wall time, "
            "y: the number of correct digits, -log10 of the error); the same figure is the file "
            f"{FIGURE_FILE} beside it.",
            "",
        ]
    L += [figure_caption(res, cfg)]
    L += [
        "",
        "## Cheapest setting per accuracy level",
        "",
        "The `ok` run of least median wall time whose error reaches the level, with its timings "
        "(median, fastest–slowest, how many). It is named the cheapest only when its timings rank "
        "it: at least two timings, and no other run reaching the level with a timing range that "
        "meets its range; otherwise the cell says which runs the timings cannot tell apart from "
        "it. A `degraded` run is never picked.",
        "",
        "| level | " + " | ".join(columns) + " |",
        "|---|" + "---|" * len(columns),
    ]
    for lv in cfg.levels:
        cells = []
        for engine in columns:
            rid = cheapest.get(engine, {}).get(lv)
            if engine in skipped:
                cells.append("series skipped")
            elif lv <= FLOOR_FACTOR * ref["error_estimate"]:
                cells.append("below the reference's resolution")
            elif rid is None:
                cells.append("not reached")
            else:
                cells.append(_cheapest_cell(runs, rid, lv))
        L.append(f"| {lv:.0e} | " + " | ".join(cells) + " |")
    L += floors_markdown(runs, cfg)
    L += _pinocchio_vs_analytic(runs)
    L += [
        "",
        "## Every run",
        "",
        "★ marks the cheapest run for the levels listed. Drift columns: max abs(uᵀu−1) (e_u), "
        "relative angular-momentum and energy balances (`validation.compare.summary.drift_figures`). "
        "Wall: median (min–max) over n timings.",
        "",
        "| # | engine | method | setting | status | error (max) | error (final) | "
        "max e_u | L bal. | E bal. | track ω (final) | wall ms | n | nfev | steps | ★ / note |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        star = ""
        if marked[r["run_id"]]:
            star = "★ " + ", ".join(f"{lv:.0e}" for lv in marked[r["run_id"]])
        note = " ".join(
            x for x in (star, "floor" if r["at_reference_floor"] else "", r["note"]) if x
        )
        wall = r["wall_time_s"]
        spread = ""
        if wall is not None and (r["wall_time_repeats"] or 0) > 1:
            spread = f" ({r['wall_time_min_s'] * 1e3:.3g}–{r['wall_time_max_s'] * 1e3:.3g})"
        L.append(
            f"| {r['run_id']} | {r['engine']} | {r['method']} | {r['setting_name']} "
            f"{r['setting']:.3g} | {r['status']} | {fmt(r['error'], '.2e')} | "
            f"{fmt(r['error_final'], '.2e')} | {fmt(r['quat_norm_error_max'], '.1e')} | "
            f"{fmt(r['angular_momentum_balance_rel'], '.1e')} | "
            f"{fmt(r['energy_balance_rel'], '.1e')} | {fmt(r['tracking_omega_final'], '.3g')} | "
            f"{fmt(None if wall is None else wall * 1e3, '.3g')}{spread} | "
            f"{fmt(r['wall_time_repeats'])} | {fmt(r['nfev'])} | "
            f"{fmt(r['nsteps'])} | {note.replace('|', '/')} |"
        )
    L += [
        "",
        "## Stabilisation (δ1, δ2) and the quaternion norm",
        "",
        f"Analytic engine, DOP853, over {cfg.t_end:g} s. `φ = uᵀu − 1` obeys φ̈ + δ1 φ̇ + δ2 φ = 0 "
        "(Eq. 58); started off the unit sphere it decays only when δ1, δ2 > 0.",
        "",
        "| δ1 | δ2 | rtol | φ(0) | φ(T) | max abs φ | max abs φ at steps |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in res.stabilization:
        L.append(
            f"| {s['delta1']:g} | {s['delta2']:g} | {s['rtol']:.0e} | "
            f"{s['initial_norm_error']:.2e} | {s['quat_norm_error_final']:.2e} | "
            f"{s['quat_norm_error_max']:.2e} | {s['quat_norm_error_at_steps_max']:.2e} |"
        )
    L += ["", "## Cost of one dynamics evaluation with each effect off", ""]

    L += effects_markdown(list(res.effects))
    L.append("")
    return "\n".join(L)


__all__ = [
    "FIGURE_FILE",
    "VIEW_NAME",
    "figure_caption",
    "fmt",
    "reference_origin",
    "skipped_note",
    "sweep_markdown",
]
