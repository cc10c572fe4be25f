"""The referee: with three or more plants, name the plants that disagree with a majority that agrees.

For each difference quantity (position of C, attitude, rod positions, velocities, angular velocity,
control torque, rod forces) the pairwise checks of :func:`validation.compare.checks.compare_plants`
give one distance ``d(a, b)`` per pair of plants (the check's value: a maximum over time, relative
for the forces, in the threshold's unit; a value that could not be computed is infinite). With the
quantity's **noise floor** ``f`` (:class:`NoiseFloor`) and ``k = REFEREE_SEPARATION``, the whole
rule is (:class:`Clause`; :func:`rule_text` prints it under the report's table):

1. every ``d ≤ f``: all agree (``AGREE``): every distance is integration and round-off noise and
   their ratios decide nothing;
2. a **group** is a set ``G`` of at least two plants, not all of them, with a finite spread
   ``s(G)`` (its largest internal distance) that is **separated**: every plant outside ``G`` is at
   least ``k · max(s(G), f)`` (and more than ``s(G)``) from every member. Two groups are nested
   or disjoint, so the groups holding more than half of the plants are nested: the innermost, the
   tightest **majority**, is the group, and the plants outside it are the **outliers**
   (``OUTLIER``), each with its distance to the group (the smallest distance to a member). (The
   innermost, not the outermost: a plant ten times off the majority's spread is named whether or
   not a plant farther still is there, as with three plants);
3. else, when there are groups but none is a majority, the plants **split** (``SPLIT``): the
   groups are named (a 3-3 split, two pairs of twins among four);
4. else no plant stands out: ``AGREE`` when every pair passes its threshold, else ``DISAGREE``
   (no two plants confirm each other).

With three plants, ``d1 ≤ d2 ≤ d3``, clauses 1-2 are the three-plant rule: all agree when
``d3 ≤ f``; the plant outside the closest pair is the outlier when ``d2 ≥ k · max(d1, f)`` (a pair
is the only group a majority of three can be, and only the closest pair can be separated); three
plants never split. In the degenerate cases, every distance infinite (no plant's values could be
compared) or a floor of 0 (a threshold of 0 and no round-off scale) with the two smallest distances
0 (an "outlier" would sit at distance 0 from a member), no plant is named.

The noise floor ``f`` of each quantity, the larger of a fraction of its threshold and its
round-off, is :mod:`validation.compare.noise_floor`'s; each verdict records it and its sentence
states it.

With fewer than three plants :func:`referee` gives no verdict: a disagreement between two plants
cannot be attributed to either (:func:`decide` still rules on two: agree or disagree).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from validation.compare.checks import Check, Comparison
from validation.compare.differences import Difference
from validation.compare.noise_floor import (
    FORCE_QUANTITIES,
    FloorPart,
    NoiseFloor,
    floor_rule_text,
    fmt,
    roundoff_scales,
)
from validation.compare.thresholds import REFEREE_SEPARATION

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

    AGREE = "agree"  # all agree (below the floor, or no plant stands out within the threshold)
    OUTLIER = "outlier"  # one or more plants outside a separated majority group
    DISAGREE = "all disagree"  # no group: no two plants confirm each other, some pair fails
    SPLIT = "split"  # separated groups, none holding more than half of the plants


class Clause(StrEnum):
    """The clause of the rule (module docstring) that decided a verdict."""

    BELOW_FLOOR = "below noise floor"  # 1: every d <= floor
    SEPARATED = "separated"  # 2: a unique largest separated majority group
    NO_MAJORITY = "no majority"  # 3: groups, none a majority
    WITHIN_THRESHOLD = "within threshold"  # 4: no group, every pair passes
    OVER_THRESHOLD = "over threshold"  # 4: no group, some pair fails


def rule_text() -> str:
    """The whole rule in words, with its constants, as the report prints it under the table."""
    k = REFEREE_SEPARATION
    return (
        "The rule, for each row's distances d (each pair's maximum over time; relative for the "
        "forces; a value that could not be computed counts as infinite). "
        + floor_rule_text()
        + "(1) All agree when every d ≤ the noise floor. "
        "(2) Else a group (two or more plants, not all) is separated when every plant outside it "
        f"is at least {k:g} × max(s, noise floor) from every member, s being the group's largest "
        "internal distance; groups are nested or disjoint, and the plants outside the innermost "
        "group holding more than half of the plants are the outliers, each at its smallest "
        "distance to the group. "
        "(3) Else, when there are groups but none is a majority, the plants split. "
        "(4) Else no plant stands out: they agree when every pair passes its threshold, and all "
        "disagree otherwise. "
        "With three plants, d1 ≤ d2 ≤ d3: all agree when d3 ≤ the noise floor, and the plant "
        f"outside the closest pair is the outlier when d2 ≥ {k:g} × max(d1, noise floor) "
        "(`validation.compare.thresholds.REFEREE_NOISE_FRACTION`, `REFEREE_ROUNDOFF_STATE`, "
        "`REFEREE_ROUNDOFF_FORCE`, `REFEREE_SEPARATION`)."
    )


@dataclass(frozen=True)
class Outlier:
    """A plant outside the majority group: its name and its distance to the group (the smallest
    distance to a member), in the quantity's unit."""

    plant: str
    distance: float

    def to_dict(self) -> dict[str, Any]:
        return {"plant": self.plant, "distance": self.distance}


@dataclass(frozen=True)
class Ruling:
    """The rule applied to one distance table (:func:`decide`), before it is put in words.

    Attributes:
        kind: see :class:`VerdictKind`.
        clause: the clause that decided.
        group: the innermost majority group (OUTLIER) or every plant (AGREE); empty otherwise.
        outliers: the plants outside the group, farthest first.
        groups: SPLIT: the separated groups, largest first (plants in no group stand alone).
        spread: the group's largest internal distance (AGREE: the largest distance; NaN else).
    """

    kind: VerdictKind
    clause: Clause
    group: tuple[str, ...] = ()
    outliers: tuple[Outlier, ...] = ()
    groups: tuple[tuple[str, ...], ...] = ()
    spread: float = math.nan


def _key(a: str, b: str) -> frozenset[str]:
    return frozenset((str(a), str(b)))


def _separated_groups(
    plants: Sequence[str], d: Mapping[frozenset[str], float], floor: float, k: float
) -> list[tuple[tuple[str, ...], float]]:
    """Every separated group (module docstring, clause 2) with its spread, in ``plants``' order.

    Two groups ``G``, ``H`` that overlap without nesting would need ``s(G) ≥ k·s(H)`` (a member
    of ``G`` outside ``H`` is that far from a shared member) and ``s(H) ≥ k·s(G)``: impossible for
    ``k > 1`` unless the spreads are 0 and the floor is 0.

    A separated group ``G`` is the ball ``{b : d(a, b) ≤ r}`` around any member ``a`` with
    ``r = max_b∈G d(a, b)`` (members are within ``s(G)``, every other plant is farther), so the
    balls around each plant at each of its distances are the only candidates: O(N⁴) work."""
    n = len(plants)
    out: dict[tuple[str, ...], float] = {}
    for a in plants:
        for r in sorted({d[_key(a, b)] for b in plants if b != a}):
            g = tuple(b for b in plants if b == a or d[_key(a, b)] <= r)
            if len(g) < 2 or len(g) == n or g in out:
                continue
            s = max(d[_key(x, y)] for i, x in enumerate(g) for y in g[i + 1 :])
            if not math.isfinite(s):
                continue
            bound = k * max(s, floor)
            far = (d[_key(o, m)] for o in plants if o not in g for m in g)
            if all(x >= bound and x > s for x in far):  # "> s" matters only for s = floor = 0
                out[g] = s
    return list(out.items())


def decide(
    plants: Sequence[str],
    distance: Mapping[tuple[str, str], float],
    passed: Mapping[tuple[str, str], bool],
    floor: float,
    separation: float = REFEREE_SEPARATION,
) -> Ruling:
    """The rule (module docstring) on one quantity's distances between ``plants``.

    Args:
        plants: the plants' names (two or more, distinct), in report order.
        distance: ``(a, b)`` -> d (either order; NaN counts as infinite).
        passed: ``(a, b)`` -> whether the pair passes its threshold.
        floor: the noise floor, in the distances' unit.
        separation: ``k``.

    Raises:
        ValueError: naming ``plants`` or ``distance`` when the table is incomplete.
    """
    plants = tuple(str(p) for p in plants)
    if len(plants) < 2 or len(set(plants)) != len(plants):
        raise ValueError(f"plants: the referee needs two or more distinct plants (got {plants!r})")
    d: dict[frozenset[str], float] = {}
    ok: dict[frozenset[str], bool] = {}
    for (a, b), v in distance.items():
        d[_key(a, b)] = math.inf if math.isnan(v) else float(v)
    for (a, b), v in passed.items():
        ok[_key(a, b)] = bool(v)
    need = {_key(a, b) for i, a in enumerate(plants) for b in plants[i + 1 :]}
    missing = sorted(" vs ".join(sorted(p)) for p in need - set(d))
    if missing:
        raise ValueError(f"distance: no value for the pair {missing[0]} (every pair is needed)")
    d = {p: d[p] for p in need}
    largest = max(d.values())
    if largest <= floor:
        return Ruling(VerdictKind.AGREE, Clause.BELOW_FLOOR, plants, spread=largest)
    groups = _separated_groups(plants, d, floor, separation)
    n = len(plants)
    majority = [(g, s) for g, s in groups if 2 * len(g) > n]
    if majority:  # nested (module docstring): the innermost is the smallest
        size = min(len(g) for g, _ in majority)
        top = [(g, s) for g, s in majority if len(g) == size]
        if len(top) == 1:  # always, but for spreads of exactly 0 with a floor of 0
            ((g, s),) = top
            outs = [Outlier(o, min(d[_key(o, m)] for m in g)) for o in plants if o not in g]
            outs.sort(key=lambda x: -x.distance)
            return Ruling(VerdictKind.OUTLIER, Clause.SEPARATED, g, tuple(outs), spread=s)
    if groups:
        maximal = [g for g, _ in groups if not any(set(g) < set(h) for h, _ in groups)]
        maximal.sort(key=lambda g: (-len(g), plants.index(g[0])))
        return Ruling(VerdictKind.SPLIT, Clause.NO_MAJORITY, groups=tuple(maximal))
    if all(ok.get(p, False) for p in need):
        return Ruling(VerdictKind.AGREE, Clause.WITHIN_THRESHOLD, plants, spread=largest)
    return Ruling(VerdictKind.DISAGREE, Clause.OVER_THRESHOLD)


@dataclass(frozen=True)
class Verdict:
    """The referee's ruling on one quantity.

    Attributes:
        quantity: the threshold name (``rod_positions``).
        kind: see :class:`VerdictKind`.
        outlier: the outliers' names joined by ``", "`` (the name when one; "" when none).
        text: one sentence for people, naming plants by their settings and stating the floor.
        values: pair subject (``analytic vs mujoco``) -> the check's value.
        unit: unit of the values and the threshold.
        threshold: the quantity's threshold.
        clause: the clause of the rule that decided it (None: not recorded).
        floor: the quantity's noise floor value (:attr:`NoiseFloor.value`), in ``unit``.
        plants: the plants ruled on, in report order.
        group: the majority group (OUTLIER) or every plant (AGREE); empty otherwise.
        outliers: the plants outside the group with their distances, farthest first.
        groups: SPLIT: the separated groups, largest first.
        noise: the floor's parts (None: not recorded).
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
    plants: tuple[str, ...] = ()
    group: tuple[str, ...] = ()
    outliers: tuple[Outlier, ...] = ()
    groups: tuple[tuple[str, ...], ...] = ()
    noise: NoiseFloor | None = None

    @property
    def floor_set_by(self) -> FloorPart | None:
        """Which part of the noise floor decided it (None: not recorded)."""
        return self.noise.decided_by if self.noise else None

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
            "noise_floor_parts": self.noise.to_dict() if self.noise else None,
            "clause": self.clause.value if self.clause else None,
            "plants": list(self.plants),
            "group": list(self.group),
            "outliers": [o.to_dict() for o in self.outliers],
            "groups": [list(g) for g in self.groups],
        }


def _names(items: Sequence[str]) -> str:
    items = list(items)
    if len(items) <= 2:
        return " and ".join(items)
    return ", ".join(items[:-1]) + f" and {items[-1]}"


def _sentence(
    r: Ruling, plants: Sequence[str], floor: NoiseFloor, unit: str, threshold: float, nm: Any
) -> str:
    """The verdict in words; every sentence states the noise floor."""
    f, n = floor.value, len(plants)
    fl = f"the noise floor {floor.phrase(unit)}"
    everyone = "both" if n == 2 else ("all three" if n == 3 else f"all {n}")
    if r.clause is Clause.BELOW_FLOOR:
        return f"{everyone} agree: every pair is below {fl} (largest {fmt(r.spread, unit)})"
    if r.kind is VerdictKind.OUTLIER:
        who = [nm(p) for p in r.group]
        inside = (
            f"agree to {fmt(r.spread, unit)} ({fl})"
            if r.spread >= f
            else f"agree below {fl} ({fmt(r.spread, unit)})"
        )
        if len(r.outliers) == 1:
            (o,) = r.outliers
            head = f"{nm(o.plant)} is the outlier, {fmt(o.distance, unit)} from the others"
        else:
            far = ", ".join(f"{nm(o.plant)} {fmt(o.distance, unit)}" for o in r.outliers)
            head = f"{len(r.outliers)} outliers, each at its distance from the group: {far}"
        return f"{head}; {_names(who)} {inside}"
    if r.kind is VerdictKind.SPLIT:
        parts = " vs ".join(_names([nm(p) for p in g]) for g in r.groups)
        grouped = {p for g in r.groups for p in g}
        alone = [nm(p) for p in plants if p not in grouped]
        rest = f"; alone: {_names(alone)}" if alone else ""
        return (
            f"split: no group holds a majority of the {n} plants (groups: {parts}{rest}; each "
            f"group at least {REFEREE_SEPARATION:g}× its spread from the others; {fl})"
        )
    if r.clause is Clause.WITHIN_THRESHOLD:
        return (
            f"no outlier (no plant is {REFEREE_SEPARATION:g}× farther from the others than they "
            f"are from each other); {everyone} agree within their threshold (largest difference "
            f"{fmt(r.spread, unit)}, threshold {fmt(threshold, unit)}; {fl})"
        )
    return (
        f"{everyone} disagree (over the threshold {fmt(threshold, unit)}); no two plants confirm "
        f"each other ({fl})"
    )


def rule(
    quantity: str,
    checks: Mapping[Any, Check],
    names: Mapping[str, str] | None = None,
    floor: NoiseFloor | None = None,
) -> Verdict:
    """The verdict on one quantity from its pairwise checks (pair subject -> check).

    Args:
        quantity: the threshold name.
        checks: one check per pair of two or more plants (every pair; keys are the checks'
            pair subjects, anything with ``plants``, or ``"a vs b"`` text).
        names: plant name -> how to name it in the text (e.g. ``MuJoCo RK4 dt 0.00025 s``).
        floor: the noise floor (default: its threshold part alone, :meth:`NoiseFloor.of` of the
            checks' absolute part).

    Raises:
        ValueError: naming ``checks`` when they do not cover every pair of two or more plants.
    """
    names = {str(k): v for k, v in (names or {}).items()}
    if len(checks) < 1:
        raise ValueError("checks: the referee needs every pair of two or more plants (got none)")
    first = next(iter(checks.values()))
    unit, threshold = first.unit, first.threshold
    plants: list[str] = []
    distance: dict[tuple[str, str], float] = {}
    passed: dict[tuple[str, str], bool] = {}
    values: dict[str, float] = {}
    for subject, c in checks.items():
        pair = tuple(getattr(subject, "plants", None) or str(subject).split(" vs "))
        if len(pair) != 2:
            raise ValueError(f"checks: {str(subject)!r} is not a pair of plants")
        a, b = (str(p) for p in pair)
        plants += [p for p in (a, b) if p not in plants]
        distance[(a, b)] = c.value
        passed[(a, b)] = c.passed
        values[str(getattr(subject, "value", subject))] = c.value
    expected = len(plants) * (len(plants) - 1) // 2
    if len(plants) < 2 or len(distance) != expected:
        raise ValueError(
            f"checks: the referee needs every pair of the plants ({expected} pairs of "
            f"{len(plants)} plants, got {len(distance)})"
        )
    floor = floor or NoiseFloor.of(first.absolute_part)
    r = decide(plants, distance, passed, floor.value)
    label = LABELS.get(quantity, quantity)

    def nm(e: str) -> str:
        return names.get(e, e)

    text = f"{label}: {_sentence(r, plants, floor, unit, threshold, nm)}"
    return Verdict(
        quantity,
        r.kind,
        ", ".join(o.plant for o in r.outliers),
        text,
        values,
        unit,
        threshold,
        r.clause,
        floor.value,
        tuple(plants),
        r.group,
        r.outliers,
        r.groups,
        floor,
    )


# ----------------------------------------------------------------------------------------------
# The referee of a comparison
# ----------------------------------------------------------------------------------------------


def _complete(checks: Sequence[Check]) -> dict[Any, Check]:
    """The checks among the largest set of plants whose every pair was checked: a plant missing a
    pair (a quantity a file does not have) is left out, the one missing most first."""
    by = {c.subject: c for c in checks}
    plants: list[str] = []
    for s in by:
        plants += [str(p) for p in s.plants if str(p) not in plants]
    have = {_key(*s.plants) for s in by}
    while len(plants) >= 2:
        missing = {p: sum(1 for o in plants if o != p and _key(p, o) not in have) for p in plants}
        worst = max(plants[::-1], key=lambda p: missing[p])
        if missing[worst] == 0:
            break
        plants.remove(worst)
    keep = set(plants)
    return {s: c for s, c in by.items() if {str(p) for p in s.plants} <= keep}


def referee(
    cmp: Comparison,
    names: Mapping[str, str] | None = None,
    trajectories: Sequence[Any] = (),
) -> tuple[Verdict, ...]:
    """Verdicts on every quantity checked between three or more plants (empty with fewer).

    Args:
        cmp: the comparison of every pair (:func:`validation.compare.checks.compare_plants`).
        names: plant name -> how to name it in the text.
        trajectories: the plants' trajectories, for the round-off scales of the states
            (:func:`roundoff_scales`; without them the states' floor is the threshold part).

    A quantity that does not apply (the control torque of a scene without one) has no verdict; a
    quantity some plant lacks (a file without ω) is ruled on among the others, if three remain.
    """
    pairs = [c for c in cmp.checks if c.subject.is_pair and c.applicable]
    plants = {str(p) for c in cmp.checks if c.subject.is_pair for p in c.subject.plants}
    if len(plants) < 3:
        return ()
    scales = roundoff_scales(cmp, trajectories)
    out = []
    for q in QUANTITIES:
        by = _complete([c for c in pairs if c.name == q])
        ruled = {str(p) for s in by for p in s.plants}
        if len(ruled) < 3:
            continue
        divisor = min(c.scale for c in by.values()) if q in FORCE_QUANTITIES else 1.0
        # the absolute part: the pairs share it (one threshold), their relative parts differ
        absolute = next(iter(by.values())).absolute_part
        floor = NoiseFloor.of(absolute, scales.get(q), divisor)
        out.append(rule(q, by, names, floor))
    return tuple(out)


def summary_lines(verdicts: Sequence[Verdict]) -> list[str]:
    """One line per verdict, outliers, splits and disagreements first."""
    order = {
        VerdictKind.OUTLIER: 0,
        VerdictKind.SPLIT: 1,
        VerdictKind.DISAGREE: 2,
        VerdictKind.AGREE: 3,
    }
    return [v.text for v in sorted(verdicts, key=lambda v: order[v.kind])]


__all__ = [
    "QUANTITIES",
    "Clause",
    "Outlier",
    "Ruling",
    "Verdict",
    "VerdictKind",
    "decide",
    "referee",
    "rule",
    "rule_text",
    "summary_lines",
]
