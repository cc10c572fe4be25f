"""Settling a disagreement: a model difference, or a numerical limit of the settings?

A campaign runs every plant at the scene's default settings. Where a plant disagrees because those
settings are too coarse for the scene (MuJoCo's fixed step at a few hundred rad/s, the analytic
plant's rtol 1e-12 on a fast unstable spin) the disagreement is real but says nothing against the
plant's model; a verdict must not blame the model for the settings it was given. So every minimal
counterexample is settled:

1. **Each plant's own error estimate.** Each plant runs the minimal scene twice, at its default
   settings and at :meth:`analytic.plant.Plant.tightened` ones (tolerances / 100, a fixed step / 4:
   a far smaller error, ``docs/plugins.md``); the difference of the two runs, per compared quantity
   (the comparison's :func:`~validation.compare.checks.difference_series`), estimates the plant's
   own error at its default settings (within 1 % of the true error on a closed-form motion,
   ``tests/cross/test_tightened.py``).
2. **The judgement at tightened settings.** The tightened runs are compared and refereed as the
   campaign's were (:func:`validation.studies.fuzz.judge.judge_runs`).

The cause (:class:`Cause`) of a plant that raised or stopped:

* ``settings``: it finishes at its tightened settings;
* ``scene``: it stops at tightened settings too, and every other plant stops or stalls at the
  same time (within :data:`SINGULAR_SPREAD_SAMPLES` output samples): the motion itself ends there
  (a finite-time blow-up of the controlled motion, which every engine meets);
* ``range``: it stops at tightened settings too, no other plant failed (one may pass its time
  limit), and a run that finished reaches a coordinate, velocity or acceleration beyond the
  stopped plant's ``value_bound`` (MuJoCo's ``mjMAXVAL`` = 1e10: a mass flung off a spinning rod
  without a spring runs away exponentially): the motion left that engine's range, by its design;
* ``conditioning``: it stops round-off limited (:func:`analytic.error_scale.is_roundoff_stop`: a
  one-ulp change of its state moves a step by its whole tolerance, and its steps shrink to
  nothing) at its default and its tightened settings: the motion is beyond what double
  precision resolves at that tolerance, which says nothing of the plant's model;
* ``unsettled``: it cannot tighten, or its tightened run passed its time limit; or the other
  plants that ran fail a pair check between each other (a majority that disagrees with itself
  beyond a threshold confirms nothing, not even that the motion goes on);
* ``model``: none of these.

Of an outlier or a failed check, the first rule that applies, in this order:

1. **A run cut short.** A plant it is about (the outlier and its group, a pair's two plants) whose
   run its engine's guard ended (a reset, a stop, a non-finite state:
   :func:`validation.studies.fuzz.judge.cut_short`) was compared only up to its stop, so the
   comparison is no evidence against that plant's model: the disagreement takes its stop's cause
   when that is ``scene``, ``range`` or ``conditioning``, is judged at tightened settings (below) when the plant
   finishes there (``settings``; its own error at default settings is then unknown), and is
   ``unsettled`` otherwise (the stop, a finding of its own, carries its cause). A run cut short
   at tightened settings: ``unsettled``.
2. ``conditioning``: on a state quantity, the motion amplifies a perturbation of the initial
   state at round-off level (:data:`PERTURBATION` relative) into at least
   :data:`CONDITIONING_FRACTION` of the disagreement, in the first plant's own runs: two
   engines, whose errors are never smaller than that, cannot agree on such a scene at any
   settings.
3. ``unsettled``: a plant it is about cannot tighten its settings (a plugin that does not say
   how), or its tightened run failed or passed its time limit.
4. ``settings``: the disagreement is gone at tightened settings; the plant whose own error is
   the largest is named, with its settings.
5. ``unsettled``, an outlier only: the plants of the group that makes it the outlier fail a pair
   check between each other (any quantity), at default or tightened settings: a majority that
   disagrees with itself beyond a threshold confirms nothing.
6. **The margin** (an outlier, a failed pair check, on a difference quantity): its value (an
   outlier's distance to the group, a check's value) against :data:`SETTLE_MARGIN` × the sum of
   the own errors that could explain it (the outlier's and the group's largest; the pair's two).
   ``unsettled`` when one of them is unknown (its run did not finish at both settings);
   on the relative forces (:data:`~validation.studies.fuzz.judge.RELATIVE_DIFFERENCES`) the own
   errors, in N·m or N, are divided by the check's scale (``Outcome.scales``; an outlier's
   smallest with a group member), ``unsettled`` when it is not known. Within: ``settings``;
   beyond: ``model``, what is left is a difference of the models (or of round-off, which no
   tightening removes: the rod through C).
7. ``model``: a plant's own check (a balance, tracking) that persists at tightened settings.

Every sentence states only comparisons that were made, each with the numbers it compared
(``0.00032 ≤ 10 × (mujoco's own error 130 + the group's largest, pinocchio's 5.6e-07) / the
check's scale 4e+05 = 0.00325``).

A plant raising or stopping is settled with only that plant tightened (the others run at their
default settings, to see whether they stop at the same time); every other disagreement with every
plant tightened.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from analytic.error_scale import is_roundoff_stop
from validation.compare.checks import CheckState, Subject
from validation.studies.fuzz.judge import RELATIVE_DIFFERENCES, Disagreement, Kind, Outcome
from validation.studies.fuzz.settle_runs import (
    PERTURBATION,
    perturbed,
    settle_collect,
    settle_data,
    settle_plant,
)

SETTLE_MARGIN = 10.0
"""An outlier is blamed on the model only when its distance from the agreeing plants exceeds this
many times the sum of its own error estimate and the largest of theirs (on that quantity, at the
default settings). Two trajectories that each carry an error E_a, E_b differ by at most E_a + E_b;
the estimates are good to about 1 % where tightening divides the error by 100 or more, and to a
factor of a few where it cannot (an error that no longer follows the tolerance near scipy's floor
of 100 ε); a decade, as the referee's own separation (REFEREE_SEPARATION), keeps a distance that
the settings could explain from being called a model difference."""


CONDITIONING_FRACTION = 0.1
"""A disagreement is the scene's conditioning when the first plant's run from the perturbed
initial state differs from its own run by at least this fraction of the disagreement's value
(the failed check's value, or the outlier's distance) on the same quantity: a round-off-sized
cause then makes a tenth of it, and the rest is the same amplification of the engines' own
differences, which no settings remove."""

ABSOLUTE_QUANTITIES = frozenset(
    ("position_C", "attitude", "rod_positions", "velocity_C", "rod_velocities", "angular_velocity")
)
"""The quantities whose check values and referee distances are in their own unit, as the own
error estimates and the conditioning test's differences are: the state. The forces' are
relative to the largest force (validation.compare.thresholds), so the margin and conditioning
rules, which compare the two, leave them to the tightened judgement."""

SINGULAR_SPREAD_SAMPLES = 2.0
"""Plants that stop or stall at simulated times within this many output intervals of each other
stop at the same time: a stopped run is known to its last output sample (one interval), a stalled
one to its last progress report; a second interval for the plant that stops just past a sample."""


class Cause(StrEnum):
    """What a disagreement comes from (module docstring)."""

    MODEL = "model"
    SETTINGS = "settings"
    SCENE = "scene"
    RANGE = "range"
    CONDITIONING = "conditioning"
    UNSETTLED = "unsettled"


@dataclass(frozen=True)
class Settlement:
    """How a minimal counterexample was settled.

    Attributes:
        cause: see :class:`Cause`.
        text: one sentence saying why, with the numbers that decided.
        culprit: for ``settings``, the plant whose own error is the largest on the quantity ("" else).
        own_errors: plant -> quantity -> its own error estimate at its default settings (the
            quantity's unit: m, rad, m/s, rad/s, N·m, N), the quantities of the comparison.
        settings: plant -> [its default settings, its tightened settings] (``Plant.describe``;
            the second "" when it cannot tighten).
        tightened: the minimal scene judged with every plant at tightened settings.
    """

    cause: Cause
    text: str
    culprit: str = ""
    own_errors: dict[str, dict[str, float]] = field(default_factory=dict)
    settings: dict[str, list[str]] = field(default_factory=dict)
    tightened: Outcome = field(default_factory=Outcome)

    def to_dict(self) -> dict[str, Any]:
        return {
            "cause": self.cause.value,
            "text": self.text,
            "culprit": self.culprit,
            "own_errors": {p: dict(q) for p, q in self.own_errors.items()},
            "settings": {p: list(s) for p, s in self.settings.items()},
            "tightened": self.tightened.to_dict(),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Settlement:
        return cls(
            Cause(d["cause"]),
            str(d["text"]),
            str(d.get("culprit", "")),
            {p: {k: float(v) for k, v in q.items()} for p, q in d["own_errors"].items()},
            {p: [str(x) for x in s] for p, s in d["settings"].items()},
            Outcome.from_dict(d["tightened"]),
        )


def _fmt(x: float) -> str:
    return f"{x:.3g}"


def _pair_of(label: str) -> tuple[tuple[str, ...], str]:
    """The plants and the quantity of a check label: ``analytic_vs_pinocchio.rod_positions`` ->
    ``(("analytic", "pinocchio"), "rod_positions")``, a plant's own ``mujoco.energy`` ->
    ``(("mujoco",), "energy")``, the reference pair's bare ``rod_positions`` -> its two plants
    (``validation.compare.checks.Check.label``)."""
    subject, dot, name = label.rpartition(".")
    if not dot:
        return tuple(Subject.BOTH.plants), label
    return tuple(subject.split("_vs_")), name


def _involved(d: Disagreement, outcome: Outcome, plants: Sequence[str]) -> list[str]:
    """The plants a disagreement is about: the outlier and the group it is separated from, a failed
    pair's two plants, a plant's own check's plant, a plant that failed."""
    if d.kind is Kind.OUTLIER:
        return [d.plant, *[g for g in _group(d, outcome) if g != d.plant]]
    if d.kind is Kind.CHECK:
        pair = _pair_of(d.what)[0]
        return [p for p in plants if p in pair] or list(plants)
    return [d.plant]


def _verdict(d: Disagreement, outcome: Outcome) -> Mapping[str, Any]:
    return next((v for v in outcome.verdicts if v.get("quantity") == d.what), {})


def _group(d: Disagreement, outcome: Outcome) -> list[str]:
    """The majority group the referee separated the outlier ``d`` from."""
    return [str(g) for g in _verdict(d, outcome).get("group", []) if g != d.plant]


def _quantity(d: Disagreement) -> str:
    return d.what if d.kind is Kind.OUTLIER else _pair_of(d.what)[1]


def _check_value(d: Disagreement, outcome: Outcome) -> float:
    v = outcome.checks.get(d.what)
    return float(v[0]) if v else math.nan


def _distance(d: Disagreement, outcome: Outcome) -> float:
    for o in _verdict(d, outcome).get("outliers", []):
        if o.get("plant") == d.plant:
            return float(o["distance"])
    return math.nan


def _cut_short(p: str, outcome: Outcome) -> Disagreement | None:
    """Plant ``p``'s run in ``outcome`` cut short (its :data:`Kind.STOPPED`), None when it was not."""
    return next((x for x in outcome.disagreements if x.kind is Kind.STOPPED and x.plant == p), None)


def _end_text(p: str, outcome: Outcome) -> str:
    """``at t = 0.41 s: unstable: bad qacc (MuJoCo reset the state)``: where and why a run ended."""
    at = outcome.reached.get(p, math.nan)
    where = f" at t = {at:.4g} s" if math.isfinite(at) else ""
    why = outcome.messages.get(p, "")
    return f"{where}{': ' + why if why else ''}"


def _failed_pairs(group: Sequence[str], outcome: Outcome) -> list[str]:
    """The pair checks between two members of ``group`` that fail in ``outcome``, each as
    ``label value > threshold``."""
    out = []
    for label, (value, threshold, state) in outcome.checks.items():
        pair = _pair_of(label)[0]
        if len(pair) == 2 and set(pair) <= set(group) and state == CheckState.FAIL.value:
            out.append(f"{label} {_fmt(value)} > threshold {_fmt(threshold)}")
    return out


def _scale(d: Disagreement, outcome: Outcome, involved: Sequence[str]) -> float:
    """The divisor of a relative quantity's value (NaN when not recorded): a failed pair check's
    own, or for an outlier the smallest of its pair checks with the group's members (the largest
    own error bound relative to it: the margin test's benefit of the doubt goes to the settings)."""
    if d.kind is Kind.CHECK:
        return float(outcome.scales.get(d.what, math.nan))
    q, members = d.what, set(involved) - {d.plant}
    found = [
        s for label, s in outcome.scales.items()
        if _pair_of(label)[1] == q and d.plant in _pair_of(label)[0]
        and set(_pair_of(label)[0]) - {d.plant} <= members
    ]
    return min(found) if found else math.nan


def _unknown_why(p: str, task: Mapping[str, Any], untightened: Mapping[str, str]) -> str:
    run = task.get("default_runs", {}).get(p, {})
    status = run.get("status", "")
    if status and status != "ok":
        return f"its run at its default settings {'was ' if status == 'timeout' else ''}{status}"
    if p in untightened:
        return untightened[p]
    return "its tightened run did not finish"


def settle(
    d: Disagreement, outcome: Outcome, task: Mapping[str, Any], plants: Sequence[str]
) -> Settlement:
    """The cause of ``d``, shown by the minimal scene's ``outcome`` at default settings, given the
    settling task's result ``task`` (:func:`settle_data`) on ``plants`` (module docstring). Every
    comparison the sentence quotes was made, with the numbers it quotes."""
    own = {p: dict(q) for p, q in task["own_errors"].items()}
    described = {p: list(s) for p, s in task["settings"].items()}
    tightened = Outcome.from_dict(task["tightened"])
    untightened = dict(task["untightened"])
    involved = _involved(d, outcome, plants)
    q = _quantity(d)

    def make(cause: Cause, text: str, culprit: str = "") -> Settlement:
        return Settlement(cause, text, culprit, own, described, tightened)

    if d.kind in (Kind.RAISED, Kind.STOPPED):
        return _settle_failure(d, outcome, task, make, described, tightened, untightened)
    # 1. a comparison with a run its engine's guard cut short blames nothing on that engine's model
    for p in involved:
        stop = _cut_short(p, outcome)
        if stop is None:
            continue
        st = settle(stop, outcome, task, plants)
        head = (f"{d.kind.value} on {q} compares {p}'s run cut short by its engine"
                f"{_end_text(p, outcome)}")
        if st.cause in (Cause.SCENE, Cause.RANGE, Cause.CONDITIONING):
            return make(st.cause, f"{head}; its stop is settled as {st.cause.value}: {st.text}")
        if st.cause is not Cause.SETTINGS:
            return make(
                Cause.UNSETTLED,
                f"not settled: {head}, which is no evidence against its model (its stop, a "
                f"finding of its own: {st.cause.value}: {st.text})",
            )
        # p finishes at its tightened settings: judged there, below (its own error is unknown)
    for p in involved:
        if _cut_short(p, tightened) is not None:
            return make(
                Cause.UNSETTLED,
                f"not settled: {p}'s run at its tightened settings "
                f"({described.get(p, ['', ''])[1]}) was cut short{_end_text(p, tightened)}",
            )
    value = _distance(d, outcome) if d.kind is Kind.OUTLIER else _check_value(d, outcome)
    # 2. the scene's conditioning
    for p, sens in task.get("sensitivity", {}).items() if q in ABSOLUTE_QUANTITIES else ():
        moved = float(sens.get(q, math.nan))
        if math.isfinite(value) and value > 0 and moved >= CONDITIONING_FRACTION * value:
            return make(
                Cause.CONDITIONING,
                f"the scene's conditioning: {p}'s run from an initial state moved by "
                f"{PERTURBATION:g} relative differs from its own run by {_fmt(moved)} on {q}, "
                f"≥ {CONDITIONING_FRACTION:g} × the disagreement's {_fmt(value)}: no two engines "
                "can agree closer",
            )
    # 3. a plant that could not be tightened
    missing = [p for p in involved if p in untightened]
    if missing:
        why = "; ".join(f"{p}: {untightened[p]}" for p in missing)
        return make(Cause.UNSETTLED, f"not settled: {why}")
    tight_names = ", ".join(described[p][1] for p in involved if p in described)
    errors = {p: own.get(p, {}).get(q, math.nan) for p in involved}
    known_errors = {p: e for p, e in errors.items() if math.isfinite(e)}
    culprit = max(known_errors, key=known_errors.get) if known_errors else ""
    if not culprit and len(involved) == 1:  # a plant's own check (a balance): that plant
        culprit = involved[0]
    own_text = ", ".join(f"{p} {_fmt(e)} ({described[p][0]})" for p, e in known_errors.items())
    own_part = f"; own errors on {q} at the default settings: {own_text}" if own_text else ""
    # 4. gone at tightened settings
    if not tightened.shows(d):
        return make(
            Cause.SETTINGS,
            f"a numerical limit of the settings: gone at tightened settings ({tight_names})"
            f"{own_part}",
            culprit,
        )
    # 5. an outlier needs a majority that agrees with itself, at both settings
    if d.kind is Kind.OUTLIER:
        group = _group(d, outcome)
        for where, o in (("default", outcome), ("tightened", tightened)):
            failed = _failed_pairs(group, o)
            if failed:
                return make(
                    Cause.UNSETTLED,
                    f"not settled: {' and '.join(group)}, the group that makes {d.plant} the "
                    f"outlier on {q}, disagree with each other at the {where} settings "
                    f"({'; '.join(failed)}): no majority to trust",
                )
    pair_check = d.kind is Kind.CHECK and len(_pair_of(d.what)[0]) == 2
    if not (d.kind is Kind.OUTLIER or pair_check) or q not in ABSOLUTE_QUANTITIES | (
        RELATIVE_DIFFERENCES
    ):
        return make(Cause.MODEL, f"persists at tightened settings ({tight_names}){own_part}")
    # 6. the margin: the distance against the own errors that could explain it
    explain = list(_pair_of(d.what)[0]) if pair_check else involved
    if d.kind is Kind.OUTLIER and len(explain) < 2:
        return make(Cause.UNSETTLED, f"not settled: the group {d.plant} is an outlier from is "
                    "not recorded")
    errors = {p: own.get(p, {}).get(q, math.nan) for p in explain}
    unknown = [p for p in explain if not math.isfinite(errors[p])]
    if unknown:
        why = "; ".join(f"{p}: {_unknown_why(p, task, untightened)}" for p in unknown)
        return make(Cause.UNSETTLED, f"not settled: no own error on {q} for {why}")
    if d.kind is Kind.OUTLIER:
        who = f"{d.plant}'s distance on {q}"
        member = max(explain[1:], key=lambda p: errors[p])
        terms = [(f"{d.plant}'s own error", errors[d.plant]),
                 (f"the group's largest, {member}'s", errors[member])]
    else:
        a, b = explain
        who = f"the {d.what} check's value"
        terms = [(f"{a}'s own error", errors[a]), (f"{b}'s", errors[b])]
    bound = sum(e for _n, e in terms)
    over = ""
    if q in RELATIVE_DIFFERENCES:
        scale = _scale(d, outcome, involved)
        if not (math.isfinite(scale) and scale > 0):
            return make(Cause.UNSETTLED, f"not settled: the scale of the relative {q} is not known")
        bound /= scale
        over = f" / the check's scale {_fmt(scale)}"
    if not math.isfinite(value):
        return make(Cause.UNSETTLED, f"not settled: {who} could not be computed")
    within = value <= SETTLE_MARGIN * bound
    quoted = (f"{who} {_fmt(value)} {'≤' if within else '>'} {SETTLE_MARGIN:g} × ("
              + " + ".join(f"{n} {_fmt(e)}" for n, e in terms) + f"){over} = "
              f"{_fmt(SETTLE_MARGIN * bound)}")
    if within:
        return make(
            Cause.SETTINGS, f"a numerical limit of the settings: {quoted}{own_part}", culprit
        )
    return make(
        Cause.MODEL, f"persists at tightened settings ({tight_names}) and {quoted}{own_part}"
    )


def _settle_failure(
    d: Disagreement,
    outcome: Outcome,
    task: Mapping[str, Any],
    make: Any,
    described: Mapping[str, list[str]],
    tightened: Outcome,
    untightened: Mapping[str, str],
) -> Settlement:
    """A plant that raised or stopped (module docstring: settings, scene, range, model)."""
    tight = described.get(d.plant, ["", ""])[1]
    if d.plant in tightened.ran and not any(
        x.plant == d.plant and x.kind in (Kind.RAISED, Kind.STOPPED)
        for x in tightened.disagreements
    ):
        return make(
            Cause.SETTINGS,
            f"a numerical limit of the settings: {d.plant} finishes at {tight}",
            d.plant,
        )
    why = untightened.get(d.plant, "")
    if not tight or "over its time limit" in why:
        return make(Cause.UNSETTLED, f"not settled: {d.plant}: {why}")
    runs = dict(task.get("default_runs", {}))
    others = {p: r for p, r in runs.items() if p != d.plant}
    ends = {p: float(r["reached"]) for p, r in runs.items()
            if r["status"] in ("stopped", "timeout") and math.isfinite(float(r["reached"]))}
    interval = float(task.get("interval", math.nan))
    if (
        others
        and d.plant in ends
        and all(p in ends for p in others)
        and max(ends.values()) - min(ends.values()) <= SINGULAR_SPREAD_SAMPLES * interval
    ):
        where = ", ".join(
            f"{p} {'stopped' if runs[p]['status'] == 'stopped' else 'stalled'} at "
            f"t = {t:.4g} s" for p, t in ends.items()
        )
        return make(
            Cause.SCENE,
            f"the motion itself ends near t = {min(ends.values()):.4g} s: every plant stops "
            f"or stalls there ({where}; {d.plant} also at {tight}), a singularity of the "
            "controlled motion rather than a plant's failure",
        )
    bound = float(task.get("bounds", {}).get(d.plant, math.inf))
    finished = {p: r for p, r in others.items() if r["status"] == "ok"}
    if (
        finished
        and all(r["status"] in ("ok", "timeout") for r in others.values())
        and math.isfinite(bound)
    ):
        reach = max(
            ((k, v, p) for p, r in finished.items() for k, v in r["largest"].items()),
            key=lambda x: x[1],
        )
        if reach[1] > bound:
            return make(
                Cause.RANGE,
                f"the motion leaves {d.plant}'s range: {reach[2]} reaches {reach[0]} "
                f"{reach[1]:.3g} (SI units) against {d.plant}'s bound {bound:g}, and "
                f"{d.plant} stops at its tightened settings too ({tight}); no other plant "
                "fails",
            )
    default_why = outcome.messages.get(d.plant, "")
    tight_why = tightened.messages.get(d.plant, "")
    if is_roundoff_stop(default_why) and is_roundoff_stop(tight_why):
        return make(
            Cause.CONDITIONING,
            f"beyond double precision: {d.plant} stops round-off limited at its default and at its "
            f"tightened settings ({tight}){_end_text(d.plant, outcome)}; a tighter tolerance only "
            "asks for more digits than the state carries, and no engine's run is judgeable there",
        )
    others_ran = [p for p in outcome.ran if p != d.plant]
    failed = _failed_pairs(others_ran, outcome) if len(others_ran) >= 2 else []
    if failed:
        return make(
            Cause.UNSETTLED,
            f"not settled: {d.plant} fails at its tightened settings too ({tight}), but "
            f"{' and '.join(others_ran)}, the plants that ran, disagree with each other "
            f"({'; '.join(failed)}): no majority to trust that the motion goes on",
        )
    return make(Cause.MODEL, f"{d.plant} fails at its tightened settings too ({tight})")


__all__ = [
    "ABSOLUTE_QUANTITIES",
    "CONDITIONING_FRACTION",
    "PERTURBATION",
    "SETTLE_MARGIN",
    "SINGULAR_SPREAD_SAMPLES",
    "Cause",
    "Settlement",
    "perturbed",
    "settle",
    "settle_collect",
    "settle_data",
    "settle_plant",
]
