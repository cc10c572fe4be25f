"""Run a scene on every plant under one controller, compare, and write the evidence.

The job, :func:`run_validation`, is its steps:

1. **request**: every input checked once into a frozen :class:`ValidationRequest`
   (:mod:`validation.validate.request`), which the rest trusts, with the pointwise check of the
   plants that offer one (:mod:`validation.validate.pointwise`: their ``q̈`` against MuJoCo C's
   and the analytic model's at a few states, each finding warned); ``tumble validate`` calls
   :func:`validation_request` and :func:`run_request` apart (it names its output directory after
   the scene in between);
2. **plants**: the analytic plant (scipy, the scene's solver settings), the MuJoCo twin (the
   scene's integrator and time step, overridable) and, when installed, the Pinocchio referee, all
   driven by the analytic controller, run by the job's :class:`~validation.runs.stages.StagePool`;
3. **comparison**: :func:`validation.compare.checks.compare_plants` and the referee's rulings;
4. **evidence**: the recording and the figures (:mod:`validation.validate.evidence`), then
   ``report.md`` and ``report.json``, all in ``out_dir`` as one output run
   (:func:`validation.runs.outputs.output_run`).

Where and how each stage runs (worker processes or here, their priorities, time limits, signal
holds, a lost worker redone, the staging directory and its commit) is :mod:`validation.runs`'
(:mod:`validation.runs.stages`, :mod:`validation.runs.outputs`), not this module's.

A run that fails (an engine error, a plant stopping early, MuJoCo's bridge missing, a figure or the
recording that could not be made) still writes what it has, marked FAILED; one a signal stops
(Ctrl-C, SIGTERM, at any stage) writes the report of how far each plant got, marked INTERRUPTED,
without comparison, figures or recording. The verdict is PASSED only when every check passed and
every file the report names is in the committed directory, whole
(:func:`validation.runs.manifest.check_committed`); a file that cannot be written (a full disk, in
this process or a worker) is an :class:`~validation.runs.atomic.OutputError`: no verdict, the previous contents of
``out_dir`` kept. A built-in stage whose worker process was killed from outside (``kill -9``) is
done again here, and the report says so. The teaching demo is :mod:`validation.studies.demo`.

A plant is not trusted with anything but its own run (:mod:`validation.runs.contract`): it is
given a read-only copy of the scene of its own; what it returns is checked against the plant
contract before it is compared; a run over its time limit (:func:`plant_time_limit`: the caller's
``time_limit``, else :data:`PLUGIN_TIME_LIMIT_S` for a plugin and none for a built-in) is stopped;
and a plant whose worker exits, crashes or is killed, whose run raises anything (``SystemExit``
too), breaks the contract, or whose ``check_scene`` (with anything but the ``ValueError`` of a
refusal), ``default_settings`` or ``describe`` raises, fails alone, in one line naming it: the other
plants run and are compared, and the verdict is FAILED (exit 1), never a crash of this process.
A lost plugin worker is never run again here (its crash would become this process's).
"""

from __future__ import annotations

import dataclasses
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from analytic.scene import Scene
from analytic.scene.dump import scene_to_toml
from analytic.trajectory import Engine, Trajectory
from mj_bridge.plants import PinocchioPlant
from validation.compare.checks import Comparison, compare_plants
from validation.compare.pointwise import PointwiseCheck
from validation.compare.referee import Verdict, referee
from validation.preflight import LeftOut
from validation.recording.live import live_plant_task
from validation.recording.stream import AppId
from validation.report.figures import DEFAULT_FORMATS, FigureFormat
from validation.report.report import RunVerdict, versions, write_report
from validation.runs.atomic import write_text
from validation.runs.interrupts import interrupt_name, signals_held
from validation.runs.manifest import check_committed as _check_committed  # the fault tests' name
from validation.runs.outputs import OutputRun, output_run
from validation.runs.plant_runs import (  # PLUGIN_TIME_LIMIT_S, plant_time_limit: re-exported
    PLUGIN_TIME_LIMIT_S,
    PlantRun,
    Progress,
    check_time_limit,
    plant_task,
    plant_time_limit,
    stage_progress,
)
from validation.runs.stages import StagePool
from validation.scenes import DEFAULT_SCENE  # re-exported: the one default of every command
from validation.validate.evidence import (
    EVIDENCE_HELPERS,
    RECORDING,
    Evidence,
    make_evidence,
    prepare_comparison,
)
from validation.validate.records import NO_JOINED, JoinedRuns, ValidationResult
from validation.validate.request import (
    ValidationRequest,
    one_line,
    prepared_plants,
    validation_request,
)


def run_validation(
    scene: Scene | str | Path,
    out_dir: str | Path,
    integrator: Any = None,
    dt: float | None = None,
    t_end: float | None = None,
    progress: Progress | None = None,
    plants: Sequence[Engine | str] | str | None = None,
    figure_formats: Sequence[FigureFormat | str] = DEFAULT_FORMATS,
    concurrent: bool = True,
    time_limit: float | None = None,
) -> ValidationResult:
    """Run ``scene`` on every chosen plant under one controller, compare every pair, rule on
    disagreements, and write the report and ``run.rrd``.

    Args:
        scene: a :class:`Scene`, a scene file, or a built-in scene name.
        out_dir: output directory. It receives this run's files as one set
            (:func:`validation.runs.outputs.output_run`): ``manifest.json`` lists them with their
            hashes and the run id; a failed run's partial set is marked failed, an interrupted one
            interrupted (and the KeyboardInterrupt re-raised after the files are in place).
        integrator: MuJoCo integrator (default the scene's ``[mujoco] integrator``).
        dt: MuJoCo time step, s (default the scene's ``[mujoco] timestep``).
        t_end: horizon, s (default the scene's ``[output] t_end``).
        progress: optional ``progress(stage, t)`` callback, stage the plant's name (a one-argument
            callable hears the analytic plant only).
        plants: which plants (engine names, or ``"analytic,mujoco"``), at least two, each named
            once (:func:`validation.preflight.validation_plants`); default every installed
            plant (:func:`mj_bridge.plants.installed_plants`). With three, the referee names the
            plant that disagrees with the two that agree (:mod:`validation.compare.referee`).
        figure_formats: the figures' file formats, PNG by default (``("png", "svg")`` adds SVG
            files for papers; :class:`validation.report.figures.FigureFormat`).
        concurrent: run the plants side by side, and the recording beside the figures, in
            worker processes where that is safe (:mod:`validation.runs.workers`); False runs every
            stage here, one after the other. The files are the same either way.
        time_limit: wall-time limit of each plant's run, s (default :func:`plant_time_limit`'s:
            :data:`PLUGIN_TIME_LIMIT_S` for a plugin, none for a built-in); a run over it is
            stopped and fails that plant, naming the limit, and the others are compared. In a
            worker the run is ended whatever it does; run here (no workers) it is stopped at its
            next Python bytecode (a C call that never returns cannot be).

    Returns:
        a frozen :class:`ValidationResult`; ``passed`` is False when any check fails or a plant
        could not run.

    Raises:
        ValueError: bad input (scene, plants, integrator, dt, t_end, time_limit, out_dir), before
            any plant runs.
        OutputBusy: another run is writing into ``out_dir``.
        OutputError: the files could not be written (a full disk, in any stage: the report,
            a figure, the recording, in a worker too); ``out_dir`` keeps its previous contents
            and no verdict is given. Also when a file the result names is not found whole in
            the committed directory.
    """
    request = validation_request(  # the Python boundary: every input checked once, here
        scene,
        plants=plants,
        integrator=integrator,
        dt=dt,
        t_end=t_end,
        figure_formats=figure_formats,
        time_limit=time_limit,
    )
    return run_request(request, out_dir, progress=progress, concurrent=concurrent)


def run_request(
    request: ValidationRequest,
    out_dir: str | Path,
    progress: Progress | None = None,
    concurrent: bool = True,
    joined: JoinedRuns = NO_JOINED,
    command: str = "validate",
) -> ValidationResult:
    """:func:`run_validation` of an input checked already (:func:`validation_request`, at the
    command line's or the Python API's boundary): nothing is checked again. Same result, files and
    errors otherwise. ``joined``: runs made elsewhere that join the plants' (:class:`JoinedRuns`;
    ``request.plants`` may then be fewer than two, or none); ``command``: the output set's
    command (its manifest)."""
    plants = prepared_plants(request)
    with output_run(out_dir, command) as run:
        res = _validate_into(
            run, request, plants.runs, plants.names, plants.refused, progress, concurrent, joined
        )
    files = {name: run.final(name) for name in res.files}
    files["manifest.json"] = run.final("manifest.json")
    _check_committed(run.target, files)
    return dataclasses.replace(res, out_dir=run.target, files=files)


_plant_task = plant_task
"""One plant's run (:func:`validation.runs.plant_runs.plant_task`), by this name for the tests that
replace it (a worker killed on its first call)."""

_stage_progress = stage_progress  # the name the report's tests know it by


def _validate_into(
    run: OutputRun,
    request: ValidationRequest,
    runs: Sequence[PlantRun],
    names: Mapping[str, str],
    refused: Sequence[str],
    progress: Progress | None,
    concurrent: bool = True,
    joined: JoinedRuns = NO_JOINED,
) -> ValidationResult:
    """:func:`run_validation`'s steps after the request, writing into the staging directory
    ``run.path``: the plants, the comparison, the evidence and the report (module docstring).
    ``runs``: the plants that can run, ``names`` their one-line descriptions, ``refused`` the
    failures of those that cannot (:func:`validation.validate.request.prepared_plants`); the
    ``joined`` runs follow the plants' (:class:`JoinedRuns`).

    With ``concurrent`` the stages run side by side in workers where that is safe
    (:class:`~validation.runs.stages.StagePool`); the files are those of a run one stage after the
    other. An interrupt (Ctrl-C, SIGTERM) at any stage stops every worker at once; the report of
    how far each plant got is written, INTERRUPTED (no comparison of a partial run, no figures, no
    recording: the stop is prompt whatever the horizon), and the interrupt raised after it. A
    file that cannot be written raises :class:`~validation.runs.atomic.OutputError` (no verdict, no files).
    """
    sc, horizon = request.scene, request.horizon
    t_all = time.perf_counter()
    walls: dict[str, float] = {}
    failures: list[str] = list(refused)
    redone: list[str] = []
    names = dict(names) | dict(joined.names)
    trajectories: list[Trajectory] = []
    cmp: Comparison | None = None
    verdicts: tuple[Verdict, ...] = ()
    evidence = Evidence()
    interrupted = False
    with StagePool(concurrent, EVIDENCE_HELPERS, prepare_here=prepare_comparison) as pool:
        try:  # the plants, then the comparison
            reference = runs[0].plant.engine if runs else None  # drawn solid, as the recording
            task = live_plant_task(_plant_task, AppId.VALIDATE, run.run_id, reference)  # now
            got = pool.run_plants(runs, sc, horizon, progress, task=task)
            walls.update(got.walls)
            failures += got.failures
            redone += got.redone
            interrupted = got.interrupted
            trajectories = [*got.trajectories, *joined.trajectories]
            if trajectories and trajectories[0].t.size and not interrupted:
                cmp, verdicts = _compare(
                    trajectories, request, names, walls, failures, joined.amend
                )
        except KeyboardInterrupt:
            interrupted = True
        meta = _meta(
            run, sc, runs, names, horizon, verdicts, joined, request.left_out, request.pointwise
        )
        # the scene as it ran, in the scene file's conventions: `tumble validate OUT/scene.toml`
        # reruns it
        files: dict[str, Path] = {
            "scene.toml": write_text(run.path / "scene.toml", scene_to_toml(sc))
        }
        if not interrupted:
            try:  # the evidence
                evidence = make_evidence(
                    pool,
                    run.path,
                    run.run_id,
                    sc,
                    trajectories,
                    cmp,
                    meta,
                    request.figure_formats,
                    walls,
                )
            except KeyboardInterrupt:
                interrupted = True
    if interrupted:  # the evidence of an interrupted run is left out, whatever was made
        failures.insert(0, _interrupted_sentence(trajectories, runs))
        meta["evidence"] = "no comparison, figures or recording: the run was interrupted"
        evidence = Evidence()
    files.update(evidence.files)
    failures += evidence.failures
    redone += evidence.redone
    if redone:
        meta["redone"] = list(redone)
    failure = _failure(failures, runs, joined, trajectories)
    walls["total"] = time.perf_counter() - t_all
    meta["wall_times_s"] = dict(walls)
    t0 = time.perf_counter()

    def report(failure: str, interrupted: bool) -> Any:
        return write_report(
            run.path,
            cmp,
            trajectories,
            meta,
            failure=failure,
            verdicts=verdicts,
            formats=request.figure_formats,
            scene=sc,
            figures=evidence.figures,
            interrupted=interrupted,
            recording=RECORDING if RECORDING in files else None,
        )

    # A signal while the report is written is not allowed to leave a report that says PASSED in
    # a set marked interrupted: the report is written again, INTERRUPTED.
    with signals_held(raise_after=False) as caught:
        rep = report(failure, interrupted)
        files.update({"report.md": rep.markdown, "report.json": rep.json})
        if rep.html is not None:
            files["report.html"] = rep.html
        files.update({f.name: f for f in rep.figures})
        run.keep_only(files)
        if caught and not interrupted:
            interrupted = True
            said = f"interrupted by {interrupt_name()} as the report was written"
            rep = report("; ".join([said, *([failure] if failure else [])]), interrupted)
        if rep.failure:
            run.mark_failed(rep.failure)
    walls["report"] = time.perf_counter() - t0
    if interrupted:
        raise KeyboardInterrupt  # the partial set is committed, marked interrupted
    return ValidationResult(
        scene=sc.name,
        out_dir=run.path,
        passed=rep.verdict is RunVerdict.PASSED,
        checks=cmp.checks if cmp is not None else (),
        comparison=cmp,
        failure=rep.failure,
        files=files,
        wall_times=walls,
        verdicts=verdicts,
    )


def _failure(
    failures: Sequence[str],
    runs: Sequence[PlantRun],
    joined: JoinedRuns,
    trajectories: Sequence[Trajectory],
) -> str:
    """The run's failure in one line ("" if it did not fail): what failed, else too few plants to
    compare, else the plants that gave no trajectory."""
    failure = "; ".join(failures)
    if len(runs) + len(joined.trajectories) < 2 and not failure:
        failure = "only one plant: nothing to compare it with"
    if len(trajectories) < len(runs) + len(joined.trajectories) and not failure:
        got = {tr.engine for tr in trajectories}
        missing = [r.plant.engine for r in runs if r.plant.engine not in got]
        failure = f"no trajectory from {', '.join(missing) or 'a plant'}"
    return failure


def _compare(
    trajectories: Sequence[Trajectory],
    request: ValidationRequest,
    names: dict[str, str],
    walls: dict[str, float],
    failures: list[str],
    amend: Callable[[Comparison], Comparison] | None = None,
) -> tuple[Comparison | None, tuple[Verdict, ...]]:
    """Every pair compared (then ``amend``-ed, :class:`JoinedRuns`) and the referee's rulings; a
    comparison that raises is a failure said in the report (an interrupt goes on)."""
    try:
        t0 = time.perf_counter()
        cmp = compare_plants(
            trajectories, request.scene, t_end=request.horizon, thresholds=request.thresholds
        )
        if amend is not None:
            cmp = amend(cmp)
        walls["compare"] = time.perf_counter() - t0
        return cmp, tuple(referee(cmp, names, trajectories))
    except Exception as exc:
        failures.append(f"comparison: {one_line(exc)}")
        traceback.print_exc()
        return None, ()


def _referee_note(sc: Scene) -> str:
    """Why a run of fewer than three plants has no referee: Pinocchio not installed, unable to
    run this scene (its reason), or not chosen."""
    if PinocchioPlant.unavailable():
        return "the referee (Pinocchio) is not installed: pip install 'pin>=4.1' (the [pinocchio] extra)"
    try:
        PinocchioPlant().check_scene(sc)
    except ValueError as exc:
        return f"the referee (Pinocchio) cannot run this scene: {exc}"
    return "the referee needs three plants"


def _meta(
    run: OutputRun,
    sc: Scene,
    runs: Sequence[PlantRun],
    names: dict[str, str],
    horizon: float,
    verdicts: Sequence[Verdict],
    joined: JoinedRuns = NO_JOINED,
    left_out: Sequence[LeftOut] = (),
    pointwise: PointwiseCheck | None = None,
) -> dict[str, Any]:
    """The run's metadata for the report (the wall times are added when they are known); the
    ``joined`` runs are plants too, named as ``joined.names`` says, with ``joined.meta``; the
    ``pointwise`` check made before the run, under ``pointwise`` when a plant offered one."""
    mj = next((r.settings for r in runs if r.plant.engine == Engine.MUJOCO), None)
    referee_note = "" if len(runs) + len(joined.trajectories) >= 3 else _referee_note(sc)
    # the plants of the default set or of `--plants all` that refused the scene, each once
    told = [str(x) for x in left_out if not (referee_note and x.engine == Engine.PINOCCHIO)]
    referee_note = "; ".join([*told, *([referee_note] if referee_note else [])])
    meta: dict[str, Any] = {
        "run_id": run.run_id,
        "scene": {
            "name": sc.name,
            "source": sc.source,
            "description": sc.description,
            "effects": sorted(e.value for e in sc.effects),
        },
        "horizon_s": horizon,
        "output_rate_hz": sc.output.rate,
        "plants": [{"engine": r.plant.engine, "settings": names[r.plant.engine]} for r in runs],
        "analytic_solver": {
            "method": sc.solver.method.value,
            "rtol": sc.solver.rtol,
            "atol": sc.solver.atol,
            "max_step": sc.solver.max_step,
        },
        "mujoco_settings": {
            "integrator": (mj.integrator.value if mj else sc.mujoco.integrator.value),
            "timestep": mj.dt if mj else sc.mujoco.timestep,
            "spring_model": sc.mujoco.spring_model.value,
        },
        "controller": "analytic (Udwadia–Kalaba, Eq. 89) in every plant",
        "referee": [v.to_dict() for v in verdicts],
        "referee_note": referee_note,
        "versions": versions(),
    }
    if pointwise is not None and not pointwise.empty:
        meta["pointwise"] = pointwise.to_dict()
    meta["plants"] += [
        {"engine": str(tr.engine), "settings": names.get(str(tr.engine), str(tr.engine))}
        for tr in joined.trajectories
    ]
    return meta | dict(joined.meta)


def _interrupted_sentence(trajectories: Sequence[Trajectory], runs: Sequence[PlantRun]) -> str:
    """``interrupted by SIGTERM: analytic reached t = 3.2 s, mujoco t = 1.1 s, pinocchio not run``."""
    reached = {tr.engine: float(tr.t[-1]) if tr.t.size else 0.0 for tr in trajectories}
    parts = [
        f"{r.plant.engine} reached t = {reached[r.plant.engine]:.6g} s"
        if r.plant.engine in reached
        else f"{r.plant.engine} has no trajectory"
        for r in runs
    ]
    return f"interrupted by {interrupt_name()}: " + ", ".join(parts)


__all__ = [
    "DEFAULT_SCENE",
    "NO_JOINED",
    "PLUGIN_TIME_LIMIT_S",
    "JoinedRuns",
    "ValidationRequest",
    "ValidationResult",
    "check_time_limit",
    "plant_time_limit",
    "run_request",
    "run_validation",
    "validation_request",
]
