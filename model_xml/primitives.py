"""A second description of BR: geometry primitives and densities, with MuJoCo computing the mass,
the centre of mass and the principal axes (no explicit inertial).

Primitives are given in a *design* frame (e.g. block coordinates of the paper's Example 1):

* ``BOX``: ``size`` = half-sizes (m), solid, volumetric ``density`` (kg/m³);
* ``CYLINDER``: ``size = [radius, half_length]`` (m), solid, axis along the primitive's z;
* ``TUBE``: a hollow cylinder with open ends and a wall of any ``thickness``, ``size = [outer radius,
  half_length]``: a closed triangle mesh with MuJoCo's exact (volumetric) mesh inertia. Its polygons
  (``TUBE_SEGMENTS`` sides) have the circles' areas, so the mass is exact and the moments are off by
  O((2π/N)⁴) (~4e-7 for N = 256). End caps are ``CYLINDER`` discs;
* ``CLOSED_SHELL``: a hollow cylinder with end caps, thin-walled: MuJoCo's shell inertia with areal
  density ``density · thickness`` (exact as the wall thickness -> 0).

:func:`mass_properties` compiles them on one free body and reads MuJoCo's ``body_mass``,
``body_ipos`` (CoM, design frame), ``body_iquat`` (principal axes) and ``body_inertia`` (principal
moments, MuJoCo orders them by decreasing size). :func:`rod_in_principal` expresses a rod line
(point O' and direction) in the principal frame: the paper's ``a`` and ``d``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import mujoco
import numpy as np

from model_xml.rotations import quat_to_mat, quat_z_to

ALUMINIUM_DENSITY = 2700.0  # kg/m³, the paper's Example 1 material (Sec. V.A.1)


class PrimitiveKind(StrEnum):
    BOX = "box"
    CYLINDER = "cylinder"
    TUBE = "tube"
    CLOSED_SHELL = "closed_shell"


TUBE_SEGMENTS = 256


@dataclass(frozen=True)
class Primitive:
    """One solid piece of BR in the design frame.

    Attributes:
        kind: the shape.
        size: half-sizes (box, shape (3,)) or ``[radius, half_length]`` (cylinders, shape (2,)), m.
        pos: centre, design frame, m, shape (3,).
        axis: the cylinder's axis (or the box's z axis), design frame, shape (3,).
        density: kg/m³.
        thickness: wall thickness of a ``CLOSED_SHELL``, m (0 otherwise).
    """

    kind: PrimitiveKind
    size: tuple[float, ...]
    pos: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    density: float = ALUMINIUM_DENSITY
    thickness: float = 0.0

    def __post_init__(self):
        want = 3 if self.kind is PrimitiveKind.BOX else 2
        if len(self.size) != want or min(self.size) <= 0:
            raise ValueError(
                f"Primitive.size: {self.kind.value} needs {want} positive numbers (got {self.size!r})"
            )
        if not self.density > 0:
            raise ValueError(f"Primitive.density: must be positive (got {self.density!r})")
        walled = self.kind in (PrimitiveKind.CLOSED_SHELL, PrimitiveKind.TUBE)
        if walled != (self.thickness > 0):
            raise ValueError(
                f"Primitive.thickness: positive for closed_shell and tube only (got "
                f"{self.thickness!r} for {self.kind.value})"
            )
        if self.kind is PrimitiveKind.TUBE and self.thickness >= self.size[0]:
            raise ValueError(
                f"Primitive.thickness: must be below the tube's radius {self.size[0]!r} "
                f"(got {self.thickness!r})"
            )


@dataclass(frozen=True)
class MassProperties:
    """What MuJoCo computes from the primitives.

    Attributes:
        mass: kg.
        com: centre of mass, design frame, m, shape (3,).
        moments: principal moments about the CoM, kg·m², shape (3,), MuJoCo's order (decreasing).
        axes: principal axes as columns, design frame, shape (3, 3) (right-handed).
    """

    mass: float
    com: np.ndarray
    moments: np.ndarray
    axes: np.ndarray


def primitive_spec(primitives: list[Primitive]) -> mujoco.MjSpec:
    """A spec with one free body ``BR`` made of the primitives (inertia from the geoms)."""
    if not primitives:
        raise ValueError("primitives: need at least one primitive (got [])")
    spec = mujoco.MjSpec()
    spec.modelname = "BR_from_primitives"
    body = spec.worldbody.add_body(name="BR")
    body.add_freejoint(name="root")
    for k, pr in enumerate(primitives):
        g = body.add_geom(name=f"piece{k}")
        g.pos = np.asarray(pr.pos, float)
        g.quat = quat_z_to(pr.axis)
        g.contype = 0
        g.conaffinity = 0
        if pr.kind is PrimitiveKind.TUBE:
            mesh = spec.add_mesh(name=f"tube{k}")
            V, F = tube_mesh(pr.size[0], pr.size[0] - pr.thickness, pr.size[1])
            mesh.uservert = V.ravel()
            mesh.userface = F.ravel()
            mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_EXACT
            g.type = mujoco.mjtGeom.mjGEOM_MESH
            g.meshname = mesh.name
            g.density = pr.density
        elif pr.kind is PrimitiveKind.BOX:
            g.type = mujoco.mjtGeom.mjGEOM_BOX
            g.size = list(pr.size)
            g.density = pr.density
        else:
            g.type = mujoco.mjtGeom.mjGEOM_CYLINDER
            g.size = [*pr.size, 0.0]
            if pr.kind is PrimitiveKind.CLOSED_SHELL:
                g.typeinertia = mujoco.mjtGeomInertia.mjINERTIA_SHELL
                g.density = pr.density * pr.thickness  # areal density, kg/m²
            else:
                g.density = pr.density
    return spec


def tube_mesh(
    r_out: float, r_in: float, half_length: float, segments: int = TUBE_SEGMENTS
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (4N, 3) and outward-oriented triangles (8N, 3) of an open-ended thick tube along z.

    Radii are scaled by ``sqrt(θ / sin θ)`` (θ = 2π/N) so each polygon has its circle's area.
    """
    th = 2.0 * np.pi / segments
    k = np.sqrt(th / np.sin(th))
    ang = np.arange(segments) * th
    ring = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    V = np.concatenate(
        [
            np.column_stack([rad * k * ring, np.full(segments, z)])
            for rad in (r_out, r_in)
            for z in (-half_length, half_length)
        ]
    )
    ob, ot, ib, it = 0, segments, 2 * segments, 3 * segments
    F = []
    for i in range(segments):
        j = (i + 1) % segments
        F += [[ob + i, ob + j, ot + j], [ob + i, ot + j, ot + i]]  # outer wall
        F += [[ib + i, it + j, ib + j], [ib + i, it + i, it + j]]  # inner wall (faces the axis)
        F += [[ot + i, ot + j, it + j], [ot + i, it + j, it + i]]  # top annulus
        F += [[ob + i, ib + j, ob + j], [ob + i, ib + i, ib + j]]  # bottom annulus
    return V, np.array(F, dtype=int)


def mass_properties(primitives: list[Primitive]) -> MassProperties:
    """Compile the primitives and read MuJoCo's mass, CoM and principal frame."""
    m = primitive_spec(primitives).compile()
    b = m.body("BR").id
    return MassProperties(
        mass=float(m.body_mass[b]),
        com=m.body_ipos[b].copy(),
        moments=m.body_inertia[b].copy(),
        axes=quat_to_mat(m.body_iquat[b]),
    )


def rod_in_principal(
    props: MassProperties, point: np.ndarray, direction: np.ndarray, axes: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The rod line in principal coordinates: ``a`` (unit) and ``d`` (C -> O', m), shape (3,) each.

    Args:
        props: from :func:`mass_properties`.
        point: O' in the design frame, m.
        direction: the rod direction in the design frame.
        axes: principal axes as columns (default ``props.axes``), e.g. reordered to a paper's order.
    """
    A = props.axes if axes is None else np.asarray(axes, float)
    dvec = np.asarray(direction, float)
    a = A.T @ (dvec / np.linalg.norm(dvec))
    d = A.T @ (np.asarray(point, float) - props.com)
    return a, d


def paper_example1_primitives(density: float = ALUMINIUM_DENSITY) -> tuple[list[Primitive], dict]:
    """Example 1's block and rod (Sec. V.A.1; the geometry is consistent: ``docs/errata.md``, item 9).

    A 10 x 6 x 2 m block centred at the origin of block coordinates and a solid rod (r0 = 1 m,
    16 m) standing on its top face with its axis at (4, 2). Returns the primitives and the rod line
    ``{"point": O', "direction": a}`` in block coordinates.
    """
    block = Primitive(PrimitiveKind.BOX, (5.0, 3.0, 1.0), np.zeros(3), density=density)
    rod = Primitive(PrimitiveKind.CYLINDER, (1.0, 8.0), np.array([4.0, 2.0, 9.0]), density=density)
    return [block, rod], {"point": np.array([4.0, 2.0, 1.0]), "direction": np.array([0, 0, 1.0])}


def match_axes(props: MassProperties, moments: np.ndarray, reference_axis=None) -> np.ndarray:
    """Principal axes (columns) reordered to match the given order of ``moments`` (e.g. a paper's),
    with signs chosen right-handed and, if ``reference_axis`` (a vector in the target principal
    frame, e.g. the paper's ``a``) is given, so that the design-frame direction ``[0,0,1]`` maps
    closest to it. Returns shape (3, 3)."""
    order = [int(np.argmin(np.abs(props.moments - mo))) for mo in moments]
    if len(set(order)) != 3:
        raise ValueError(f"moments: cannot match {list(moments)!r} to {props.moments.tolist()!r}")
    A = props.axes[:, order]
    best, best_err = None, np.inf
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                B = A * np.array([sx, sy, sz])
                if np.linalg.det(B) < 0:
                    continue
                err = 0.0
                if reference_axis is not None:
                    err = float(np.linalg.norm(B.T @ [0, 0, 1.0] - reference_axis))
                if err < best_err:
                    best, best_err = B, err
    return best
