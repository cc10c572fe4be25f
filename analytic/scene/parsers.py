"""One parser per table of a scene file: a :class:`~analytic.scene.table.Table` in, its record out.

Each reads its keys through the table (declared kinds and defaults, :mod:`analytic.scene.schema`)
and refuses what the table alone can tell is wrong, naming the field; rules across tables are in
:mod:`analytic.scene.rules`. Attitudes: ``docs/errata.md`` items 6 and 8 (Eqs. 62, 63).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from analytic.effects import MjIntegrator, ShapeKind, SolverMethod, SpringModel, Weighting
from analytic.effects.registry import SPRING_LAWS
from analytic.kinematics import axis_angle_quat, matrix_quat, quat_mul
from analytic.scene.limits import MAX_INERTIA, MAX_MASSES, QUAT_NORMALISE_TOL, QUAT_REFUSE_TOL
from analytic.scene.records import (
    Body,
    BodyShape,
    Control,
    ExternalTorque,
    InitialState,
    Masses,
    MassTrack,
    MujocoSettings,
    OmegaTrack,
    OutputSettings,
    Rod,
    SolverSettings,
    Springs,
)
from analytic.scene.schema import Kind, generic_table
from analytic.scene.table import Table
from analytic.scene.twin import TRIANGLE_RTOL, mass_in_range
from analytic.scene.values import (
    as_matrix,
    as_number,
    direction,
    frozen,
    indices,
    nearest_rotation,
    show,
    unit_vector,
)


def parse_thresholds(t: Table) -> dict[str, Any]:
    """The ``[thresholds]`` table's shape: each entry a finite non-negative number or
    ``{value = number, rtol = number, reason = "..."}`` (rtol optional, finite, ≥ 0); the hard-case suite's ``hard_*`` entries a number or,
    for its stated criterion, a sentence. Which names exist is for the layer that uses them."""
    out: dict[str, Any] = {}
    for key in list(t.data):
        name = t.name(key)
        v = t.raw(key, kinds=(Kind.NUMBER_OR_VALUE_TABLE, Kind.NUMBER_OR_STRING))
        if key.startswith("hard_"):
            out[key] = v if isinstance(v, str) else as_number(v, name, nonneg=True)
        elif isinstance(v, Mapping):
            sub = Table(v, name, generic_table(t.schema, key))
            sub.used.update(("value", "rtol", "reason"))
            sub.finish()  # an unknown key first: a misspelt "value" is named as such
            entry = {"value": sub.number("value", nonneg=True)}
            if sub.has("rtol"):
                entry["rtol"] = sub.number("rtol", nonneg=True)
            if sub.has("reason"):
                entry["reason"] = sub.string("reason")
            sub.finish()
            out[key] = entry
        else:
            out[key] = as_number(v, name, nonneg=True)
    return out


def parse_body(t: Table) -> Body:
    mass = mass_in_range(t.number("mass", positive=True), t.name("mass"))
    inertia = t.vector("inertia", 3, positive=True)
    for i, x in enumerate(inertia.tolist()):
        if x > MAX_INERTIA:
            raise ValueError(
                f"{t.name('inertia')}[{i}]: must be at most {MAX_INERTIA:g} kg·m² (got {x!r})"
            )
    j = np.sort(inertia)
    if j[2] > j[0] + j[1] * (1 + 1e-12):
        raise ValueError(
            f"body.inertia: principal moments violate the triangle inequality (got {inertia.tolist()!r})"
        )
    shape = BodyShape()
    st = t.table("shape")
    if st is not None:
        shape = parse_shape(st)
    t.finish()
    return Body(mass=mass, inertia=inertia, shape=shape)


def parse_shape(t: Table) -> BodyShape:
    kind = t.enum("kind", ShapeKind)
    kw: dict[str, Any] = {"kind": kind}
    if kind is ShapeKind.BOX_AND_ROD:
        kw["box_half_sizes"] = t.vector("box_half_sizes", 3, positive=True)
        kw["box_center"] = t.vector("box_center", 3)
        if t.has("box_rotation"):
            kw["box_rotation"] = frozen(
                nearest_rotation(
                    as_matrix(
                        t.raw("box_rotation", kinds=(Kind.MATRIX3,)), t.name("box_rotation"), 3, 3
                    ),
                    t.name("box_rotation"),
                )
            )
    elif kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        kw["cylinder_radius"] = t.number("cylinder_radius", positive=True)
        kw["cylinder_length"] = t.number("cylinder_length", positive=True)
        kw["cylinder_thickness"] = t.number("cylinder_thickness", positive=True)
        kw["cylinder_axis"] = direction(t.vector("cylinder_axis", 3), t.name("cylinder_axis"))
    if kind is not ShapeKind.NONE:
        kw["rod_radius"] = t.number("rod_radius", positive=True)
        kw["rod_start"] = t.number("rod_start")
        kw["rod_length"] = t.number("rod_length", positive=True)
    t.finish()
    return BodyShape(**kw)


def parse_rod(t: Table) -> Rod:
    axis = unit_vector(t.vector("axis", 3), t.name("axis"))
    offset = t.vector("offset", 3)
    t.finish()
    return Rod(axis=axis, offset=offset)


def parse_masses(t: Table | None, axis: np.ndarray) -> Masses:
    if t is None:
        z = frozen(np.zeros(0))
        return Masses(mass=z, p_e=z, inertia=frozen(np.zeros((0, 3, 3))))
    raw_m = t.raw("mass", kinds=(Kind.VECTOR_N,))
    if isinstance(raw_m, list | tuple) and len(raw_m) > MAX_MASSES:
        raise ValueError(
            f"{t.name('mass')}: at most {MAX_MASSES:,} masses (got a list of {len(raw_m):,})"
        )
    m = t.vector("mass", positive=True)
    for i, x in enumerate(m):
        mass_in_range(float(x), f"{t.name('mass')}[{i}]")
    n = m.shape[0]
    p_e = t.vector("p_e", n)
    inertia = np.zeros((n, 3, 3))
    has_ring = t.has("ring_radius")
    has_axi = t.has("inertia_axial") or t.has("inertia_transverse")
    has_full = t.has("inertia_body")
    if has_ring + has_axi + has_full > 1:
        raise ValueError(
            f"{t.name('ring_radius')}: give one of ring_radius, inertia_axial/inertia_transverse, "
            f"inertia_body (got {sorted(k for k in t.data if k.startswith(('ring', 'inertia')))!r})"
        )
    aa = np.outer(axis, axis)
    if has_ring:
        # A thin ring about the rod: axial m r², transverse m r²/2 -> m r²/2 (I + a aᵀ) (Eq. 62;
        # docs/errata.md item 8).
        r = t.vector("ring_radius", n, nonneg=True)
        for i in range(n):
            if float(m[i]) * float(r[i]) * float(r[i]) > MAX_INERTIA:
                raise ValueError(
                    f"{t.name('ring_radius')}[{i}]: makes an axial moment m r² above "
                    f"{MAX_INERTIA:g} kg·m² (got {float(r[i])!r} m)"
                )
        inertia = (m * r**2 / 2)[:, None, None] * (np.eye(3) + aa)[None]
    elif has_axi:
        ia = t.vector("inertia_axial", n, nonneg=True)
        it = t.vector("inertia_transverse", n, nonneg=True)
        for key, vals in (("inertia_axial", ia), ("inertia_transverse", it)):
            for i, x in enumerate(vals.tolist()):
                if x > MAX_INERTIA:
                    raise ValueError(
                        f"{t.name(key)}[{i}]: must be at most {MAX_INERTIA:g} kg·m² (got {x!r})"
                    )
        for i in range(n):
            if ia[i] > 2 * it[i] * (1 + 1e-12):
                raise ValueError(
                    f"{t.name('inertia_axial')}[{i}]: exceeds twice the transverse moment "
                    f"(got {ia[i]!r} > 2 x {it[i]!r})"
                )
        inertia = it[:, None, None] * (np.eye(3) - aa)[None] + ia[:, None, None] * aa[None]
    elif has_full:
        raw = t.raw("inertia_body", kinds=(Kind.MATRICES_N,))
        if not isinstance(raw, list) or len(raw) != n:
            raise ValueError(
                f"{t.name('inertia_body')}: must hold {n} 3x3 matrices (got {show(raw)})"
            )
        for i, mat in enumerate(raw):
            name = f"{t.name('inertia_body')}[{i}]"
            J = as_matrix(mat, name, 3, 3)
            if not np.allclose(J, J.T, rtol=1e-12, atol=0):
                raise ValueError(f"{name}: must be symmetric (got {J.tolist()!r})")
            if np.max(np.abs(J)) > MAX_INERTIA:
                raise ValueError(
                    f"{name}: entries must be at most {MAX_INERTIA:g} kg·m² (got {J.tolist()!r})"
                )
            e = np.linalg.eigvalsh(J)
            if e[0] < 0:
                raise ValueError(f"{name}: must be positive semidefinite (got {J.tolist()!r})")
            # Principal moments of a rigid body satisfy A + B >= C (MuJoCo's compiler refuses
            # them otherwise); round-off up to TRIANGLE_RTOL is what model_xml repairs.
            if e[2] - e[0] - e[1] > TRIANGLE_RTOL * e[2]:
                raise ValueError(
                    f"{name}: principal moments {e.tolist()!r} violate the triangle inequality "
                    f"A + B >= C (got {J.tolist()!r})"
                )
            inertia[i] = J
    t.finish()
    return Masses(mass=m, p_e=p_e, inertia=frozen(inertia))


def parse_springs(t: Table | None, n: int) -> Springs:
    """``[springs]``: each spring law's coefficients (n + 1, ≥ 0; zeros when not given)."""
    zeros = frozen(np.zeros(n + 1))
    if t is None:
        return Springs(coefficients={law.key.key: zeros for law in SPRING_LAWS})
    given = frozenset(law.key.key for law in SPRING_LAWS if t.has(law.key.key))
    coefficients = {
        law.key.key: t.vector(law.key.key, n + 1, zeros, nonneg=True) for law in SPRING_LAWS
    }
    t.finish()
    return Springs(coefficients=coefficients, given=given)


def parse_initial(t: Table, n: int) -> InitialState:
    R = t.vector("R", 3)
    Rdot = t.vector("Rdot", 3)
    omega = t.vector("omega", 3)
    p = t.vector("p", n) if n else t.vector("p", 0, frozen(np.zeros(0)))
    pdot = t.vector("pdot", n, frozen(np.zeros(n)))
    attitude = t.table("attitude")
    u = IDENTITY_QUATERNION if attitude is None else parse_attitude(attitude)
    t.finish()
    return InitialState(R=R, Rdot=Rdot, u=u, omega=omega, p=p, pdot=pdot)


IDENTITY_QUATERNION = frozen([1.0, 0.0, 0.0, 0.0])
"""``u(0)`` when ``[initial.attitude]`` is absent: body axes along XYZ."""


def parse_attitude(t: Table) -> np.ndarray:
    """Quaternion (w first) or axis-angle composed with a reference-from-principal rotation.

    ``S(u(0)) = Rot(axis, angle) · reference_from_principal`` (Example 1 needs the principal -> block
    rotation ``P`` of Eq. 63 here: ``docs/errata.md``, item 6).
    """
    allow_off = t.boolean("allow_off_manifold")
    if t.has("quaternion"):
        for k in ("axis", "angle", "angle_deg", "reference_from_principal"):
            if t.has(k):
                raise ValueError(f"{t.name(k)}: give either quaternion or axis-angle, not both")
        u = np.array(t.vector("quaternion", 4))
        nrm = float(np.linalg.norm(u))
        if nrm == 0.0:
            raise ValueError(f"{t.name('quaternion')}: must be nonzero (got {u.tolist()!r})")
        if not allow_off:
            if abs(nrm - 1.0) > QUAT_REFUSE_TOL:
                raise ValueError(
                    f"{t.name('quaternion')}: norm {nrm!r} is off the unit sphere by more than "
                    f"{QUAT_REFUSE_TOL} (set allow_off_manifold = true to start off it on purpose)"
                )
            if abs(nrm - 1.0) > QUAT_NORMALISE_TOL:
                warnings.warn(f"{t.name('quaternion')}: norm {nrm!r} normalised to 1", stacklevel=4)
                u = u / nrm
        t.finish()
        return frozen(u)
    axis = direction(t.vector("axis", 3), t.name("axis"))
    if t.has("angle") and t.has("angle_deg"):
        raise ValueError(f"{t.name('angle')}: give angle (rad) or angle_deg, not both")
    if t.has("angle_deg"):
        angle = math.radians(t.number("angle_deg"))
    else:
        angle = t.number("angle")
    ref = np.eye(3)
    if t.has("reference_from_principal"):
        name = t.name("reference_from_principal")
        raw_ref = t.raw("reference_from_principal", kinds=(Kind.MATRIX3,))
        ref = nearest_rotation(as_matrix(raw_ref, name, 3, 3), name)
    t.finish()
    if allow_off:
        raise ValueError(f"{t.name('allow_off_manifold')}: only meaningful with a quaternion")
    u = quat_mul(axis_angle_quat(axis, angle), matrix_quat(ref))
    return frozen(u / np.linalg.norm(u))


def parse_control(t: Table, n: int) -> Control:
    weighting = t.enum("weighting", Weighting)
    omega = None
    ot = t.table("omega")
    if ot is not None:
        comps = indices(ot.raw("components", kinds=(Kind.INDICES,)), ot.name("components"), 3)
        b = ot.vector("b", 3)
        sigma = ot.vector("sigma", 3)
        k = len(comps)
        if ot.has("gamma") and ot.has("gain"):
            raise ValueError(f"{ot.name('gain')}: give gamma or gain, not both")
        if ot.has("gain"):
            gain = as_matrix(ot.raw("gain", kinds=(Kind.MATRIX_K,)), ot.name("gain"), k, k)
            if (
                not np.allclose(gain, gain.T, rtol=1e-12, atol=0)
                or np.min(np.linalg.eigvalsh(gain)) <= 0
            ):
                raise ValueError(
                    f"{ot.name('gain')}: must be symmetric positive definite (got {gain.tolist()!r})"
                )
        else:
            gain = frozen(ot.number("gamma", positive=True) * np.eye(k))
        ot.finish()
        omega = OmegaTrack(components=comps, b=b, sigma=sigma, gain=frozen(gain))
    masses = None
    mt = t.table("masses")
    if mt is not None:
        if n == 0:
            raise ValueError(f"{mt.path}: there are no masses to control (n = 0)")
        idx = (
            indices(mt.raw("indices", kinds=(Kind.INDICES,)), mt.name("indices"), n)
            if mt.has("indices")
            else tuple(range(n))
        )
        k = len(idx)
        masses = MassTrack(
            indices=idx,
            l=mt.vector("l", k),
            lam=mt.vector("lambda", k),
            alpha=mt.vector("alpha", k, positive=True),
            beta=mt.vector("beta", k, positive=True),
        )
        mt.finish()
    t.finish()
    return Control(weighting=weighting, omega=omega, masses=masses)


def parse_external_torque(t: Table | None) -> ExternalTorque | None:
    if t is None:
        return None
    et = ExternalTorque(
        constant=t.vector("constant", 3),
        amplitude=t.vector("amplitude", 3),
        frequency=t.number("frequency"),
    )
    t.finish()
    return et


def parse_solver(t: Table) -> SolverSettings:
    s = SolverSettings(
        method=t.enum("method", SolverMethod),
        rtol=t.number("rtol", positive=True),
        atol=t.number("atol", positive=True),
        max_step=t.number("max_step", positive=True) if t.has("max_step") else math.inf,
    )
    t.finish()
    return s


def parse_output(t: Table) -> OutputSettings:
    o = OutputSettings(t_end=t.number("t_end", positive=True), rate=t.number("rate", positive=True))
    t.finish()
    return o


def parse_mujoco(t: Table) -> MujocoSettings:
    m = MujocoSettings(
        integrator=t.enum("integrator", MjIntegrator),
        timestep=t.number("timestep", positive=True),
        spring_model=t.enum("spring_model", SpringModel),
    )
    t.finish()
    return m


__all__ = [
    "IDENTITY_QUATERNION",
    "parse_body",
    "parse_control",
    "parse_external_torque",
    "parse_initial",
    "parse_masses",
    "parse_mujoco",
    "parse_output",
    "parse_rod",
    "parse_solver",
    "parse_springs",
    "parse_thresholds",
]
