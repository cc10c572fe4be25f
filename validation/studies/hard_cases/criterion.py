"""The criterion of a hard case: the ``[hard_case]`` table of its scene file, read and validated.

The format is documented in ``docs/hard_cases.md``. In short::

    [thresholds]                              # the bounds, by name (numbers only)
    hard_reference_rel = 1e-9
    hard_mujoco_reference_rel = 1e-8          # hard_<plant>_<x>: plant's own value of hard_<x>

    [hard_case]
    criterion = "one sentence: what the case shows"
    fast = true                               # in the fast subset (short on every plant)

    [hard_case.not_applicable]                # optional: plant -> why the case cannot apply
    mujoco = "MuJoCo renormalises ..."

    [[hard_case.check]]                       # one per judged figure (for every plant it applies to)
    what = "angular_velocity"                 # a Measure
    against = "euler"                         # a Reference
    bound = "hard_reference_rel"              # a hard_* name of [thresholds] (none for indicators)
    why = "why this bound"
    until = 20.0                              # optional, s: only samples up to here (against analytic)
    note_if_failed = "..."                    # optional: reported when the check fails

    [[hard_case.report]]                      # optional: figures reported, not judged
    what = "attitude"
    against = "euler"
    why = "..."

    [hard_case.solvers]                       # parameters of a reference that needs them
    methods = ["Radau", "LSODA"]
    rtol = 1e-8
    atol = 1e-10

Nothing in the file is evaluated: every value is a number, a string from a closed set (the
catalogue's enums, :mod:`validation.studies.hard_cases.catalogue`; a plant; a built-in scene name)
or a sentence. A change to the format (a key, a rule between keys) costs this module only: the
records of a read criterion (:class:`Criterion`, :class:`CheckSpec`) and their reader. Every error is a ``ValueError`` naming the
field (``hard_case.check[2].bound: ...``) and the value.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from analytic.effects import SolverMethod
from analytic.scene import Scene
from analytic.trajectory import Engine
from validation.scenes import builtin_names
from validation.studies.hard_cases.catalogue import (
    IMPLICIT,
    MEASURES,
    UNTIL_REFERENCES,
    Measure,
    MeasureInfo,
    Reference,
)

HARD_PREFIX = "hard_"
"""The prefix of a hard case's bounds in ``[thresholds]`` (``validation.compare.thresholds`` skips them)."""

_R = Reference


@dataclass(frozen=True)
class CheckSpec:
    """One ``[[hard_case.check]]`` (judged) or ``[[hard_case.report]]`` (reported) entry.

    Attributes:
        what, against: the measure and its reference (a key of :data:`MEASURES`).
        bound: the ``hard_*`` threshold (``""`` for an indicator, judged against 0, and for a
            report).
        why: why this figure, and why its bound.
        until: the last sample time used, s (None: the whole run).
        note_if_failed: reported with the row when the check fails.
        judged: False for a report.
        field: where it stands in the file (``hard_case.check[2]``), for messages.
    """

    what: Measure
    against: Reference
    bound: str
    why: str
    until: float | None = None
    note_if_failed: str = ""
    judged: bool = True
    field: str = ""

    @property
    def info(self) -> MeasureInfo:
        return MEASURES[(self.what, self.against)]

    @property
    def name(self) -> str:
        """``attitude_vs_euler``; against the analytic plant just ``attitude`` (the check's
        subject says the pair); ``(t ≤ 20 s)`` appended for ``until``."""
        base = (
            self.what.value
            if self.against in (_R.ANALYTIC, _R.RUN, _R.BALANCES)
            else f"{self.what.value}_vs_{self.against.value}"
        )
        return base if self.until is None else f"{base} (t ≤ {self.until:g} s)"


@dataclass(frozen=True)
class SolverParams:
    """``[hard_case.solvers]``: the other scipy methods and their tolerances."""

    methods: tuple[SolverMethod, ...]
    rtol: float
    atol: float


@dataclass(frozen=True)
class MirrorParams:
    """``[hard_case.mirror]``: the built-in scene whose u(0) is this scene's, negated."""

    scene: str


@dataclass(frozen=True)
class PinvParams:
    """``[hard_case.pinv_law]``: the requirement rows duplicated.

    Attributes:
        duplicate_mass: the mass (0-based) whose row is appended again unchanged (redundant).
        conflict_axis: the ω component (0-based) whose row is appended again with its right-hand
            side shifted by ``conflict`` (rad/s²).
    """

    duplicate_mass: int
    conflict_axis: int
    conflict: float


@dataclass(frozen=True)
class Criterion:
    """A hard case's ``[hard_case]`` table and its ``hard_*`` bounds, validated.

    Attributes:
        criterion: the sentence in the table's criterion column.
        fast: in the fast subset.
        checks: judged entries, in file order; reports: reported entries.
        not_applicable: plant -> why the case cannot apply to it.
        bounds: ``hard_*`` name -> value (the scene's ``[thresholds]``).
        solvers, mirror, pinv_law: the parameters of those references (None when unused).
    """

    criterion: str
    fast: bool
    checks: tuple[CheckSpec, ...]
    reports: tuple[CheckSpec, ...] = ()
    not_applicable: Mapping[str, str] = field(default_factory=dict)
    bounds: Mapping[str, float] = field(default_factory=dict)
    solvers: SolverParams | None = None
    mirror: MirrorParams | None = None
    pinv_law: PinvParams | None = None

    @property
    def references(self) -> frozenset[Reference]:
        return frozenset(s.against for s in (*self.checks, *self.reports))

    def bound_for(self, spec: CheckSpec, plant: str) -> tuple[str, float]:
        """``(name, value)`` of ``spec``'s bound for ``plant``: the scene's ``hard_<plant>_<x>``
        where it gives one, else ``hard_<x>``; an indicator's is ``("", 0.0)``."""
        if not spec.bound:
            return "", 0.0
        own = f"{HARD_PREFIX}{plant}_{spec.bound.removeprefix(HARD_PREFIX)}"
        name = own if own in self.bounds else spec.bound
        return name, self.bounds[name]


# ----------------------------------------------------------------------------------------------
# Reading
# ----------------------------------------------------------------------------------------------


def known_plants() -> tuple[str, ...]:
    """The plant names a criterion may name: the built-ins and every installed plant plugin's
    (:mod:`mj_bridge.registry`, names only: nothing is imported)."""
    # deferred: mj_bridge.registry reads installed metadata (importlib.metadata, ~20 ms by python -X importtime), paid only when plants are ordered
    from mj_bridge.registry import BUILTIN, plugin_names

    return BUILTIN + plugin_names()


_TOP_KEYS = {
    "criterion",
    "fast",
    "not_applicable",
    "check",
    "report",
    _R.SOLVERS.value,
    _R.MIRROR.value,
    _R.PINV_LAW.value,
}


def parse_criterion(scene: Scene) -> Criterion:
    """The criterion of a hard-case scene (``scene.extra["hard_case"]`` and the ``hard_*``
    entries of its ``[thresholds]``).

    Raises:
        ValueError: naming the field (``hard_case.check[1].what``, ``thresholds.hard_x``) and the
            value, for a missing table, an unknown key or value, a bound that is not a number of
            ``[thresholds]``, a ``hard_*`` number no check uses, or a reference without its
            parameters.
    """
    raw = dict(getattr(scene, "extra", {}) or {})
    table = raw.get("hard_case")
    if table is None:
        raise ValueError("hard_case: missing required table (a hard case states its criterion)")
    _mapping(table, "hard_case")
    _no_unknown(table, _TOP_KEYS, "hard_case")
    criterion = _sentence(table, "criterion", "hard_case")
    fast = table.get("fast")
    if not isinstance(fast, bool):
        raise ValueError(f"hard_case.fast: must be true or false (got {fast!r})")
    bounds = _bounds(raw.get("thresholds", {}) or {})
    checks = _entries(table, "check", judged=True, bounds=bounds)
    if not checks:
        raise ValueError("hard_case.check: a hard case needs at least one [[hard_case.check]]")
    reports = _entries(table, "report", judged=False, bounds=bounds)
    not_applicable = _not_applicable(table.get("not_applicable", {}))
    out = Criterion(
        criterion=criterion,
        fast=fast,
        checks=checks,
        reports=reports,
        not_applicable=not_applicable,
        bounds=bounds,
        solvers=_solvers(table.get(_R.SOLVERS.value)),
        mirror=_mirror(table.get(_R.MIRROR.value)),
        pinv_law=_pinv(table.get(_R.PINV_LAW.value), scene),
    )
    _check_parameters(out, table)
    _check_bounds_used(out)
    return out


def _mapping(v: Any, name: str) -> Mapping[str, Any]:
    if not isinstance(v, Mapping):
        raise ValueError(f"{name}: must be a table (got {v!r})")
    return v


def _no_unknown(table: Mapping[str, Any], allowed: set[str], name: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ValueError(
            f"{name}.{unknown[0]}: unknown key (allowed: {', '.join(sorted(allowed))})"
        )


def _sentence(table: Mapping[str, Any], key: str, name: str, required: bool = True) -> str:
    v = table.get(key)
    if v is None and not required:
        return ""
    if not isinstance(v, str) or not v.strip():
        raise ValueError(f"{name}.{key}: must be a non-empty string (got {v!r})")
    return v


def _number(v: Any, name: str, *, positive: bool = True) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ValueError(f"{name}: must be a finite number (got {v!r})")
    if positive and not v > 0:
        raise ValueError(f"{name}: must be positive (got {v!r})")
    return float(v)


def _enum(v: Any, kind: type[StrEnum], name: str) -> Any:
    try:
        return kind(v)
    except (ValueError, TypeError):
        allowed = ", ".join(repr(e.value) for e in kind)
        raise ValueError(f"{name}: unknown value {v!r} (allowed: {allowed})") from None


def _bounds(thresholds: Mapping[str, Any]) -> dict[str, float]:
    """The ``hard_*`` numbers of ``[thresholds]`` (a sentence there is refused: the criterion
    lives in ``[hard_case]``)."""
    out = {}
    for k, v in thresholds.items():
        if not k.startswith(HARD_PREFIX):
            continue
        if isinstance(v, str):
            raise ValueError(
                f"thresholds.{k}: a bound must be a number (got {v!r}); the criterion and the "
                f"reasons belong in [hard_case]"
            )
        out[k] = _number(v, f"thresholds.{k}", positive=False)
        if out[k] < 0:
            raise ValueError(f"thresholds.{k}: must be non-negative (got {v!r})")
    return out


def _entries(
    table: Mapping[str, Any], key: str, *, judged: bool, bounds: Mapping[str, float]
) -> tuple[CheckSpec, ...]:
    items = table.get(key, [])
    if not isinstance(items, list):
        raise ValueError(f"hard_case.{key}: must be an array of tables [[hard_case.{key}]]")
    allowed = {"what", "against", "why", "until"}
    if judged:
        allowed |= {"bound", "note_if_failed"}
    out = []
    seen: dict[str, str] = {}
    for i, item in enumerate(items):
        name = f"hard_case.{key}[{i}]"
        _mapping(item, name)
        _no_unknown(item, allowed, name)
        what = _enum(item.get("what"), Measure, f"{name}.what")
        against = _enum(item.get("against"), Reference, f"{name}.against")
        pair = (what, against)
        if pair not in MEASURES or pair in IMPLICIT:
            known = ", ".join(
                m.value for (m, r) in MEASURES if r is against and (m, r) not in IMPLICIT
            )
            raise ValueError(
                f"{name}.what: {what.value!r} is not measured against {against.value!r} "
                f"(against {against.value!r}: {known or 'nothing to name'})"
            )
        info = MEASURES[pair]
        bound = ""
        if judged and info.indicator:
            if "bound" in item:
                raise ValueError(
                    f"{name}.bound: {what.value!r} is an indicator (1 fails, 0 passes), judged "
                    f"against 0 with no bound (got {item['bound']!r})"
                )
        elif judged:
            bound = item.get("bound")
            if not isinstance(bound, str) or not bound.startswith(HARD_PREFIX):
                raise ValueError(
                    f"{name}.bound: must name a {HARD_PREFIX}* entry of [thresholds] (got {bound!r})"
                )
            if bound not in bounds:
                known = ", ".join(sorted(bounds)) or "none"
                raise ValueError(
                    f"{name}.bound: no number {bound!r} in [thresholds] (there: {known})"
                )
        until = None
        if "until" in item:
            if against not in UNTIL_REFERENCES:
                raise ValueError(
                    f"{name}.until: only for checks against "
                    f"{' or '.join(repr(r.value) for r in sorted(UNTIL_REFERENCES))} "
                    f"(got against {against.value!r})"
                )
            until = _number(item["until"], f"{name}.until")
        spec = CheckSpec(
            what=what,
            against=against,
            bound=bound,
            why=_sentence(item, "why", name),
            until=until,
            note_if_failed=_sentence(item, "note_if_failed", name, required=False),
            judged=judged,
            field=name,
        )
        if spec.name in seen:
            raise ValueError(f"{name}: the same figure as {seen[spec.name]} ({spec.name})")
        seen[spec.name] = name
        out.append(spec)
    return tuple(out)


def _not_applicable(v: Any) -> dict[str, str]:
    _mapping(v, "hard_case.not_applicable")
    out = {}
    for plant, why in v.items():
        name = f"hard_case.not_applicable.{plant}"
        known = known_plants()
        if plant not in known:
            raise ValueError(f"{name}: unknown plant (allowed: {', '.join(known)})")
        if plant == Engine.ANALYTIC.value:
            raise ValueError(f"{name}: the analytic plant is the reference of every case")
        if not isinstance(why, str) or not why.strip():
            raise ValueError(f"{name}: must be a non-empty string saying why (got {why!r})")
        out[plant] = why
    return out


def _solvers(v: Any) -> SolverParams | None:
    if v is None:
        return None
    name = "hard_case.solvers"
    _mapping(v, name)
    _no_unknown(v, {"methods", "rtol", "atol"}, name)
    methods = v.get("methods")
    if not isinstance(methods, list) or not methods:
        raise ValueError(f"{name}.methods: must be a non-empty list of methods (got {methods!r})")
    ms = tuple(_enum(m, SolverMethod, f"{name}.methods[{i}]") for i, m in enumerate(methods))
    return SolverParams(
        ms, _number(v.get("rtol"), f"{name}.rtol"), _number(v.get("atol"), f"{name}.atol")
    )


def _mirror(v: Any) -> MirrorParams | None:
    if v is None:
        return None
    name = "hard_case.mirror"
    _mapping(v, name)
    _no_unknown(v, {"scene"}, name)
    scene = v.get("scene")
    known = [n for n in builtin_names() if not n.startswith("hard/")]
    if scene not in known:  # a name from a closed list: no path is built from the file
        raise ValueError(
            f"{name}.scene: must be a built-in scene ({', '.join(known)}; got {scene!r})"
        )
    return MirrorParams(scene)


def _pinv(v: Any, scene: Scene) -> PinvParams | None:
    if v is None:
        return None
    name = "hard_case.pinv_law"
    _mapping(v, name)
    _no_unknown(v, {"duplicate_mass", "conflict_axis", "conflict"}, name)
    omega, masses = scene.control.omega, scene.control.masses
    tracked_masses = [i + 1 for i in (masses.indices if masses is not None else ())]
    tracked_axes = [c + 1 for c in (omega.components if omega is not None else ())]
    m = v.get("duplicate_mass")
    if isinstance(m, bool) or m not in tracked_masses:
        raise ValueError(
            f"{name}.duplicate_mass: must be a tracked mass, 1-based ({tracked_masses}; got {m!r})"
        )
    ax = v.get("conflict_axis")
    if isinstance(ax, bool) or ax not in tracked_axes:
        raise ValueError(
            f"{name}.conflict_axis: must be a tracked ω component, 1-based ({tracked_axes}; got {ax!r})"
        )
    return PinvParams(int(m) - 1, int(ax) - 1, _number(v.get("conflict"), f"{name}.conflict"))


def _check_parameters(c: Criterion, table: Mapping[str, Any]) -> None:
    """A reference that needs parameters has them; parameters of an unused reference are
    refused (they would do nothing)."""
    need = {
        _R.SOLVERS: c.solvers,
        _R.MIRROR: c.mirror,
        _R.ANALYTIC_MIRROR: c.mirror,
        _R.PINV_LAW: c.pinv_law,
    }
    for ref, params in need.items():
        if ref in c.references and params is None:
            key = _R.MIRROR.value if ref is _R.ANALYTIC_MIRROR else ref.value
            raise ValueError(
                f"hard_case.{key}: missing required table (checks against {ref.value!r})"
            )
    used = {_R.MIRROR.value if r is _R.ANALYTIC_MIRROR else r.value for r in c.references}
    for key in (_R.SOLVERS.value, _R.MIRROR.value, _R.PINV_LAW.value):
        if key in table and key not in used:
            raise ValueError(f"hard_case.{key}: no check is made against {key!r}")


def _check_bounds_used(c: Criterion) -> None:
    """Every ``hard_*`` number is some check's bound, or a plant's own value of one."""
    used = {s.bound for s in c.checks if s.bound}
    for k in c.bounds:
        if k in used:
            continue
        rest = k.removeprefix(HARD_PREFIX)
        plant = next((p for p in known_plants() if rest.startswith(f"{p}_")), None)
        if plant is not None and f"{HARD_PREFIX}{rest.removeprefix(plant + '_')}" in used:
            continue
        raise ValueError(f"thresholds.{k}: no [[hard_case.check]] uses this bound")


__all__ = [
    "HARD_PREFIX",
    "CheckSpec",
    "Criterion",
    "MirrorParams",
    "PinvParams",
    "SolverParams",
    "known_plants",
    "parse_criterion",
]
