"""One scene run on every chosen plant under the same controller, and judged.

:func:`judge_scene` is a module-level function of plain inputs (a scene file's dict, plant names or
picklable :class:`analytic.plant.Plant` instances, a horizon): it travels to process pools and
Dask workers like the sweep's tasks. It runs each plant at the scene's default settings, compares
them with the comparison's own checks (:func:`validation.compare.compare_plants`, the scene's
thresholds) and asks the referee (:func:`validation.compare.referee`); no figure, recording or
file is made. What it returns, :class:`Outcome`, is plain data (JSON-able through ``to_dict``).

A disagreement (:class:`Disagreement`) is one of: a failed check (its label, e.g.
``analytic_vs_mujoco.rod_positions`` or ``mujoco.energy``), a referee outlier (quantity and the
plant outside the agreeing two), or a plant that raised or stopped before the horizon (its
engine's own guard: a reset, a non-finite state, a failed step; or a run that reports it finished
with a non-finite state, :func:`cut_short`). A run cut short is still compared up to its last
sample, so the referee may name it an outlier there: the outcome records what the referee said,
and settling (:mod:`validation.studies.fuzz.settle`) never calls such an outlier a model
difference. A scene the loader or a plant refuses is a refusal with its reason, never a
disagreement.

Every plant run has a hard wall-time limit (:data:`RUN_BUDGET_S`, or the caller's): on Linux it
runs in a worker process that is killed when the limit passes, whether or not the plant ever
reports progress, forked from here in a single-threaded process (the serial campaign, the process
pool's workers) and by a fork server in a multi-threaded one (a thread or Dask executor,
:func:`run_limited`); elsewhere the limit is checked at the plant's progress reports only. A run over its limit is a timeout
(``Outcome.timeouts``: plant -> the limit, s), its own kind of finding: neither a refusal nor a
disagreement; the plants that finished are still compared with each other.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from multiprocessing import RawValue
from typing import Any

import numpy as np

from analytic.plant import Plant
from analytic.scene import Scene, scene_from_dict
from analytic.trajectory import RunStatus, Trajectory
from mj_bridge.plants import plant
from validation.compare.checks import compare_plants
from validation.compare.referee import VerdictKind, referee
from validation.runs import warm_plants, warmup, workers
from validation.runs.contract import ContractError, contract_problem
from validation.studies.sweep.running import BudgetExceeded

RELATIVE_DIFFERENCES = frozenset(("control_torque", "rod_forces"))
"""The difference quantities whose pair checks are relative: their value is the largest
difference divided by the check's scale (``Outcome.scales``), the largest force of the pair's
reference (``validation.compare.thresholds``)."""


class Kind(StrEnum):
    """What kind of disagreement."""

    CHECK = "failed check"  # a check of compare_plants failed: ``what`` is its label
    OUTLIER = "outlier"  # the referee named ``plant`` the outlier on quantity ``what``
    RAISED = "plant raised"  # ``plant`` raised an exception: ``what`` is its type
    STOPPED = "plant stopped"  # ``plant`` returned before the horizon or non-finite (cut_short)


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
        timeouts: plant -> the wall-time limit (s) its run was stopped at (depends on the
            machine's speed and load, unlike everything else here).
        reached: plant -> the simulated time (s) a run that stopped before the horizon reached
            (its last output sample) or a run stopped at its time limit had reached (its last
            progress report; with ``timeouts``, machine-dependent).
        scales: check label -> the divisor of a relative check (its ``Check.scale``, in the
            signal's unit: the largest control torque, N·m, or rod force, N, of the pair's
            reference over their common samples); only relative checks are listed.
    """

    refused: dict[str, str] = field(default_factory=dict)
    ran: tuple[str, ...] = ()
    checks: dict[str, tuple[float, float, str]] = field(default_factory=dict)
    verdicts: tuple[dict[str, Any], ...] = ()
    disagreements: tuple[Disagreement, ...] = ()
    messages: dict[str, str] = field(default_factory=dict)
    walls: dict[str, float] = field(default_factory=dict)
    timeouts: dict[str, float] = field(default_factory=dict)
    reached: dict[str, float] = field(default_factory=dict)
    scales: dict[str, float] = field(default_factory=dict)

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
            "timeouts": dict(self.timeouts),
            "reached": dict(self.reached),
            "scales": dict(self.scales),
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
            timeouts={k: float(v) for k, v in d.get("timeouts", {}).items()},
            reached={k: float(v) for k, v in d.get("reached", {}).items()},
            scales={k: float(v) for k, v in d.get("scales", {}).items()},
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

    return plant(pl)


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".strip()


def _scene(data: dict[str, Any]) -> Scene:
    return scene_from_dict(data)


RUN_BUDGET_S = 30.0
"""Wall-time limit of one plant's run, s: a safety net against a scene far costlier than the
space means to draw; a run over it is stopped (killed, where it runs in a forked worker) and
counted as a timeout, never as a disagreement, since whether it trips depends on the machine."""


class OverTime(Exception):
    """A plant's run passed its wall-time limit (``limit_s``, s) and was stopped, having reached
    the simulated time ``reached_s`` (s; NaN when unknown)."""

    def __init__(self, plant: str, limit_s: float, reached_s: float = math.nan):
        at = f" at t = {reached_s:.6g} s" if math.isfinite(reached_s) else ""
        super().__init__(f"plant {plant} over its time limit ({limit_s:g} s){at}")
        self.plant = plant
        self.limit_s = limit_s
        self.reached_s = reached_s


class _Raised(Exception):
    """The plant raised in its worker: ``kind`` is the exception's type name."""

    def __init__(self, kind: str, message: str):
        super().__init__(f"{kind}: {message}".strip())
        self.kind = kind


def _simulate_task(
    pl: Plant,
    scene: Scene,
    horizon: float,
    settings: Any = None,
    reached: Any = None,
    progress=None,
    report=None,
) -> Trajectory:
    """One plant's run at ``settings`` (None: its defaults; the forked worker's task; ``report`` is
    not used). ``reached``, a shared ``multiprocessing`` double, holds the simulated time the run
    has reached (s), so the parent knows where a run it stops at its time limit was."""

    def told(t: float) -> None:
        if reached is not None:
            reached.value = t
        if progress is not None:
            progress(t)

    # a campaign's scenes are meant to break plants: their warnings (numpy's overflow, MuJoCo's
    # instability) would flood the terminal, and what they say is in the run's status and message
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.simplefilter("ignore", UserWarning)
        return pl.simulate(scene, settings, t_end=horizon, progress=told)


def _load_kernels(name: str, scene: Scene) -> None:
    """Make plant ``name`` ready here for ``scene``'s solve, once per process, before its runs are
    forked: its kernels loaded and one short run of a built-in scene of that solve
    (:func:`validation.runs.warm_plants.warm`), so a forked run inherits them instead of loading
    the kernels from numba's cache again (about 0.5 s per plant and run) and paying the plant's
    first use (a Pinocchio run 0.52 s instead of 0.05 s). ``scene`` itself is never simulated
    here (no limit applies here); a failure is left for the run to report."""
    warm_plants.warm(name, warmup.compiled_solver(scene))


SERVER_PRELOAD = ("validation.runs.kernel_preload", __name__)
"""What the fork server imports once (:func:`validation.runs.workers.start_served`): every plant's
kernels for every solve (:mod:`validation.runs.kernel_preload`), then this module and the plants'
modules it imports, so a served run starts with them loaded."""


def run_limited(
    name: str, pl: Plant, scene: Scene, horizon: float, limit_s: float, settings: Any = None
) -> Trajectory:
    """``pl``'s run of ``scene`` over ``horizon`` s at ``settings`` (None: the plant's defaults)
    within ``limit_s`` s of wall time, stopped at the
    limit whether or not the plant ever reports progress (module docstring).

    Where :func:`validation.runs.workers.can_fork` (a single-threaded process on Linux: the serial
    campaign, a process pool's worker) the run is forked from here, after its kernels are loaded
    here once (:func:`_load_kernels`). In a multi-threaded process (a Dask worker, a thread pool)
    forking is not safe; there, where :func:`validation.runs.workers.can_serve`, the run is forked
    by ``multiprocessing``'s fork server (single-threaded, started once per process, with every
    plant's kernels preloaded: :data:`SERVER_PRELOAD`). Either child is killed at the limit. Only
    where neither exists (not Linux, or workers switched off) does the run go here, with the
    limit checked at the plant's progress reports.

    Raises:
        OverTime: the limit passed (the worker, if any, is ended and reaped).
        _Raised: the plant raised (its type name and first line).
        KeyboardInterrupt: an interrupt here or in the worker (the worker is ended).
    """
    reached = RawValue("d", math.nan)
    if workers.can_fork():
        _load_kernels(name, scene)
        job = workers.start(
            f"fuzz-{name}", _simulate_task, pl, scene, horizon, settings, reached,
            time_limit_s=limit_s,
        )
    elif workers.can_serve():
        job = workers.start_served(
            f"fuzz-{name}", _simulate_task, pl, scene, horizon, settings, reached,
            preload=SERVER_PRELOAD, time_limit_s=limit_s,
        )
    else:
        progress, over_budget = _budget_progress(limit_s)
        try:
            return _simulate_task(pl, scene, horizon, settings, reached, progress)
        except over_budget as exc:
            raise OverTime(name, limit_s, reached.value) from exc
        except KeyboardInterrupt:
            raise
        except Exception as exc:
            raise _Raised(type(exc).__name__, _one_line(exc).partition(": ")[2]) from exc
    try:
        return job.result()  # ended at the limit by the workers; a finished one exits on its own
    except workers.OverTime as exc:
        raise OverTime(name, limit_s, reached.value) from exc
    except workers.WorkerError as exc:
        raise _Raised(exc.kind, exc.message) from exc
    except workers.WorkerLost as exc:
        raise _Raised(type(exc).__name__, str(exc)) from exc
    except BaseException:  # over time, or interrupted here: the worker is ended and reaped
        workers.stop([job])
        raise


def _budget_progress(budget_s: float):
    start = time.perf_counter()

    def progress(t: float) -> None:
        elapsed = time.perf_counter() - start
        if elapsed > budget_s:
            raise BudgetExceeded(budget_s, elapsed, t)

    return progress, BudgetExceeded


def prepare(
    data: dict[str, Any], plants: Sequence[Plant | str], horizon: float
) -> tuple[Scene | None, dict[str, str], list[tuple[str, Plant]]]:
    """The scene of the file's dict ``data`` (None when the loader refuses it), the refusals
    (plant, or ``scene``, -> one-line reason) and the plants that can run it, ``(name, plant)``."""
    try:
        with warnings.catch_warnings():  # the loader's notes (an axis normalised) on a drawn or
            warnings.simplefilter("ignore", UserWarning)  # shrunk scene: no one to read them
            scene = _scene(data)
        scene.output.with_t_end(horizon, "horizon")
    except ValueError as exc:
        return None, {"scene": _one_line(exc)}, []
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
    return scene, refused, chosen


def judge_runs(
    scene: Scene,
    horizon: float,
    trajs: Sequence[Trajectory],
    ran: Sequence[str],
    found: Sequence[Disagreement] = (),
    **fields: Any,
) -> Outcome:
    """The outcome of the runs ``trajs`` (of the plants ``ran``, in order) of ``scene``: the
    comparison's checks and the referee's verdicts, added to the disagreements already ``found``
    (a plant that raised or stopped); ``fields`` are the outcome's other fields."""
    found = list(found)
    checks: dict[str, tuple[float, float, str]] = {}
    scales: dict[str, float] = {}
    verdicts: tuple[dict[str, Any], ...] = ()
    if len(trajs) >= 2:
        cmp = compare_plants(list(trajs), scene, t_end=horizon)
        for c in cmp.checks:
            if not c.applicable:
                continue
            value = float(c.value) if math.isfinite(c.value) else math.inf
            checks[c.label] = (value, float(c.threshold), c.state.value)
            if c.subject.is_pair and c.name in RELATIVE_DIFFERENCES:
                scales[c.label] = float(c.scale)
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
        ran=tuple(ran),
        checks=checks,
        verdicts=verdicts,
        disagreements=tuple(sorted(set(found))),
        scales=scales,
        **fields,
    )


@dataclass(frozen=True)
class PlantRun:
    """How one plant's run of a scene went (plain data: it travels back from any worker).

    Attributes:
        name: the plant.
        traj: its trajectory; None when it raised or passed its time limit.
        wall: the run's wall time, s.
        limit_s: the time limit the run was stopped at (s), None when it was not.
        raised: the type name of what the plant raised ("" when it did not).
        message: why it raised, stopped or was stopped ("" for a run that finished).
        reached: the simulated time a run that stopped or was stopped reached, s (NaN: unknown,
            or it finished).
    """

    name: str
    traj: Trajectory | None
    wall: float
    limit_s: float | None = None
    raised: str = ""
    message: str = ""
    reached: float = math.nan


NON_FINITE = "non-finite"
"""What a :data:`Kind.STOPPED` disagreement says of a run that reports it finished but holds a
non-finite coordinate or velocity."""


NON_FINITE_MESSAGE = "a non-finite state in a run it reports finished"
"""The outcome's message for such a run (its plant gave none)."""


def cut_short(tr: Trajectory) -> str:
    """Why a returned run does not stand for the motion up to its horizon, "" when it does: its
    status when it did not finish (``failed``: its engine's own guard ended it, a reset, a
    non-finite state, a failed step), :data:`NON_FINITE` when it reports it finished but holds a
    non-finite coordinate or velocity. Such a run is a :data:`Kind.STOPPED` disagreement."""
    if tr.status is not RunStatus.OK:
        return str(tr.status.value)
    if not (np.all(np.isfinite(np.asarray(tr.q))) and np.all(np.isfinite(np.asarray(tr.qdot)))):
        return NON_FINITE
    return ""


def run_one(name: str, pl: Plant, scene: Scene, horizon: float, budget_s: float) -> PlantRun:
    """Plant ``pl``'s run of ``scene`` over ``horizon`` s within ``budget_s`` s (:func:`run_limited`);
    only an interrupt escapes. A return value that breaks the plant contract
    (:func:`validation.runs.contract.contract_problem`) is the plant raising ``ContractError``."""
    t0 = time.perf_counter()
    try:
        tr = run_limited(name, pl, scene, horizon, budget_s)
    except OverTime as exc:
        return PlantRun(name, None, time.perf_counter() - t0, exc.limit_s, "", str(exc),
                        exc.reached_s)
    except _Raised as exc:  # a plant failing is a finding, whatever it raises
        return PlantRun(name, None, time.perf_counter() - t0, None, exc.kind, str(exc))
    return returned_run(name, tr, scene, horizon, time.perf_counter() - t0)


def returned_run(name: str, tr: Any, scene: Scene, horizon: float, wall: float) -> PlantRun:
    """The :class:`PlantRun` of what plant ``name`` returned for ``scene`` over ``horizon`` s in
    ``wall`` s: checked against the plant contract first
    (:func:`validation.runs.contract.contract_problem`; a broken one is the plant raising
    ``ContractError``), then a run cut short by the plant's own guard says where it stopped.

    Raises:
        KeyboardInterrupt: the run says it was interrupted.
    """
    why = contract_problem(tr, name, scene, horizon)  # what it returned, checked before it is compared
    if why:
        return PlantRun(name, None, wall, None, ContractError.__name__, f"broke the plant contract: {why}")
    if tr.status is RunStatus.INTERRUPTED:
        raise KeyboardInterrupt(tr.message)
    if tr.status is not RunStatus.OK:
        why = tr.message.splitlines()[0] if tr.message else str(tr.status)
        return PlantRun(name, tr, wall, None, "", why, float(tr.t[-1]) if len(tr.t) else 0.0)
    return PlantRun(name, tr, wall)


def outcome_of(
    scene: Scene, horizon: float, refused: dict[str, str], runs: Sequence[PlantRun]
) -> Outcome:
    """The outcome of ``runs`` (in the plants' order) of ``scene``: each plant that raised or
    stopped, and the runs that returned compared and refereed (:func:`judge_runs`)."""
    trajs, ran, messages, walls, found = [], [], {}, {}, []
    timeouts: dict[str, float] = {}
    reached: dict[str, float] = {}
    for r in runs:
        walls[r.name] = r.wall
        if r.message:
            messages[r.name] = r.message
        if math.isfinite(r.reached):
            reached[r.name] = r.reached
        if r.limit_s is not None:
            timeouts[r.name] = r.limit_s
            continue
        if r.raised:
            found.append(Disagreement(Kind.RAISED, r.raised, r.name))
            continue
        if cut_short(r.traj):
            found.append(Disagreement(Kind.STOPPED, cut_short(r.traj), r.name))
            if cut_short(r.traj) == NON_FINITE:
                messages.setdefault(r.name, NON_FINITE_MESSAGE)
        trajs.append(r.traj)
        ran.append(r.name)
    return judge_runs(
        scene, horizon, trajs, ran, found,
        refused=refused, messages=messages, walls=walls, timeouts=timeouts, reached=reached,
    )


def plant_task(
    data: dict[str, Any], p: Plant | str, horizon: float, budget_s: float
) -> dict[str, Any]:
    """An executor's task: plant ``p``'s run of the scene file's dict ``data`` (a scene the
    caller has already prepared, :func:`prepare`, and found the plant able to run). Back:
    ``run`` (:class:`PlantRun`) and ``walls`` (plant -> wall, s)."""
    scene, refused, chosen = prepare(data, [p], horizon)
    if scene is None or not chosen:  # the caller checked; a worker's registry may differ
        why = next(iter(refused.values()), "refused")
        return {"run": PlantRun(plant_name(p), None, 0.0, None, "ValueError", why), "walls": {}}
    name, pl = chosen[0]
    r = run_one(name, pl, scene, horizon, budget_s)
    return {"run": r, "walls": {name: r.wall}}


def judge_scene(
    data: dict[str, Any],
    plants: Sequence[Plant | str],
    horizon: float,
    budget_s: float = RUN_BUDGET_S,
) -> Outcome:
    """Run the scene file's dict ``data`` on ``plants`` over ``horizon`` s (the scene's default
    settings), one after the other here, each within ``budget_s`` s of wall time
    (:data:`RUN_BUDGET_S`), and judge it (module docstring). Only an interrupt
    (``KeyboardInterrupt``) escapes. A campaign runs the plants of a scene as separate tasks
    instead (:func:`plant_task`, :func:`outcome_of`)."""
    scene, refused, chosen = prepare(data, plants, horizon)
    if scene is None:
        return Outcome(refused=refused)
    runs = [run_one(name, pl, scene, horizon, budget_s) for name, pl in chosen]
    return outcome_of(scene, horizon, refused, runs)


__all__ = [
    "NON_FINITE",
    "RELATIVE_DIFFERENCES",
    "RUN_BUDGET_S",
    "Disagreement",
    "Kind",
    "Outcome",
    "OverTime",
    "PlantRun",
    "cut_short",
    "judge_runs",
    "judge_scene",
    "outcome_of",
    "plant_name",
    "plant_task",
    "prepare",
    "resolve_plant",
    "returned_run",
    "run_limited",
    "run_one",
]
