"""One scene run on every chosen plant under the same controller, and judged.

:func:`judge_scene` is a module-level function of plain inputs (a scene file's dict, plant names or
picklable :class:`analytic.plant.Plant` instances, a horizon): it travels to process pools and
Dask workers like the sweep's tasks. It runs each plant at the scene's default settings, compares
them with the comparison's own checks (:func:`validation.compare.compare_plants`, the scene's
thresholds) and asks the referee (:func:`validation.compare.referee`); no figure, recording or
file is made. What it returns, :class:`Outcome`, is plain data (JSON-able through ``to_dict``).

A disagreement (:class:`Disagreement`) is one of: a failed check (its label, e.g.
``analytic_vs_mujoco.rod_positions`` or ``mujoco.energy``), a referee outlier (quantity and the
plant outside the agreeing two), or a plant that raised or stopped before the horizon. A scene
the loader or a plant refuses is a refusal with its reason, never a disagreement.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from analytic.plant import Plant
from analytic.scene import Scene, scene_from_dict
from analytic.trajectory import RunStatus


class Kind(StrEnum):
    """What kind of disagreement."""

    CHECK = "failed check"  # a check of compare_plants failed: ``what`` is its label
    OUTLIER = "outlier"  # the referee named ``plant`` the outlier on quantity ``what``
    RAISED = "plant raised"  # ``plant`` raised an exception: ``what`` is its type
    STOPPED = "plant stopped"  # ``plant`` returned before the horizon (failed or diverged)


@dataclass(frozen=True, order=True)
class Disagreement:
    """One disagreement: its kind, what (a check label, a quantity, an exception type), and the
    plant it names ("" for a failed pair check or a plant-independent one)."""

    kind: Kind
    what: str
    plant: str = ""

    @property
    def key(self) -> str:
        """``outlier:rod_positions:pinocchio``: unique, stable, file-name safe after slugging."""
        return ":".join(x for x in (self.kind.name.lower(), self.what, self.plant) if x)

    def to_dict(self) -> dict[str, str]:
        return {"kind": self.kind.value, "what": self.what, "plant": self.plant, "key": self.key}

    @classmethod
    def from_dict(cls, d: dict[str, str]) -> Disagreement:
        return cls(Kind(d["kind"]), d["what"], d.get("plant", ""))


@dataclass(frozen=True)
class Outcome:
    """How one scene went.

    Attributes:
        refused: plant (or ``scene`` for the loader) -> the refusal's one-line reason.
        ran: the plants that ran, in the order given.
        checks: check label -> (value, threshold, state) of every applicable check.
        verdicts: the referee's verdicts (``Verdict.to_dict()``), empty with fewer than 3 plants.
        disagreements: sorted, without repeats.
        messages: plant -> why it raised or stopped.
        walls: plant -> wall time of its run, s.
    """

    refused: dict[str, str] = field(default_factory=dict)
    ran: tuple[str, ...] = ()
    checks: dict[str, tuple[float, float, str]] = field(default_factory=dict)
    verdicts: tuple[dict[str, Any], ...] = ()
    disagreements: tuple[Disagreement, ...] = ()
    messages: dict[str, str] = field(default_factory=dict)
    walls: dict[str, float] = field(default_factory=dict)

    @property
    def judged(self) -> bool:
        """At least two plants ran (there was something to compare)."""
        return len(self.ran) >= 2

    def shows(self, d: Disagreement) -> bool:
        """Whether this outcome still shows ``d``."""
        return d in self.disagreements

    def to_dict(self) -> dict[str, Any]:
        return {
            "refused": dict(self.refused),
            "ran": list(self.ran),
            "checks": {k: list(v) for k, v in self.checks.items()},
            "verdicts": list(self.verdicts),
            "disagreements": [d.to_dict() for d in self.disagreements],
            "messages": dict(self.messages),
            "walls": dict(self.walls),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Outcome:
        return cls(
            refused=dict(d["refused"]),
            ran=tuple(d["ran"]),
            checks={k: (float(v[0]), float(v[1]), str(v[2])) for k, v in d["checks"].items()},
            verdicts=tuple(d["verdicts"]),
            disagreements=tuple(Disagreement.from_dict(x) for x in d["disagreements"]),
            messages=dict(d["messages"]),
            walls={k: float(v) for k, v in d["walls"].items()},
        )


def plant_name(pl: Plant | str) -> str:
    """A plant's name (``mujoco``), given by name or as an instance."""
    if isinstance(pl, str):
        return pl
    return str(getattr(pl.engine, "value", pl.engine))


def resolve_plant(pl: Plant | str) -> Plant:
    """The plant itself: an instance as given, a name through the registry
    (:func:`mj_bridge.plants.plant`; ``ValueError`` naming ``plants`` for an unknown one)."""
    if isinstance(pl, Plant):
        return pl
    from mj_bridge.plants import plant  # the engines load in the worker that runs them

    return plant(pl)


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".strip()


def _scene(data: dict[str, Any]) -> Scene:
    return scene_from_dict(data)


RUN_BUDGET_S = 30.0
"""Wall-time budget of one plant's run, s: a safety net against a scene far costlier than the
space means to draw; a run over it is counted as ``over budget`` (a refusal, with the plant and
the time reached), never as a disagreement, since whether it trips depends on the machine's load."""


def _budget_progress(budget_s: float):
    from validation.studies.sweep.running import BudgetExceeded

    start = time.perf_counter()

    def progress(t: float) -> None:
        elapsed = time.perf_counter() - start
        if elapsed > budget_s:
            raise BudgetExceeded(budget_s, elapsed, t)

    return progress, BudgetExceeded


def judge_scene(
    data: dict[str, Any],
    plants: Sequence[Plant | str],
    horizon: float,
    budget_s: float = RUN_BUDGET_S,
) -> Outcome:
    """Run the scene file's dict ``data`` on ``plants`` over ``horizon`` s (the scene's default
    settings), each within ``budget_s`` s of wall time (:data:`RUN_BUDGET_S`), and judge it
    (module docstring). Only an interrupt (``KeyboardInterrupt``) escapes."""
    try:
        scene = _scene(data)
        scene.output.with_t_end(horizon, "horizon")
    except ValueError as exc:
        return Outcome(refused={"scene": _one_line(exc)})
    refused: dict[str, str] = {}
    chosen: list[tuple[str, Plant]] = []
    for p in plants:
        name = plant_name(p)
        try:
            pl = resolve_plant(p)
            why = pl.unavailable()
            if why:
                raise ValueError(why)
            pl.check_scene(scene)
        except ValueError as exc:
            refused[name] = _one_line(exc)
            continue
        chosen.append((name, pl))
    trajs, ran, messages, walls, found = [], [], {}, {}, []
    for name, pl in chosen:
        t0 = time.perf_counter()
        progress, over_budget = _budget_progress(budget_s)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                tr = pl.simulate(scene, t_end=horizon, progress=progress)
        except KeyboardInterrupt:
            raise
        except over_budget as exc:
            walls[name] = time.perf_counter() - t0
            refused[name] = f"over budget: {exc}"
            continue
        except Exception as exc:  # a plant failing is a finding, whatever it raises
            walls[name] = time.perf_counter() - t0
            messages[name] = _one_line(exc)
            found.append(Disagreement(Kind.RAISED, type(exc).__name__, name))
            continue
        walls[name] = time.perf_counter() - t0
        if tr.status is RunStatus.INTERRUPTED:
            raise KeyboardInterrupt(tr.message)
        if tr.status is not RunStatus.OK:
            messages[name] = tr.message.splitlines()[0] if tr.message else str(tr.status)
            found.append(Disagreement(Kind.STOPPED, str(tr.status.value), name))
        trajs.append(tr)
        ran.append(name)
    checks: dict[str, tuple[float, float, str]] = {}
    verdicts: tuple[dict[str, Any], ...] = ()
    if len(trajs) >= 2:
        from validation.compare.checks import compare_plants
        from validation.compare.referee import VerdictKind, referee

        cmp = compare_plants(trajs, scene, t_end=horizon)
        for c in cmp.checks:
            if not c.applicable:
                continue
            value = float(c.value) if math.isfinite(c.value) else math.inf
            checks[c.label] = (value, float(c.threshold), c.state.value)
            if not c.passed:
                found.append(Disagreement(Kind.CHECK, c.label))
        vs = referee(cmp)
        verdicts = tuple(v.to_dict() for v in vs)
        found += [
            Disagreement(Kind.OUTLIER, v.quantity, v.outlier)
            for v in vs
            if v.kind is VerdictKind.OUTLIER
        ]
    return Outcome(
        refused=refused,
        ran=tuple(ran),
        checks=checks,
        verdicts=verdicts,
        disagreements=tuple(sorted(set(found))),
        messages=messages,
        walls=walls,
    )


__all__ = ["RUN_BUDGET_S", "Disagreement", "Kind", "Outcome", "judge_scene", "plant_name", "resolve_plant"]
