"""The referee: with three plants, name the one that disagrees with the two that agree.

For each difference quantity (position of C, attitude, rod positions, velocities, angular velocity,
control torque, rod forces) the three pairwise checks of :func:`validation.compare.checks.compare_plants`
give three values ``d1 ≤ d2 ≤ d3`` (each the check's value: a maximum over time, relative for the
forces), in the threshold's unit. With the quantity's **noise floor**
``floor = REFEREE_NOISE_FRACTION × threshold`` and ``k = REFEREE_SEPARATION`` (both in
:mod:`validation.compare.thresholds`, with their reasons), the whole rule is (:class:`Clause`):

1. ``d3 ≤ floor``: all three agree (``AGREE``): every distance is integration and round-off noise,
   a thousand times inside the threshold, and their ratios decide nothing;
2. ``d2 ≥ k · max(d1, floor)``: the plant outside the closest pair is the **outlier**
   (``OUTLIER``): its distances to the other two are ``d2``, ``d3``; the other two agree to ``d1``
   (a ``d1`` below the floor counts as the floor);
3. otherwise no single plant stands out: ``AGREE`` when every pair passes its threshold, else
   ``DISAGREE`` (all three disagree; the report says so).

Each verdict records the clause that decided it and the floor, and its sentence names them, so
every verdict can be re-derived from the rule as :func:`rule_text` prints it under the report's
table. With fewer than three plants no verdict can be given: a disagreement between two plants
cannot be attributed to either.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from validation.compare.checks import Check, Comparison, Difference, Subject, subject_order_key
from validation.compare.thresholds import REFEREE_NOISE_FRACTION, REFEREE_SEPARATION

QUANTITIES = tuple(d.value for d in Difference)
"""The difference quantities the referee rules on (names of :mod:`validation.compare.thresholds`)."""

LABELS = {
    "position_C": "position of C",
    "attitude": "attitude",
    "rod_positions": "rod positions",
    "velocity_C": "velocity of C",
    "rod_velocities": "rod velocities",
    "angular_velocity": "angular velocity",
    "control_torque": "control torque (relative)",
    "rod_forces": "rod forces (relative)",
}


class VerdictKind(StrEnum):
    """What the referee found for one quantity."""

    AGREE = "agree"
    OUTLIER = "outlier"
    DISAGREE = "all disagree"


class Clause(StrEnum):
    """The clause of the rule (module docstring) that decided a verdict."""

    BELOW_FLOOR = "below noise floor"  # 1: d3 <= floor
    SEPARATED = "separated"  # 2: d2 >= k max(d1, floor)
    WITHIN_THRESHOLD = "within threshold"  # 3: no outlier, every pair passes
    OVER_THRESHOLD = "over threshold"  # 3: no outlier, some pair fails


def noise_floor(threshold: float) -> float:
    """The referee's noise floor of a quantity with this threshold (same unit)."""
    return REFEREE_NOISE_FRACTION * threshold


def rule_text() -> str:
    """The whole rule in words, with its constants, as the report prints it under the table."""
    return (
        "The rule, for each row's three values d1 ≤ d2 ≤ d3 (each pair's maximum over time; "
        "relative for the forces): "
        f"(1) all three agree when d3 ≤ the noise floor, {REFEREE_NOISE_FRACTION:g} × the "
        "threshold (column *noise floor*): distances a thousand times inside the threshold are "
        "integration and round-off noise, and their ratios decide nothing; "
        f"(2) else the plant outside the closest pair is the outlier when "
        f"d2 ≥ {REFEREE_SEPARATION:g} × max(d1, noise floor); "
        "(3) else no plant stands out: they agree when every pair passes its threshold, and all "
        "three disagree otherwise "
        "(`validation.compare.thresholds.REFEREE_NOISE_FRACTION`, `REFEREE_SEPARATION`)."
    )


@dataclass(frozen=True)
class Verdict:
    """The referee's ruling on one quantity.

    Attributes:
        quantity: the threshold name (``rod_positions``).
        kind: see :class:`VerdictKind`.
        outlier: the outlier's engine name ("" unless ``kind`` is OUTLIER).
        text: one sentence for people, naming plants by their settings.
        values: pair subject (``analytic vs mujoco``) -> the check's value.
        unit: unit of the values and the threshold.
        threshold: the quantity's threshold.
        clause: the clause of the rule that decided it (None: not recorded).
        floor: the quantity's noise floor (:func:`noise_floor`), in ``unit``.
    """

    quantity: str
    kind: VerdictKind
    outlier: str
    text: str
    values: Mapping[str, float] = field(default_factory=dict)
    unit: str = ""
    threshold: float = math.nan
    clause: Clause | None = None
    floor: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        return {
            "quantity": self.quantity,
            "verdict": self.kind.value,
            "outlier": self.outlier,
            "text": self.text,
            "values": dict(self.values),
            "unit": self.unit,
            "threshold": self.threshold,
            "noise_floor": self.floor,
            "clause": self.clause.value if self.clause else None,
        }


def _fmt(x: float, unit: str) -> str:
    u = "" if unit == "1" else f" {unit}"
    return f"{x:.2g}{u}"


def _span(lo: float, hi: float, unit: str) -> str:
    a, b = _fmt(lo, unit), _fmt(hi, unit)
    return a if a == b else f"{a} to {b}"


def rule(
    quantity: str,
    checks: Mapping[Subject, Check],
    names: Mapping[str, str] | None = None,
) -> Verdict:
    """The verdict on one quantity from its three pairwise checks (subject -> check).

    Args:
        quantity: the threshold name.
        checks: exactly three pair subjects covering three plants.
        names: engine name -> how to name it in the text (e.g. ``MuJoCo RK4 dt 0.00025 s``).
    """
    if len(checks) != 3:
        raise ValueError(
            f"checks: the referee needs the three pairs of three plants (got {len(checks)})"
        )
    names = dict(names or {})

    def size(c: Check) -> float:  # a value that could not be computed is the worst
        return math.inf if math.isnan(c.value) else c.value

    items = sorted(checks.items(), key=lambda kv: (size(kv[1]), kv[0].value))
    (p1, c1), (_, c2), (_, c3) = items
    d1, d2, d3 = size(c1), size(c2), size(c3)
    unit, threshold = c1.unit, c1.threshold
    floor = noise_floor(threshold)
    values = {p.value: checks[p].value for p in sorted(checks, key=subject_order_key)}
    label = LABELS.get(quantity, quantity)
    plants = {e for p, _ in items for e in p.plants}
    y, z = p1.plants
    (x,) = plants - {y, z}

    def nm(e: str) -> str:
        return names.get(e, e)

    def verdict(kind: VerdictKind, clause: Clause, text: str, outlier: str = "") -> Verdict:
        return Verdict(
            quantity, kind, outlier, f"{label}: {text}", values, unit, threshold, clause, floor
        )

    if d3 <= floor:
        return verdict(
            VerdictKind.AGREE,
            Clause.BELOW_FLOOR,
            f"all three agree: every distance is below the noise floor {_fmt(floor, unit)} "
            f"(largest {_fmt(d3, unit)})",
        )
    if d2 >= REFEREE_SEPARATION * max(d1, floor):
        closest = (
            f"agree to {_fmt(d1, unit)}"
            if d1 >= floor
            else f"agree below the noise floor {_fmt(floor, unit)} ({_fmt(d1, unit)})"
        )
        return verdict(
            VerdictKind.OUTLIER,
            Clause.SEPARATED,
            f"{nm(x)} is the outlier, {_span(d2, d3, unit)} from the others; "
            f"{nm(y)} and {nm(z)} {closest}",
            x,
        )
    if all(c.passed for c in (c1, c2, c3)):
        return verdict(
            VerdictKind.AGREE,
            Clause.WITHIN_THRESHOLD,
            f"no outlier (the distances are within {REFEREE_SEPARATION:g}× of each other); the "
            f"three agree within their threshold (largest difference {_fmt(d3, unit)}, "
            f"threshold {_fmt(threshold, unit)})",
        )
    return verdict(
        VerdictKind.DISAGREE,
        Clause.OVER_THRESHOLD,
        f"all three disagree ({_fmt(d1, unit)} to {_fmt(d3, unit)}, threshold "
        f"{_fmt(threshold, unit)}); no two plants confirm each other",
    )


def referee(cmp: Comparison, names: Mapping[str, str] | None = None) -> tuple[Verdict, ...]:
    """Verdicts on every quantity that all three pairs of ``cmp`` checked (empty otherwise; a
    quantity that does not apply, such as the control torque of a scene without one, has none)."""
    pairs = {c.subject for c in cmp.checks if c.subject.is_pair}
    if len(pairs) != 3:
        return ()
    out = []
    for q in QUANTITIES:
        by = {
            c.subject: c for c in cmp.checks if c.subject.is_pair and c.name == q and c.applicable
        }
        if len(by) == 3:
            out.append(rule(q, by, names))
    return tuple(out)


def summary_lines(verdicts: Sequence[Verdict]) -> list[str]:
    """One line per verdict, outliers and disagreements first."""
    order = {VerdictKind.OUTLIER: 0, VerdictKind.DISAGREE: 1, VerdictKind.AGREE: 2}
    return [v.text for v in sorted(verdicts, key=lambda v: order[v.kind])]


__all__ = [
    "QUANTITIES",
    "Clause",
    "Verdict",
    "VerdictKind",
    "noise_floor",
    "referee",
    "rule",
    "rule_text",
    "summary_lines",
]
