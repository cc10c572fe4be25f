"""Run a scene on every plant under one controller, compare, and write the evidence.

:func:`run_validation`: the analytic plant (scipy, the scene's solver settings), the MuJoCo twin
(the scene's integrator and time step, overridable) and, when installed, the Pinocchio referee, all
driven by the analytic controller; :func:`validation.compare.checks.compare_plants`; then ``report.md``,
``report.json``, the figures (PNG, and SVG or PDF on request) and ``run.rrd`` in ``out_dir``. A run
that fails (an engine error, a plant stopping early, MuJoCo's bridge missing, a figure or the
recording that could not be made) still writes what it has, marked FAILED; one a signal stops
(Ctrl-C, SIGTERM, at any stage) writes the report of how far each plant got, marked INTERRUPTED,
without comparison, figures or recording. The verdict is PASSED only when every check passed and every file the report
names is in the committed directory, whole (:func:`_check_committed`); a file that cannot be
written (a full disk, in this process or a worker) is an :class:`OutputError`: no verdict, the
previous contents of ``out_dir`` kept. A built-in stage whose worker process was killed from
outside (``kill -9``) is done again here, and the report says so. The teaching demo is
:mod:`validation.studies.demo`.

A plant is not trusted with anything but its own run (:mod:`validation.runs.contract`): it is
given a read-only copy of the scene of its own; what it returns is checked against the plant
contract before it is compared; a run over its time limit (:func:`plant_time_limit`: the caller's
``time_limit``, else :data:`PLUGIN_TIME_LIMIT_S` for a plugin and none for a built-in) is stopped;
and a plant whose worker exits, crashes or is killed, whose run raises anything (``SystemExit``
too), breaks the contract, or whose ``check_scene`` (with anything but the ``ValueError`` of a
refusal), ``default_settings`` or ``describe`` raises, fails alone, in one line naming it: the other
plants run and are compared, and the verdict is FAILED (exit 1), never a crash of this process.
A lost plugin worker is never run again here (its crash would become this process's).

Inputs are checked once per boundary: :func:`validation_request` checks everything (scene,
thresholds, plants, overrides, figure formats) into a frozen :class:`ValidationRequest`, which
:func:`run_request` trusts; :func:`run_validation` is the two, and ``tumble validate`` calls them
apart (it names its output directory after the scene in between).
"""

from __future__ import annotations

import dataclasses
import time
import traceback
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.scene import Scene
from analytic.scene.dump import scene_to_toml
from analytic.threshold import Threshold
from analytic.trajectory import Engine, Trajectory
from mj_bridge.plants import MujocoRunSettings, PinocchioPlant, plant
from validation.compare.checks import Check, Comparison, compare_plants
from validation.compare.referee import Verdict, referee
from validation.compare.thresholds import thresholds_for
from validation.preflight import LeftOut, check_validation_inputs, plant_choice
from validation.report.figures import (
    DEFAULT_FORMATS,
    FIGURES,
    FigureContext,
    FigureFormat,
    parse_formats,
    prepare_drawing,
)
from validation.report.report import (
    RunVerdict,
    draw_figures,
    is_write_failure,
    versions,
    write_report,
)
from validation.runs import workers
from validation.runs.atomic import OutputError, write_text
from validation.runs.contract import plant_scene
from validation.runs.interrupts import interrupt_name
from validation.runs.outputs import OutputRun, output_run, parse_manifest
from validation.runs.plant_runs import (  # PLUGIN_TIME_LIMIT_S, plant_time_limit: re-exported
    PLUGIN_TIME_LIMIT_S,
    Progress,
    check_time_limit,
    plant_task,
    plant_time_limit,
    run_plants,
    stage_progress,
)
from validation.scenes import (  # DEFAULT_SCENE re-exported: the one default of every command
    DEFAULT_SCENE,
    resolve_scene,
    with_threshold_overrides,
)


@dataclass(frozen=True)
class ValidationResult:
    """The outcome of :func:`run_validation`.

    Attributes:
        scene: scene name.
        out_dir: where the files are.
        passed: every check passed, nothing failed, and every file of ``files`` is whole in
            ``out_dir`` (the report's verdict is PASSED).
        checks: every check (empty if no comparison could be made).
        comparison: the comparison (None if no analytic trajectory exists).
        failure: why the run failed ("" if it did not).
        files: name -> path of every file written.
        wall_times: stage -> seconds (each plant, compare, report, recording, total).
        verdicts: the referee's rulings (three plants), see :mod:`validation.compare.referee`.
    """

    scene: str
    out_dir: Path
    passed: bool
    checks: tuple[Check, ...]
    comparison: Comparison | None
    failure: str = ""
    files: dict[str, Path] = field(default_factory=dict)
    wall_times: dict[str, float] = field(default_factory=dict)
    verdicts: tuple[Verdict, ...] = ()

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)


@dataclass(frozen=True)
class JoinedRuns:
    """Runs made elsewhere that join the plants' results as more plants (:mod:`validation.external`:
    another engine's trajectory file, a reference pack's trajectory): compared, refereed,
    reported, drawn and recorded as the plants are.

    Attributes:
        trajectories: each a complete run of the request's scene on its output grid, its
            ``engine`` a plant name of its own (none of the running plants'), in report order
            after the plants that run.
        names: plant name -> how the report and the referee's sentences name it.
        amend: applied to the comparison before the referee rules (the judge marks the checks a
            file cannot support "not judged"); None: the comparison as made.
        meta: more entries of the report's run metadata (where each joined run came from).
    """

    trajectories: tuple[Trajectory, ...] = ()
    names: Mapping[str, str] = field(default_factory=dict)
    amend: Callable[[Comparison], Comparison] | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)


NO_JOINED = JoinedRuns()
"""No run joins: :func:`run_validation`'s plants alone."""


@dataclass(frozen=True)
class ValidationRequest:
    """A validation's input, checked whole by :func:`validation_request` before any plant runs.

    Attributes:
        scene: the scene (checked: fields, ``[thresholds]``; every plant accepts it).
        thresholds: name -> threshold in force (the comparison's).
        plants: the plants, in report order, at least two, each once.
        integrator: MuJoCo integrator override (None: the scene's).
        dt: MuJoCo time step override, s (None: the scene's).
        t_end: horizon override, s (None: the scene's).
        horizon: the horizon in force, s.
        figure_formats: the figures' file formats, each once.
        left_out: the plants of the default set or of ``--plants all`` that refused the scene,
            each with its reason (the report's referee note names them).
        time_limit: the wall-time limit of each plant's run, s (None: :func:`plant_time_limit`'s
            defaults).
        unusable: plant -> why it cannot be run (its ``check_scene`` raised something other than
            the ``ValueError`` of a refusal): that plant fails alone, the others run.
    """

    scene: Scene
    thresholds: Mapping[str, Threshold]
    plants: tuple[str, ...]
    integrator: Any
    dt: float | None
    t_end: float | None
    horizon: float
    figure_formats: tuple[FigureFormat, ...]
    left_out: tuple[LeftOut, ...] = ()
    time_limit: float | None = None
    unusable: Mapping[str, str] = field(default_factory=dict)

    def limit_of(self, engine: str) -> float | None:
        """Plant ``engine``'s wall-time limit, s (:func:`plant_time_limit`)."""
        return plant_time_limit(engine, self.time_limit)


def _figure_formats(formats: Sequence[FigureFormat | str] | str) -> tuple[FigureFormat, ...]:
    """The formats as enums, once each; ValueError naming ``figure_format`` (before any work)."""
    if isinstance(formats, str):
        return parse_formats(formats)
    out = parse_formats(",".join(str(getattr(f, "value", f)) for f in formats)) if formats else ()
    if not out:
        raise ValueError("figure_format: at least one format is needed (got none)")
    return out


def validation_request(
    scene: Scene | str | Path | None,
    *,
    plants: Sequence[Engine | str] | str | None = None,
    integrator: Any = None,
    dt: float | None = None,
    t_end: float | None = None,
    figure_formats: Sequence[FigureFormat | str] | str = DEFAULT_FORMATS,
    thresholds: Mapping[str, Any] | None = None,
    time_limit: float | None = None,
) -> ValidationRequest:
    """Check a validation's whole input, once: the scene (a :class:`Scene` as given, else
    :func:`validation.scenes.resolve_scene`) with ``thresholds`` (overrides, name -> number or
    ``{value, reason}``) laid over its ``[thresholds]``, and those thresholds
    (:func:`validation.compare.thresholds.thresholds_for`); the plants
    (:func:`validation_plants`); the overrides (:func:`check_validation_inputs`); the figure
    formats; the time limit (:func:`check_time_limit`); and that every plant accepts the scene
    (its ``check_scene``; one that raises anything but ``ValueError`` is noted ``unusable``, to
    fail alone). Builds nothing and runs nothing.

    Raises:
        ValueError: naming the field and the value (scene, thresholds, plants, integrator, dt,
            t_end, figure_format, time_limit).
    """
    if not isinstance(scene, Scene):
        scene = resolve_scene(scene, check_thresholds=False)  # checked below, once
    sc = with_threshold_overrides(scene, thresholds)
    checked_thresholds = thresholds_for(sc)
    choice = plant_choice(plants, sc)
    chosen = choice.plants
    check_validation_inputs(
        sc, integrator=integrator, dt=dt, t_end=t_end, mujoco=Engine.MUJOCO in chosen
    )
    formats = _figure_formats(figure_formats)
    if t_end is not None and not (t_end > 0):
        raise ValueError(f"t_end: must be a positive time in s (got {t_end!r})")
    limit = check_time_limit(time_limit)
    unusable: dict[str, str] = {}
    for e in chosen:
        try:
            plant(e).check_scene(plant_scene(sc))
        except ValueError:
            raise  # the plant refuses the scene: bad input
        except Exception as exc:  # a plant's own bug: that plant fails alone
            unusable[e] = f"check_scene raised {_one_line(exc)}"
    return ValidationRequest(
        scene=sc,
        thresholds=checked_thresholds,
        plants=tuple(chosen),
        integrator=integrator,
        dt=dt,
        t_end=t_end,
        horizon=float(t_end) if t_end is not None else sc.output.t_end,
        figure_formats=formats,
        left_out=choice.left_out,
        time_limit=limit,
        unusable=unusable,
    )


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


def _plant_settings(engine: str, sc: Scene, integrator: Any, dt: float | None) -> Any:
    """Each plant's settings: the scene's, with the MuJoCo overrides of the command line."""
    if engine == Engine.MUJOCO:
        return MujocoRunSettings(
            sc.mujoco.integrator if integrator is None else integrator,
            sc.mujoco.timestep if dt is None else dt,
        )
    return plant(engine).default_settings(sc)


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
    sc = request.scene
    runs, names, refused = _prepared_plants(request)
    with output_run(out_dir, command) as run:
        res = _validate_into(
            run,
            sc,
            runs,
            request.horizon,
            progress,
            request.figure_formats,
            concurrent,
            thresholds=request.thresholds,
            joined=joined,
            left_out=request.left_out,
            names=names,
            refused=refused,
            limits={pl.engine: request.limit_of(pl.engine) for pl, _ in runs},
        )
    files = {name: run.final(name) for name in res.files}
    files["manifest.json"] = run.final("manifest.json")
    _check_committed(run.target, files)
    return dataclasses.replace(res, out_dir=run.target, files=files)


def _prepared_plants(
    request: ValidationRequest,
) -> tuple[list[tuple[Any, Any]], dict[str, str], list[str]]:
    """Each plant of ``request`` with its settings and its one-line description, in order, and
    the failures of those that cannot run: ``unusable`` ones, and those whose
    ``default_settings`` or ``describe`` raises (or describes itself with no text)."""
    runs: list[tuple[Any, Any]] = []
    names: dict[str, str] = {}
    refused: list[str] = []
    for e in request.plants:
        pl = plant(e)
        if e in request.unusable:
            refused.append(f"{pl.label} plant: not run: {request.unusable[e]}")
            continue
        call = "default_settings"
        try:  # a plant's own bug in either: that plant fails alone
            settings = _plant_settings(e, plant_scene(request.scene), request.integrator, request.dt)
            call = "describe"
            name = pl.describe(settings)
        except Exception as exc:
            refused.append(f"{pl.label} plant: not run: {call} raised {_one_line(exc)}")
            continue
        if not (isinstance(name, str) and name.strip()):
            refused.append(f"{pl.label} plant: not run: describe returned {name!r}, not a line of text")
            continue
        runs.append((pl, settings))
        names[pl.engine] = name.splitlines()[0]
    return runs, names, refused


def _check_committed(target: Path, files: dict[str, Path]) -> None:
    """Every file the result names is in the committed directory, whole: listed in its
    ``manifest.json`` (:func:`validation.runs.outputs.parse_manifest`) with the size found there (the
    verdict is given only then).

    Raises:
        OutputError: the manifest is not readable, or a file is missing or not the size its
            manifest records.
    """
    try:
        listed = parse_manifest((target / "manifest.json").read_bytes())
    except (OSError, ValueError) as exc:
        raise OutputError(target / "manifest.json", f"not readable after the commit ({exc})") from exc
    for name, path in files.items():
        if name == "manifest.json":
            continue
        try:
            size = path.stat().st_size
        except OSError as exc:
            raise OutputError(path, f"missing after the commit ({exc.strerror})") from exc
        recorded = listed[name].bytes if name in listed else None
        if recorded != size:
            raise OutputError(path, f"{size} bytes after the commit, the manifest says {recorded}")


_plant_task = plant_task
"""One plant's run (:func:`validation.runs.plant_runs.plant_task`), by this name for the tests that
replace it (a worker killed on its first call)."""

_stage_progress = stage_progress  # the name the report's tests know it by


def _recording_task(
    path: Path, sc: Scene, plants, cmp, run_id: str, *, report
) -> tuple[Any, float]:
    # deferred: rerun and scipy.spatial, ~0.25 s (python -X importtime), in the worker
    from validation.recording.recording import write_recording

    t0 = time.perf_counter()
    info = write_recording(path, sc, plants, cmp, recording_id=run_id)
    return info, time.perf_counter() - t0


RECORDING = "run.rrd"

EVIDENCE_SHARES: tuple[tuple[str, ...], ...] = (
    (RECORDING, "errors"),
    ("tracking", "invariants", "control"),
)
"""How the recording and the figures (:data:`validation.report.figures.FIGURES`) are shared between the
two evidence workers, balanced as measured on the default scene (one process, 2-core machine):
the recording 0.1 s, the error figure (a panel per compared quantity) 0.8-1.0 s, the others
0.3-0.4 s each."""


def _evidence_task(share: Sequence[str], rec_args, fig_args, *, report) -> dict[str, Any]:
    """The recording (when ``share`` names it and there are trajectories) and the figures named
    in ``share``: ``{"recording": (info, wall), "figures": ((paths, entries, errors), wall)}``."""
    done: dict[str, Any] = {}
    if RECORDING in share and rec_args is not None:
        try:
            done["recording"] = _recording_task(*rec_args, report=report)
        except Exception as exc:  # a bug: said in the report (FAILED); the figures are still drawn
            if is_write_failure(exc):
                raise _as_output_error(exc, rec_args[0]) from exc
            done["recording_error"] = _one_line(exc)
    names = [n for n in share if n != RECORDING]
    if names:
        t0 = time.perf_counter()
        drawn = draw_figures(*fig_args, names=names)
        done["figures"] = (drawn, time.perf_counter() - t0)
    return done


def _as_output_error(exc: BaseException, path: Path) -> OutputError:
    """``exc`` (a filesystem's refusal to write, :func:`validation.report.report.is_write_failure`) as
    the :class:`OutputError` it means: the run's set cannot be completed."""
    return exc if isinstance(exc, OutputError) else OutputError(path, exc)


def _import_rerun() -> None:
    from validation.runs.environment import import_rerun

    import_rerun()  # first: NO_COLOR for rerun's first import only
    import rerun.blueprint  # noqa: F401

    import validation.recording.recording  # noqa: F401  (scipy.spatial)


def _prepare_rerun_and_figures() -> None:
    _import_rerun()
    _prepare_figures()


def _prepare_figures() -> None:
    """matplotlib imported and one throw-away figure drawn (:func:`validation.report.figures.prepare_drawing`):
    the fonts and caches the first figure needs are loaded (in an evidence worker, before it is
    given its inputs)."""
    try:
        prepare_drawing()
    except Exception:  # an optimisation only: the figures, drawn later, report their own errors
        pass


def _worker_result(job: workers.Job, redo: Callable[[], Any], redone: list[str]) -> Any:
    """An evidence worker's result; when its worker was lost, ``redo()`` does it here (said in
    ``redone``). A file it could not write is an :class:`OutputError`; an interrupt goes on."""
    try:
        return job.result()
    except workers.WorkerLost as exc:
        if job.interrupted:
            raise KeyboardInterrupt(str(exc)) from None
        redone.append(f"{exc}; made again in the main process")
        return redo()
    except workers.WorkerError as exc:
        raise RuntimeError(str(exc)) from None


def _referee_note(sc: Scene) -> str:
    """Why a run of fewer than three plants has no referee: Pinocchio not installed, unable to
    run this scene (its reason), or not chosen."""
    if PinocchioPlant.unavailable():
        return (
            "the referee (Pinocchio) is not installed: pip install 'pin>=4.1' (the [pinocchio] extra)"
        )
    try:
        PinocchioPlant().check_scene(sc)
    except ValueError as exc:
        return f"the referee (Pinocchio) cannot run this scene: {exc}"
    return "the referee needs three plants"


def _meta(
    run: OutputRun,
    sc: Scene,
    runs: Sequence[tuple[Any, Any]],
    names: dict[str, str],
    horizon: float,
    verdicts: Sequence[Verdict],
    joined: JoinedRuns = NO_JOINED,
    left_out: Sequence[LeftOut] = (),
) -> dict[str, Any]:
    """The run's metadata for the report (the wall times are added when they are known); the
    ``joined`` runs are plants too, named as ``joined.names`` says, with ``joined.meta``."""
    mj = next((st for pl, st in runs if pl.engine == Engine.MUJOCO), None)
    referee_note = "" if len(runs) + len(joined.trajectories) >= 3 else _referee_note(sc)
    # the plants of the default set or of `--plants all` that refused the scene, each once
    told = [str(x) for x in left_out if not (referee_note and x.engine == Engine.PINOCCHIO)]
    referee_note = "; ".join([*told, *([referee_note] if referee_note else [])])
    meta = {
        "run_id": run.run_id,
        "scene": {
            "name": sc.name,
            "source": sc.source,
            "description": sc.description,
            "effects": sorted(e.value for e in sc.effects),
        },
        "horizon_s": horizon,
        "output_rate_hz": sc.output.rate,
        "plants": [
            {"engine": pl.engine, "settings": names[pl.engine]} for pl, _ in runs
        ],
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
    meta["plants"] += [
        {"engine": str(tr.engine), "settings": names.get(str(tr.engine), str(tr.engine))}
        for tr in joined.trajectories
    ]
    return meta | dict(joined.meta)


def _validate_into(
    run: OutputRun,
    sc: Scene,
    runs: Sequence[tuple[Any, Any]],
    horizon: float,
    progress: Progress | None,
    formats: Sequence[FigureFormat] = DEFAULT_FORMATS,
    concurrent: bool = True,
    thresholds: Mapping[str, Threshold] | None = None,
    joined: JoinedRuns = NO_JOINED,
    left_out: Sequence[LeftOut] = (),
    names: Mapping[str, str] | None = None,
    refused: Sequence[str] = (),
    limits: Mapping[str, float | None] | None = None,
) -> ValidationResult:
    """:func:`run_validation`'s work, writing into the staging directory ``run.path``; the
    ``joined`` runs follow the plants' (:class:`JoinedRuns`). ``names``: plant -> its one-line
    description (None: each plant's ``describe``); ``refused``: the failures of the plants that
    could not be run (:func:`_prepared_plants`); ``limits``: plant -> its wall-time limit, s.

    With ``concurrent`` (and where :func:`validation.runs.workers.can_fork`), the plants run side by
    side in workers, and two more workers import rerun and matplotlib meanwhile, then write the
    recording and draw the figures side by side; the files are those of a run one stage after
    the other.

    An interrupt (Ctrl-C, SIGTERM) at any stage stops every worker at once; the report of how far
    each plant got is written, INTERRUPTED (no comparison of a partial run, no figures, no
    recording: the stop is prompt whatever the horizon), and the interrupt raised after it. A file that cannot be written raises :class:`OutputError` (no verdict, no files).
    """
    out = run.path
    walls: dict[str, float] = {}
    failures: list[str] = list(refused)
    redone: list[str] = []
    t_all = time.perf_counter()
    fork = concurrent and workers.can_fork()
    jobs: list[workers.Job] = []
    trajectories: list[Trajectory] = []
    cmp: Comparison | None = None
    verdicts: tuple[Verdict, ...] = ()
    if names is None:
        names = {pl.engine: pl.describe(settings) for pl, settings in runs}
    names = dict(names)
    interrupted = False

    def start_evidence(plant_jobs: Sequence[workers.Job] = ()) -> None:
        """Once every plant runs: scipy.linalg (for the comparison) imported here, then the two
        evidence workers, each importing matplotlib (and loading its fonts and caches by one
        throw-away figure) and one rerun meanwhile, at idle priority: the plants keep the CPUs.
        This process stays at its own priority, so a signal is heard at once: it tells the
        plants, and is raised once the import is whole."""
        if fork:
            with workers.signals_held(on_signal=lambda: workers.interrupt(plant_jobs)):
                import scipy.linalg  # noqa: F401  (the comparison's exponentials, next)
        jobs[:] = [
            workers.start(
                f"evidence {k + 1}",
                _evidence_task,
                prepare=_prepare_rerun_and_figures if RECORDING in share else _prepare_figures,
                later=True,
                idle_until_given=True,  # the plants keep the CPUs
                fork=fork,
            )
            for k, share in enumerate(EVIDENCE_SHARES)
        ]

    try:
        trajectories, interrupted = run_plants(
            runs,
            sc,
            horizon,
            progress,
            fork,
            walls,
            failures,
            redone,
            on_started=start_evidence,
            limits=limits,
            task=_plant_task,  # looked up here, at the call: a test may replace it
        )
        trajectories += joined.trajectories
        names.update(joined.names)
        if trajectories and trajectories[0].t.size and not interrupted:
            cmp, verdicts = _compare(
                trajectories, sc, horizon, names, walls, failures, thresholds, joined.amend
            )
    except KeyboardInterrupt:
        interrupted = True
    except BaseException:
        workers.stop(jobs)
        raise
    meta = _meta(run, sc, runs, names, horizon, verdicts, joined, left_out)
    # the scene as it ran, in the scene file's conventions: `tumble validate OUT/scene.toml` reruns it
    files: dict[str, Path] = {"scene.toml": write_text(out / "scene.toml", scene_to_toml(sc))}
    drawn: Sequence[list] = ([], [], [])
    evidence: tuple = ()
    if not interrupted:
        try:
            if not jobs:
                start_evidence()
            evidence = _evidence(jobs, run, sc, trajectories, cmp, meta, formats, walls)
        except KeyboardInterrupt:
            interrupted = True
        finally:
            workers.stop(jobs)
    else:
        workers.stop(jobs)
    if interrupted:  # the evidence of an interrupted run is left out, whatever was made
        failures.insert(0, _interrupted_sentence(trajectories, runs))
        meta["evidence"] = "no comparison, figures or recording: the run was interrupted"
    elif evidence:
        *drawn, made, evidence_failures, evidence_redone = evidence
        files.update(made)
        failures += evidence_failures
        redone += evidence_redone
    if redone:
        meta["redone"] = list(redone)
    failure = "; ".join(failures)
    if len(runs) + len(joined.trajectories) < 2 and not failure:
        failure = "only one plant: nothing to compare it with"
    if len(trajectories) < len(runs) + len(joined.trajectories) and not failure:
        got = {tr.engine for tr in trajectories}
        missing = [pl.engine for pl, _ in runs if pl.engine not in got]
        failure = f"no trajectory from {', '.join(missing) or 'a plant'}"
    walls["total"] = time.perf_counter() - t_all
    meta["wall_times_s"] = dict(walls)
    t0 = time.perf_counter()

    def report(failure: str, interrupted: bool) -> Any:
        return write_report(
            out,
            cmp,
            trajectories,
            meta,
            failure=failure,
            verdicts=verdicts,
            formats=formats,
            scene=sc,
            figures=drawn,
            interrupted=interrupted,
        )

    # A signal while the report is written is not allowed to leave a report that says PASSED in
    # a set marked interrupted: the report is written again, INTERRUPTED.
    with workers.signals_held(raise_after=False) as caught:
        rep = report(failure, interrupted)
        files.update({"report.md": rep.markdown, "report.json": rep.json})
        files.update({f.name: f for f in rep.figures})
        _keep_only(out, files)
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
        out_dir=out,
        passed=rep.verdict is RunVerdict.PASSED,
        checks=cmp.checks if cmp is not None else (),
        comparison=cmp,
        failure=rep.failure,
        files=files,
        wall_times=walls,
        verdicts=verdicts,
    )


def _compare(
    trajectories: Sequence[Trajectory],
    sc: Scene,
    horizon: float,
    names: dict[str, str],
    walls: dict[str, float],
    failures: list[str],
    thresholds: Mapping[str, Threshold] | None = None,
    amend: Callable[[Comparison], Comparison] | None = None,
) -> tuple[Comparison | None, tuple[Verdict, ...]]:
    """Every pair compared (then ``amend``-ed, :class:`JoinedRuns`) and the referee's rulings; a
    comparison that raises is a failure said in the report (an interrupt goes on)."""
    try:
        t0 = time.perf_counter()
        cmp = compare_plants(trajectories, sc, t_end=horizon, thresholds=thresholds)
        if amend is not None:
            cmp = amend(cmp)
        walls["compare"] = time.perf_counter() - t0
        return cmp, tuple(referee(cmp, names, trajectories))
    except Exception as exc:
        failures.append(f"comparison: {_one_line(exc)}")
        traceback.print_exc()
        return None, ()


def _evidence(
    jobs: Sequence[workers.Job],
    run: OutputRun,
    sc: Scene,
    trajectories: Sequence[Trajectory],
    cmp: Comparison | None,
    meta: dict[str, Any],
    formats: Sequence[FigureFormat],
    walls: dict[str, float],
) -> tuple:
    """The recording and the figures, by the evidence ``jobs`` (in workers or here):
    ``(paths, entries, figure errors, files, failures, redone)``. A worker that was lost is
    redone here; a file that could not be written raises :class:`OutputError`; a recording or
    figure that could not be made is an error the report states (the run FAILED)."""
    out = run.path
    ctx = FigureContext.from_meta(meta, cmp.scene if cmp is not None else "")
    rec_args = (out / RECORDING, sc, trajectories, cmp, run.run_id) if trajectories else None
    fig_args = (out, cmp, trajectories, ctx, formats)
    # The worker without a recording first: the other may still be importing rerun, and a
    # pipe blocks until its reader reads.
    by_readiness = sorted(zip(jobs, EVIDENCE_SHARES, strict=True), key=lambda js: RECORDING in js[1])
    for job, share in by_readiness:
        job.give(share, rec_args, fig_args)
    if workers.wait(jobs):  # an interrupt while the evidence is made stops the run
        raise KeyboardInterrupt
    files: dict[str, Path] = {}
    paths: list[Path] = []
    entries: dict[str, Any] = {}
    fig_errors: list[str] = []
    failures: list[str] = []
    redone: list[str] = []
    walls["figures"] = 0.0
    for job, share in zip(jobs, EVIDENCE_SHARES, strict=True):
        try:
            done = _worker_result(
                job,
                lambda share=share: _evidence_task(share, rec_args, fig_args, report=None),
                redone,
            )
        except OutputError:
            raise
        except Exception as exc:  # a bug: said in the report, the run FAILED
            fig_errors.append(f"{', '.join(share)}: {_one_line(exc)}")
            continue
        if "recording" in done:
            rinfo, walls["recording"] = done["recording"]
            files[RECORDING] = rinfo.path
        if "recording_error" in done:
            failures.append(f"recording: {done['recording_error']}")
        if "figures" in done:
            (got_paths, got_entries, got_errors), wall = done["figures"]
            paths += got_paths
            entries.update({e.name: e for e in got_entries})
            fig_errors += got_errors
            walls["figures"] += wall
    if trajectories and RECORDING not in files and not failures:
        failures.append("recording: not written")
    ordered = [entries[n] for n in FIGURES if n in entries]
    return paths, ordered, fig_errors, files, failures, redone


def _interrupted_sentence(trajectories: Sequence[Trajectory], runs: Sequence[tuple[Any, Any]]) -> str:
    """``interrupted by SIGTERM: analytic reached t = 3.2 s, mujoco t = 1.1 s, pinocchio not run``."""
    reached = {tr.engine: float(tr.t[-1]) if tr.t.size else 0.0 for tr in trajectories}
    parts = [
        f"{pl.engine} reached t = {reached[pl.engine]:.6g} s"
        if pl.engine in reached
        else f"{pl.engine} has no trajectory"
        for pl, _ in runs
    ]
    return f"interrupted by {interrupt_name()}: " + ", ".join(parts)


def _keep_only(out: Path, files: dict[str, Path]) -> None:
    """Remove from the staging directory ``out`` (this run's own, created for it) every file
    the report does not name (a figure drawn before an interrupt stopped the others, a
    recording left out): the committed set is what the report names, nothing more."""
    named = {p.name for p in files.values()}
    for p in out.iterdir():
        if not p.name.startswith(".") and p.is_file() and p.name not in named:
            p.unlink(missing_ok=True)


__all__ = [
    "DEFAULT_SCENE",
    "PLUGIN_TIME_LIMIT_S",
    "ValidationRequest",
    "ValidationResult",
    "plant_time_limit",
    "run_request",
    "run_validation",
    "validation_request",
]
