"""Settling's runs: each plant's part of settling a minimal counterexample (its run at its
default settings, at its tightened ones, of a perturbed initial state) and the parts collected
into the settling task's result, which :func:`validation.studies.fuzz.settle.settle` reads.

Plain data back (a campaign submits each plant's part to its executor): a run ended by its
engine's guard, or one reported finished with a non-finite state
(:func:`validation.studies.fuzz.judge.cut_short`), is ``stopped`` and gives no own error
estimate and no sensitivity.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from analytic.plant import Plant
from analytic.trajectory import RunStatus, Trajectory
from validation.compare.checks import difference_series
from validation.studies.fuzz.judge import (
    RUN_BUDGET_S,
    Disagreement,
    Kind,
    Outcome,
    OverTime,
    _Raised,
    cut_short,
    judge_runs,
    prepare,
    run_limited,
)

PERTURBATION = 1e-12
"""The conditioning test's perturbation of the initial state: each component of ω(0), p(0) and
ṗ(0) moved by this times max(1, its magnitude) (rad/s, m, m/s): the size of the differences
every two engines carry from their first steps (a double's round-off is 1.1e-16; one step of an
integrator at the scene tolerances errs by up to ~1e-12)."""

def _own_errors(given: Trajectory, tight: Trajectory) -> dict[str, float]:
    """Max over time of each difference of the two runs (quantity -> value, its unit)."""
    out = {}
    for s in difference_series(given, tight):
        name = s.key.split(".", 1)[1]
        v = float(np.max(s.values)) if s.values.size else 0.0
        out[name] = v if math.isfinite(v) else math.inf
    return out


def _largest(tr: Trajectory) -> dict[str, float]:
    """The largest magnitudes a run reaches: ``coordinate`` (max |q|), ``velocity`` (max |q̇|)
    and ``acceleration``, the largest mean over an output interval, max |Δq̇ / Δt|: a lower bound
    of the largest acceleration (a mean never exceeds the largest value it averages)."""
    q, qd, t = np.asarray(tr.q), np.asarray(tr.qdot), np.asarray(tr.t)
    acc = np.abs(np.diff(qd, axis=0)) / np.diff(t)[:, None] if len(t) > 1 else np.zeros((1, 1))
    return {
        "coordinate": float(np.max(np.abs(q))) if q.size else 0.0,
        "velocity": float(np.max(np.abs(qd))) if qd.size else 0.0,
        "acceleration": float(np.max(acc)) if acc.size else 0.0,
    }


def _default_run(
    name: str, pl: Plant, scene: Any, horizon: float, budget_s: float
) -> tuple[dict, Trajectory | None]:
    """A plant's run at its default settings and how it ended: ``status`` (``ok``, ``stopped``,
    ``timeout``, ``raised``), ``reached`` (simulated time, s; NaN when unknown) and, for a run
    that finished, ``largest`` (:func:`_largest`)."""
    try:
        tr = run_limited(name, pl, scene, horizon, budget_s)
    except OverTime as exc:
        return {"status": "timeout", "reached": exc.reached_s}, None
    except _Raised:
        return {"status": "raised", "reached": math.nan}, None
    if tr.status is RunStatus.INTERRUPTED:
        raise KeyboardInterrupt(tr.message)
    ok = not cut_short(tr)
    end = float(tr.t[-1]) if len(tr.t) else 0.0
    record = {"status": "ok" if ok else "stopped", "reached": end}
    if ok:
        record["largest"] = _largest(tr)
    return record, tr


def perturbed(data: dict[str, Any]) -> dict[str, Any]:
    """The scene file's dict ``data`` with its initial ω, p and ṗ moved by :data:`PERTURBATION`
    (each component by that times max(1, its magnitude))."""
    out = copy.deepcopy(data)
    init = out.setdefault("initial", {})
    for key in ("omega", "p", "pdot"):
        if key in init:
            init[key] = [float(x) + PERTURBATION * max(1.0, abs(float(x))) for x in init[key]]
    if "omega" not in init:
        init["omega"] = [PERTURBATION] * 3
    return out


def settle_plant(
    data: dict[str, Any],
    p: Plant | str,
    horizon: float,
    budget_s: float,
    tighten: bool,
    condition: bool = False,
) -> dict[str, Any]:
    """An executor's task: plant ``p``'s part of settling the scene file's dict ``data`` (a scene
    the caller has prepared and found the plant able to run): its run at its default settings
    (how it ended: :func:`_default_run`) and, when ``tighten``, its run at its tightened settings
    and the own error estimate between the two; when ``condition``, its run of the
    :func:`perturbed` scene and how far that moves it. Each run within ``budget_s`` s. Back:
    ``name``, ``default_run``, ``bound`` (its ``value_bound``), ``sensitivity`` (quantity -> the
    perturbed run's difference; empty without ``condition`` or a finished default run), and with
    ``tighten``: ``settings`` ([default, tightened] descriptions), ``untightened`` (why not, ""
    when it was), ``tight`` (the tightened trajectory, None without one), ``own_errors``
    (quantity -> estimate)."""
    scene, refused, chosen = prepare(data, [p], horizon)
    if scene is None or not chosen:
        name = next(iter(refused), "scene")
        why = next(iter(refused.values()), "refused")
        return {"name": name, "default_run": {"status": "raised", "reached": math.nan},
                "bound": math.inf, "settings": ["", ""], "untightened": why, "tight": None,
                "own_errors": {}, "sensitivity": {}}
    name, pl = chosen[0]
    out: dict[str, Any] = {"name": name, "bound": float(pl.value_bound), "sensitivity": {}}
    out["default_run"], given = _default_run(name, pl, scene, horizon, budget_s)
    if condition and given is not None and not cut_short(given):
        moved, _refused, _chosen = prepare(perturbed(data), [p], horizon)
        try:
            other = run_limited(name, pl, moved, horizon, budget_s) if moved else None
        except (OverTime, _Raised):
            other = None
        if other is not None and not cut_short(other):
            out["sensitivity"] = _own_errors(given, other)
    if not tighten:
        return out
    given_settings = pl.default_settings(scene)
    tight_settings = pl.tightened(scene, given_settings)
    out["settings"] = [
        pl.describe(given_settings),
        pl.describe(tight_settings) if tight_settings is not None else "",
    ]
    out.update(untightened="", tight=None, own_errors={})
    if tight_settings is None:
        out["untightened"] = f"the {name} plant cannot tighten its settings"
        return out
    try:
        tight = run_limited(name, pl, scene, horizon, budget_s, tight_settings)
    except (OverTime, _Raised) as exc:
        out["untightened"] = str(exc)
        return out
    if tight.status is RunStatus.INTERRUPTED:
        raise KeyboardInterrupt(tight.message)
    out["tight"] = tight
    if not cut_short(tight) and given is not None and not cut_short(given):
        out["own_errors"] = _own_errors(given, tight)
    return out


def settle_collect(
    scene: Any, horizon: float, refused: dict[str, str], parts: Sequence[Mapping[str, Any]]
) -> dict[str, Any]:
    """The settling task's result (what :func:`settle` reads) from each plant's part
    (:func:`settle_plant`, in the plants' order): the tightened runs judged together."""
    if scene is None:
        return {"own_errors": {}, "settings": {}, "untightened": dict(refused),
                "default_runs": {}, "bounds": {}, "sensitivity": {}, "interval": math.nan,
                "tightened": Outcome(refused=dict(refused)).to_dict()}
    untightened = dict(refused)
    own, described, runs, found = {}, {}, [], []
    messages: dict[str, str] = {}
    reached: dict[str, float] = {}
    for part in parts:
        name = part["name"]
        if "settings" in part:
            described[name] = list(part["settings"])
        if part.get("untightened"):
            untightened[name] = part["untightened"]
        if part.get("own_errors"):
            own[name] = dict(part["own_errors"])
        tight = part.get("tight")
        if tight is not None:
            runs.append((name, tight))
            if cut_short(tight):
                found.append(Disagreement(Kind.STOPPED, cut_short(tight), name))
                messages[name] = (tight.message.splitlines() or [cut_short(tight)])[0]
                if len(tight.t):
                    reached[name] = float(tight.t[-1])
    tightened = judge_runs(
        scene, horizon, [t for _n, t in runs], [n for n, _t in runs], found,
        messages=messages, reached=reached,
    )
    return {
        "own_errors": own,
        "settings": described,
        "untightened": untightened,
        "default_runs": {p["name"]: p["default_run"] for p in parts},
        "bounds": {p["name"]: p["bound"] for p in parts},
        "sensitivity": {p["name"]: dict(p["sensitivity"]) for p in parts if p.get("sensitivity")},
        "interval": 1.0 / scene.output.rate,
        "tightened": tightened.to_dict(),
    }


def settle_data(
    data: dict[str, Any],
    plants: Sequence[Plant | str],
    horizon: float,
    budget_s: float = RUN_BUDGET_S,
    tighten: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Settling's runs of the scene file's dict ``data``, one plant after the other here: each
    plant's :func:`settle_plant` (tightened unless ``tighten`` names others; None: every plant),
    collected by :func:`settle_collect`. Plain data back: ``own_errors``, ``settings``,
    ``untightened`` (plants that cannot tighten, or whose tightened run did not finish: plant ->
    why), ``tightened`` (``Outcome.to_dict()``), ``default_runs`` (plant -> how its run at its
    default settings ended), ``bounds`` (plant -> ``value_bound``) and ``interval`` (the output
    interval, s). A campaign submits each plant's part as its own task instead."""
    scene, refused, chosen = prepare(data, plants, horizon)
    parts = [
        settle_plant(data, pl, horizon, budget_s, tighten is None or name in tighten, i == 0)
        for i, (name, pl) in enumerate(chosen)
    ]
    return settle_collect(scene, horizon, refused, parts)


__all__ = ["PERTURBATION", "perturbed", "settle_collect", "settle_data", "settle_plant"]
