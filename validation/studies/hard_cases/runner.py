"""The one runner of the hard cases: ``tumble hard-cases``, ``python -m validation hard-cases`` and
``tests/validation/studies/test_hard_cases.py`` all run the cases through :func:`run_case`.

A case is a scene file in ``validation/scenes/hard/`` with its criterion (``[hard_case]``,
:mod:`validation.studies.hard_cases.criterion`). For each plant the case applies to, the runner makes the
implicit checks of every run (``completed``: the run reached its horizon, the comparison's own
check; ``finite``), then each ``[[hard_case.check]]`` against its bound, as a
:class:`validation.compare.checks.Check`: on one plant (subject the plant) or against the analytic plant
(subject the pair; the check belongs to the plant compared). ``hard_<plant>_<x>`` is that plant's
own bound where the scene gives one, else ``hard_<x>``.
"""

from __future__ import annotations

import dataclasses
import functools
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from analytic.effects import Precision
from analytic.scene import Scene, load_scene
from analytic.trajectory import RunStatus
from mj_bridge import plants as _plants
from validation.compare.checks import Check, Subject, completed_check, judge
from validation.runs import interrupts
from validation.runs.outputs import output_run
from validation.scenes import HARD_DIR
from validation.studies.hard_cases.catalogue import MEASURES, Applies, Measure, Reference
from validation.studies.hard_cases.criterion import CheckSpec, Criterion, parse_criterion
from validation.studies.hard_cases.html_report import write_all
from validation.studies.hard_cases.judgeable import NotJudgeable, assess
from validation.studies.hard_cases.measures import ANALYTIC, CaseRuns, finite, label, measure
from validation.studies.hard_cases.references.pinv_law import ENGINE_LAW_PLANTS
from validation.studies.hard_cases.references.solvers import SCIPY_PLANTS
from validation.studies.hard_cases.table import (
    HardCaseRow,
    HardCaseTable,
    Reported,
    Verdict,
)
from validation.studies.roundoff import precision_of


@dataclass(frozen=True)
class HardCase:
    """A hard case: its name, scene file, scene and validated criterion."""

    name: str
    path: Path
    scene: Scene
    criterion: Criterion


def load_case(path: Path) -> HardCase:
    """The hard case of the scene file ``path``; ValueError naming the field (and the case)."""
    scene = load_scene(path)
    try:
        criterion = parse_criterion(scene)
    except ValueError as exc:
        raise ValueError(f"{exc} (in hard/{path.stem})") from None
    return HardCase(path.stem, path, scene, criterion)


@functools.cache
def cases() -> dict[str, HardCase]:
    """Every hard case, by name (the scene files of ``validation/scenes/hard/``, sorted)."""
    return {p.stem: load_case(p) for p in sorted(HARD_DIR.glob("*.toml"))}


def case_names(fast_only: bool = False) -> tuple[str, ...]:
    """The names of the cases (only the fast subset with ``fast_only``), in table order."""
    return tuple(n for n, c in cases().items() if c.criterion.fast or not fast_only)


def suite_plants(plants: Iterable[str] | None = None) -> tuple[tuple[str, ...], dict[str, str]]:
    """``(plants to run, not installed: plant -> reason)``: every installed plant by default, else
    those named (report order); ``ValueError`` naming ``plants`` for an unknown or missing one or
    one without the analytic plant (the reference of every case)."""
    not_installed = {
        e: why
        for e, cls in _plants.registered().items()
        if cls.default and (why := cls.unavailable())
    }
    if plants is None:
        chosen = _plants.installed_plants()
    else:
        names = [str(p) for p in plants]
        chosen = _plants.parse_plants(",".join(names)) if names else ()
    if ANALYTIC not in chosen:
        raise ValueError(f"plants: the hard cases need the analytic plant (got {list(chosen)})")
    return chosen, not_installed


def _applies(spec: CheckSpec, plant: str) -> bool:
    applies = MEASURES[(spec.what, spec.against)].applies
    if applies is Applies.OTHERS:
        return plant != ANALYTIC
    if applies is Applies.ANALYTIC:
        return plant == ANALYTIC
    if applies is Applies.SCIPY:
        return plant in SCIPY_PLANTS
    if applies is Applies.ENGINE_LAW:
        return plant in ENGINE_LAW_PLANTS
    return True


def _subject(spec: CheckSpec, plant: str) -> Subject:
    if spec.against in (Reference.ANALYTIC, Reference.ANALYTIC_MIRROR):
        return Subject.pair(ANALYTIC, plant)
    return Subject.plant(plant)


def _run_checks(runs: CaseRuns, plant: str) -> list[Check]:
    """``completed`` and ``finite`` of every run made on ``plant``."""
    out = [c for c in runs.checks if c.subject == plant]
    for r in runs.runs:
        if r.plant != plant:
            continue
        tag = f" ({r.what})" if r.what else ""
        done = completed_check(r.trajectory, r.t_end)
        out.append(dataclasses.replace(done, name=f"completed{tag}"))
        ok = finite(r.trajectory)
        out.append(
            judge(
                f"finite{tag}",
                Subject.plant(plant),
                0.0 if ok else 1.0,
                0.0,
                "1",
                MEASURES[(Measure.FINITE, Reference.RUN)].meaning,
            )
        )
    return out


def plant_precision(plant: str, scene: Scene) -> Precision:
    """The precision ``plant`` runs ``scene`` in: its default settings' (the settings a case
    runs it with, :func:`validation.studies.roundoff.precision_of`)."""
    return precision_of(_plants.plant(plant).default_settings(scene))


def _spec_checks(
    runs: CaseRuns, spec: CheckSpec, plant: str, unjudged: list[NotJudgeable]
) -> list[Check]:
    bound_name, bound = runs.criterion.bound_for(spec, plant)
    info = spec.info
    precision = plant_precision(plant, runs.scene)
    out = []
    for qualifier, value in measure(runs, spec, plant):
        name = spec.name + (f" ({qualifier})" if qualifier else "")
        c = judge(name, _subject(spec, plant), value, bound, info.unit, spec.why, bound=bound_name)
        if precision is not Precision.FLOAT64:
            tr, t_end = runs.run(plant), runs.scene.output.t_end
            nj = assess(spec, plant, c.label, precision, bound_name, bound, value, tr, t_end)
            if nj is not None:  # below the round-off: neither a PASS nor a FAIL
                c = dataclasses.replace(c, passed=True, applicable=False, reason=nj.reason)
                unjudged.append(nj)
                out.append(c)
                continue
        if not c.passed and spec.note_if_failed:
            runs.notes.append(
                f"{plant}: {name} = {value:.2e} {info.unit} > {bound:g}: {spec.note_if_failed}"
            )
        out.append(c)
    return out


def _reported(runs: CaseRuns, spec: CheckSpec, plant: str) -> list[Reported]:
    return [
        Reported(plant, spec.name + (f" ({q})" if q else ""), v, spec.info.unit, spec.why)
        for q, v in measure(runs, spec, plant)
    ]


def _cost_note(runs: CaseRuns) -> str | None:
    costs = []
    for r in runs.runs:
        if r.what:
            continue
        info = r.trajectory.info
        how = f" ({info['backend']})" if "backend" in info else ""
        costs.append(f"{label(r.plant)}{how} {info.get('wall_time_s', float('nan')):.2f} s")
    if not costs:
        return None
    return f"n = {runs.scene.n}: {', '.join(costs)} for {runs.scene.output.t_end:g} s simulated"


def _plant_figures(
    runs: CaseRuns, plant: str, checks: list[Check], reported: list[Reported]
) -> dict[str, Any]:
    # judged figures (an indicator's 0 / 1 is its check's verdict, not a figure)
    figs: dict[str, Any] = {c.name: c.value for c in checks if c.bound}
    figs.update({r.name: r.value for r in reported})
    figs.update(runs.figures.get(plant, {}))
    main = next((r for r in runs.runs if r.plant == plant and not r.what), None)
    if main is not None:
        tr = main.trajectory
        figs["status"] = tr.status.value
        if tr.status is not RunStatus.OK:
            figs["message"] = tr.message
        figs["wall s"] = tr.info.get("wall_time_s")
        if "nfev" in tr.info:
            figs["nfev"] = tr.info["nfev"]
    return figs


@dataclass(frozen=True)
class Evaluation:
    """What a case found on its plants: every check (per plant: its runs' implicit checks, then
    the file's checks in order), the reported figures, plant -> figures, and the notes."""

    checks: tuple[Check, ...]
    reported: tuple[Reported, ...]
    figures: Mapping[str, dict[str, Any]]
    notes: tuple[str, ...]
    not_judgeable: tuple[NotJudgeable, ...] = ()


def evaluate(case: HardCase, plants: tuple[str, ...]) -> Evaluation:
    """Every check and report of ``case`` on ``plants`` (each where it applies)."""
    runs = CaseRuns(case.name, case.path, case.scene, case.criterion, plants)
    found = {}
    unjudged: list[NotJudgeable] = []
    for plant in plants:
        checks = [
            c
            for s in case.criterion.checks
            if _applies(s, plant)
            for c in _spec_checks(runs, s, plant, unjudged)
        ]
        reported = [
            r
            for s in case.criterion.reports
            if _applies(s, plant)
            for r in _reported(runs, s, plant)
        ]
        found[plant] = (checks, reported)
    cost = _cost_note(runs)
    return Evaluation(
        checks=tuple(c for p in plants for c in (*_run_checks(runs, p), *found[p][0])),
        reported=tuple(r for p in plants for r in found[p][1]),
        figures={p: _plant_figures(runs, p, *found[p]) for p in plants},
        notes=tuple(runs.notes + ([cost] if cost else [])),
        not_judgeable=tuple(unjudged),
    )


def _unjudged_plugins(
    case: HardCase, chosen: tuple[str, ...], not_applicable: Mapping[str, str]
) -> dict[str, str]:
    """The plants beyond the built-ins (plugins) that none of the case's checks and reports
    applies to (e.g. ``engine_law`` needs an engine's own matrices), N/A with that reason; a
    built-in plant judged on nothing stays an ERROR (a bug of the case)."""
    # deferred: mj_bridge.registry reads installed metadata (importlib.metadata, ~20 ms by python -X importtime), paid only when plants are ordered
    from mj_bridge.registry import BUILTIN

    specs = (*case.criterion.checks, *case.criterion.reports)
    return {
        e: "no check of this case applies to this plant (its measures need what the plugin "
        "does not provide: an engine's own matrices or scipy's methods)"
        for e in chosen
        if e not in BUILTIN and e not in not_applicable and not any(_applies(s, e) for s in specs)
    }


def run_case(name: str, plants: Iterable[str] | None = None) -> HardCaseRow:
    """Run one hard case on ``plants`` (default every installed plant); an exception becomes an
    ``ERROR`` row carrying its message (the user's Ctrl-C stops the suite)."""
    known = cases()
    if name not in known:
        raise ValueError(f"names: unknown hard case {name!r} (known: {', '.join(known)})")
    chosen, _ = suite_plants(plants)
    case = known[name]
    not_applicable = {e: why for e, why in case.criterion.not_applicable.items() if e in chosen}
    not_applicable |= _unjudged_plugins(case, chosen, not_applicable)
    applicable = tuple(e for e in chosen if e not in not_applicable)
    wall0 = time.perf_counter()
    error = ""
    precisions: dict[str, Precision] = {}
    try:
        precisions = {e: plant_precision(e, case.scene) for e in applicable}
        ev = evaluate(case, applicable)
        verdict = Verdict.PASS if all(c.passed for c in ev.checks) else Verdict.FAIL
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # a crash of a case is a finding: reported, the suite goes on
        interrupts.raise_if_interrupt(exc)  # not when a signal caused it (an import it cut)
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        error = f"{type(exc).__name__}: {exc}"
        ev = Evaluation((), (), {}, (f"raised at {Path(tb.filename).name}:{tb.lineno}",))
        verdict = Verdict.ERROR
    return HardCaseRow(
        case=name,
        criterion=case.criterion.criterion,
        plants=chosen,
        figures=ev.figures,
        not_applicable=not_applicable,
        checks=ev.checks,
        verdict=verdict,
        wall_time_s=time.perf_counter() - wall0,
        notes=ev.notes,
        error=error,
        reported=ev.reported,
        not_judgeable=ev.not_judgeable,
        precisions=precisions,
    )


def _run_into(
    out: Path,
    selected: list[str],
    progress: Callable[[str, int, int], None] | None,
    plants: tuple[str, ...],
    not_installed: Mapping[str, str],
) -> HardCaseTable:
    """Run the ``selected`` cases, rewriting the table in ``out`` after each one."""
    rows: list[HardCaseRow] = []

    def table(complete: bool, message: str) -> HardCaseTable:
        return HardCaseTable(tuple(rows), complete, message, plants, dict(not_installed))

    current = table(True, "no case selected")
    for i, name in enumerate(selected):
        if progress is not None:
            progress(name, i, len(selected))
        try:
            rows.append(run_case(name, plants))
        except BaseException as exc:
            ki = interrupts.interrupt_of(exc)  # also an exception a signal caused
            if ki is None:
                raise
            current = table(False, f"interrupted during {name}")
            write_all(current, out)
            if ki is exc:
                raise
            raise ki from exc
        done = i + 1 == len(selected)
        current = table(done, "" if done else f"{len(selected) - i - 1} cases still to run")
        write_all(current, out)
    if not selected:
        write_all(current, out)
    return current


def run_hard_cases(
    out_dir: str | Path,
    names: Iterable[str] | None = None,
    fast_only: bool = False,
    progress: Callable[[str, int, int], None] | None = None,
    plants: Iterable[str] | None = None,
) -> HardCaseTable:
    """Run the hard cases and write ``hard_cases.md`` / ``.html`` / ``.json`` to ``out_dir``.

    Args:
        out_dir: output directory (created).
        names: cases to run (default all, in table order); unknown names raise ValueError.
        fast_only: only the fast subset (``[hard_case] fast = true``).
        progress: called as ``progress(case, index, total)`` before each case.
        plants: plants to run every case on (default every installed plant; the analytic plant
            is required); a plant that is not installed is named in the table with the reason.

    Returns:
        the :class:`HardCaseTable`; the files are rewritten after every case, so an interrupted
        suite (KeyboardInterrupt) leaves the rows it finished, marked incomplete, and re-raises.
    """
    known = cases()
    selected = list(known) if names is None else list(names)
    for n in selected:
        if n not in known:
            raise ValueError(f"names: unknown hard case {n!r} (known: {', '.join(known)})")
    chosen, not_installed = suite_plants(plants)
    if fast_only:
        selected = [n for n in selected if known[n].criterion.fast]
    with output_run(out_dir, "hard-cases") as run:
        table = _run_into(run.path, selected, progress, chosen, not_installed)
    return table


__all__ = [
    "HARD_DIR",
    "Evaluation",
    "HardCase",
    "case_names",
    "cases",
    "evaluate",
    "load_case",
    "plant_precision",
    "run_case",
    "run_hard_cases",
    "suite_plants",
]
