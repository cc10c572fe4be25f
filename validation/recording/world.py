"""The 3D part of a recording: every plant's body, its arrows and the path of C, Z up; and the
differences between plants, exaggerated by a stated power of ten.

Entity layout under ``{p0}`` (``""`` for ``run.rrd``, ``/stepN`` in the demo)::

    {p0}/world                               ViewCoordinates RIGHT_HAND_Z_UP (gravity is −Z), static
    {p0}/world/{plant}/body                  Transform3D: translation R (inertial, m), quaternion u
    {p0}/world/{plant}/body/shape            BR's picture (box, or hollow cylinder), static
    {p0}/world/{plant}/body/rod              the rod, static
    {p0}/world/{plant}/body/masses           Points3D at d + p_i a (body axes, m)
    {p0}/world/{plant}/body/omega            Arrows3D ω (body axes; m per rad/s, ArrowScales)
    {p0}/world/{plant}/body/torque           Arrows3D τ (body axes; m per N·m)
    {p0}/world/{plant}/trail                 LineStrips3D: one segment of the path of C per sample
    {p0}/world/exaggerated/{plant}/body      every other plant's body (shape, rod, masses) with
                                             its difference from the reference plant multiplied
                                             by difference_factors()[plant] (inertial, m)
    {p0}/world/exaggerated/{plant}/offset    Arrows3D from the reference C to the exaggerated C,
                                             labelled with the plant and the factor

The blueprint (:mod:`validation.recording.layout`) shows ``{p0}/world`` without ``exaggerated`` in the
view with every plant, and each exaggerated plant with the reference body (its entities, not a
copy) in a view of its own.

The first plant is the reference, drawn solid; every other plant is drawn in its own colour as a
wireframe over it, with translucent masses a little larger than the reference's, so a plant
that agrees to 1e-9 m still shows (its edges over the solid body), and the blueprint's entity
toggles show or hide each plant's root ``{p0}/world/{plant}``.

The trail is logged as one segment [C(t_{i-1}), C(t_i)] per sample, and the blueprint shows the
segments from the start up to the time cursor (a per-entity visible time range): the file grows
linearly with the run (re-logging the path so far at every sample grew quadratically).

Quaternions are w first inside the project and converted to x, y, z, w here only.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from analytic.effects import ShapeKind
from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison, Group, Subject
from validation.compare.differences import Difference
from validation.recording.style import (
    MASS_RGBA,
    OMEGA_RGBA,
    RGBA,
    ROD_RGBA,
    TIMELINE,
    TORQUE_RGBA,
    plant_color,
    power_of_ten,
    toward,
)

DIFFERENCE_TARGET = 0.3
"""The exaggerated difference is at most this fraction of BR's size (and at least a tenth of
it): the factor is the largest power of ten that keeps the largest difference below it."""
GHOST_MASS_SCALE = 1.25
"""Another plant's masses are drawn this much larger than the reference's, so they show as a
translucent shell around them instead of hiding inside."""
TRAIL_RADIUS = 0.005
"""Radius of the trail's line, as a fraction of BR's size."""


@dataclass(frozen=True)
class ArrowScales:
    """Arrow lengths in the 3D view: ``omega`` in m per rad/s, ``torque`` in m per N·m."""

    omega: float
    torque: float


def body_size(scene: Any) -> float:
    """A characteristic size of BR's picture, m (for arrow lengths, radii and the difference
    factor); at least 1 m."""
    sh = scene.body.shape
    sizes = [sh.rod_length]
    if sh.kind is ShapeKind.BOX_AND_ROD:
        sizes.append(2 * float(np.max(sh.box_half_sizes)))
    elif sh.kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        sizes += [2 * sh.cylinder_radius, sh.cylinder_length]
    sizes.append(float(np.max(np.abs(scene.masses.p_e))) if scene.n else 0.0)
    return max(max(sizes), 1.0)


def arrow_scales(scene: Any, plants: Sequence[Trajectory]) -> ArrowScales:
    """Scales that make the longest ω and τ arrows (over every plant) half of BR's size."""
    L = 0.5 * body_size(scene)

    def longest(field: str) -> float:
        return max(
            (float(np.max(np.linalg.norm(getattr(p, field), axis=1), initial=0.0)) for p in plants),
            default=0.0,
        )

    w, tau = longest("omega"), longest("torque")
    return ArrowScales(L / w if w > 0 else 0.0, L / tau if tau > 0 else 0.0)


# ----------------------------------------------------------------------------------------------
# Differences between plants
# ----------------------------------------------------------------------------------------------


def difference_factor(d_max: float, size: float) -> float:
    """The power of ten (at least 1) by which a difference of at most ``d_max`` metres is
    multiplied so that it is drawn as at most :data:`DIFFERENCE_TARGET` of ``size``; 1 when the
    difference is zero (nothing to exaggerate) or not finite (a diverged run is drawn as is)."""
    if not (math.isfinite(d_max) and d_max > 0.0):
        return 1.0
    return max(10.0 ** math.floor(math.log10(DIFFERENCE_TARGET * size / d_max)), 1.0)


def plant_order(comparison: Comparison) -> tuple[str, ...]:
    """The plants of a comparison in the order they were compared (the reference first)."""
    return tuple(dict.fromkeys(s.subject.value for s in comparison.series if not s.subject.is_pair))


def largest_difference(
    scene: Any, comparison: Comparison | None, reference: str, other: str
) -> float | None:
    """The largest difference between two plants' pictures, m: the largest over time of the
    distance between their C, BR's size times their attitude angle, and the largest rod
    position difference; None when the comparison does not hold this pair."""
    if comparison is None or reference == other:
        return None
    try:
        pair = Subject.pair(reference, other)
    except ValueError:
        return None
    by = {
        s.name: s.values
        for s in comparison.series
        if s.subject == pair and s.group is Group.DIFFERENCE
    }
    if Difference.POSITION_C not in by:
        return None
    parts = [
        by[Difference.POSITION_C],
        body_size(scene) * by.get(Difference.ATTITUDE, np.zeros(0)),
        by.get(Difference.ROD_POSITIONS, np.zeros(0)),
    ]
    values = np.concatenate([np.ravel(p) for p in parts])
    if values.size == 0:
        return 0.0
    return float(np.max(values)) if np.all(np.isfinite(values)) else math.inf


def _largest_difference_of(scene: Any, ref: Trajectory, other: Trajectory) -> float:
    k = min(ref.t.shape[0], other.t.shape[0])
    if k == 0:
        return 0.0
    qr, qo = ref.q[:k], other.q[:k]
    if not (np.all(np.isfinite(qr)) and np.all(np.isfinite(qo))):
        return math.inf
    d = [np.linalg.norm(qr[:, :3] - qo[:, :3], axis=1)]
    rel = _rotation(qr[:, 3:7]).inv() * _rotation(qo[:, 3:7])
    d.append(body_size(scene) * rel.magnitude())
    if ref.n:
        d.append(np.max(np.abs(qr[:, 7:] - qo[:, 7:]), axis=1))
    values = np.concatenate(d)
    return float(np.max(values)) if np.all(np.isfinite(values)) else math.inf


def _names(
    comparison: Comparison | None, plants: Sequence[str] | None, trajectories: Sequence[Trajectory]
) -> list[str]:
    names = list(plants or [tr.engine for tr in trajectories])
    if not names and comparison is not None:
        names = list(plant_order(comparison))
    return names


def largest_differences(
    scene: Any,
    comparison: Comparison | None,
    plants: Sequence[str] | None = None,
    trajectories: Sequence[Trajectory] = (),
) -> dict[str, float]:
    """For every plant after the first (the reference), its :func:`largest_difference` from the
    reference, m: read from ``comparison`` (so the blueprint, which has no trajectories, and the
    logged entities agree), from ``trajectories`` when the comparison lacks the pair; absent
    when neither has it. ``plants``: engine names, the reference first (default: the
    trajectories' order, or the comparison's)."""
    names = _names(comparison, plants, trajectories)
    by_name = {tr.engine: tr for tr in trajectories}
    out: dict[str, float] = {}
    for other in names[1:]:
        if other == names[0]:
            continue
        d = largest_difference(scene, comparison, names[0], other)
        if d is None and names[0] in by_name and other in by_name:
            d = _largest_difference_of(scene, by_name[names[0]], by_name[other])
        if d is not None:
            out[other] = d
    return out


def difference_factors(
    scene: Any,
    comparison: Comparison | None,
    plants: Sequence[str] | None = None,
    trajectories: Sequence[Trajectory] = (),
) -> dict[str, float]:
    """For every plant after the first, the factor by which its difference from the reference
    is drawn in its difference view (:func:`difference_factor` of
    :func:`largest_differences`; 1 when the difference is unknown)."""
    names = _names(comparison, plants, trajectories)
    largest = largest_differences(scene, comparison, names, trajectories)
    size = body_size(scene)
    return {p: difference_factor(largest.get(p, 0.0), size) for p in names[1:] if p != names[0]}


def _rotation(u_wxyz: np.ndarray) -> Rotation:
    return Rotation.from_quat(np.asarray(u_wxyz, float), scalar_first=True)


def exaggerate(q_ref: np.ndarray, q: np.ndarray, k: float) -> np.ndarray:
    """Coordinates whose difference from ``q_ref`` is ``k`` times that of ``q``, shape (N, n+7):
    ``R_ref + k (R − R_ref)``, ``u_ref ⊗ exp(k log(u_ref⁻¹ ⊗ u))`` (the relative rotation in body
    axes, its angle times k), ``p_ref + k (p − p_ref)``; w-first, unit quaternions."""
    q_ref, q = np.asarray(q_ref, float), np.asarray(q, float)
    out = q_ref + k * (q - q_ref)
    out[:, 3:7] = q[:, 3:7]  # kept where a quaternion is not finite or zero (a diverged run)
    ok = np.all(np.isfinite(q_ref[:, 3:7]) & np.isfinite(q[:, 3:7]), axis=1)
    ok &= (np.linalg.norm(q_ref[:, 3:7], axis=1) > 0) & (np.linalg.norm(q[:, 3:7], axis=1) > 0)
    if ok.any():
        ur = _rotation(q_ref[ok, 3:7])
        rel = (ur.inv() * _rotation(q[ok, 3:7])).as_rotvec()
        out[ok, 3:7] = (ur * Rotation.from_rotvec(k * rel)).as_quat(scalar_first=True)
    return out


# ----------------------------------------------------------------------------------------------
# Logging
# ----------------------------------------------------------------------------------------------


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


@dataclass(frozen=True)
class _Look:
    """How one plant's body is drawn: in ``color``; ``solid`` for the reference plant."""

    color: RGBA
    solid: bool

    def part(self, rgba: RGBA) -> RGBA:
        return rgba if self.solid else toward(rgba, self.color)


def _log_shape(rec, body: str, scene: Any, look: _Look) -> None:
    # deferred: rerun ~0.25 s (python -X importtime), only when a recording is made
    import rerun as rr

    FillMode = rr.components.FillMode
    sh = scene.body.shape
    if sh.kind is ShapeKind.BOX_AND_ROD:
        q = Rotation.from_matrix(np.asarray(sh.box_rotation)).as_quat()
        rec.log(
            f"{body}/shape",
            rr.Boxes3D(
                half_sizes=[sh.box_half_sizes],
                centers=[sh.box_center],
                quaternions=[rr.Quaternion(xyzw=q)],
                colors=[look.color],
                fill_mode=FillMode.Solid if look.solid else FillMode.MajorWireframe,
            ),
            static=True,
        )
    elif sh.kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        q = _z_to(sh.cylinder_axis)
        inner = max(sh.cylinder_radius - sh.cylinder_thickness, 0.0)
        rec.log(
            f"{body}/shape",
            rr.Cylinders3D(
                lengths=[sh.cylinder_length, sh.cylinder_length],
                radii=[sh.cylinder_radius, inner],
                centers=[[0.0, 0.0, 0.0]] * 2,
                quaternions=[rr.Quaternion(xyzw=q)] * 2,
                colors=[look.color] * 2,
                fill_mode=(
                    FillMode.TransparentFillMajorWireframe
                    if look.solid
                    else FillMode.MajorWireframe
                ),
            ),
            static=True,
        )
    if sh.kind is not ShapeKind.NONE or scene.n:
        a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
        center = d + (sh.rod_start + 0.5 * sh.rod_length) * a
        rec.log(
            f"{body}/rod",
            rr.Cylinders3D(
                lengths=[sh.rod_length],
                radii=[sh.rod_radius],
                centers=[center],
                quaternions=[rr.Quaternion(xyzw=_z_to(a))],
                colors=[look.part(ROD_RGBA)],
                fill_mode=FillMode.Solid if look.solid else FillMode.MajorWireframe,
            ),
            static=True,
        )


class _Sender:
    """``send(path, t, columns)`` on the simulation timeline; remembers every path it sent to."""

    def __init__(self, rec):
        self.rec = rec
        self.entities: list[str] = []

    def __call__(self, path: str, t: np.ndarray, columns) -> None:
        import rerun as rr

        self.rec.send_columns(
            path, indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(t, float))], columns=columns
        )
        self.entities.append(path)


def _log_body(
    send: _Sender,
    body: str,
    scene: Any,
    t: np.ndarray,
    q: np.ndarray,
    look: _Look,
) -> None:
    """Shape, rod (static), pose and masses (in columns) of one body at coordinates ``q``."""
    import rerun as rr

    rec, N = send.rec, t.shape[0]
    _log_shape(rec, body, scene, look)
    send(body, t, rr.Transform3D.columns(translation=q[:, :3], quaternion=_xyzw(q[:, 3:7])))
    n = q.shape[1] - 7
    if not n:
        return
    _log_masses_look(rec, body, scene, look)
    pos = _mass_positions(scene, q)
    send(f"{body}/masses", t, rr.Points3D.columns(positions=pos.reshape(-1, 3)).partition([n] * N))


def _log_masses_look(rec, body: str, scene: Any, look: _Look) -> None:
    import rerun as rr

    n = scene.n
    mass = np.asarray(scene.masses.mass, float)
    radii = 0.03 * body_size(scene) * (mass / max(float(np.max(mass)), 1e-300)) ** (1 / 3)
    rec.log(
        f"{body}/masses",
        rr.Points3D.from_fields(
            radii=radii if look.solid else GHOST_MASS_SCALE * radii,
            colors=[look.part(MASS_RGBA)] * n,
            labels=[f"m{i + 1}" for i in range(n)] if look.solid else None,
            show_labels=look.solid,
        ),
        static=True,
    )


def _mass_positions(scene: Any, q: np.ndarray) -> np.ndarray:
    """The masses at ``d + p_i a`` (body axes, m) of coordinates ``q`` (N, n+7): (N, n, 3)."""
    a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
    return d[None, None, :] + q[:, 7:, None] * a[None, None, :]


def body_entity(engine: str, p0: str = "") -> str:
    """The entity of plant ``engine``'s body (its pose), as :func:`log_world` logs it."""
    return f"{p0}/world/{engine}/body"


def log_body_look(rec, engine: str, scene: Any, solid: bool, p0: str = "") -> None:
    """The static parts of plant ``engine``'s body as :func:`log_world` draws them (``solid``:
    the reference plant's look): the view's axes, the shape, the rod and the masses' look, so
    that :func:`send_poses` moves a body a viewer can see."""
    import rerun as rr

    look = _Look(plant_color(engine), solid=solid)
    body = body_entity(engine, p0)
    rec.log(f"{p0}/world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    _log_shape(rec, body, scene, look)
    if scene.n:
        _log_masses_look(rec, body, scene, look)


def send_poses(rec, engine: str, scene: Any, t: np.ndarray, q: np.ndarray, p0: str = "") -> None:
    """Plant ``engine``'s body at coordinates ``q`` (N, n+7) at simulated times ``t`` (N,), s, in
    columns on the entities of :func:`log_world`: its pose, and its masses when ``scene`` is
    given."""
    import rerun as rr

    t, q = np.asarray(t, float), np.asarray(q, float)
    body, N = body_entity(engine, p0), t.shape[0]
    index = [rr.TimeColumn(TIMELINE, duration=t)]
    pose = rr.Transform3D.columns(translation=q[:, :3], quaternion=_xyzw(q[:, 3:7]))
    rec.send_columns(body, indexes=index, columns=pose)
    n = q.shape[1] - 7
    if scene is not None and n > 0:
        pos = _mass_positions(scene, q).reshape(-1, 3)
        rec.send_columns(
            f"{body}/masses",
            indexes=index,
            columns=rr.Points3D.columns(positions=pos).partition([n] * N),
        )


def _log_arrows(send: _Sender, body: str, tr: Trajectory, scales: ArrowScales, look: _Look) -> None:
    import rerun as rr

    N = tr.t.shape[0]
    for name, rgba, label, vectors in (
        ("omega", OMEGA_RGBA, "ω", tr.omega * scales.omega),
        ("torque", TORQUE_RGBA, "τ", tr.torque * scales.torque),
    ):
        send.rec.log(
            f"{body}/{name}",
            rr.Arrows3D.from_fields(
                colors=[look.part(rgba)],
                labels=[label] if look.solid else None,
                show_labels=look.solid,
            ),
            static=True,
        )
        send(
            f"{body}/{name}",
            tr.t,
            rr.Arrows3D.columns(vectors=vectors, origins=np.zeros((N, 3))),
        )


def _log_trail(send: _Sender, path: str, scene: Any, tr: Trajectory, look: _Look) -> None:
    """The path of C as one segment per sample (from the previous sample's C), inertial, m."""
    import rerun as rr

    R = tr.q[:, :3]
    send.rec.log(
        path,
        rr.LineStrips3D.from_fields(colors=[look.color], radii=[TRAIL_RADIUS * body_size(scene)]),
        static=True,
    )
    if R.shape[0] < 2:
        return
    segments = np.stack([R[:-1], R[1:]], axis=1)  # (N-1, 2, 3)
    send(path, tr.t[1:], rr.LineStrips3D.columns(strips=segments).partition([1] * len(segments)))


def log_world(
    rec,
    p0: str,
    scene: Any,
    plants: Sequence[Trajectory],
    scales: ArrowScales,
    factors: Mapping[str, float],
) -> list[str]:
    """Log every plant's body, arrows and trail under ``{p0}/world``, and each other plant's
    exaggerated difference under ``{p0}/world/exaggerated`` (``factors``: see
    :func:`difference_factors`); returns the entity paths that received time series."""
    import rerun as rr

    send = _Sender(rec)
    rec.log(f"{p0}/world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    plants = [tr for tr in plants if tr.t.shape[0]]
    for k, tr in enumerate(plants):
        name = tr.engine
        look = _Look(plant_color(name), solid=k == 0)
        body = f"{p0}/world/{name}/body"
        _log_body(send, body, scene, tr.t, tr.q, look)
        _log_arrows(send, body, tr, scales, look)
        _log_trail(send, f"{p0}/world/{name}/trail", scene, tr, look)
    if len(plants) > 1:
        ref = plants[0]
        for tr in plants[1:]:
            name = tr.engine
            if name not in factors or name == ref.engine:
                continue
            n = min(ref.t.shape[0], tr.t.shape[0])
            t, k = ref.t[:n], factors[name]
            root = f"{p0}/world/exaggerated/{name}"
            qx = exaggerate(ref.q[:n], tr.q[:n], k)
            look = _Look(plant_color(name), solid=False)
            _log_body(send, f"{root}/body", scene, t, qx, look)
            rec.log(
                f"{root}/offset",
                rr.Arrows3D.from_fields(
                    colors=[look.color],
                    radii=[TRAIL_RADIUS * body_size(scene)],
                    labels=[f"{name} ×{power_of_ten(k)}"],
                    show_labels=True,
                ),
                static=True,
            )
            send(
                f"{root}/offset",
                t,
                rr.Arrows3D.columns(origins=ref.q[:n, :3], vectors=qx[:, :3] - ref.q[:n, :3]),
            )
    return send.entities


__all__ = [
    "DIFFERENCE_TARGET",
    "ArrowScales",
    "arrow_scales",
    "body_entity",
    "body_size",
    "difference_factor",
    "difference_factors",
    "exaggerate",
    "largest_difference",
    "largest_differences",
    "log_body_look",
    "log_world",
    "plant_order",
    "send_poses",
]
