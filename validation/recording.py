"""Rerun recordings (``run.rrd``) of finished trajectories: both plants in one 3D view.

Everything is logged in columns (``send_columns``) from the finished trajectories through an explicit
:class:`rerun.RecordingStream`, on one timeline ``sim_time`` (s), without the wall-clock timeline,
so one process can write several files and a file depends only on the trajectories.

Entity layout for a run logged under ``prefix`` (``""`` for ``run.rrd``, ``stepN`` in the demo)::

    {prefix}/world/{plant}/body            Transform3D: translation R (inertial, m), quaternion u
    {prefix}/world/{plant}/body/shape      BR's picture (box, or hollow cylinder), static
    {prefix}/world/{plant}/body/rod        the rod, static
    {prefix}/world/{plant}/body/masses     Points3D at d + p_i a (body axes, m)
    {prefix}/world/{plant}/body/omega      Arrows3D ω (body axes; scaled, see the narrative)
    {prefix}/world/{plant}/body/torque     Arrows3D τ (body axes; scaled)
    {prefix}/world/{plant}/trail           LineStrips3D: the path of C so far (inertial)
    {prefix}/plots/errors/{name}           Scalars log10 of each analytic-vs-MuJoCo difference
    {prefix}/plots/tracking/{name}/{plant} Scalars log10 of each plant's tracking error
    {prefix}/plots/invariants/{name}/{plant}  Scalars log10 of each plant's balance drift
    {prefix}/plots/control/torque/{plant}  Scalars τ_x, τ_y, τ_z (N·m)
    {prefix}/plots/control/rod_forces/{plant}  Scalars F_1 … F_n (N)
    {prefix}/narrative                     TextDocument (markdown), static

The MuJoCo plant is drawn as a translucent ghost over the analytic one. Rerun has no log-scale axis,
so the errors and drifts are logged as ``log10`` (exact zeros as :data:`LOG10_FLOOR`).
Quaternions are w first inside the project and converted to x, y, z, w here only.
"""

from __future__ import annotations

import contextlib
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from analytic.effects import ShapeKind
from analytic.trajectory import Trajectory
from validation.compare import Comparison, Group, Subject

TIMELINE = "sim_time"
LOG10_FLOOR = -20.0  # log10 logged for an exact zero (a difference of identical numbers)
TRAIL_POINTS = 150  # the trail of C is the path so far, decimated to at most this many points
ANALYTIC_RGBA = {
    "shape": (70, 130, 200, 255),
    "rod": (150, 150, 160, 255),
    "masses": (230, 80, 60, 255),
    "trail": (70, 130, 200, 255),
    "omega": (40, 170, 80, 255),
    "torque": (200, 60, 200, 255),
}
GHOST_ALPHA = 70
PLANT_COLOR = {
    Subject.ANALYTIC: (31, 119, 180, 255),
    Subject.MUJOCO: (255, 127, 14, 255),
    Subject.PINOCCHIO: (44, 160, 44, 255),
    Subject.BOTH: (214, 39, 40, 255),
    Subject.ANALYTIC_PINOCCHIO: (148, 103, 189, 255),
    Subject.MUJOCO_PINOCCHIO: (140, 86, 75, 255),
}


def _xyzw(u_wxyz: np.ndarray) -> np.ndarray:
    """w-first quaternions (..., 4) -> rerun's x, y, z, w, normalised."""
    u = np.asarray(u_wxyz, float)
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    return np.concatenate([u[..., 1:], u[..., :1]], axis=-1)


def _z_to(axis: np.ndarray) -> np.ndarray:
    """x, y, z, w quaternion of a rotation taking local z to ``axis`` (cylinders are along z)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    rot, _ = Rotation.align_vectors([a], [[0.0, 0.0, 1.0]])
    return rot.as_quat()


Ghost = bool | tuple[int, int, int, int]
"""False for the solid first plant; True, or the plant's RGBA tint, for a translucent ghost."""


def _ghost(rgba: tuple[int, int, int, int], ghost: Ghost) -> tuple[int, int, int, int]:
    """``rgba`` as drawn: unchanged for the first plant; paler, translucent and (with a tint)
    shifted toward the plant's colour for a ghost, so two ghosts can be told apart."""
    if ghost is False:
        return rgba
    r, g, b, _ = rgba
    tr, tg, tb = (255, 255, 255) if ghost is True else ghost[:3]
    return (
        int(0.5 * r + 0.5 * tr),
        int(0.5 * g + 0.5 * tg),
        int(0.5 * b + 0.5 * tb),
        GHOST_ALPHA,
    )


def _size(scene: Any) -> float:
    """A characteristic size of BR's picture, m (for arrow lengths and mass radii)."""
    sh = scene.body.shape
    sizes = [sh.rod_length]
    if sh.kind is ShapeKind.BOX_AND_ROD:
        sizes.append(2 * float(np.max(sh.box_half_sizes)))
    elif sh.kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        sizes += [2 * sh.cylinder_radius, sh.cylinder_length]
    sizes.append(float(np.max(np.abs(scene.masses.p_e))) if scene.n else 0.0)
    return max(max(sizes), 1.0)


@dataclass(frozen=True)
class ArrowScales:
    """Arrow lengths in the 3D view: ``omega`` in m per rad/s, ``torque`` in m per N·m."""

    omega: float
    torque: float


@dataclass(frozen=True)
class RecordingInfo:
    """What :func:`write_recording` wrote: ``path``, its ``entities`` and the ``wall_time_s``."""

    path: Path
    entities: tuple[str, ...]
    samples: int
    wall_time_s: float


def _log_shape(rec, base: str, scene: Any, ghost: Ghost) -> None:
    import rerun as rr

    sh = scene.body.shape
    if sh.kind is ShapeKind.BOX_AND_ROD:
        q = Rotation.from_matrix(np.asarray(sh.box_rotation)).as_quat()
        rr_obj = rr.Boxes3D(
            half_sizes=[sh.box_half_sizes],
            centers=[sh.box_center],
            quaternions=[rr.Quaternion(xyzw=q)],
            colors=[_ghost(ANALYTIC_RGBA["shape"], ghost)],
            fill_mode=rr.components.FillMode.Solid,
        )
        rec.log(f"{base}/shape", rr_obj, static=True)
    elif sh.kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        q = _z_to(sh.cylinder_axis)
        inner = max(sh.cylinder_radius - sh.cylinder_thickness, 0.0)
        rec.log(
            f"{base}/shape",
            rr.Cylinders3D(
                lengths=[sh.cylinder_length, sh.cylinder_length],
                radii=[sh.cylinder_radius, inner],
                centers=[[0.0, 0.0, 0.0]] * 2,
                quaternions=[rr.Quaternion(xyzw=q)] * 2,
                colors=[_ghost(ANALYTIC_RGBA["shape"], ghost)] * 2,
                fill_mode=rr.components.FillMode.TransparentFillMajorWireframe,
            ),
            static=True,
        )
    if sh.kind is not ShapeKind.NONE or scene.n:
        a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
        center = d + (sh.rod_start + 0.5 * sh.rod_length) * a
        rec.log(
            f"{base}/rod",
            rr.Cylinders3D(
                lengths=[sh.rod_length],
                radii=[sh.rod_radius],
                centers=[center],
                quaternions=[rr.Quaternion(xyzw=_z_to(a))],
                colors=[_ghost(ANALYTIC_RGBA["rod"], ghost)],
            ),
            static=True,
        )


def _trail(R: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """Growing, decimated trails of C: the strip at sample i holds the path up to i."""
    N = R.shape[0]
    strips, lengths = [], []
    for i in range(N):
        k = min(i + 1, TRAIL_POINTS)
        idx = np.unique(np.linspace(0, i, k).round().astype(int))
        strips.append(R[idx])
        lengths.append(len(idx))
    return np.concatenate(strips), lengths


def _log10(v: np.ndarray) -> np.ndarray:
    v = np.abs(np.asarray(v, float))
    with np.errstate(divide="ignore"):
        out = np.log10(v)
    return np.where(v > 0, out, LOG10_FLOOR)


def arrow_scales(scene: Any, plants: Sequence[Trajectory]) -> ArrowScales:
    """Scales that make the longest ω and τ arrows about half of BR's size."""
    L = 0.5 * _size(scene)
    w = max(
        (float(np.max(np.linalg.norm(p.omega, axis=1), initial=0.0)) for p in plants), default=0.0
    )
    tau = max(
        (float(np.max(np.linalg.norm(p.torque, axis=1), initial=0.0)) for p in plants), default=0.0
    )
    return ArrowScales(L / w if w > 0 else 0.0, L / tau if tau > 0 else 0.0)


def log_run(
    rec,
    scene: Any,
    plants: Sequence[Trajectory],
    comparison: Comparison | None = None,
    narrative: str = "",
    prefix: str = "",
) -> tuple[list[str], ArrowScales]:
    """Log one run (one plant or several) into ``rec`` under ``prefix``; returns the entity paths
    and the arrow scales. The first plant is drawn solid, every other as a translucent ghost."""
    import rerun as rr

    p0 = f"/{prefix.strip('/')}" if prefix.strip("/") else ""
    entities: list[str] = []
    scales = arrow_scales(scene, plants)
    a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
    mass_r = (
        _size(scene)
        * 0.03
        * (np.asarray(scene.masses.mass) / max(np.max(scene.masses.mass, initial=1.0), 1e-300))
        ** (1 / 3)
    )

    def send(path: str, t: np.ndarray, columns) -> None:
        rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=t)], columns=columns)
        entities.append(path)

    for k, tr in enumerate(plants):
        subj = Subject(tr.engine.value)
        ghost: Ghost = False if k == 0 else PLANT_COLOR[subj]
        base = f"{p0}/world/{subj.value}"
        body = f"{base}/body"
        t, N = tr.t, tr.t.shape[0]
        if N == 0:
            continue
        _log_shape(rec, body, scene, ghost)
        send(
            body, t, rr.Transform3D.columns(translation=tr.q[:, :3], quaternion=_xyzw(tr.q[:, 3:7]))
        )
        if tr.n:
            pos = d[None, None, :] + tr.p[:, :, None] * a[None, None, :]  # body axes, (N, n, 3)
            rec.log(
                f"{body}/masses",
                rr.Points3D.from_fields(
                    radii=mass_r,
                    colors=[_ghost(ANALYTIC_RGBA["masses"], ghost)] * tr.n,
                    labels=[f"m{i + 1}" for i in range(tr.n)],
                ),
                static=True,
            )
            send(
                f"{body}/masses",
                t,
                rr.Points3D.columns(positions=pos.reshape(-1, 3)).partition([tr.n] * N),
            )
        rec.log(
            f"{body}/omega",
            rr.Arrows3D.from_fields(colors=[_ghost(ANALYTIC_RGBA["omega"], ghost)], labels=["ω"]),
            static=True,
        )
        send(
            f"{body}/omega",
            t,
            rr.Arrows3D.columns(vectors=tr.omega * scales.omega, origins=np.zeros((N, 3))),
        )
        rec.log(
            f"{body}/torque",
            rr.Arrows3D.from_fields(colors=[_ghost(ANALYTIC_RGBA["torque"], ghost)], labels=["τ"]),
            static=True,
        )
        send(
            f"{body}/torque",
            t,
            rr.Arrows3D.columns(vectors=tr.torque * scales.torque, origins=np.zeros((N, 3))),
        )
        pts, lens = _trail(tr.q[:, :3])
        rec.log(
            f"{base}/trail",
            rr.LineStrips3D.from_fields(
                colors=[_ghost(ANALYTIC_RGBA["trail"], ghost)], radii=[0.05 * _size(scene) / 10]
            ),
            static=True,
        )
        send(
            f"{base}/trail",
            t,
            rr.LineStrips3D.columns(strips=np.split(pts, np.cumsum(lens)[:-1])).partition([1] * N),
        )

        # control forces: both plants in the same plot (one entity per plant under one origin)
        comps = ["τ_x", "τ_y", "τ_z"]
        rec.log(
            f"{p0}/plots/control/torque/{subj.value}",
            rr.SeriesLines(
                names=[f"{subj.value} {c}" for c in comps],
                colors=[_plant_shade(subj, j) for j in range(3)],
            ),
            static=True,
        )
        send(
            f"{p0}/plots/control/torque/{subj.value}",
            t,
            rr.Scalars.columns(scalars=tr.torque.ravel()).partition([3] * N),
        )
        if tr.n:
            rec.log(
                f"{p0}/plots/control/rod_forces/{subj.value}",
                rr.SeriesLines(
                    names=[f"{subj.value} F_{i + 1}" for i in range(tr.n)],
                    colors=[_plant_shade(subj, j) for j in range(tr.n)],
                ),
                static=True,
            )
            send(
                f"{p0}/plots/control/rod_forces/{subj.value}",
                t,
                rr.Scalars.columns(scalars=tr.rod_forces.ravel()).partition([tr.n] * N),
            )

    if comparison is not None:
        for s in comparison.series:
            if s.group is Group.CONTROL or s.t.size == 0:
                continue
            if s.subject is Subject.BOTH:
                path = f"{p0}/plots/errors/{s.name}"
                name, color = f"log10 {s.label} [{s.unit}]", PLANT_COLOR[s.subject]
            elif s.subject.is_pair:
                path = f"{p0}/plots/errors/{s.name}/{s.subject.slug}"
                name, color = (
                    f"{s.subject.value}: log10 {s.name} [{s.unit}]",
                    PLANT_COLOR[s.subject],
                )
            else:
                folder = "invariants" if s.group is Group.INVARIANT else s.group.value
                path = f"{p0}/plots/{folder}/{s.name}/{s.subject.value}"
                name, color = (
                    f"{s.subject.value}: log10 {s.label} [{s.unit}]",
                    PLANT_COLOR[s.subject],
                )
            rec.log(path, rr.SeriesLines(names=[name], colors=[color]), static=True)
            send(path, s.t, rr.Scalars.columns(scalars=_log10(s.values)))

    text = narrative or default_narrative(scene, plants, comparison, scales)
    rec.log(f"{p0}/narrative", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)
    entities.append(f"{p0}/narrative")
    return entities, scales


def _plant_shade(subj: Subject, j: int) -> tuple[int, int, int, int]:
    """Blues for the analytic plant, oranges for MuJoCo; j-th component gets a different shade."""
    base = np.array(PLANT_COLOR[subj][:3], float)
    f = [1.0, 0.65, 0.35, 0.8, 0.5, 0.2][j % 6]
    c = base * f + 255 * (1 - f) * (0.3 if j % 2 else 0.0)
    return (*np.clip(c, 0, 255).astype(int).tolist(), 255)


def default_narrative(
    scene: Any, plants: Sequence[Trajectory], comparison: Comparison | None, scales: ArrowScales
) -> str:
    """A short markdown text saying what the run is."""
    lines = [f"# {scene.name}", "", scene.description, ""]
    engines = [p.engine.value for p in plants]
    names = (
        " and ".join(engines)
        if len(engines) < 3
        else ", ".join(engines[:-1]) + f" and {engines[-1]}"
    )
    lines.append(
        f"Plants: {names}, all under the same analytic controller (Udwadia–Kalaba, Eq. 89)."
        if len(plants) > 1
        else f"Plant: {names}."
    )
    if len(plants) > 1:
        ghosts = " and ".join(engines[1:])
        lines.append(
            f"The {ghosts} bod{'ies are' if len(engines) > 2 else 'y is'} drawn as translucent "
            f"ghost{'s' if len(engines) > 2 else ''} over the {engines[0]} one."
        )
    lines += [
        "",
        f"Effects: {', '.join(sorted(e.value for e in scene.effects))}.",
        "",
        f"Arrows at C in body axes: green ω ({scales.omega:.3g} m per rad/s), purple control "
        f"torque τ ({scales.torque:.3g} m per N·m). The line is the path of C.",
        "",
        f"Plots: errors and drifts as log10 (an exact zero is logged as {LOG10_FLOOR:g}).",
    ]
    if comparison is not None:
        verdict = "PASSED" if comparison.passed else "FAILED"
        lines += ["", f"**Verdict: {verdict}** ({len(comparison.checks)} checks)."]
        for c in comparison.failed_checks:
            lines.append(f"- {c.label} = {c.value:.3e} {c.unit} > {c.threshold:.3e}")
    return "\n".join(lines)


def blueprint_for(
    prefix: str,
    scene: Any,
    comparison: Comparison | None,
    two_plants: bool,
    name: str | None = None,
):
    """The layout of one run: the 3D view and the narrative on the left, the plots on the right."""
    import rerun.blueprint as rrb

    p0 = f"/{prefix.strip('/')}" if prefix.strip("/") else ""
    plots = []
    if comparison is not None and two_plants:
        pairs = {x.subject for x in comparison.series if x.subject.is_pair}
        title = (
            "log10 |analytic − MuJoCo|"
            if pairs == {Subject.BOTH}
            else "log10 differences of each pair of plants"
        )
        plots.append(rrb.TimeSeriesView(origin=f"{p0}/plots/errors", name=title))
    if comparison is not None:
        groups = {s.group for s in comparison.series}
        if Group.TRACKING in groups:
            plots.append(
                rrb.TimeSeriesView(origin=f"{p0}/plots/tracking", name="log10 tracking errors")
            )
        plots.append(
            rrb.TimeSeriesView(origin=f"{p0}/plots/invariants", name="log10 invariant drifts")
        )
    ctrl = [rrb.TimeSeriesView(origin=f"{p0}/plots/control/torque", name="control torque (N·m)")]
    if scene.n:
        ctrl.append(
            rrb.TimeSeriesView(origin=f"{p0}/plots/control/rod_forces", name="rod forces (N)")
        )
    plots.append(rrb.Tabs(*ctrl) if len(ctrl) > 1 else ctrl[0])
    view3d = rrb.Spatial3DView(
        origin=f"{p0}/world" if p0 else "/world",
        name=(
            "first plant solid, the others as ghosts"
            if comparison is not None
            and len({x.subject for x in comparison.series if x.subject.is_pair}) > 1
            else "analytic (solid) and MuJoCo (ghost)"
            if two_plants
            else "3D"
        ),
        eye_controls=rrb.EyeControls3D(tracking_entity=f"{p0}/world/analytic/body"),
    )
    return rrb.Horizontal(
        rrb.Vertical(
            view3d,
            rrb.TextDocumentView(origin=f"{p0}/narrative", name="what this is"),
            row_shares=[3, 1],
        ),
        rrb.Vertical(*plots),
        column_shares=[3, 2],
        name=name or scene.name,
    )


RRD_FLUSH_TIMEOUT_S = 120.0
"""Longest wait for Rerun's batcher to hand over a recording's bytes (memory only, no disk): a
recording of a 60 s run takes well under a second, so two minutes means it is stuck, not slow."""


def new_stream(app_id: str = "tumble", recording_id: str | None = None):
    """An explicit stream (not the global one) without the wall-clock timeline."""
    import rerun as rr

    rec = rr.RecordingStream(app_id, recording_id=recording_id or str(uuid.uuid4()))
    rec.set_log_time_enabled(False)
    return rec


def check_rrd(path: str | Path) -> None:
    """Raise ``ValueError`` unless ``path`` is a whole ``.rrd`` (it reads back, footer included)."""
    import warnings

    from rerun.chunk import RrdReader

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # "no footer" is only a warning in rerun
            RrdReader(str(path)).store()
    except Exception as exc:
        raise ValueError(f"{path}: not a complete recording ({exc})".splitlines()[0]) from exc


@contextlib.contextmanager
def atomic_stream(
    path: str | Path,
    app_id: str = "tumble",
    blueprint: Any = None,
    recording_id: str | None = None,
):
    """``with atomic_stream(path) as rec:`` log into ``rec``; ``path`` appears when the block ends.

    Rerun encodes into memory (``binary_stream``), never onto the disk, so a full disk cannot
    stall its writer; the bytes are then written by :func:`validation.atomic.write_bytes`, read
    back (:func:`check_rrd`) and only then moved over ``path``. On any exception, or when the
    recording is incomplete, ``path`` keeps its previous contents.
    """
    from validation.atomic import write_bytes

    path = Path(path)
    rec = new_stream(app_id, recording_id)
    stream = rec.binary_stream()
    if blueprint is not None:
        rec.send_blueprint(blueprint, make_active=False, make_default=True)
    try:
        yield rec
        rec.flush(timeout_sec=RRD_FLUSH_TIMEOUT_S)
        data = stream.read(flush=True, flush_timeout_sec=RRD_FLUSH_TIMEOUT_S) or b""
    finally:
        rec.disconnect()
    data += stream.read(flush=False) or b""  # anything the disconnect wrote (the footer)
    write_bytes(path, data, check=check_rrd)


def write_recording(
    path: str | Path,
    scene: Any,
    plants: Sequence[Trajectory],
    comparison: Comparison | None = None,
    narrative: str = "",
    recording_id: str | None = None,
) -> RecordingInfo:
    """Write ``run.rrd`` for one run (blueprint included); atomically, checked (:func:`atomic_stream`).

    ``recording_id``: Rerun's recording id (the run id of the output directory, when there is one).
    """
    import rerun.blueprint as rrb

    path = Path(path)
    t0 = time.perf_counter()
    bp = rrb.Blueprint(
        blueprint_for("", scene, comparison, len(plants) > 1),
        rrb.TimePanel(state="expanded"),
        collapse_panels=False,
    )
    with atomic_stream(path, blueprint=bp, recording_id=recording_id) as rec:
        entities, _ = log_run(rec, scene, plants, comparison, narrative)
    samples = max((p.t.shape[0] for p in plants), default=0)
    return RecordingInfo(path, tuple(dict.fromkeys(entities)), samples, time.perf_counter() - t0)


__all__ = [
    "LOG10_FLOOR",
    "TIMELINE",
    "ArrowScales",
    "RecordingInfo",
    "arrow_scales",
    "atomic_stream",
    "blueprint_for",
    "check_rrd",
    "default_narrative",
    "log_run",
    "new_stream",
    "write_recording",
]
