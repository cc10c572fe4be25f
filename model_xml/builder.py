"""The MuJoCo twin of a scene, built with MuJoCo's model-editing API (``mujoco.MjSpec``).

Layout (names are a contract other modules rely on; mass indices 1-based as in the paper):

* body ``BR`` on free joint ``root``: explicit inertial ``m_BR``, ``J_BR`` with the inertial frame
  at C along the principal axes (the paper's body frame). By default BR's body frame *is* that
  frame, so ``qpos[0:3] = R`` and ``qpos[3:7] = u``; :class:`BodyFrame` places it elsewhere (the
  state mapping in :mod:`mj_bridge` handles both).
* bodies ``mass1..massN`` (children of BR) at ``O' = d`` with slide joints ``p1..pN`` along ``a``: the
  joint coordinate is the paper's ``p_i`` (Eq. 21: ``r_i = R + S(u)(d + p_i a)``). Each carries its
  mass and, with the ``mass_inertia`` effect, its own inertia (Remark 1, the ring about ``a``).
* fixed tendons ``spring1..springN+1`` (spring j joins mass j-1 and j; the two end springs act on
  one joint): length ``p_j - p_{j-1}``, native polynomial stiffness ``[k_l, 0, k_n]`` and
  ``springlength`` from ``p_e`` (Eq. 38), so MuJoCo integrates them in every integrator stage and
  counts their energy. With ``spring_model = "actuator"`` the tendons carry no stiffness and one
  general actuator ``springJ_act`` per tendon applies ``-(k_l x + k_n x³)``: the linear part as an
  affine bias, the cubic part through MuJoCo's user-bias callback (see :mod:`mj_bridge.callbacks`).
* control channels (only when the scene is controlled or has a given torque): motors ``torque_x``,
  ``torque_y``, ``torque_z`` on the free joint's rotational dofs (torque about the paper's body axes)
  and, when controlled, motors ``force1..forceN`` on the slide joints (rod force on mass i). Their
  gear is :data:`CONTROL_GEAR` (2^24): ``ctrl`` = torque (N·m) or force (N) / 2^24.
* visual geoms only (massless, never colliding): the block or hollow cylinder, the rod, spheres.

Effects map onto the model: no gravity effect -> zero gravity; a spring term that is off has zero
stiffness, no spring effect -> no tendons; no control and no given torque -> no actuators.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from analytic.effects import Effect, MjIntegrator, ShapeKind, SpringModel
from analytic.effects.registry import SPRING_LAWS
from analytic.scene import Scene
from analytic.scene.twin import TRIANGLE_RTOL, twin_point_inertia
from model_xml.coordinates import paper_to_frame_state
from model_xml.rotations import (
    mat_to_quat,
    principal_frame,
    quat_conj,
    quat_mul,
    quat_to_mat,
    quat_z_to,
)
from model_xml.tendon_terms import TENDON_TERMS

BODY = "BR"
ROOT = "root"
TORQUE_ACTUATORS = ("torque_x", "torque_y", "torque_z")
KEY_INITIAL = "initial"

_INTEGRATORS = {
    MjIntegrator.EULER: mujoco.mjtIntegrator.mjINT_EULER,
    MjIntegrator.RK4: mujoco.mjtIntegrator.mjINT_RK4,
    MjIntegrator.IMPLICIT: mujoco.mjtIntegrator.mjINT_IMPLICIT,
    MjIntegrator.IMPLICITFAST: mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}

# MuJoCo zeroes every ctrl (warning "huge value", mjWARN_BADCTRL) once one exceeds mjMAXVAL = 1e10, and
# the paper-scale rod forces and torques reach that (1.3e10 N with masses 1e3 x m_BR). The control
# actuators therefore carry a gear of CONTROL_GEAR: ctrl is the force (N) or torque (N·m) divided by
# 2^24 ≈ 1.7e7. A power of two scales exactly (no rounding), so accuracy is unchanged, and the
# channels reach 1.7e17 N / N·m.
CONTROL_GEAR = 2.0**24

# MuJoCo refuses moving bodies whose inertia is below mjMINVAL (1e-15). A point mass gets an isotropic
# inertia eps (analytic.scene.twin.twin_point_inertia: the one formula, with its numbers), and exactly
# that much is taken off BR's principal moments: the mass body rotates with BR (slide joint), so an
# isotropic inertia on it adds exactly eps·I to the system's rotational inertia, and the total is
# unchanged. The loader refuses a BR that cannot give that much up (analytic.scene.twin), so the
# twin's limits are checked when a scene is loaded, before any plant runs.


def mass_name(i: int) -> str:
    """Body name of mass i (0-based i -> ``mass{i+1}``)."""
    return f"mass{i + 1}"


def joint_name(i: int) -> str:
    return f"p{i + 1}"


def tendon_name(j: int) -> str:
    """Tendon of spring j (0-based j -> ``spring{j+1}``); spring j joins mass j-1 and mass j."""
    return f"spring{j + 1}"


def spring_actuator_name(j: int) -> str:
    return f"spring{j + 1}_act"


def force_actuator_name(i: int) -> str:
    return f"force{i + 1}"


@dataclass(frozen=True)
class BodyFrame:
    """Pose of BR's MuJoCo body frame relative to the paper's body frame (C, principal axes).

    Attributes:
        pos: origin of the MuJoCo body frame, paper body axes, m, shape (3,).
        quat: orientation (w first) taking MuJoCo-body-frame vectors to paper body axes, shape (4,).
    """

    pos: np.ndarray = field(default_factory=lambda: np.zeros(3))
    quat: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))

    def __post_init__(self) -> None:
        pos = np.asarray(self.pos, float)
        quat = np.asarray(self.quat, float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ValueError(f"BodyFrame.pos: must be 3 finite numbers (got {self.pos!r})")
        if quat.shape != (4,) or abs(np.linalg.norm(quat) - 1.0) > 1e-12:
            raise ValueError(f"BodyFrame.quat: must be a unit quaternion (got {self.quat!r})")
        object.__setattr__(self, "pos", pos)
        object.__setattr__(self, "quat", quat)

    @property
    def is_identity(self) -> bool:
        return bool(np.all(self.pos == 0) and np.all(self.quat == [1.0, 0.0, 0.0, 0.0]))


@dataclass(frozen=True)
class SpringTendon:
    """One spring as a fixed tendon: ``length = Σ coef·p``, rest length, and the coefficient of
    each spring law that is on (:data:`TENDON_TERMS`), by effect."""

    joints: tuple[int, ...]
    coefs: tuple[float, ...]
    rest: float
    coefficients: Mapping[Effect, float]

    @property
    def k_linear(self) -> float:
        return self.coefficients.get(Effect.SPRINGS_LINEAR, 0.0)

    @property
    def k_cubic(self) -> float:
        return self.coefficients.get(Effect.SPRINGS_CUBIC, 0.0)

    def polynomial(self, attribute: str, as_actuators: bool) -> list[float]:
        """The tendon's ``stiffness`` or ``damping`` polynomial (MuJoCo's three coefficients)."""
        out = [0.0, 0.0, 0.0]
        for effect, term in TENDON_TERMS.items():
            if term.attribute == attribute and not (as_actuators and term.by_actuator):
                out[term.power] = self.coefficients.get(effect, 0.0)
        return out


def spring_tendons(scene: Scene) -> list[SpringTendon]:
    """The n+1 springs of Eq. (38) as tendons (empty when no spring effect is on or n = 0).

    Spring j (0-based) has extension ``x_j - x_{j-1}`` with ``x = p - p_e`` and ``x_{-1} = x_n = 0``.
    Its force is odd in the extension and its rate (no quadratic term), so a tendon may measure
    the extension with either sign; the sign is flipped when the rest length would be exactly -1,
    MuJoCo's sentinel for "length at qpos0".
    """
    n = scene.n
    laws = [law for law in SPRING_LAWS if scene.has(law.effect)]
    missing = [law.effect.value for law in laws if law.effect not in TENDON_TERMS]
    if missing:
        raise ValueError(f"scene.effects: the MJCF twin cannot carry {', '.join(missing)}")
    if n == 0 or not laws:
        return []
    pe = np.asarray(scene.masses.p_e, float)
    out = []
    for j in range(n + 1):
        joints, coefs, rest = [], [], 0.0
        if j < n:
            joints.append(j)
            coefs.append(1.0)
            rest += pe[j]
        if j > 0:
            joints.append(j - 1)
            coefs.append(-1.0)
            rest -= pe[j - 1]
        if rest == -1.0:
            coefs = [-c for c in coefs]
            rest = 1.0
        out.append(
            SpringTendon(
                joints=tuple(joints),
                coefs=tuple(coefs),
                rest=float(rest),
                coefficients={law.effect: float(scene.springs.of(law)[j]) for law in laws},
            )
        )
    return out


def point_inertia(scene: Scene) -> float:
    """Isotropic inertia given to a mass body without its own inertia, kg·m² (see module notes)."""
    return twin_point_inertia(scene)[0]


def mass_inertias(scene: Scene) -> tuple[np.ndarray, float]:
    """Inertia of each mass body in paper body axes (n, 3, 3) and the total isotropic padding taken
    off BR (kg·m²)."""
    n = scene.n
    eps = point_inertia(scene)
    out = np.zeros((n, 3, 3))
    pad = 0.0
    for i in range(n):
        J = (
            np.array(scene.masses.inertia[i], float)
            if scene.has(Effect.MASS_INERTIA)
            else np.zeros((3, 3))
        )
        if np.min(np.linalg.eigvalsh(J)) <= eps:
            J = J + eps * np.eye(3)
            pad += eps
        out[i] = J
    return out, pad


def _visual(geom: mujoco.MjsGeom, rgba: Sequence[float]) -> None:
    geom.density = 0.0
    geom.contype = 0
    geom.conaffinity = 0
    geom.group = 1
    geom.rgba = rgba


def build_spec(scene: Scene, body_frame: BodyFrame | None = None) -> mujoco.MjSpec:
    """The MuJoCo twin of ``scene`` as an :class:`mujoco.MjSpec` (see the module docstring).

    Args:
        scene: a validated scene.
        body_frame: where BR's MuJoCo body frame sits relative to C and the principal axes
            (default: at C, along the principal axes).

    Returns:
        an uncompiled spec; ``spec.compile()`` gives the ``MjModel``.
    """
    bf = body_frame or BodyFrame()
    Rf = quat_to_mat(bf.quat)  # frame -> paper body axes
    Rt = Rf.T  # paper body axes -> frame

    # a point given in paper body coordinates, in frame coordinates
    def pt(x: Sequence[float] | np.ndarray) -> np.ndarray:
        return Rt @ (np.asarray(x, float) - bf.pos)

    def vec(v: Sequence[float] | np.ndarray) -> np.ndarray:
        return Rt @ np.asarray(v, float)

    # an orientation given relative to paper body axes, relative to the frame
    def rot(q: np.ndarray) -> np.ndarray:
        return quat_mul(quat_conj(bf.quat), q)

    spec = mujoco.MjSpec()
    spec.modelname = scene.name
    opt = spec.option
    opt.timestep = float(scene.mujoco.timestep)
    opt.integrator = int(_INTEGRATORS[scene.mujoco.integrator])
    opt.gravity = np.asarray(scene.gravity, float) if scene.has(Effect.GRAVITY) else np.zeros(3)
    opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)

    n = scene.n
    a = np.asarray(scene.rod.axis, float)
    d = np.asarray(scene.rod.offset, float)
    J_masses, pad = mass_inertias(scene)

    br = spec.worldbody.add_body(name=BODY)
    br.explicitinertial = True
    br.mass = float(scene.body.mass)
    br.inertia = np.asarray(scene.body.inertia, float) - pad
    br.ipos = pt(np.zeros(3))
    br.iquat = quat_conj(bf.quat)
    br.add_freejoint(name=ROOT)

    shape = scene.body.shape
    grey, blue, red = [0.7, 0.7, 0.75, 0.6], [0.3, 0.4, 0.8, 1.0], [0.85, 0.2, 0.2, 1.0]
    if shape.kind is ShapeKind.BOX_AND_ROD:
        g = br.add_geom(name="block", type=mujoco.mjtGeom.mjGEOM_BOX)
        g.size = np.asarray(shape.box_half_sizes, float)
        g.pos = pt(shape.box_center)
        g.quat = rot(mat_to_quat(np.asarray(shape.box_rotation, float)))
        _visual(g, grey)
    elif shape.kind is ShapeKind.HOLLOW_CYLINDER_AND_ROD:
        g = br.add_geom(name="cylinder", type=mujoco.mjtGeom.mjGEOM_CYLINDER)
        g.size = [shape.cylinder_radius, 0.5 * shape.cylinder_length, 0.0]
        g.pos = pt(np.zeros(3))
        g.quat = rot(quat_z_to(shape.cylinder_axis))
        _visual(g, [0.7, 0.7, 0.75, 0.25])
    if shape.kind is not ShapeKind.NONE:
        g = br.add_geom(name="rod", type=mujoco.mjtGeom.mjGEOM_CYLINDER)
        g.size = [shape.rod_radius, 0.5 * shape.rod_length, 0.0]
        g.pos = pt(d + (shape.rod_start + 0.5 * shape.rod_length) * a)
        g.quat = rot(quat_z_to(a))
        _visual(g, blue)
    sphere_r = 2.0 * shape.rod_radius if shape.kind is not ShapeKind.NONE else 0.1

    for i in range(n):
        mb = br.add_body(name=mass_name(i))
        mb.pos = pt(d)
        mb.explicitinertial = True
        mb.mass = float(scene.masses.mass[i])
        moments, q_principal = principal_frame(Rt @ J_masses[i] @ Rf)
        if 0.0 < moments[2] - moments[0] - moments[1] <= TRIANGLE_RTOL * moments[2]:
            moments[2] = moments[0] + moments[1]  # a ring's A + B = C, broken by eigh round-off
        mb.inertia = moments
        mb.iquat = q_principal
        mb.ipos = np.zeros(3)
        mb.add_joint(name=joint_name(i), type=mujoco.mjtJoint.mjJNT_SLIDE, axis=vec(a))
        g = mb.add_geom(name=f"{mass_name(i)}_sphere", type=mujoco.mjtGeom.mjGEOM_SPHERE)
        g.size = [sphere_r, 0.0, 0.0]
        _visual(g, red)

    tendons = spring_tendons(scene)
    as_actuators = SpringModel(scene.mujoco.spring_model) is SpringModel.ACTUATOR
    for j, sp in enumerate(tendons):
        t = spec.add_tendon(name=tendon_name(j))
        for jj, c in zip(sp.joints, sp.coefs, strict=True):
            t.wrap_joint(joint_name(jj), c)
        t.springlength = [sp.rest, sp.rest]
        stiffness = sp.polynomial("stiffness", as_actuators)
        if any(stiffness):
            t.stiffness = stiffness
        damping = sp.polynomial("damping", as_actuators)
        if any(damping):
            t.damping = damping
    if as_actuators:
        for j, sp in enumerate(tendons):
            act = spec.add_actuator(name=spring_actuator_name(j), target=tendon_name(j))
            act.trntype = mujoco.mjtTrn.mjTRN_TENDON
            act.dyntype = mujoco.mjtDyn.mjDYN_NONE
            act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            gain = np.zeros(mujoco.mjNGAIN)
            act.gainprm = gain
            bias = np.zeros(mujoco.mjNBIAS)
            # affine bias b0 + b1·L: -k_l (L - rest); user bias adds -k_n (L - rest)³ (biasprm[3:5])
            bias[0] = sp.k_linear * sp.rest
            bias[1] = -sp.k_linear
            if sp.k_cubic != 0.0:
                act.biastype = mujoco.mjtBias.mjBIAS_USER
                bias[3] = -sp.k_cubic
                bias[4] = sp.rest
            else:
                act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
            act.biasprm = bias
            act.ctrllimited = 0

    if scene.controlled or scene.has(Effect.EXTERNAL_TORQUE):
        for c, name in enumerate(TORQUE_ACTUATORS):
            act = spec.add_actuator(name=name, target=ROOT)
            act.trntype = mujoco.mjtTrn.mjTRN_JOINT
            gear = np.zeros(6)
            gear[3:] = CONTROL_GEAR * Rt[:, c]  # paper body axis c, in frame coordinates
            act.gear = gear
            act.ctrllimited = 0
    if scene.controlled:
        for i in range(n):
            act = spec.add_actuator(name=force_actuator_name(i), target=joint_name(i))
            act.trntype = mujoco.mjtTrn.mjTRN_JOINT
            act.gear = [CONTROL_GEAR, 0, 0, 0, 0, 0]
            act.ctrllimited = 0

    # keyframe "initial": the scene's initial state in MuJoCo coordinates
    qpos, qvel = paper_to_frame_state(scene.initial.q0(), scene.initial.qdot0(), bf.pos, bf.quat)
    key = spec.add_key(name=KEY_INITIAL)
    key.qpos = qpos
    key.qvel = qvel
    return spec


def compile_scene(scene: Scene, body_frame: BodyFrame | None = None) -> mujoco.MjModel:
    """``build_spec(scene).compile()``."""
    return build_spec(scene, body_frame).compile()
