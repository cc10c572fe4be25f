"""Shrinking: a disagreement reduced to a minimal scene that still shows it.

The shrinker is greedy and deterministic (a fixed list of simplifying passes, each kept only when
the candidate scene still shows *the same* :class:`~validation.studies.fuzz.judge.Disagreement`:
same check label, or same quantity with the same outlier, or the same plant failing the same
way), repeated until a whole round changes nothing or the evaluation budget is spent. The passes,
simplest first:

1. the shortest horizon (halved down to :data:`MIN_HORIZON_S`);
2. the fewest masses (all dropped; then halves; then one at a time);
3. effects switched off (given torque, mass control, ω control, gravity, cubic then linear
   springs, the masses' own inertia), the weighting back to the default ``M^-1``;
4. the rod through C (zero offset) and along the nearest body axis; identity attitude; zero
   initial position, velocity of C and rod velocities, rod positions at equilibrium;
5. round numbers: each table's numbers to one significant figure, then each number alone.

Why not Hypothesis's shrinker: it shrinks only examples it generated itself, through its own
choice sequence; a counterexample found by a seeded campaign spread over an executor cannot be
handed to it through its public API (explicit ``@example`` inputs are never shrunk, and its
example database's format is internal). Driving the whole campaign from Hypothesis instead would
make generation adaptive and serial, which breaks "same scenes on every executor". The passes
above are the moves Hypothesis's shrinker would make on this space (fewer elements, flags off,
simpler numbers), and each candidate is a valid scene file or is simply not taken.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Protocol

from analytic.effects import Effect, Weighting
from analytic.effects.registry import DECLARATIONS
from analytic.scene.schema import KEYS
from validation.studies.fuzz.judge import Disagreement, Outcome

MIN_HORIZON_S = 0.05
"""Shortest horizon a shrink tries, s (5 samples at 100 Hz)."""
MAX_EVALUATIONS = 80
"""Most scene evaluations one shrink makes (each runs every plant)."""

Scene = dict[str, Any]


@dataclass(frozen=True)
class Shrunk:
    """A shrink's result: the minimal scene dict, its horizon and outcome, evaluations made."""

    data: Scene
    horizon: float
    outcome: Outcome
    evaluations: int


def _effects(d: Scene) -> list[str]:
    return d["scene"]["effects"]


def _n(d: Scene) -> int:
    return len(d.get("masses", {}).get("mass", []))


def _keep_masses(d: Scene, keep: list[int]) -> Scene:
    """``d`` with only the masses of 0-based indices ``keep`` (the springs between the kept
    neighbours: spring ``i`` is below mass ``i``, the last one above the last mass)."""
    e = copy.deepcopy(d)
    if not keep:
        for key in ("masses", "springs"):
            e.pop(key, None)
        for key in ("p", "pdot"):
            e["initial"].pop(key, None)
        drop = {d.effect.value for d in DECLARATIONS if d.needs_masses}
        e["scene"]["effects"] = [x for x in _effects(e) if x not in drop]
        e.get("control", {}).pop("masses", None)
        if "control" in e and set(e["control"]) <= {"weighting"}:
            del e["control"]
        return e
    for key in list(e.get("masses", {})):
        e["masses"][key] = [e["masses"][key][i] for i in keep]
    for key in ("p", "pdot"):
        if key in e["initial"]:
            e["initial"][key] = [e["initial"][key][i] for i in keep]
    for key in list(e.get("springs", {})):
        vals = e["springs"][key]
        e["springs"][key] = [vals[i] for i in keep] + [vals[-1]]
    cm = e.get("control", {}).get("masses")
    if cm is not None:
        new = {old: k + 1 for k, old in enumerate(keep)}
        rows = [j for j, i in enumerate(cm["indices"]) if i - 1 in new]
        if not rows:
            e["control"].pop("masses")
            e["scene"]["effects"] = [x for x in _effects(e) if x != Effect.CONTROL_MASSES.value]
            if set(e["control"]) <= {"weighting"}:
                del e["control"]
        else:
            for key in list(cm):
                cm[key] = [cm[key][j] for j in rows]
            cm["indices"] = [new[i - 1] for i in cm["indices"]]
    return e


def _without(d: Scene, effect: Effect) -> Scene | None:
    """``d`` without ``effect`` and every key and table declared as read by it alone
    (:attr:`analytic.scene.key.Key.effect`); a table it leaves empty goes too, and a
    ``[control]`` left with its weighting alone."""
    if effect.value not in _effects(d):
        return None
    e = copy.deepcopy(d)
    e["scene"]["effects"] = [x for x in _effects(e) if x != effect.value]
    for key in KEYS:
        if key.effect is not effect:
            continue
        parent: Any = e
        for part in key.table.split(".") if key.table else ():
            parent = parent.get(part) if isinstance(parent, dict) else None
        if isinstance(parent, dict):
            parent.pop(key.key, None)
            if key.table in ("springs", "masses") and not parent:
                e.pop(key.table, None)
    if "control" in e and set(e["control"]) <= {"weighting"}:
        del e["control"]
    return e


def _set(d: Scene, path: tuple[str, ...], value: Any) -> Scene | None:
    """``d`` with the value at ``path`` replaced (None when absent or already that value)."""
    node = d
    for k in path[:-1]:
        node = node.get(k)
        if not isinstance(node, dict):
            return None
    if path[-1] not in node or node[path[-1]] == value:
        return None
    e = copy.deepcopy(d)
    node = e
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return e


def round_sig(x: float, digits: int = 1) -> float:
    """``x`` to ``digits`` significant figures (0 stays 0)."""
    if x == 0 or not math.isfinite(x):
        return x
    return float(f"{x:.{digits - 1}e}")


def _round_tree(v: Any) -> Any:
    if isinstance(v, bool) or isinstance(v, int):
        return v
    if isinstance(v, float):
        return round_sig(v)
    if isinstance(v, list):
        return [_round_tree(x) for x in v]
    return v


SHRINK_ORDER: tuple[Effect, ...] = (
    Effect.EXTERNAL_TORQUE,
    Effect.CONTROL_MASSES,
    Effect.CONTROL_OMEGA,
    Effect.GRAVITY,
    Effect.SPRINGS_CUBIC,
    Effect.SPRINGS_LINEAR,
    Effect.MASS_INERTIA,
)
SHRINK_ORDER += tuple(d.effect for d in DECLARATIONS if d.effect not in SHRINK_ORDER)
"""The order in which the shrinker tries a scene without each effect: the given torque and the
control first, then the forces, the masses' inertia last; an effect declared later is tried after
these (so the shrinking of a scene without it is what it was)."""


NUMERIC_TABLES = (
    ("body",),
    ("rod",),
    ("masses",),
    ("springs",),
    ("gravity",),
    ("initial",),
    ("control", "omega"),
    ("control", "masses"),
    ("external_torque",),
)


def _leaves(d: Scene) -> Iterator[tuple[tuple[str, ...], int | None]]:
    """Every float leaf of the numeric tables: (path to the key, index in its list or None)."""
    for table in NUMERIC_TABLES:
        node: Any = d
        for k in table:
            node = node.get(k) if isinstance(node, dict) else None
        if not isinstance(node, dict):
            continue
        for key, v in node.items():
            if isinstance(v, float):
                yield (*table, key), None
            elif isinstance(v, list) and all(isinstance(x, float) for x in v):
                for i in range(len(v)):
                    yield (*table, key), i


def _get(d: Scene, path: tuple[str, ...]) -> Any:
    node: Any = d
    for k in path:
        node = node[k]
    return node


def candidates(d: Scene, horizon: float) -> Iterator[tuple[str, Scene, float]]:
    """Simpler variants of ``d`` (module docstring's order): (what, scene dict, horizon)."""
    h = horizon / 2
    while h >= MIN_HORIZON_S:
        yield f"horizon {h:g} s", d, h
        h /= 2
    n = _n(d)
    if n:
        yield "no masses", _keep_masses(d, []), horizon
        if n > 1:
            half = n // 2
            yield f"first {half} masses", _keep_masses(d, list(range(half))), horizon
            yield f"last {n - half} masses", _keep_masses(d, list(range(half, n))), horizon
            for i in reversed(range(n)):
                yield (
                    f"without mass {i + 1}",
                    _keep_masses(d, [j for j in range(n) if j != i]),
                    horizon,
                )
    for eff in SHRINK_ORDER:
        e = _without(d, eff)
        if e is not None:
            yield f"without {eff.value}", e, horizon
    simple: list[tuple[str, tuple[str, ...], Any]] = [
        ("weighting M^-1", ("control", "weighting"), Weighting.M_INV.value),
        ("rod through C", ("rod", "offset"), [0.0, 0.0, 0.0]),
    ]
    axis = d.get("rod", {}).get("axis")
    if axis:
        k = max(range(3), key=lambda i: abs(axis[i]))
        aligned = [0.0, 0.0, 0.0]
        aligned[k] = 1.0 if axis[k] >= 0 else -1.0
        simple.append(("rod along a body axis", ("rod", "axis"), aligned))
    simple += [
        ("identity attitude", ("initial", "attitude", "quaternion"), [1.0, 0.0, 0.0, 0.0]),
        ("C at rest at the origin", ("initial", "R"), [0.0, 0.0, 0.0]),
        ("no velocity of C", ("initial", "Rdot"), [0.0, 0.0, 0.0]),
    ]
    if n:
        simple += [
            ("no rod velocities", ("initial", "pdot"), [0.0] * n),
            ("masses at equilibrium", ("initial", "p"), list(d["masses"]["p_e"])),
        ]
    for what, path, value in simple:
        e = _set(d, path, value)
        if e is not None:
            yield what, e, horizon
    for table in NUMERIC_TABLES:
        node: Any = d
        for k in table:
            node = node.get(k) if isinstance(node, dict) else None
        if isinstance(node, dict):
            rounded = _round_tree(node)
            if rounded != node:
                e = copy.deepcopy(d)
                parent = _get(e, table[:-1]) if len(table) > 1 else e
                parent[table[-1]] = rounded
                yield f"[{'.'.join(table)}] rounded", e, horizon
    for path, i in _leaves(d):
        v = _get(d, path) if i is None else _get(d, path)[i]
        r = round_sig(v)
        if r == v:
            continue
        e = copy.deepcopy(d)
        if i is None:
            _get(e, path[:-1])[path[-1]] = r
        else:
            _get(e, path)[i] = r
        yield f"{'.'.join(path)}{'' if i is None else f'[{i + 1}]'} rounded", e, horizon


class Handle(Protocol):
    """A candidate's evaluation under way: :meth:`outcome` waits for it, :meth:`cancel` drops it
    (``validation.studies.fuzz.campaign.Pending``)."""

    def outcome(self) -> Outcome: ...

    def cancel(self) -> None: ...


def shrink(
    data: Scene,
    horizon: float,
    target: Disagreement,
    evaluate: Callable[[Scene, float], Outcome],
    max_evaluations: int = MAX_EVALUATIONS,
    first: Outcome | None = None,
    submit: Callable[[Scene, float], Handle] | None = None,
    lookahead: int = 1,
) -> Shrunk:
    """The smallest variant of ``data`` (module docstring) on which ``evaluate(scene, horizon)``
    still shows ``target``; ``first`` is the outcome of ``data`` itself (evaluated when None).

    With ``submit`` (start an evaluation, :class:`Handle`), the next ``lookahead`` candidates are
    evaluated side by side and the first of them, in the passes' order, that shows ``target`` is
    taken, the later ones dropped: the same scene, outcome and evaluation count as one at a time
    (a dropped evaluation is not counted), in less wall time on several workers.

    Raises:
        ValueError: naming ``target`` when ``data`` does not show it to begin with.
    """
    outcome = first if first is not None else evaluate(data, horizon)
    used = 0 if first is not None else 1
    if not outcome.shows(target):
        raise ValueError(f"target: the scene does not show {target.key!r}")
    best, best_h = data, horizon
    changed = True
    while changed and used < max_evaluations:
        changed = False
        tried: set[str] = set()  # moves refused in this round: not retried until the next one
        progressed = True
        while progressed and used < max_evaluations:
            progressed = False
            todo = [c for c in candidates(best, best_h) if c[0] not in tried]
            i = 0
            while i < len(todo) and used < max_evaluations and not progressed:
                window = todo[i : i + max(1, min(lookahead, max_evaluations - used))]
                handles = [submit(c, h) for _, c, h in window] if submit is not None else []
                for j, (what, cand, h) in enumerate(window):
                    used += 1
                    tried.add(what)
                    out = handles[j].outcome() if handles else evaluate(cand, h)
                    if out.shows(target):
                        best, best_h, outcome = cand, h, out
                        changed = progressed = True
                        for later in handles[j + 1 :]:
                            later.cancel()
                        break  # the candidates of the smaller scene, the refused moves skipped
                i += len(window)
    return Shrunk(best, best_h, outcome, used)


__all__ = [
    "MAX_EVALUATIONS",
    "MIN_HORIZON_S",
    "Handle",
    "Shrunk",
    "candidates",
    "round_sig",
    "shrink",
]
