"""The comparison of N plants: its records, and how every pair and every plant is judged.

:func:`compare_plants` diffs every pair of plants (:func:`difference_series`, the quantities of
:mod:`validation.compare.differences`) and judges each plant on its own (:func:`plant_series`: its
tracking errors against the requirement ``|e_ω|`` (rad/s) and ``max_i |e_p,i|`` (m), their
deviations from the closed-form error dynamics of :mod:`validation.compare.tracking_laws`, the
quaternion norm error ``|uᵀu - 1|``, the balances of :mod:`validation.compare.balances`, the control
torque ``|τ|`` and each rod force). Every quantity is a scalar per output sample, so it can be
summarised as max, RMS, final value and time of the max (:class:`Summary`), plotted on a log axis
and logged to Rerun. Keys: ``diff.<name>`` for analytic vs MuJoCo, ``diff_<pair>.<name>`` for any
other pair, ``<plant>.<name>`` for one plant's.

Each check (:class:`Check`) compares one summarised value with a named threshold from
:mod:`validation.compare.thresholds` (the scene's ``[thresholds]`` override the defaults). For the
states' differences and the tracking laws the bound is ``value + rtol · scale``
(:meth:`analytic.threshold.Threshold.bound`), ``scale`` the quantity's own magnitude over the run
(:data:`validation.compare.differences.MAGNITUDES`; for a tracking law the plant's own ``|ω|`` or
controlled ``|p_i|``); a relative check divides by its reference signal's largest magnitude.
The records here are what every output serialises (``report.json``'s checks and summaries): a
change to their shape costs this module; a change to what is compared costs the module named above.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from analytic.threshold import Bound, BoundPart
from analytic.trajectory import RunStatus, Trajectory
from validation.compare.balances import BALANCES, BalanceTerms
from validation.compare.differences import TIME_MATCH_TOL, Difference, differences, pair_magnitude
from validation.compare.reductions import largest_row_norm, maxabs, norm
from validation.compare.subject import Subject, diff_key, pair_subject
from validation.compare.thresholds import Threshold, thresholds_for
from validation.compare.tracking_laws import law_deviations, tracking_magnitudes


class Group(StrEnum):
    """What a series shows (one figure / one Rerun plot per group)."""

    DIFFERENCE = "difference"
    TRACKING = "tracking"
    INVARIANT = "invariant"
    CONTROL = "control"


def _frozen(a: Any) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Summary:
    """Summary of a series over time: ``max`` (of the values), ``rms``, ``final`` value and
    ``t_max`` (s), the time of the max. NaN when the series is empty or has no finite sample."""

    max: float
    rms: float
    final: float
    t_max: float

    @classmethod
    def of(cls, t: np.ndarray, values: np.ndarray) -> Summary:
        t = np.asarray(t, float)
        v = np.asarray(values, float)
        if v.size == 0:
            return cls(math.nan, math.nan, math.nan, math.nan)
        finite = np.isfinite(v)
        if not finite.all():
            # A non-finite sample is the worst value: report it as the max, at its time.
            i = int(np.argmin(finite))
            return cls(math.inf, math.inf, float(v[-1]), float(t[i]))
        i = int(np.argmax(v))
        return cls(float(v[i]), float(np.sqrt(np.mean(v * v))), float(v[-1]), float(t[i]))

    def to_dict(self) -> dict[str, float]:
        return {"max": self.max, "rms": self.rms, "final": self.final, "t_max": self.t_max}


@dataclass(frozen=True)
class Series:
    """One scalar quantity per sample.

    Attributes:
        key: unique name, ``diff.<name>`` or ``<plant>.<name>``.
        label: what it is, for people.
        unit: SI unit ("1" for dimensionless).
        group: see :class:`Group`.
        subject: see :class:`Subject`.
        t: sample times, s, shape (N,).
        values: shape (N,).
    """

    key: str
    label: str
    unit: str
    group: Group
    subject: Subject
    t: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.subject, Subject):
            object.__setattr__(self, "subject", Subject(self.subject))
        object.__setattr__(self, "t", _frozen(self.t))
        object.__setattr__(self, "values", _frozen(self.values))
        if self.t.shape != self.values.shape or self.t.ndim != 1:
            raise ValueError(
                f"{self.key}.values: shape must equal t's (N,) = {self.t.shape} (got {self.values.shape})"
            )

    @property
    def summary(self) -> Summary:
        return Summary.of(self.t, self.values)

    @property
    def name(self) -> str:
        return self.key.split(".", 1)[1]


class CheckState(StrEnum):
    """A check's outcome, as every output states it (``report.md``'s verdict column, the
    ``verdict`` of report.json's check records)."""

    PASS = "pass"
    FAIL = "FAIL"
    NOT_APPLICABLE = "not applicable"  # nothing to check (no control torque in either plant)


@dataclass(frozen=True)
class Check:
    """One verdict.

    Attributes:
        name: the threshold's name (``position_C``) or ``completed``.
        subject: whose value it is.
        value: the checked value (max over time, divided by ``scale`` for relative checks).
        threshold: the effective bound; passes when ``value <= threshold`` (``completed``: the
            run reached its horizon, value = time reached, threshold = horizon). For a bound with
            a relative part, ``absolute_part + relative_part``.
        unit: unit of value and threshold.
        passed: the verdict.
        reason: why the threshold has its value (or why the check failed).
        series: key of the series the value summarises ("" when none).
        scale: the divisor of a relative check, in the signal's unit (1.0 for absolute checks).
        t_max: time of the worst value, s.
        bound: the name of the threshold when ``name`` is not it ("" when it is): a hard case's
            ``hard_*`` bound (:mod:`validation.studies.hard_cases`), which several checks share.
        applicable: False when there is nothing to check (neither plant has the quantity, e.g. no
            control torque in a scene that controls no angular velocity): the check is neither
            passed nor failed but NOT_APPLICABLE (``passed`` is True so it fails nothing;
            ``value`` and ``t_max`` are NaN; ``reason`` says why).
        absolute_part: the threshold's absolute part (its ``value``, atol), in ``unit``; NaN
            given means ``threshold`` (a bound without a relative part).
        relative_part: ``rtol × magnitude``, in ``unit`` (0 without a relative part).
        magnitude: the quantity's own scale the relative part multiplies (the largest departure
            of C from its uniformly accelerated motion, ``|p_i|``, ``|ṗ_i|`` or ``|ω|`` over time
            and the compared plants), in
            ``unit``; 0 without a relative part.
        decided_by: :class:`~analytic.threshold.BoundPart`, the larger part (ABSOLUTE on a tie
            or without a relative part).
    """

    name: str
    subject: Subject
    value: float
    threshold: float
    unit: str
    passed: bool
    reason: str
    series: str = ""
    scale: float = 1.0
    t_max: float = math.nan
    bound: str = ""
    applicable: bool = True
    absolute_part: float = math.nan
    relative_part: float = 0.0
    magnitude: float = 0.0
    decided_by: BoundPart = BoundPart.ABSOLUTE

    def __post_init__(self) -> None:
        if not isinstance(self.subject, Subject):
            object.__setattr__(self, "subject", Subject(self.subject))
        if math.isnan(self.absolute_part):
            object.__setattr__(self, "absolute_part", float(self.threshold))
        object.__setattr__(self, "decided_by", BoundPart(self.decided_by))

    @property
    def state(self) -> CheckState:
        """PASS, FAIL or NOT_APPLICABLE."""
        if not self.applicable:
            return CheckState.NOT_APPLICABLE
        return CheckState.PASS if self.passed else CheckState.FAIL

    @property
    def label(self) -> str:
        """``position_C`` (analytic vs MuJoCo), ``analytic_vs_pinocchio.position_C``,
        ``mujoco.energy``: unique within a comparison."""
        if self.subject == Subject.BOTH:
            return self.name
        return f"{self.subject.slug}.{self.name}"

    def to_dict(self) -> dict[str, Any]:
        out = {
            "name": self.name,
            "subject": self.subject.value,
            "value": self.value,
            "threshold": self.threshold,
            "unit": self.unit,
            "passed": self.passed,
            "verdict": self.state.value,
            "applicable": self.applicable,
            "reason": self.reason,
            "series": self.series,
            "scale": self.scale,
            "t_max": self.t_max,
            "absolute_part": self.absolute_part,
            "relative_part": self.relative_part,
            "magnitude": self.magnitude,
            "decided_by": self.decided_by.value,
        }
        if self.bound:
            out["bound"] = self.bound
        return out


@dataclass(frozen=True)
class Comparison:
    """The result of :func:`compare`: every series, every check, and notes.

    Attributes:
        scene: scene name.
        t: common sample times, s, shape (N,).
        series: all series (differences first, then each plant's).
        checks: all checks.
        notes: what was not compared and why (e.g. MuJoCo missing, a run failed part way).
        thresholds: the thresholds in force.
    """

    scene: str
    t: np.ndarray
    series: tuple[Series, ...]
    checks: tuple[Check, ...]
    notes: tuple[str, ...] = ()
    thresholds: Mapping[str, Threshold] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return bool(self.checks) and all(c.passed for c in self.checks)

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)

    @property
    def applicable_checks(self) -> tuple[Check, ...]:
        """The checks that check something (not NOT_APPLICABLE)."""
        return tuple(c for c in self.checks if c.applicable)

    def get(self, key: str) -> Series:
        for s in self.series:
            if s.key == key:
                return s
        raise KeyError(f"no series {key!r} (have: {', '.join(s.key for s in self.series)})")

    def check(self, label: str) -> Check:
        for c in self.checks:
            if c.label == label:
                return c
        raise KeyError(f"no check {label!r} (have: {', '.join(c.label for c in self.checks)})")

    def to_dict(self) -> dict[str, Any]:
        return {
            "scene": self.scene,
            "passed": self.passed,
            "samples": int(self.t.shape[0]),
            "t_end": float(self.t[-1]) if self.t.size else None,
            "checks": [c.to_dict() for c in self.checks],
            "summaries": {
                s.key: {"label": s.label, "unit": s.unit, **s.summary.to_dict()}
                for s in self.series
            },
            "notes": list(self.notes),
        }


# ----------------------------------------------------------------------------------------------
# Series
# ----------------------------------------------------------------------------------------------


def difference_series(a: Trajectory, b: Trajectory) -> tuple[Series, ...]:
    """Differences of two plants on their common samples
    (:func:`validation.compare.differences.differences`), as series of the pair."""
    t, values = differences(a, b)
    D, S = Group.DIFFERENCE, pair_subject(a, b)
    return tuple(
        Series(diff_key(S, d.quantity.value), d.label, d.unit, D, S, t, d.values) for d in values
    )


def plant_series(traj: Trajectory, scene: Any = None) -> tuple[Series, ...]:
    """One plant's tracking errors, invariants' balances and control forces (module docstring)."""
    subj = Subject.plant(traj.engine)
    t = traj.t
    out: list[Series] = []

    def add(name: str, label: str, unit: str, group: Group, values: np.ndarray) -> None:
        out.append(Series(f"{subj.value}.{name}", label, unit, group, subj, t, values))

    T, I, C = Group.TRACKING, Group.INVARIANT, Group.CONTROL
    if traj.tracking.omega_components:
        add("e_omega", "tracking error |ω − ω̄|", "rad/s", T, norm(traj.tracking.e_omega))
    if traj.tracking.mass_indices:
        add("e_p", "tracking error max_i |p_i − p̄_i|", "m", T, maxabs(traj.tracking.e_p))
    if scene is not None:
        dev_w, dev_p = law_deviations(traj, scene)
        if dev_w is not None:
            add("e_omega_law", "|e_ω − exp(−P t) e_ω(0)|", "rad/s", T, dev_w)
        if dev_p is not None:
            add("e_p_law", "max_i |e_p − e_ref| (ë + αė + βe = 0)", "m", T, dev_p)
    add(
        "quat_norm",
        "quaternion norm error |uᵀu − 1|",
        "1",
        I,
        np.abs(traj.invariants.quat_norm_error),
    )
    terms = BalanceTerms.of(traj.invariants)
    for b in BALANCES:
        add(b.balance.value, b.label, b.unit, I, b.residual(terms))
    add("torque", "control torque |τ| (body axes)", "N·m", C, norm(traj.torque))
    for i in range(traj.n):
        add(f"rod_force_{i + 1}", f"rod force on mass {i + 1}", "N", C, traj.rod_forces[:, i])
    return tuple(out)


# ----------------------------------------------------------------------------------------------
# Checks
# ----------------------------------------------------------------------------------------------


def _not_applicable(th: Threshold, subject: Subject, why: str) -> Check:
    """A check of ``th`` with nothing to check (:attr:`Check.applicable` False), saying why."""
    return Check(th.name, subject, math.nan, th.value, th.unit, True, why, applicable=False)


def _bound_check(
    th: Threshold, subject: Subject, series: Series, scale: float = 1.0, magnitude: float = 0.0
) -> Check:
    """The check of ``series``' max against ``th``: divided by ``max(scale, floor)`` for a
    relative threshold; against ``th.value + th.rtol · magnitude`` (``magnitude``: the quantity's
    own scale over the run, in its unit) for an absolute one."""
    s = series.summary
    if th.relative:
        scale = max(float(scale), th.floor)
        value = s.max / scale
        bound = Bound(th.value)
    else:
        scale = 1.0
        value = s.max
        bound = th.bound(magnitude)
    passed = bool(np.isfinite(value) and value <= bound.value)
    return Check(
        th.name,
        subject,
        float(value),
        bound.value,
        th.unit,
        passed,
        th.reason,
        series.key,
        scale,
        s.t_max,
        absolute_part=bound.absolute,
        relative_part=bound.relative,
        magnitude=bound.scale,
        decided_by=bound.decided_by,
    )


def judge(
    name: str,
    subject: Subject,
    value: float,
    threshold: float,
    unit: str,
    reason: str,
    *,
    bound: str = "",
    t_max: float = math.nan,
) -> Check:
    """A check of one value already summarised: passes when ``value`` is finite and at most
    ``threshold`` (a NaN or an infinity fails); ``bound`` names the threshold when ``name`` is not
    it. For values that are not a series' summary (a closed form met at sampled states, a count)."""
    value = float(value)
    passed = bool(math.isfinite(value) and value <= threshold)
    return Check(
        name, subject, value, float(threshold), unit, passed, reason, t_max=t_max, bound=bound
    )


def completed_check(traj: Trajectory, t_end: float | None = None) -> Check:
    """The ``completed`` check of one run: status ``ok`` and its last sample at ``t_end`` (s;
    default the run's own last sample)."""
    reached = float(traj.t[-1]) if traj.t.size else math.nan
    horizon = float(t_end) if t_end is not None else reached
    ok = traj.status is RunStatus.OK and traj.t.size > 0 and reached >= horizon - TIME_MATCH_TOL
    reason = (
        "the run reached its horizon"
        if ok
        else f"the run did not finish: {traj.message or traj.status.value}"
    )
    return Check("completed", Subject.plant(traj.engine), reached, horizon, "s", bool(ok), reason)


def compare(
    analytic: Trajectory,
    mujoco: Trajectory | None,
    scene: Any = None,
    thresholds: Mapping[str, Threshold] | None = None,
    t_end: float | None = None,
) -> Comparison:
    """Compare two plants (or check one, when ``mujoco`` is None).

    Args:
        analytic: the reference trajectory (relative checks divide by its scales).
        mujoco: the other plant's trajectory (any engine), or None.
        scene: the scene (for the tracking gains and its ``[thresholds]``); without it the
            closed-form tracking checks are skipped.
        thresholds: thresholds in force (default ``thresholds_for(scene)``).
        t_end: the horizon both runs were asked for, s (default the scene's); a run that stops
            earlier fails its ``completed`` check.

    Returns:
        a frozen :class:`Comparison`.
    """
    th = dict(thresholds) if thresholds is not None else thresholds_for(scene)
    if t_end is None and scene is not None:
        t_end = scene.output.t_end
    notes: list[str] = []
    series: list[Series] = []
    checks: list[Check] = []
    plants = [p for p in (analytic, mujoco) if p is not None]

    for p in plants:
        checks.append(completed_check(p, t_end))
        if p.status is not RunStatus.OK:
            notes.append(
                f"{p.engine} run failed: {p.message} (compared up to t = {p.t[-1]:.6g} s)"
                if p.t.size
                else f"{p.engine} run failed before its first sample: {p.message}"
            )

    if mujoco is not None:
        pair = pair_subject(analytic, mujoco)
        diffs = difference_series(analytic, mujoco)
        series.extend(diffs)
        by = {s.name: s for s in diffs}
        k = by["position_C"].t.shape[0]
        for name in list(Difference)[:6]:  # the absolute ones; the forces are relative, below
            size = pair_magnitude(name, analytic, mujoco, k, scene)
            checks.append(_bound_check(th[name], pair, by[name], magnitude=size))
        if np.any(analytic.torque[:k]) or np.any(mujoco.torque[:k]):
            checks.append(
                _bound_check(
                    th["control_torque"],
                    pair,
                    by["control_torque"],
                    largest_row_norm(analytic.torque[:k]),
                )
            )
        else:
            checks.append(
                _not_applicable(
                    th["control_torque"], pair, "neither plant applies a control torque"
                )
            )
        if analytic.n and (np.any(analytic.rod_forces[:k]) or np.any(mujoco.rod_forces[:k])):
            checks.append(
                _bound_check(
                    th["rod_forces"],
                    pair,
                    by["rod_forces"],
                    float(np.max(np.abs(analytic.rod_forces[:k]), initial=0.0)),
                )
            )
        elif analytic.n:
            checks.append(
                _not_applicable(th["rod_forces"], pair, "neither plant applies a rod force")
            )
    else:
        notes.append("no MuJoCo trajectory: only the analytic plant's own checks were made")

    if scene is None:
        notes.append("no scene given: the closed-form tracking checks were skipped")
    for p in plants:
        ps = plant_series(p, scene)
        series.extend(ps)
        by = {s.name: s for s in ps}
        subj = Subject.plant(p.engine)
        w_size, p_size = tracking_magnitudes(p)
        if "e_omega_law" in by:
            checks.append(
                _bound_check(th["tracking_omega"], subj, by["e_omega_law"], magnitude=w_size)
            )
        if "e_p_law" in by:
            checks.append(_bound_check(th["tracking_p"], subj, by["e_p_law"], magnitude=p_size))
        checks.append(_bound_check(th["quat_norm"], subj, by["quat_norm"]))
        terms = BalanceTerms.of(p.invariants)
        for b in BALANCES:  # relative to the balanced quantity (validation.compare.balances)
            balance = b.balance.value
            checks.append(_bound_check(th[balance], subj, by[balance], b.scale(terms)))

    t = series[0].t if series else analytic.t
    return Comparison(
        scene=analytic.scene,
        t=_frozen(t),
        series=tuple(series),
        checks=tuple(checks),
        notes=tuple(notes),
        thresholds=th,
    )


def compare_plants(
    plants: Sequence[Trajectory],
    scene: Any = None,
    thresholds: Mapping[str, Threshold] | None = None,
    t_end: float | None = None,
) -> Comparison:
    """Compare every pair of plants, and check each plant once.

    The first plant is the reference of the first pair (the two-plant comparison of
    :func:`compare`, keys ``diff.<name>``); every other pair adds its difference series
    (``diff_<pair>.<name>``) and checks (labels ``<pair>.<name>``) under the same thresholds, and
    every plant after the second adds its own checks (tracking, invariants).

    Args:
        plants: one trajectory per plant, in report order (the analytic plant first).
        scene, thresholds, t_end: as for :func:`compare`.
    """
    if not plants:
        raise ValueError("plants: no trajectory to compare")
    first = compare(plants[0], plants[1] if len(plants) > 1 else None, scene, thresholds, t_end)
    series, checks, notes = list(first.series), list(first.checks), list(first.notes)
    for i, j in itertools.combinations(range(len(plants)), 2):
        if (i, j) == (0, 1):
            continue
        c = compare(plants[i], plants[j], scene, first.thresholds, t_end)
        pair = pair_subject(plants[i], plants[j])
        series += [x for x in c.series if x.subject == pair]
        checks += [x for x in c.checks if x.subject == pair]
        if i == 0:  # plant j's own series and checks, once
            own = Subject.plant(plants[j].engine)
            series += [x for x in c.series if x.subject == own]
            checks += [x for x in c.checks if x.subject == own]
            notes += [n for n in c.notes if n not in notes]
    return dataclasses.replace(
        first, series=tuple(series), checks=tuple(checks), notes=tuple(notes)
    )


__all__ = [
    "Check",
    "CheckState",
    "Comparison",
    "Group",
    "Series",
    "Subject",
    "Summary",
    "compare",
    "compare_plants",
    "completed_check",
    "difference_series",
    "judge",
    "plant_series",
]
