"""One series: one plant and solver (rtols, loose to tight) or integrator (dts, large to small),
every setting run for its accuracy and timed (:mod:`validation.studies.sweep.timing`), in one task of the
executor.

A series stops, and its remaining settings are reported ``skipped`` with the reason, when a run

* is too slow: stopped at its budget, or predicted to pass it from the last two runs
  (:func:`predicted_wall`) and then not started;
* fails or diverges after an earlier setting worked;
* is at the reference's floor (error within ``FLOOR_FACTOR`` of its estimated error): a tighter
  setting's error could not be resolved;
* (an accelerated plant's series) shows its precision's floor: a step a quarter of the last
  lowered the error by less than ``PRECISION_FLOOR_GAIN``. The last step is marked
  ``at_precision_floor`` (the smallest step that helped) and the run that showed it is kept.

An accelerated plant's series (MJX, MuJoCo Warp) runs over its own horizon
(:meth:`~validation.studies.sweep.config.SweepConfig.horizon`) against the reference up to it.

A MuJoCo run in which a sampled control reached ``MJ_MAXVAL`` ran without that control for a step
(MuJoCo drops it as unstable): it is ``degraded``, not ``ok`` (measured and timed, never picked as
the cheapest setting).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analytic.scene import Scene
from validation.studies.sweep import metrics, running, timing
from validation.studies.sweep.config import (
    ACCELERATED,
    ACCELERATED_STAGES,
    MJ_MAXVAL,
    PRECISION_FLOOR_GAIN,
    RTOL_ENGINES,
    STAGES,
    Outcome,
    SweepConfig,
)
from validation.studies.sweep.metrics import RefSamples
from validation.studies.sweep.rows import SAMPLES_KEY, blank_row


def fill_row(row: dict[str, Any], tr, ref: RefSamples) -> None:
    """The accuracy columns of ``row`` from the run ``tr``: errors, drifts, tracking, counts."""
    row.update(metrics.errors_against(tr, ref))
    row.update(metrics.drifts(tr))
    row.update(metrics.tracking(tr))
    row["nsteps"] = int(tr.info.get("nsteps", 0))
    if row["engine"] in RTOL_ENGINES:
        row["nfev"] = int(tr.info["nfev"])
    elif row["engine"] in ACCELERATED:
        row["nfev"] = row["nsteps"] * ACCELERATED_STAGES
    else:
        row["nfev"] = row["nsteps"] * STAGES.get(row["method"], 1)
        big = max(
            float(np.max(np.abs(tr.torque), initial=0.0)),
            float(np.max(np.abs(tr.rod_forces), initial=0.0)),
        )
        if big >= MJ_MAXVAL:
            row["note"] = (
                f"a sampled control reached {big:.3g} ≥ {MJ_MAXVAL:g}: MuJoCo treats such a ctrl "
                "as unstable and drops it for that step"
            )


def predicted_wall(engine: str, done: list[tuple[float, float]], setting: float) -> float | None:
    """The predicted wall time (s) of the next setting from the series' finished runs ``done``
    ([(setting, wall)], in order), from the last two: a time-step plant's (MuJoCo, MJX, Warp)
    cost is ``a + b/dt`` (a per run
    and per output sample, b per step: both fitted, neither negative); a scipy plant's grows from
    one rtol to the next by the last ratio (at least 1x). None with fewer than two runs."""
    if len(done) < 2:
        return None
    (s0, w0), (s1, w1) = done[-2], done[-1]
    if engine not in RTOL_ENGINES:  # a time-step series: MuJoCo, MJX, MuJoCo Warp
        b = max((w1 - w0) / (1.0 / s1 - 1.0 / s0), 0.0) if s1 != s0 else 0.0
        a = max(w1 - b / s1, 0.0)
        return max(a + b / setting, w1)
    return w1 * max(w1 / w0, 1.0) if w0 > 0 else None


def precision_floor(previous: dict[str, Any], row: dict[str, Any]) -> str:
    """The note of a run that shows its precision's floor ("" when it does not): its step is
    smaller than ``previous``'s and its error fell by less than ``PRECISION_FLOOR_GAIN``."""
    e0, e1 = previous["error"], row["error"]
    if not (row["setting"] < previous["setting"] and e0 > 0 and math.isfinite(e1)):
        return ""
    gain = e0 / e1 if e1 > 0 else math.inf
    if gain >= PRECISION_FLOOR_GAIN:
        return ""
    return (
        f"error floor: a {previous['setting'] / row['setting']:.3g}x smaller step "
        f"changed the error {e0:.2g} -> {e1:.2g} ({gain:.2g}x, < {PRECISION_FLOOR_GAIN:g}x); "
        f"the smallest step that helped is dt {previous['setting']:.3g} s"
    )


def run_series(
    scene: Scene,
    engine: str,
    method: str,
    cfg: SweepConfig,
    ref: RefSamples,
    floor: float = 0.0,
) -> list[dict[str, Any]]:
    """Rows for every setting of ``engine`` / ``method`` (:data:`validation.studies.sweep.rows.COLUMNS`).

    ``floor``: the error the reference resolves (``FLOOR_FACTOR`` x its estimated error); a run at
    or below it is marked ``at_reference_floor`` and ends the series.
    """
    settings = cfg.settings(engine)
    rows: list[dict[str, Any]] = []
    if not settings:
        return rows
    name = "rtol" if engine in RTOL_ENGINES else "dt"
    budget = cfg.budget(engine)
    ref = metrics.ref_until(ref, cfg.horizon(engine))
    last_ok: dict[str, Any] | None = None
    stop = ""
    any_ok = False
    done: list[tuple[float, float]] = []  # (setting, median wall) of the runs that ended ok
    try:
        timing.warm_up(scene, engine, method, settings[0], cfg)
    except Exception:  # the setting's own run below reports what is wrong
        pass
    for s in settings:
        row = blank_row(engine, method, s, cfg)
        rows.append(row)
        if stop:
            row.update(status=Outcome.SKIPPED, note=stop)
            continue
        predicted = predicted_wall(engine, done, s)
        if predicted is not None and predicted > budget:
            basis = "cost growth" if engine in RTOL_ENGINES else "cost a + b/dt"
            basis += " from the last two runs"
            row.update(
                status=Outcome.TOO_SLOW,
                wall_time_predicted_s=predicted,
                note=f"too slow: predicted {predicted:.3g} s > {budget:g} s ({basis}); not run",
            )
            stop = f"series stopped at {name} = {s:.3g}: predicted too slow"
            continue
        try:
            tr = running.run_setting(scene, engine, method, s, cfg, budget=budget)
        except running.BudgetExceeded as exc:
            row.update(status=Outcome.TOO_SLOW, note=f"too slow: {exc}")
            row.update(timing.summary([exc.elapsed_s]), wall_time_repeats=0)
            stop = f"series stopped: {name} {s:.3g} took longer than {budget:g} s"
            continue
        except Exception as exc:  # a setting the engine refuses is a result, not a crash
            row.update(status=Outcome.FAILED, note=f"{type(exc).__name__}: {exc}")
            if any_ok:
                stop = f"series stopped: failed at {name} = {s:.3g}"
            continue
        fill_row(row, tr, ref)
        first = timing.wall_of(tr)
        if tr.status.value != "ok":
            row.update(status=Outcome.FAILED, note=tr.message)
        elif not (math.isfinite(row["error"]) and row["error"] <= cfg.diverge_error):
            row.update(
                status=Outcome.DIVERGED,
                note=f"error {row['error']:.3g} > {cfg.diverge_error:g} (or not finite)",
            )
        else:
            # a control dropped by MuJoCo for a step (fill_row's note): not the run asked for
            row["status"] = Outcome.DEGRADED if row.get("note") else Outcome.OK
            any_ok = True
            samples = timing.timings(scene, engine, method, s, cfg, first)
            row[SAMPLES_KEY] = samples
            row.update(timing.summary(samples))
            done.append((s, row["wall_time_s"]))
            row["at_reference_floor"] = bool(row["error"] <= floor)
            if row["at_reference_floor"]:
                stop = (
                    f"series stopped at the reference's floor ({name} {s:.3g} reached error "
                    f"{row['error']:.2g} ≤ {floor:.2g}): a tighter setting is not resolved"
                )
            elif engine in ACCELERATED and last_ok is not None:
                seen = precision_floor(last_ok, row)
                if seen:
                    last_ok["at_precision_floor"] = True
                    last_ok["note"] = "error floor: the smallest step that lowered the error"
                    row["note"] = seen
                    stop = (
                        f"series stopped past its {row['precision']} error floor (dt "
                        f"{last_ok['setting']:.3g} s): a smaller step does not lower the error"
                    )
            if row["status"] == Outcome.OK:
                last_ok = row
            continue
        row.update(timing.summary([first]), wall_time_repeats=0)
        row["at_reference_floor"] = False
        if any_ok:
            stop = f"series stopped: {row['status']} at {name} = {s:.3g}"
    for row in rows:
        if row["at_reference_floor"] is None:
            row["at_reference_floor"] = False
    return rows


__all__ = ["fill_row", "precision_floor", "predicted_wall", "run_series"]
