"""``judge``: another engine's run of a scene, judged beside the built-in plants.

The file (``docs/trajectory-format.md``, :func:`validation.external.read.read_trajectory`) becomes one
more plant, named by its label; the chosen built-in plants (default: every installed one that can
run the scene) run beside it as referees, through the stages of
:func:`validation.validate.run_request` (:class:`validation.validate.JoinedRuns`): every pair
compared, each plant checked, the referee, ``report.md``/``report.json``, the figures and
``run.rrd``. With a reference pack (:mod:`validation.external.reference_pack`) no plant runs: the
pack's trajectory is the other plant, named ``reference``.

A check that needs a column group the file does not hold is **not judged** (:data:`NEEDS`): its
state is not applicable, its reason ``not judged: no omega columns``; it never passes or fails.
The report's notes name the file, its SHA-256 and every group it lacks.

A file that covers less than the scene's horizon is judged over the horizon it covers when the
caller says so (``t_end``, ``up_to_file_end``: :mod:`validation.external.horizon`); the report
states the horizon judged (its first note, ``run.judged_horizon`` in ``report.json``).

Inputs are checked once, before any plant runs (:func:`judge_request`): the scene, the horizon, the
file (one line naming the row and column), the label, the plants, the pack; the result is the
:class:`validation.validate.ValidationResult` of ``run_validation``.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from analytic.scene import Scene
from analytic.trajectory import Engine
from mj_bridge.plants import (
    ALL,
    installed_plants,
    parse_plants,
    plant,
    plants_for_scene,
    registered,
)
from mj_bridge.registry import NAME_PATTERN
from validation.compare.checks import Check, Comparison
from validation.compare.thresholds import thresholds_for
from validation.external.columns import ColumnGroup
from validation.external.horizon import HorizonSource, JudgedHorizon, horizon_on_grid, shortened
from validation.external.read import read_trajectory
from validation.external.record import ExternalTrajectory, does_work
from validation.external.reference_pack import REFERENCE_PLANT, read_pack
from validation.preflight import accepting_plants, check_validation_inputs
from validation.report.figures import DEFAULT_FORMATS, FigureFormat
from validation.runs.outputs import default_out_dir
from validation.scenes import resolve_scene, with_threshold_overrides
from validation.validate import (
    JoinedRuns,
    Progress,
    ValidationRequest,
    ValidationResult,
    run_request,
)
from validation.validate.request import checked_formats

LABEL_PATTERN = NAME_PATTERN
"""A plant label is a plant name (:data:`mj_bridge.registry.NAME_PATTERN`): a lower-case letter,
then lower-case letters, digits and ``_``, at most 32 characters (a word in report keys, Rerun
entity paths and file names, carrying nothing to escape)."""

_V, _W, _PD = ColumnGroup.VELOCITY, ColumnGroup.ANGULAR_VELOCITY, ColumnGroup.ROD_VELOCITIES
_BALANCE = (_V, _W, _PD)
NEEDS: Mapping[str, tuple[ColumnGroup, ...]] = {
    "velocity_C": (_V,),
    "rod_velocities": (_PD,),
    "angular_velocity": (_W,),
    "control_torque": (ColumnGroup.TORQUE,),
    "rod_forces": (ColumnGroup.ROD_FORCES,),
    "tracking_omega": (_W,),
    "tracking_p": (_PD,),  # ė(0) of Eq. 78's closed form is ṗ(0) + l λ sin(λ t0)
    "linear_momentum": _BALANCE,
    "angular_momentum": _BALANCE,
    "energy": _BALANCE,
}
"""Check name -> the optional column groups it needs from a file (the momenta and the energy
need every velocity; their balances need the ``work`` group too when something does work on the
system, :func:`validation.external.record.does_work`). Checks not named here (completed, position
of C, attitude, rod positions, quaternion norm) need the required columns only."""

_BALANCES = frozenset({"linear_momentum", "angular_momentum", "energy"})


def needed_groups(name: str, scene: Scene) -> tuple[ColumnGroup, ...]:
    """The optional column groups check ``name`` needs from a file of ``scene`` (:data:`NEEDS`)."""
    groups = NEEDS.get(name, ())
    if name in _BALANCES and does_work(scene):
        groups = (*groups, ColumnGroup.WORK)
    return groups


def plant_label(label: str | None, path: str | Path, taken: Sequence[str] = ()) -> str:
    """The plant name of a trajectory file: ``label`` as given (checked), else the file's stem
    made a label (lower case, every other character ``_``, ``ext_`` first when it does not begin
    with a letter).

    Raises:
        ValueError: naming ``label``: not of :data:`LABEL_PATTERN`, or a plant's name (a built-in
            plant's, ``reference``, or one of ``taken``).
    """
    if label is None:
        stem = re.sub(r"[^a-z0-9_]", "_", Path(path).stem.lower()) or "file"
        text = (stem if stem[0].isalpha() else f"ext_{stem}")[:32]
        field = f"label (from the file name {Path(path).name!r})"
    else:
        text = str(label)
        field = "label"
        if not LABEL_PATTERN.fullmatch(text):
            raise ValueError(
                f"label: {text!r:.60} is not a plant name (a lower-case letter, then lower-case "
                "letters, digits or '_', at most 32 characters)"
            )
    reserved = {e.value for e in Engine} | set(registered()) | {ALL, REFERENCE_PLANT, *taken}
    if text in reserved:
        raise ValueError(
            f"{field}: {text!r} is the name of a plant; give the file's engine another name "
            "(--label)"
        )
    return text


def not_judged(cmp: Comparison, files: Sequence[ExternalTrajectory], scene: Scene) -> Comparison:
    """``cmp`` with every check that needs a column group one of ``files`` lacks made not judged
    (not applicable, reason ``not judged: no omega columns``), and a note per file naming it, its
    SHA-256 and the checks not judged."""
    by_name = {str(f.trajectory.engine): f for f in files}
    checks: list[Check] = []
    skipped: dict[str, list[str]] = {name: [] for name in by_name}
    for c in cmp.checks:
        whose = [p for p in c.subject.plants if p in by_name]
        missing = [
            g for p in whose for g in needed_groups(c.name, scene) if not by_name[p].has(g)
        ]
        if not missing:
            checks.append(c)
            continue
        for p in whose:
            skipped[p].append(c.label)
        checks.append(
            dataclasses.replace(
                c,
                value=float("nan"),
                passed=True,
                applicable=False,
                reason=ExternalTrajectory.not_judged(missing[0]),
                t_max=float("nan"),
            )
        )
    notes = list(cmp.notes)
    for name, f in by_name.items():
        notes.append(
            f"{name}: read from the trajectory file {Path(f.source).name!r} "
            f"({f.format.value}, SHA-256 {f.sha256}), not run here"
        )
        for g in sorted(f.absent, key=list(ColumnGroup).index):
            if g is ColumnGroup.WORK and not does_work(scene):
                continue  # nothing does work: the integrals are zeros, nothing is lost
            which = [lab for lab in skipped[name] if _needs(lab, g, scene)]
            if which:
                notes.append(f"{name}: {ExternalTrajectory.not_judged(g)} ({', '.join(which)})")
    return dataclasses.replace(cmp, checks=tuple(checks), notes=tuple(notes))


def _needs(label: str, group: ColumnGroup, scene: Scene) -> bool:
    return group in needed_groups(label.rsplit(".", 1)[-1], scene)


@dataclass(frozen=True)
class JudgeRequest:
    """A judge's input, checked whole by :func:`judge_request` before any plant runs.

    Attributes:
        validation: the plants that run beside the file (none with a reference pack), the scene,
            thresholds, horizon and figure formats, as ``run_request`` takes them.
        external: the file's run, read and checked, its plant name the label.
        reference: the reference pack's trajectory (plant ``reference``), or None.
        horizon: the horizon judged, beside the scene's own (the report states it).
    """

    validation: ValidationRequest
    external: ExternalTrajectory
    reference: ExternalTrajectory | None = None
    horizon: JudgedHorizon | None = None

    @property
    def label(self) -> str:
        return str(self.external.trajectory.engine)

    @property
    def files(self) -> tuple[ExternalTrajectory, ...]:
        """The runs read from files, in report order (the reference first)."""
        return (*([self.reference] if self.reference else []), self.external)


def _plants(plants: Sequence[str] | str | None, scene: Scene) -> tuple[str, ...]:
    """The referee plants: every installed one that can run ``scene``, or those named (each
    installed and accepting the scene); ValueError naming ``plants``."""
    if plants is None:
        return plants_for_scene(scene, installed_plants())
    text = plants if isinstance(plants, str) else ",".join(str(getattr(p, "value", p)) for p in plants)
    chosen = parse_plants(text)
    if [n.strip() for n in text.split(",") if n.strip()] == [ALL]:  # as a default set: warn, go on
        return accepting_plants(scene, chosen).plants
    for e in chosen:
        try:
            plant(e).check_scene(scene)
        except ValueError as exc:
            raise ValueError(f"plants: {e} cannot run {scene.name!r}: {exc}") from None
    return tuple(str(e) for e in chosen)


def judge_request(
    scene: Scene | str | Path | None,
    trajectory_file: str | Path,
    *,
    label: str | None = None,
    plants: Sequence[str] | str | None = None,
    reference: str | Path | None = None,
    t_end: float | None = None,
    up_to_file_end: bool = False,
    figure_formats: Sequence[FigureFormat | str] | str = DEFAULT_FORMATS,
    thresholds: Mapping[str, Any] | None = None,
) -> JudgeRequest:
    """Check a judge's whole input, once; build nothing and run nothing.

    The scene (a :class:`Scene`, a scene file or a built-in name) with ``thresholds`` laid over its
    ``[thresholds]`` and its horizon shortened to ``t_end`` (in (0, the scene's t_end], on its
    output grid: :func:`validation.external.horizon.horizon_on_grid`; the file then holds the
    grid up to it); the plants (:func:`_plants`; none may be named with ``reference``); the label
    (:func:`plant_label`); the file (with ``up_to_file_end``, a file that stops on the grid early
    is judged up to its last row: the horizon is shortened to it); the reference pack (its scene
    must be this scene, its horizon at least the one judged, its record accurate enough).

    Raises:
        ValueError: one line naming the field and the value, or the file's row and column
            (:class:`~validation.external.errors.TrajectoryFileError`), or the pack's file.
    """
    if not isinstance(scene, Scene):
        scene = resolve_scene(scene, check_thresholds=False)  # checked below, once
    scene_t_end = scene.output.t_end
    source = HorizonSource.SCENE
    if t_end is not None:
        scene = shortened(scene, horizon_on_grid(scene, t_end, "t_end"))
        source = HorizonSource.T_END
    if not isinstance(up_to_file_end, bool):
        raise ValueError(f"up_to_file_end: must be true or false (got {up_to_file_end!r:.60})")
    sc = with_threshold_overrides(scene, thresholds)
    checked = thresholds_for(sc)
    if reference is not None and plants:
        raise ValueError(
            f"plants: a reference pack is judged against without running plants (got {plants!r})"
        )
    chosen = () if reference is not None else _plants(plants, sc)
    if reference is None and not chosen:
        raise ValueError(f"plants: no installed plant can run {sc.name!r} beside the file")
    check_validation_inputs(sc, mujoco=Engine.MUJOCO in chosen)
    formats = checked_formats(figure_formats)
    name = plant_label(label, trajectory_file, chosen)
    external = read_trajectory(trajectory_file, sc, engine=name, up_to_file_end=up_to_file_end)
    covered = float(external.trajectory.t[-1])
    if covered != sc.output.t_end:  # the file stops on the grid early, and the user said so
        sc = shortened(sc, covered)
        source = HorizonSource.FILE_END
    ref = read_pack(reference, sc) if reference is not None else None
    horizon = JudgedHorizon(
        t_end=sc.output.t_end,
        scene_t_end=scene_t_end,
        samples=int(external.trajectory.t.shape[0]),
        source=source,
    )
    request = ValidationRequest(
        scene=sc,
        thresholds=checked,
        plants=tuple(chosen),
        integrator=None,
        dt=None,
        t_end=None,
        horizon=sc.output.t_end,
        figure_formats=formats,
    )
    return JudgeRequest(validation=request, external=external, reference=ref, horizon=horizon)


def run_judge(
    request: JudgeRequest,
    out_dir: str | Path,
    progress: Progress | None = None,
    concurrent: bool = True,
) -> ValidationResult:
    """:func:`judge` of an input checked already (:func:`judge_request`): the plants run, the
    files join them, and the evidence is written into ``out_dir`` (one output set, command
    ``judge``)."""
    sc = request.validation.scene
    names = {
        str(f.trajectory.engine): (
            f"{f.trajectory.engine} (trajectory file {Path(f.source).name}, "
            f"SHA-256 {f.sha256[:12]}…)"
        )
        for f in request.files
    }
    meta: dict[str, Any] = {
        "judged_files": [
            {
                "plant": str(f.trajectory.engine),
                "file": Path(f.source).name,
                "format": f.format.value,
                "sha256": f.sha256,
                "columns": sorted(g.value for g in f.present),
                "not_judged": [
                    ExternalTrajectory.not_judged(g)
                    for g in sorted(f.absent, key=list(ColumnGroup).index)
                    if g is not ColumnGroup.WORK or does_work(sc)
                ],
            }
            for f in request.files
        ],
        "controller": (
            "analytic (Udwadia–Kalaba, Eq. 89) in every plant that ran here; the trajectory "
            "files' own"
        ),
    }
    files = request.files
    horizon = request.horizon
    if horizon is not None:
        meta["judged_horizon"] = horizon.to_dict()

    def amend(cmp: Comparison) -> Comparison:
        out = not_judged(cmp, files, sc)
        if horizon is None:
            return out
        return dataclasses.replace(out, notes=(horizon.sentence, *out.notes))

    joined = JoinedRuns(
        trajectories=tuple(f.trajectory for f in files),
        names=names,
        amend=amend,
        meta=meta,
    )
    return run_request(
        request.validation,
        out_dir,
        progress=progress,
        concurrent=concurrent,
        joined=joined,
        command="judge",
    )


def judge(
    scene: Scene | str | Path | None,
    trajectory_file: str | Path,
    out_dir: str | Path | None = None,
    *,
    label: str | None = None,
    plants: Sequence[str] | str | None = None,
    reference: str | Path | None = None,
    t_end: float | None = None,
    up_to_file_end: bool = False,
    figure_formats: Sequence[FigureFormat | str] | str = DEFAULT_FORMATS,
    thresholds: Mapping[str, Any] | None = None,
    progress: Progress | None = None,
    concurrent: bool = True,
) -> ValidationResult:
    """Judge another engine's run of ``scene`` (a trajectory file) beside the built-in plants.

    Args:
        scene: a :class:`Scene`, a scene file, or a built-in scene name.
        trajectory_file: the run, CSV or Parquet (``docs/trajectory-format.md``), on the scene's
            output grid up to ``t_end``.
        t_end: the horizon judged, s: in (0, the scene's t_end], on the scene's output grid
            (default the scene's t_end).
        up_to_file_end: a file that stops on the grid before ``t_end`` is judged up to its last
            row (otherwise it is refused, the message naming this option); the report states
            the horizon judged (its first note, and ``run.judged_horizon`` in report.json).
        out_dir: output directory (default ``out/judge_<scene slug>``); as ``run_validation``'s.
        label: the file's plant name (default from the file name, :func:`plant_label`).
        plants: the built-in plants run beside it (default every installed one that can run the
            scene); with three of them and the file, the referee rules on four plants.
        reference: a reference pack directory (``tumble reference``): judge against its
            trajectory instead of running plants.
        figure_formats, thresholds, progress, concurrent: as ``run_validation``'s.

    Returns:
        the :class:`ValidationResult`: ``passed`` when every judged check passes; the checks
        the file cannot support are not applicable with the reason ``not judged: no ... columns``.

    Raises:
        ValueError: bad input, one line (a bad file: its row and column), before any plant runs.
        OutputBusy, OutputError: as ``run_validation``.
    """
    request = judge_request(
        scene,
        trajectory_file,
        label=label,
        plants=plants,
        reference=reference,
        t_end=t_end,
        up_to_file_end=up_to_file_end,
        figure_formats=figure_formats,
        thresholds=thresholds,
    )
    if out_dir is None:

        out_dir = default_out_dir("judge_", request.validation.scene.name)
    return run_judge(request, out_dir, progress=progress, concurrent=concurrent)


__all__ = [
    "LABEL_PATTERN",
    "NEEDS",
    "REFERENCE_PLANT",
    "JudgeRequest",
    "judge",
    "judge_request",
    "needed_groups",
    "not_judged",
    "plant_label",
    "run_judge",
]
