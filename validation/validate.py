"""Run a scene on every plant under one controller, compare, and write the evidence.

:func:`run_validation`: the analytic plant (scipy, the scene's solver settings), the MuJoCo twin
(the scene's integrator and time step, overridable) and, when installed, the Pinocchio referee, all
driven by the analytic controller; :func:`validation.compare.compare_plants`; then ``report.md``,
``report.json``, the figures (PNG, and SVG or PDF on request) and ``run.rrd`` in ``out_dir``. A run
that fails (an engine error, a plant stopping early, MuJoCo's bridge missing) still writes what it
has, marked FAILED. The teaching demo is :mod:`validation.demo`.
"""

from __future__ import annotations

import dataclasses
import inspect
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.scene import Scene, load_scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from validation.atomic import OutputError
from validation.compare import Check, Comparison, compare_plants
from validation.demo import DemoResult, DemoStep, write_demo  # noqa: F401  (moved; old imports)
from validation.figures import DEFAULT_FORMATS, FigureFormat, parse_formats
from validation.outputs import OutputRun, output_run
from validation.preflight import check_validation_inputs
from validation.recording import write_recording
from validation.referee import Verdict, referee
from validation.report import versions, write_report

SCENES = Path(__file__).resolve().parent / "scenes"
DEFAULT_SCENE = "paper_example1_controlled"

Progress = Callable[[str, float], None] | Callable[[float], None]
"""``progress(stage, t)`` (stage ``analytic`` or ``mujoco``) or ``progress(t)``: t is the simulated
time reached, s. A one-argument callable is told the analytic plant's progress only."""


def _stage_progress(progress: Any, stage: str) -> Callable[[float], None] | None:
    """Adapt either form of ``progress`` to the engines' ``progress(t)``."""
    if progress is None:
        return None
    try:
        params = inspect.signature(progress).parameters.values()
        two = sum(
            p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params
        ) >= 2 or any(p.kind is p.VAR_POSITIONAL for p in params)
    except (TypeError, ValueError):
        two = False
    if two:
        return lambda t: progress(stage, t)
    return progress if stage == "analytic" else None


@dataclass(frozen=True)
class ValidationResult:
    """The outcome of :func:`run_validation`.

    Attributes:
        scene: scene name.
        out_dir: where the files are.
        passed: every check passed and nothing failed.
        checks: every check (empty if no comparison could be made).
        comparison: the comparison (None if no analytic trajectory exists).
        failure: why the run failed ("" if it did not).
        files: name -> path of every file written.
        wall_times: stage -> seconds (each plant, compare, report, recording, total).
        verdicts: the referee's rulings (three plants), see :mod:`validation.referee`.
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


def _scene(scene: Scene | str | Path) -> Scene:
    if isinstance(scene, Scene):
        return scene
    p = Path(scene)
    if not p.exists() and (SCENES / f"{scene}.toml").exists():
        p = SCENES / f"{scene}.toml"
    return load_scene(p)


def _figure_formats(formats: Sequence[FigureFormat | str] | str) -> tuple[FigureFormat, ...]:
    """The formats as enums, once each; ValueError naming ``figure_format`` (before any work)."""
    if isinstance(formats, str):
        return parse_formats(formats)
    out = parse_formats(",".join(str(getattr(f, "value", f)) for f in formats)) if formats else ()
    if not out:
        raise ValueError("figure_format: at least one format is needed (got none)")
    return out


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


def _plant_settings(engine: Engine, sc: Scene, integrator: Any, dt: float | None) -> Any:
    """Each plant's settings: the scene's, with the MuJoCo overrides of the command line."""
    from mj_bridge.plants import MujocoRunSettings, plant

    if engine is Engine.MUJOCO:
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
) -> ValidationResult:
    """Run ``scene`` on every chosen plant under one controller, compare every pair, rule on
    disagreements, and write the report and ``run.rrd``.

    Args:
        scene: a :class:`Scene`, a scene file, or a built-in scene name.
        out_dir: output directory. It receives this run's files as one set
            (:func:`validation.outputs.output_run`): ``manifest.json`` lists them with their
            hashes and the run id; a failed run's partial set is marked failed, an interrupted one
            interrupted (and the KeyboardInterrupt re-raised after the files are in place).
        integrator: MuJoCo integrator (default the scene's ``[mujoco] integrator``).
        dt: MuJoCo time step, s (default the scene's ``[mujoco] timestep``).
        t_end: horizon, s (default the scene's ``[output] t_end``).
        progress: optional ``progress(stage, t)`` callback, stage the plant's name (a one-argument
            callable hears the analytic plant only).
        plants: which plants (engine names, or ``"analytic,mujoco"``); default every installed
            plant (:func:`mj_bridge.plants.installed_plants`). With three, the referee names the
            plant that disagrees with the two that agree (:mod:`validation.referee`).
        figure_formats: the figures' file formats, PNG by default (``("png", "svg")`` adds SVG
            files for papers; :class:`validation.figures.FigureFormat`).

    Returns:
        a frozen :class:`ValidationResult`; ``passed`` is False when any check fails or a plant
        could not run.

    Raises:
        ValueError: bad input (scene, plants, integrator, dt, t_end, out_dir), before any plant
            runs.
        OutputBusy: another run is writing into ``out_dir``.
        OutputError: the files could not be written; ``out_dir`` keeps its previous contents.
    """
    from mj_bridge.plants import installed_plants, parse_plants, plant

    sc = _scene(scene)
    if plants is None:
        chosen = installed_plants()
    elif isinstance(plants, str):
        chosen = parse_plants(plants)
    else:
        chosen = parse_plants(",".join(str(getattr(p, "value", p)) for p in plants))
    check_validation_inputs(  # before any plant runs
        sc, integrator=integrator, dt=dt, t_end=t_end, mujoco=Engine.MUJOCO in chosen
    )
    formats = _figure_formats(figure_formats)
    if t_end is not None and not (t_end > 0):
        raise ValueError(f"t_end: must be a positive time in s (got {t_end!r})")
    horizon = float(t_end) if t_end is not None else sc.output.t_end
    runs = []
    for e in chosen:
        pl = plant(e)
        pl.check_scene(sc)
        runs.append((pl, _plant_settings(e, sc, integrator, dt)))
    with output_run(out_dir, "validate") as run:
        res = _validate_into(run, sc, runs, horizon, progress, formats)
    files = {name: run.final(name) for name in res.files}
    files["manifest.json"] = run.final("manifest.json")
    return dataclasses.replace(res, out_dir=run.target, files=files)


def _validate_into(
    run: OutputRun,
    sc: Scene,
    runs: Sequence[tuple[Any, Any]],
    horizon: float,
    progress: Progress | None,
    formats: Sequence[FigureFormat] = DEFAULT_FORMATS,
) -> ValidationResult:
    """:func:`run_validation`'s work, writing into the staging directory ``run.path``."""
    from mj_bridge.plants import PinocchioPlant

    out = run.path
    walls: dict[str, float] = {}
    failures: list[str] = []
    t_all = time.perf_counter()

    def timed(stage: str, fn: Callable[[], Any]) -> Any:
        t0 = time.perf_counter()
        try:
            return fn()
        finally:
            walls[stage] = time.perf_counter() - t0

    trajectories: list[Trajectory] = []
    names: dict[str, str] = {}
    interrupted = False
    for pl, settings in runs:
        name = pl.engine.value
        names[name] = pl.describe(settings)
        if interrupted:  # Ctrl-C stops the run, it does not skip to the next plant
            failures.append(f"{pl.label} plant: not run (interrupted)")
            continue
        try:
            tr = timed(
                name,
                lambda pl=pl, settings=settings, name=name: pl.simulate(
                    sc, settings, t_end=horizon, progress=_stage_progress(progress, name)
                ),
            )
        except ValueError:
            raise  # the caller's input, not a failed run
        except Exception as exc:
            failures.append(f"{pl.label} plant: {_one_line(exc)}")
            continue
        trajectories.append(tr)
        interrupted = tr.status is RunStatus.INTERRUPTED
        if tr.status is not RunStatus.OK:
            failures.append(f"{name} plant stopped early: {tr.message}")

    cmp: Comparison | None = None
    verdicts: tuple[Verdict, ...] = ()
    if trajectories and trajectories[0].t.size:
        try:
            cmp = timed("compare", lambda: compare_plants(trajectories, sc, t_end=horizon))
            verdicts = referee(cmp, names)
        except Exception as exc:
            failures.append(f"comparison: {_one_line(exc)}")
            traceback.print_exc()
    failure = "; ".join(failures)
    passed = cmp is not None and cmp.passed and not failure and len(trajectories) == len(runs) >= 2
    if len(runs) < 2 and not failure:
        failure = "only one plant: nothing to compare it with"
        passed = False

    files: dict[str, Path] = {}
    try:
        rinfo = (
            timed(
                "recording",
                lambda: write_recording(
                    out / "run.rrd", sc, trajectories, cmp, recording_id=run.run_id
                ),
            )
            if trajectories
            else None
        )
        if rinfo is not None:
            files["run.rrd"] = rinfo.path
    except Exception as exc:
        why = exc.reason if isinstance(exc, OutputError) else _one_line(exc)
        failure = "; ".join([*failures, f"recording: {why}"])
        passed = False
    walls["total"] = time.perf_counter() - t_all
    by_engine = {pl.engine: (pl, st) for pl, st in runs}
    mj = by_engine.get(Engine.MUJOCO)
    referee_note = (
        ""
        if len(runs) >= 3
        else (
            "the referee (Pinocchio) is not installed: pip install 'pin>=4.1' (the [pinocchio] extra)"
            if PinocchioPlant.unavailable()
            else "the referee needs three plants"
        )
    )
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
            {"engine": pl.engine.value, "settings": names[pl.engine.value]} for pl, _ in runs
        ],
        "analytic_solver": {
            "method": sc.solver.method.value,
            "rtol": sc.solver.rtol,
            "atol": sc.solver.atol,
            "max_step": sc.solver.max_step,
        },
        "mujoco_settings": {
            "integrator": (mj[1].integrator.value if mj else sc.mujoco.integrator.value),
            "timestep": mj[1].dt if mj else sc.mujoco.timestep,
            "spring_model": sc.mujoco.spring_model.value,
        },
        "controller": "analytic (Udwadia–Kalaba, Eq. 89) in every plant",
        "referee": [v.to_dict() for v in verdicts],
        "referee_note": referee_note,
        "versions": versions(),
        "wall_times_s": dict(walls),
    }
    t0 = time.perf_counter()
    rep = write_report(
        out, cmp, trajectories, meta, failure=failure, verdicts=verdicts, formats=formats, scene=sc
    )
    walls["report"] = time.perf_counter() - t0
    files.update({"report.md": rep.markdown, "report.json": rep.json})
    files.update({f.name: f for f in rep.figures})
    if failure:
        run.mark_failed(failure)
    if interrupted:
        raise KeyboardInterrupt  # the partial set is committed, marked interrupted
    return ValidationResult(
        scene=sc.name,
        out_dir=out,
        passed=bool(passed),
        checks=cmp.checks if cmp is not None else (),
        comparison=cmp,
        failure=failure,
        files=files,
        wall_times=walls,
        verdicts=verdicts,
    )


__all__ = [
    "DEFAULT_SCENE",
    "ValidationResult",
    "run_validation",
]
