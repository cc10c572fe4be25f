"""The Pinocchio plant, the referee: a third, independent rigid-body engine against the analytic
model.

References: the analytic model of the paper (``TumblingModel.acceleration``: q̈ and the controller at a
state; its trajectories), Pinocchio's own kinematics (``getVelocity``, ``getClassicalAcceleration``)
for the coordinate maps, the scene's data and Pinocchio's MJCF reader (``buildModelFromMJCF`` of the
exported twin) for the mass properties.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from analytic import simulate as analytic_simulate  # noqa: E402
from analytic.effects import Effect, SolverMethod  # noqa: E402
from analytic.kinematics import S, omega_of  # noqa: E402
from analytic.model import TumblingModel  # noqa: E402
from analytic.scene import Scene, scene_from_dict  # noqa: E402
from analytic.trajectory import Engine, RunStatus  # noqa: E402
from mj_bridge.pinocchio_model import build_model, mass_inertias  # noqa: E402
from mj_bridge.pinocchio_plant import (  # noqa: E402
    PinocchioDynamics,
    PinocchioSettings,
    simulate,
)
from mj_bridge.stages import ControllerSource  # noqa: E402
from model_xml import to_mjcf  # noqa: E402
from model_xml.coordinates import (  # noqa: E402
    paper_to_pinocchio,
    pinocchio_to_paper,
    pinocchio_to_paper_acc,
    pinocchio_to_paper_batch,
)
from tests.support.mj_scenes import paper_scene  # noqa: E402
from tests.support.mj_scenes import random_state as manifold_state  # noqa: E402
from tests.support.scene_strategies import random_scene_dict  # noqa: E402

# ----------------------------------------------------------------------------------------------
# Tolerances (test-only), each with its reason
# ----------------------------------------------------------------------------------------------

ACC_REL = 1e-12
"""Pinocchio's q̈ against the analytic model's at one state, relative (Euclidean norms).
Two independent computations of the same dynamics in double precision under the same control
forces. Seen (worst over the cases below): 2.2e-15 uncontrolled, 5.5e-15 under the paper's weighting
M^-1 (either controller), 4e-15 on the paper scenes; 5.8e-14 (identity) and 1.4e-13 (M^-2) where the
analytic side's q̈ comes from its dense solve of the fundamental equation, which loses ~cond(M)
digits. A missing or wrong term (gyroscopic, spring, gravity on a mass) is O(1) relative."""

MASS_PROP_REL = 1e-14
"""Mass properties (masses, levers, inertias, placements, axes, the joint-space mass matrix)
relative to their scale: the same numbers copied (build_model) or printed at full precision and
read back (MJCF, whose inertias pass through an eigen-decomposition and its recomposition, ~1e-16)."""

MAP_ABS = 1e-14
"""Round trips of the coordinate maps, per component of O(1) states (a few roundings)."""

AGREE_M = 1e-9
"""Pinocchio against the analytic plant, m (position of C, rod positions) and rad (attitude angle of
the relative quaternion), over the scenes' 20 s. Both plants at the same DOP853 tolerance;
what is left is each integrator's error. Seen at rtol 1e-12 (C, p, attitude): Example 1 7.0e-12 m,
1.8e-11 m, 4.6e-13 rad; Example 2 4.6e-12 m, 1.2e-11 m, 7.0e-13 rad; controlled Example 2 2.5e-10 m,
6.4e-11 m, 9.4e-13 rad; controlled Example 1 see CONTROLLED_EX1_RTOL. Over 2 s at rtol 1e-12 the
worst is 6.9e-11 m (C, controlled Example 1)."""

RATE_REL = 1e-10
"""Velocities, accelerations and control forces of the two plants over 2 s of the controlled
Example 1 at rtol 1e-12, relative to their largest magnitude: seen q̇ 3.6e-12, q̈ 3.0e-12, torque
1.1e-12, rod forces 3.7e-12 (the integrators' error, amplified by the controller's gains)."""

BALANCE_REL = 1e-10
"""Energy and angular-momentum balances on Pinocchio's samples (the quadratures of the control's
work and impulse against the state's energy and momentum), relative: seen 2.3e-13 and 6.9e-13 over
2 s of the controlled Example 1 at rtol 1e-12."""

QUAT_NORM = 1e-11
"""|u|² - 1 of Pinocchio's samples: the quaternion is integrated as it is, never renormalised or
stabilised (aba gets a normalised copy), so it drifts by DOP853's error only: seen 4.0e-13 over 2 s
of the controlled Example 1 at rtol 1e-12 (the analytic plant, stabilised by Eq. 58: 2.5e-12)."""

CONTROLLED_EX1_RTOL = 2.5e-14
"""The controlled Example 1 spins up to |ω| ~ 20 rad/s while C falls ~1.6 km: at rtol 1e-12 each
plant's position of C is off its own rtol-1e-14 solution by a few 1e-9 m (measured: analytic
2.6e-9 m, Pinocchio 5.8e-9 m, i.e. ~4e-12 of |R|; the two differ by 6.4e-9 m), so the 1e-9 m
comparison runs both plants at rtol 2.5e-14 (just above scipy's floor of 100 eps), where they agree
to 1.7e-10 m in C, 2.4e-13 m in p and 9.8e-13 rad."""


def _rel(x, ref) -> float:
    return float(np.linalg.norm(np.asarray(x) - np.asarray(ref)) / np.linalg.norm(ref))


def _attitude_angle(u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """``2 atan2(|vec|, |w|)`` of the relative quaternion ``u1* ⊗ u2`` per row, rad."""
    a0, av = u1[:, 0], u1[:, 1:]
    b0, bv = u2[:, 0], u2[:, 1:]
    w = a0 * b0 + np.sum(av * bv, axis=1)
    vec = a0[:, None] * bv - b0[:, None] * av - np.cross(av, bv)
    return 2.0 * np.arctan2(np.linalg.norm(vec, axis=1), np.abs(w))


# ----------------------------------------------------------------------------------------------
# Random scenes
# ----------------------------------------------------------------------------------------------

ALL_FORCES = ["gravity", "springs.linear", "springs.cubic", "mass_inertia", "external_torque"]


def _scene(
    seed: int,
    n: int,
    *,
    inertia_kind: str = "body",
    effects=ALL_FORCES,
    controlled: bool = False,
    weighting: str = "M^-1",
) -> Scene:
    """A random scene (tests/support/scene_strategies.py) with random a, d, masses with inertia (a random SPD
    matrix per mass, a ring, or the axial + transverse form), optionally under control."""
    rng = np.random.default_rng(seed)
    kind = "ring" if inertia_kind == "ring" else "body"
    data = random_scene_dict(rng, n, list(effects), inertia_kind=kind)
    if n and inertia_kind == "physical":  # a full matrix that a mass distribution can have
        mats = []
        for _ in range(n):
            A, B = rng.uniform(0.05, 0.5, 2)
            C = rng.uniform(abs(A - B), A + B) * 0.999
            Rm = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            mats.append((Rm @ np.diag([A, B, C]) @ Rm.T).tolist())
        data["masses"]["inertia_body"] = mats
    if n and inertia_kind == "axial":
        del data["masses"]["inertia_body"]
        it = rng.uniform(0.1, 1.0, n)
        data["masses"]["inertia_axial"] = (it * rng.uniform(0.2, 1.9, n)).tolist()
        data["masses"]["inertia_transverse"] = it.tolist()
    if controlled:
        comps = sorted(rng.choice(3, size=int(rng.integers(1, 4)), replace=False) + 1)
        data["scene"]["effects"] = [*data["scene"]["effects"], "control.omega"]
        data["control"] = {
            "weighting": weighting,
            "omega": {
                "components": [int(c) for c in comps],
                "b": rng.normal(size=3).tolist(),
                "sigma": rng.uniform(0, 3, 3).tolist(),
                "gamma": float(rng.uniform(0.1, 2)),
            },
        }
        if n:
            idx = sorted(rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False) + 1)
            k = len(idx)
            data["scene"]["effects"].append("control.masses")
            data["control"]["masses"] = {
                "indices": [int(i) for i in idx],
                "l": rng.normal(scale=0.5, size=k).tolist(),
                "lambda": rng.uniform(0, 3, k).tolist(),
                "alpha": rng.uniform(0.5, 3, k).tolist(),
                "beta": rng.uniform(1, 10, k).tolist(),
            }
    return scene_from_dict(data)


KINDS = ("body", "ring", "axial")
"""Mass inertias (Remark 1): a random SPD matrix per mass (not always one a mass distribution can
have, which the analytic model and Pinocchio accept but MuJoCo refuses), a ring about the rod, the
axial + transverse form."""
MJCF_KINDS = ("physical", "ring", "axial")
"""The same for scenes exported to MJCF: a random full inertia that satisfies A + B >= C."""


# ----------------------------------------------------------------------------------------------
# Coordinate maps
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [0, 1, 3])
def test_coordinate_maps_round_trip(n):
    """paper -> Pinocchio -> paper is the identity on the manifold (unit u, u̇ ⊥ u), and
    Pinocchio -> paper -> Pinocchio for any unit quaternion; the batch map equals the single one."""
    rng = np.random.default_rng(11 + n)
    scene = _scene(5, n)
    Q, QD, QP, VP = [], [], [], []
    for _ in range(20):
        _, q, qd = manifold_state(rng, scene)
        q_pin, v_pin = paper_to_pinocchio(q, qd)
        q2, qd2 = pinocchio_to_paper(q_pin, v_pin)
        np.testing.assert_allclose(q2, q, rtol=0, atol=MAP_ABS)
        np.testing.assert_allclose(qd2, qd, rtol=0, atol=MAP_ABS)
        q_pin2, v_pin2 = paper_to_pinocchio(q2, qd2)
        np.testing.assert_allclose(q_pin2, q_pin, rtol=0, atol=MAP_ABS)
        np.testing.assert_allclose(v_pin2, v_pin, rtol=0, atol=MAP_ABS)
        Q.append(q), QD.append(qd), QP.append(q_pin), VP.append(v_pin)
    qb, qdb, _, omega = pinocchio_to_paper_batch(np.array(QP), np.array(VP), np.zeros((20, n + 6)))
    np.testing.assert_allclose(qb, np.array(Q), rtol=0, atol=MAP_ABS)
    np.testing.assert_allclose(qdb, np.array(QD), rtol=0, atol=MAP_ABS)
    np.testing.assert_allclose(omega, np.array(VP)[:, 3:6], rtol=0, atol=MAP_ABS)
    # -u is the same attitude: Pinocchio's rotation and ω are unchanged
    q, qd = Q[0].copy(), QD[0].copy()
    q[3:7] *= -1
    qd[3:7] *= -1
    q_pin, v_pin = paper_to_pinocchio(q, qd)
    np.testing.assert_allclose(
        pin.XYZQUATToSE3(q_pin[:7]).rotation, S(Q[0][3:7]), rtol=0, atol=MAP_ABS
    )
    np.testing.assert_allclose(v_pin, VP[0], rtol=0, atol=MAP_ABS)


def test_coordinate_maps_agree_with_pinocchios_kinematics():
    """The maps against Pinocchio's own kinematics: the quaternion order (x, y, z, w), the rotation,
    the inertial velocity of C (``getVelocity``, LOCAL_WORLD_ALIGNED) and its classical acceleration
    (``getClassicalAcceleration``) are the paper's S(u), Ṙ and R̈; ω and ω̇ are body-axis."""
    rng = np.random.default_rng(3)
    scene = _scene(8, 2)
    model = build_model(scene)
    data = model.createData()
    LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for _ in range(10):
        _, q, qd = manifold_state(rng, scene)
        q_pin, v_pin = paper_to_pinocchio(q, qd)
        a_pin = rng.normal(size=model.nv)
        pin.forwardKinematics(model, data, q_pin, v_pin, a_pin)
        np.testing.assert_allclose(data.oMi[1].rotation, S(q[3:7]), rtol=0, atol=MAP_ABS)
        np.testing.assert_allclose(data.oMi[1].translation, q[:3], rtol=0, atol=MAP_ABS)
        vel = pin.getVelocity(model, data, 1, LWA)
        np.testing.assert_allclose(vel.linear, qd[:3], rtol=0, atol=MAP_ABS)
        np.testing.assert_allclose(
            S(q[3:7]).T @ vel.angular, omega_of(q[3:7], qd[3:7]), rtol=0, atol=MAP_ABS
        )
        qdd = pinocchio_to_paper_acc(q_pin, v_pin, a_pin)
        acc = pin.getClassicalAcceleration(model, data, 1, LWA)
        np.testing.assert_allclose(qdd[:3], acc.linear, rtol=0, atol=10 * MAP_ABS)
        # ω̇ from ü: ω̇ = H(u) ü (Ḣ u̇ = 0 on the manifold)
        np.testing.assert_allclose(
            omega_of(q[3:7], qdd[3:7]), a_pin[3:6], rtol=0, atol=10 * MAP_ABS
        )
        np.testing.assert_allclose(qdd[7:], a_pin[6:], rtol=0, atol=0)


# ----------------------------------------------------------------------------------------------
# Mass properties
# ----------------------------------------------------------------------------------------------


def _joint_axis(model, j: int) -> np.ndarray:
    """The linear velocity, in the joint's frame, of prismatic joint j's frame for a unit rate."""
    data = model.createData()
    v = np.zeros(model.nv)
    v[model.joints[j].idx_v] = 1.0
    pin.forwardKinematics(model, data, pin.neutral(model), v)
    return np.array(data.v[j].linear)


def _mass_cases():
    cases = [(name, paper_scene(name)) for name in ("paper_example1", "paper_example2")]
    for n in range(6):
        kind = MJCF_KINDS[n % 3]
        cases.append((f"n{n}_{kind}", _scene(100 + n, n, inertia_kind=kind)))
    eff = [e for e in ALL_FORCES if e not in ("mass_inertia", "gravity")]
    cases.append(("n3_point_masses_no_gravity", _scene(7, 3, effects=eff)))
    return cases


def _close(a, b, scale=None) -> bool:
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(float(np.max(np.abs(b))), 1e-300) if scale is None else scale
    return float(np.max(np.abs(a - b), initial=0.0)) <= MASS_PROP_REL * scale


@pytest.mark.parametrize(
    ("label", "scene"), _mass_cases(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_mass_properties_equal_the_scene(label, scene):
    n = scene.n
    model = build_model(scene)
    assert (model.nq, model.nv, model.njoints) == (n + 7, n + 6, n + 2)
    assert model.joints[1].shortname() == "JointModelFreeFlyer"
    assert list(model.parents)[1:] == [0] + [1] * n  # every mass a child of BR, not a chain
    J_scale = float(np.max(scene.body.inertia))
    br = model.inertias[1]
    assert br.mass == scene.body.mass
    assert np.all(br.lever == 0.0)
    assert _close(br.inertia, np.diag(scene.body.inertia))
    assert _close(model.jointPlacements[1].homogeneous, np.eye(4))
    Ji = mass_inertias(scene)
    for i in range(n):
        j = 2 + i
        assert model.joints[j].shortname() == "JointModelPrismaticUnaligned"
        assert _close(model.joints[j].extract().axis, scene.rod.axis)
        assert _close(model.jointPlacements[j].rotation, np.eye(3))
        assert _close(model.jointPlacements[j].translation, scene.rod.offset)
        assert model.inertias[j].mass == scene.masses.mass[i]
        assert np.all(model.inertias[j].lever == 0.0)
        assert _close(model.inertias[j].inertia, Ji[i], scale=J_scale)
        if scene.has(Effect.MASS_INERTIA):
            assert _close(Ji[i], scene.masses.inertia[i], scale=J_scale)
        else:
            assert np.all(Ji[i] == 0.0)
    g = scene.gravity if scene.has(Effect.GRAVITY) else np.zeros(3)
    assert np.all(model.gravity.linear == g) and np.all(model.gravity.angular == 0.0)
    assert np.all(model.armature == 0.0)
    # the system inertia the analytic model uses (J of Eq. 51 with Remark 1)
    J_total = br.inertia + sum(model.inertias[2 + i].inertia for i in range(n))
    assert _close(J_total, TumblingModel(scene).J, scale=J_scale)


@pytest.mark.parametrize(
    ("label", "scene"), _mass_cases(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_mass_properties_equal_those_read_from_the_exported_mjcf(label, scene, tmp_path):
    """``pin.buildModelFromMJCF`` of ``model_xml.to_mjcf(scene)``: the same tree, placements, axes,
    masses, gravity; the same inertias body by body (the MJCF pads a point mass with a tiny isotropic
    inertia taken off BR, model_xml.builder.mass_inertias: compared with that padding added) and the
    same joint-space mass matrix (crba) at random configurations."""
    from model_xml.builder import mass_inertias as mjcf_mass_inertias

    path = tmp_path / f"{label}.xml"
    path.write_text(to_mjcf(scene), encoding="utf-8")
    mj = pin.buildModelFromMJCF(str(path))
    ours = build_model(scene)
    n = scene.n
    assert (mj.nq, mj.nv, mj.njoints) == (ours.nq, ours.nv, ours.njoints)
    assert list(mj.parents) == list(ours.parents)
    assert list(mj.names)[1:] == list(ours.names)[1:]
    assert mj.joints[1].shortname() == "JointModelFreeFlyer"
    # Pinocchio 4.1's MJCF reader ignores <option gravity> (it keeps its default 0, 0, -9.81), so
    # a plant built from the MJCF must set gravity from the scene, as build_model does.
    assert np.all(mj.gravity.linear == [0.0, 0.0, -9.81])
    J_scale = float(np.max(scene.body.inertia))
    padded, pad = mjcf_mass_inertias(scene)
    for j in range(1, n + 2):
        assert _close(mj.jointPlacements[j].homogeneous, ours.jointPlacements[j].homogeneous, 10.0)
        assert _close(mj.inertias[j].mass, ours.inertias[j].mass)
        assert _close(mj.inertias[j].lever, ours.inertias[j].lever, scale=1.0)
        if j >= 2:
            # the reader picks JointModelPX/PY/PZ when a is a coordinate axis: compare the motion
            # (the velocity of the joint's frame for a unit rate), not the joint type
            assert _close(_joint_axis(mj, j), _joint_axis(ours, j), scale=1.0)
            assert _close(_joint_axis(ours, j), scene.rod.axis, scale=1.0)
            want = padded[j - 2]
        else:
            want = ours.inertias[1].inertia - pad * np.eye(3)
        assert _close(mj.inertias[j].inertia, want, scale=J_scale)
    d_mj, d_ours = mj.createData(), ours.createData()
    for _ in range(5):
        q = pin.randomConfiguration(ours, -np.ones(ours.nq), np.ones(ours.nq))
        M1 = pin.crba(mj, d_mj, q)
        M2 = pin.crba(ours, d_ours, q)
        assert _close(np.triu(M1), np.triu(M2)), float(np.max(np.abs(M1 - M2)))


# ----------------------------------------------------------------------------------------------
# Pointwise dynamics
# ----------------------------------------------------------------------------------------------


def _pointwise_cases():
    cases = []
    for n in range(6):
        for kind in ("body", "ring"):
            cases.append((f"n{n}_{kind}", _scene(200 + 10 * n + len(kind), n, inertia_kind=kind)))
    cases.append(("n2_axial", _scene(301, 2, inertia_kind="axial")))
    cases.append(("n3_point_no_gravity", _scene(302, 3, effects=["springs.cubic"])))
    return cases


@pytest.mark.parametrize(
    ("label", "scene"), _pointwise_cases(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_accelerations_equal_the_analytic_model_uncontrolled(label, scene):
    plant = PinocchioDynamics(scene)
    model = TumblingModel(scene)
    rng = np.random.default_rng(len(label))
    for _ in range(10):
        t, q, qd = manifold_state(rng, scene)
        a_pin, ctl = plant.acceleration(t, q, qd)
        a_ref, _ = model.acceleration(t, q, qd)
        assert ctl is None
        assert _rel(a_pin, a_ref) <= ACC_REL, (label, _rel(a_pin, a_ref))


def _controlled_cases():
    cases = []
    for n in range(6):
        kind = KINDS[n % 3]
        cases.append((f"n{n}_{kind}_gauss", _scene(400 + n, n, inertia_kind=kind, controlled=True)))
    for w in ("M^-2", "identity"):
        for n in (0, 2, 5):
            cases.append(
                (f"n{n}_{w}", _scene(500 + n, n, inertia_kind="ring", controlled=True, weighting=w))
            )
    return cases


@pytest.mark.parametrize(
    ("label", "scene"), _controlled_cases(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_accelerations_equal_the_analytic_model_controlled(label, scene):
    """With the controller: the analytic model's controlled q̈ (Eq. 89) against Pinocchio's q̈ under
    the control forces the same controller gives at that state (torque into τ[3:6], rod forces on
    the prismatic joints, a force at C as Sᵀ F). The plant's controller here is the numpy model's, so
    both sides use the very same control forces; the compiled controller is compared for the paper's
    weighting (its own agreement with the numpy one, 1e-12, is tests/analytic/test_fast.py's)."""
    model = TumblingModel(scene)
    plants = [PinocchioDynamics(scene, ControllerSource.ANALYTIC)]
    if scene.control.weighting == "M^-1":
        plants.append(PinocchioDynamics(scene, ControllerSource.ANALYTIC_FAST))
    rng = np.random.default_rng(len(label) + 1)
    for _ in range(10):
        t, q, qd = manifold_state(rng, scene)
        a_ref, c_ref = model.acceleration(t, q, qd)
        for plant in plants:
            a_pin, ctl = plant.acceleration(t, q, qd)
            assert _rel(a_pin, a_ref) <= ACC_REL, (label, plant.controller, _rel(a_pin, a_ref))
            assert _rel(ctl.torque, c_ref.torque) <= ACC_REL
    if scene.control.weighting == "M^-2" and scene.n:
        assert np.any(c_ref.force_at_C != 0.0)  # the force at C path is exercised


def test_spring_and_given_forces_are_those_of_eq38_and_remark2():
    """The generalized force Pinocchio receives, uncontrolled: ``τ_p = −∂U_s/∂p`` (finite
    differences of the analytic spring energy), ``τ[3:6]`` = the given torque, no force at C."""
    from analytic.model import spring_energy

    scene = _scene(9, 4)
    plant = PinocchioDynamics(scene)
    model = TumblingModel(scene)
    rng = np.random.default_rng(9)
    t, q, qd = manifold_state(rng, scene)
    tau = plant.generalized_force(t, plant.state_from_paper(q, qd))
    h = 1e-6
    grad = np.array(
        [
            (
                spring_energy(model, (q[7:] + h * e)[None])[0]
                - spring_energy(model, (q[7:] - h * e)[None])[0]
            )
            / (2 * h)
            for e in np.eye(4)
        ]
    )
    np.testing.assert_allclose(tau[6:], -grad, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(tau[3:6], scene.external_torque.at(t), rtol=1e-15, atol=0)
    assert np.all(tau[:3] == 0.0)


# ----------------------------------------------------------------------------------------------
# Trajectories
# ----------------------------------------------------------------------------------------------


def _agreement(a, b) -> dict[str, float]:
    out = {
        "C": float(np.max(np.linalg.norm(a.R - b.R, axis=1))),
        "attitude": float(np.max(_attitude_angle(a.u, b.u))),
    }
    out["p"] = float(np.max(np.abs(a.p - b.p))) if a.n else 0.0
    return out


def test_trajectory_record_and_short_agreement_controlled_example1():
    """2 s of the controlled Example 1 at the scene's tolerances (rtol 1e-12): the same record as
    the analytic plant (times, shapes, engine) and the same motion, control and tracking."""
    scene = paper_scene("paper_example1_controlled")
    ana = analytic_simulate(scene, t_end=2.0)
    pn = simulate(scene, t_end=2.0)
    assert pn.engine == Engine.PINOCCHIO and pn.status is RunStatus.OK, pn.message
    np.testing.assert_array_equal(pn.t, ana.t)
    for f in ("q", "qdot", "qddot", "QC", "torque", "rod_forces", "force_at_C", "residual_norm"):
        assert getattr(pn, f).shape == getattr(ana, f).shape, f
    agree = _agreement(pn, ana)
    assert max(agree.values()) <= AGREE_M, agree
    # velocities, accelerations and the control itself, relative to their scales
    for f in ("qdot", "qddot", "torque", "rod_forces"):
        x, ref = getattr(pn, f), getattr(ana, f)
        assert np.max(np.abs(x - ref)) <= RATE_REL * np.max(np.abs(ref)), f
    assert np.max(np.abs(pn.tracking.e_p - ana.tracking.e_p)) <= AGREE_M
    # the paper's cost gives no force at C; balances closed on Pinocchio's samples too
    assert np.all(pn.force_at_C == 0.0)
    inv = pn.invariants
    assert np.max(np.abs(inv.energy_balance())) <= BALANCE_REL * np.max(np.abs(inv.energy))
    L = np.max(np.linalg.norm(inv.angular_momentum, axis=1))
    assert np.max(np.abs(inv.angular_momentum_balance())) <= BALANCE_REL * L
    assert np.max(np.abs(inv.quat_norm_error)) <= QUAT_NORM
    assert pn.info["nfev"] > 0 and pn.info["controller_fallbacks"] == 0


@pytest.mark.parametrize(
    "name",
    ["paper_example1", "paper_example1_controlled", "paper_example2", "paper_example2_controlled"],
)
def test_twenty_seconds_agree_with_the_analytic_plant(name):
    """Over the scene's 20 s, Pinocchio and the analytic plant agree to 1e-9 m / rad in C,
    the rod positions and the attitude (figures at AGREE_M); about 1 s each."""
    scene = paper_scene(name)
    rtol = atol = None
    if name == "paper_example1_controlled":
        rtol, atol = CONTROLLED_EX1_RTOL, CONTROLLED_EX1_RTOL / 10
    ana = analytic_simulate(scene, rtol=rtol, atol=atol)
    pn = simulate(scene, PinocchioSettings(rtol=rtol, atol=atol))
    assert pn.status is RunStatus.OK and pn.t[-1] == scene.output.t_end
    agree = _agreement(pn, ana)
    assert max(agree.values()) <= AGREE_M, agree
    if scene.controlled:  # and it tracks as the paper says, as closely as the analytic plant
        assert np.max(np.abs(pn.tracking.e_p[-1] - ana.tracking.e_p[-1])) <= AGREE_M


# ----------------------------------------------------------------------------------------------
# Paths, settings, failures
# ----------------------------------------------------------------------------------------------


def test_identity_weighting_runs_on_the_compiled_controller():
    """The compiled kernel does the identity weighting too: no stage's control comes from the
    numpy model, and the run agrees with the analytic plant."""
    scene = _scene(600, 2, inertia_kind="ring", controlled=True, weighting="identity")
    pn = simulate(scene, t_end=0.2)
    ana = analytic_simulate(scene, t_end=0.2)
    assert pn.status is RunStatus.OK
    assert pn.info["controller_fallbacks"] == 0 and pn.info["nfev"] > 0
    assert max(_agreement(pn, ana).values()) <= AGREE_M


def test_settings_are_checked():
    with pytest.raises(ValueError, match=r"^method:"):
        PinocchioSettings(method="Euler")
    with pytest.raises(ValueError, match=r"^controller:"):
        PinocchioSettings(controller="mujoco")
    with pytest.raises(ValueError, match=r"^rtol:"):
        PinocchioSettings(rtol=-1.0)
    s = PinocchioSettings(method="RK45", rtol=1e-9)
    assert s.method is SolverMethod.RK45
    scene = paper_scene("paper_example1")
    assert s.resolved(scene) == (1e-9, scene.solver.atol, scene.solver.max_step)
    with pytest.raises(ValueError, match=r"^t_end:"):
        simulate(scene, t_end=-1.0)


def test_interrupted_run_keeps_the_samples_reached():
    scene = paper_scene("paper_example2")

    def stop(t):
        if t > 0.3:
            raise KeyboardInterrupt

    tr = simulate(scene, t_end=2.0, progress=stop)
    assert tr.status is RunStatus.INTERRUPTED and "interrupted at t =" in tr.message
    assert 0.3 <= tr.t[-1] < 2.0 and np.all(np.isfinite(tr.q))
    assert tr.q.shape[0] == tr.t.shape[0] == tr.invariants.energy.shape[0]


def test_rhs_is_the_plants_dynamics():
    """The integrator's right-hand side (compiled stage + aba + compiled finish) equals the paper
    state's derivative from the plant's own pointwise acceleration."""
    scene = paper_scene("paper_example2_controlled")
    plant = PinocchioDynamics(scene)
    rng = np.random.default_rng(4)
    t, q, qd = manifold_state(rng, scene, scale=0.1)
    y = plant.state_from_paper(q, qd)
    ydot = plant.rhs(t, y)
    nq = plant.nq
    qdd, _ = plant.acceleration(t, q, qd)
    np.testing.assert_allclose(ydot[:3], qd[:3], rtol=0, atol=0)
    np.testing.assert_allclose(ydot[[6, 3, 4, 5]], qd[3:7], rtol=0, atol=1e-15)  # xyzw -> w first
    np.testing.assert_allclose(ydot[7:nq], qd[7:], rtol=0, atol=0)
    np.testing.assert_allclose(ydot[nq : nq + 3], qdd[:3], rtol=1e-13, atol=0)
    omega_dot = omega_of(q[3:7], qdd[3:7])
    np.testing.assert_allclose(ydot[nq + 3 : nq + 6], omega_dot, rtol=0, atol=1e-12 * 50)
    np.testing.assert_allclose(ydot[nq + 6 : 2 * nq - 1], qdd[7:], rtol=1e-13, atol=0)


def test_importing_without_pinocchio_works_and_building_says_how_to_install():
    """Everything imports without pin; only building the Pinocchio plant asks for it."""
    code = (
        "import sys; sys.modules['pinocchio'] = None\n"
        "import mj_bridge.pinocchio_plant as pp, mj_bridge.pinocchio_model as pm\n"
        "from tests.support.mj_scenes import paper_scene\n"
        "try:\n"
        "    pp.PinocchioDynamics(paper_scene('paper_example1'))\n"
        "except ImportError as e:\n"
        "    print('IMPORTERROR', e)\n"
    )
    root = Path(__file__).resolve().parents[2]
    env_path = str(root)
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=root,
        env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin", "NUMBA_DISABLE_JIT": "0"},
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert "IMPORTERROR" in out.stdout and "pip install" in out.stdout
