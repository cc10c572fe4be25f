"""model_xml: the MJCF twin built from a scene.

References: closed forms (spring law of Eq. 38, the paper's mass properties of Example 1), the
scene's own data, and the spec compiled directly (for the text round trip).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analytic.effects import Effect, SpringModel
from analytic.scene import MujocoSettings
from mj_bridge import Twin, installed
from mj_bridge.callbacks import spring_user_bias
from model_xml import (
    TORQUE_ACTUATORS,
    BodyFrame,
    build_spec,
    force_actuator_name,
    joint_name,
    mass_name,
    tendon_name,
    to_mjcf,
)
from model_xml.primitives import (
    Primitive,
    PrimitiveKind,
    mass_properties,
    match_axes,
    paper_example1_primitives,
    rod_in_principal,
)
from model_xml.regenerate import PAPER_SCENES, generate, xml_path
from tests.support import tolerances as th
from tests.support.mj_scenes import PAPER, paper_scene, random_scene, random_state

# Test-only tolerances of the checked-in MJCF comparison (the shared ones: tests/support/tolerances.py).
MJCF_NUM_REL = 1e-12
"""A number of the checked-in MJCF vs the regenerated one, relative to the attribute's largest
magnitude: the numbers come from an SVD (box rotation), eigh (principal frames) and a few rotations,
whose last bits depend on the BLAS/LAPACK build and the CPU (seen: 1-2 ulp, ~1e-16); 1e-12 leaves a
10⁴ margin yet is far below any real change of the model (the scene data have 4-5 digits)."""

MJCF_QUAT_CHORD = 1e-12
"""Quaternions compared as rotations, q and -q being one: min(|a - b|, |a + b|) of the unit
quaternions (half the angle between the rotations, rad, when small); same budget as above."""


def _qacc(m: mujoco.MjModel, qpos, qvel, ctrl) -> np.ndarray:
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    d.qvel[:] = qvel
    d.ctrl[: len(ctrl)] = ctrl
    with installed(act_bias=spring_user_bias):
        mujoco.mj_forward(m, d)
    return d.qacc.copy()


def _scenes():
    rng = np.random.default_rng(3)
    out = [(name, paper_scene(name)) for name in PAPER]
    for k in range(4):
        out.append((f"random{k}", random_scene(rng, controlled=bool(k % 2))))
    out.append(("spring_actuators", random_scene(rng, 4, spring_model="actuator")))
    return out


@pytest.mark.parametrize(
    ("label", "scene"), _scenes(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_xml_text_and_spec_give_same_qacc(label, scene):
    """Full-precision MJCF recompiles to the same dynamics as the spec (to_xml alone would not)."""
    kw = {
        "body_frame": BodyFrame(pos=np.array([0.3, -0.2, 1.1]), quat=np.array([0.6, 0.0, 0.8, 0.0]))
    }
    spec = build_spec(scene, **kw) if label == "spring_actuators" else build_spec(scene)
    m_spec = spec.compile()
    text = to_mjcf(scene, **kw) if label == "spring_actuators" else to_mjcf(scene)
    m_xml = mujoco.MjModel.from_xml_string(text)
    rng = np.random.default_rng(7)
    for _ in range(3):
        qpos = np.concatenate([rng.normal(size=3), rng.normal(size=4), rng.normal(size=scene.n)])
        qpos[3:7] /= np.linalg.norm(qpos[3:7])
        qvel = rng.normal(size=m_spec.nv)
        ctrl = rng.normal(size=m_spec.nu) * 1e3
        a1 = _qacc(m_spec, qpos, qvel, ctrl)
        a2 = _qacc(m_xml, qpos, qvel, ctrl)
        assert np.max(np.abs(a1 - a2)) <= th.XML_VS_SPEC_QACC_REL.value * np.max(np.abs(a1))
    # Bit-identity is legitimate here: one process writes the text (repr: the shortest decimal
    # that parses back to the same double, on any machine) and compiles both with the same code.
    for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "body_pos", "jnt_axis"):
        np.testing.assert_array_equal(getattr(m_spec, field), getattr(m_xml, field), err_msg=field)


def test_mujoco_to_xml_alone_is_not_enough():
    """Documents why to_mjcf exists: MuJoCo's own writer loses digits (or the inertial)."""
    scene = paper_scene("paper_example1")
    spec = build_spec(scene)
    txt = spec.to_xml()
    try:
        m_xml = mujoco.MjModel.from_xml_string(txt)
    except ValueError:
        return  # the explicit inertial at C was dropped: the text does not even compile
    assert not np.array_equal(m_xml.body_inertia, spec.compile().body_inertia)


_INT_LIST = re.compile(r"\s*[+-]?\d+(\s+[+-]?\d+)*\s*")


def _floats(text: str) -> np.ndarray | None:
    try:
        return np.array([float(x) for x in text.split()])
    except ValueError:
        return None


def _unit(q: np.ndarray) -> np.ndarray:
    return q / np.linalg.norm(q)


def _inertia_tensor(el: ET.Element) -> np.ndarray:
    R = Rotation.from_quat(_floats(el.get("quat", "1 0 0 0")), scalar_first=True).as_matrix()
    return R @ np.diag(_floats(el.get("diaginertia"))) @ R.T


def _attribute_difference(tag: str, key: str, a: str, b: str) -> str | None:
    """Why two values of one attribute differ beyond round-off (None: they agree)."""
    if a == b:
        return None
    va, vb = _floats(a), _floats(b)
    if va is None or vb is None or va.shape != vb.shape or _INT_LIST.fullmatch(a + " " + b):
        return f"{a!r} vs {b!r}"  # names, keywords, counts, flags: must be identical
    if key == "quat" and tag == "inertial":
        return None  # compared as the inertia tensor (see _mjcf_differences)
    if key == "quat":
        chord = min(np.linalg.norm(_unit(va) - _unit(vb)), np.linalg.norm(_unit(va) + _unit(vb)))
        ok = chord <= MJCF_QUAT_CHORD
        return None if ok else f"rotations {chord:.2e} apart: {a!r} vs {b!r}"
    scale = max(np.max(np.abs(va)), np.max(np.abs(vb)))
    err = np.max(np.abs(va - vb))
    ok = err <= MJCF_NUM_REL * scale
    return None if ok else f"differ by {err:.2e} (scale {scale:.3g}): {a!r} vs {b!r}"


def _mjcf_differences(want: str, got: str) -> list[str]:
    """Differences between two MJCF texts beyond the stated tolerances: the same elements in the
    same order, the same attribute names, identical non-numeric values, numbers within
    MJCF_NUM_REL, quaternions within MJCF_QUAT_CHORD as rotations. An ``<inertial>`` is compared
    by its inertia tensor Rot(quat) diag(diaginertia) Rot(quat)ᵀ rather than its quat: with two
    equal moments (a mass's ring of Remark 1, A = B) the principal frame is any rotation about the
    third axis, and eigh's choice depends on the LAPACK build."""
    out: list[str] = []

    def walk(a: ET.Element, b: ET.Element, path: str) -> None:
        here = f"{path}/{a.tag}" + (f"[{a.get('name')}]" if a.get("name") else "")
        if a.tag != b.tag:
            out.append(f"{here}: element {a.tag!r} vs {b.tag!r}")
            return
        if set(a.attrib) != set(b.attrib):
            out.append(f"{here}: attributes {sorted(a.attrib)} vs {sorted(b.attrib)}")
        if (a.text or "").strip() != (b.text or "").strip():
            out.append(f"{here}: text {a.text!r} vs {b.text!r}")
        for key in sorted(set(a.attrib) & set(b.attrib)):
            why = _attribute_difference(a.tag, key, a.get(key), b.get(key))
            if why:
                out.append(f"{here} {key}: {why}")
        if a.tag == "inertial" and a.get("diaginertia") and b.get("diaginertia"):
            Ia, Ib = _inertia_tensor(a), _inertia_tensor(b)
            err, scale = np.max(np.abs(Ia - Ib)), np.max(np.abs(Ib))
            if not err <= MJCF_NUM_REL * scale:
                out.append(f"{here}: inertia tensors differ by {err:.2e} (scale {scale:.3g})")
        if len(a) != len(b):
            out.append(f"{here}: {len(a)} vs {len(b)} child elements")
        for ca, cb in zip(a, b, strict=False):
            walk(ca, cb, here)

    walk(ET.fromstring(want), ET.fromstring(got), "")
    return out


def _compiled_inertias(text: str) -> tuple[np.ndarray, np.ndarray]:
    """Body masses and MuJoCo's com-based inertias (cinert: tensor, m·offset, m per body, in the
    world frame at qpos0), which do not depend on the choice of principal frames."""
    m = mujoco.MjModel.from_xml_string(text)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    return m.body_mass.copy(), d.cinert.copy()


@pytest.mark.parametrize("name", PAPER_SCENES)
def test_checked_in_mjcf_is_reproduced(name):
    """model_xml/<name>.xml is what ``python -m model_xml.regenerate`` writes, to round-off: the
    file may come from another machine, whose LAPACK/CPU gives other last digits, so the texts are
    compared as XML trees with numeric tolerances (see _mjcf_differences), not character by
    character; and the two compile to the same masses and inertias."""
    checked_in = xml_path(name).read_text(encoding="utf-8")
    fresh = generate(name)
    diffs = _mjcf_differences(checked_in, fresh)
    assert not diffs, f"{xml_path(name).name} is stale (python -m model_xml.regenerate): {diffs}"
    (mass_a, cin_a), (mass_b, cin_b) = _compiled_inertias(checked_in), _compiled_inertias(fresh)
    np.testing.assert_allclose(mass_a, mass_b, rtol=MJCF_NUM_REL, atol=0)
    for b in range(len(cin_b)):
        scale = np.max(np.abs(cin_b[b]))
        np.testing.assert_allclose(cin_a[b], cin_b[b], rtol=0, atol=MJCF_NUM_REL * scale)


def test_mjcf_comparison_ignores_only_round_off():
    """The tolerant comparison above still catches real changes: last digits, a sign-flipped
    quaternion and another principal frame of a ring's inertia pass; a number off by 1e-9, a renamed
    joint, a missing element pass not."""
    text = generate("paper_example1_controlled")

    def edited(edit) -> str:
        root = ET.fromstring(text)
        edit(root)
        return ET.tostring(root, encoding="unicode")

    def fmt(values) -> str:
        return " ".join(repr(float(x)) for x in values)

    def box(root):
        return next(g for g in root.iter("geom") if g.get("name") == "block")

    def last_digits(root):
        g = box(root)
        g.set("quat", fmt(_floats(g.get("quat")) * (1 + 2e-16)))
        g.set("pos", fmt(np.nextafter(_floats(g.get("pos")), np.inf)))

    def sign_flip(root):
        box(root).set("quat", fmt(-_floats(box(root).get("quat"))))

    def ring_frame(root):  # mass1's ring: A = B, so any rotation about the third principal axis
        inert = root.find(".//body[@name='mass1']/inertial")
        q = Rotation.from_quat(_floats(inert.get("quat")), scalar_first=True)
        q = q * Rotation.from_rotvec([0.0, 0.0, 0.7])
        inert.set("quat", fmt(q.as_quat(scalar_first=True)))

    for edit in (last_digits, sign_flip, ring_frame):
        assert _mjcf_differences(text, edited(edit)) == [], edit.__name__

    def number_off(root):
        g = box(root)
        g.set("pos", fmt(_floats(g.get("pos")) * (1 + 1e-9)))

    def quat_off(root):
        q = Rotation.from_quat(_floats(box(root).get("quat")), scalar_first=True)
        q = q * Rotation.from_rotvec([1e-9, 0.0, 0.0])
        box(root).set("quat", fmt(q.as_quat(scalar_first=True)))

    def inertia_off(root):
        inert = root.find(".//body[@name='mass2']/inertial")
        q = Rotation.from_quat(_floats(inert.get("quat")), scalar_first=True)
        q = q * Rotation.from_rotvec([1e-6, 0.0, 0.0])  # mixes the distinct moments B and C
        inert.set("quat", fmt(q.as_quat(scalar_first=True)))

    def renamed(root):
        root.find(".//joint[@name='p1']").set("name", "p1x")

    def dropped(root):
        root.find("tendon").remove(root.find("tendon")[0])

    for edit in (number_off, quat_off, inertia_off, renamed, dropped):
        assert _mjcf_differences(text, edited(edit)), edit.__name__


def test_names_and_layout_example2_controlled():
    scene = paper_scene("paper_example2_controlled")
    m = build_spec(scene).compile()
    n = scene.n
    assert m.nq == 7 + n and m.nv == 6 + n
    assert m.jnt_type[m.joint("root").id] == mujoco.mjtJoint.mjJNT_FREE
    for i in range(n):
        j = m.joint(joint_name(i)).id
        assert m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
        assert m.jnt_bodyid[j] == m.body(mass_name(i)).id
        np.testing.assert_allclose(m.jnt_axis[j], scene.rod.axis, rtol=0, atol=th.ULP_REL.value)
        # exact: the identity frame multiplies by 1 and adds 0; MuJoCo stores pos and mass as given
        np.testing.assert_allclose(m.body_pos[m.body(mass_name(i)).id], scene.rod.offset, atol=0)
        assert m.body_mass[m.body(mass_name(i)).id] == scene.masses.mass[i]
    assert m.ntendon == n + 1
    assert [m.tendon(tendon_name(j)).id for j in range(n + 1)] == list(range(n + 1))
    names = [m.actuator(k).name for k in range(m.nu)]
    assert names == [*TORQUE_ACTUATORS, *(force_actuator_name(i) for i in range(n))]
    # BR: explicit inertial at C along the principal axes, total mass conserved
    b = m.body("BR").id
    assert m.body_mass[b] == scene.body.mass
    np.testing.assert_array_equal(m.body_ipos[b], np.zeros(3))
    assert m.body_subtreemass[b] == pytest.approx(
        scene.body.mass + scene.masses.mass.sum(), rel=th.ULP_REL.value
    )
    # visual geoms are massless and never collide
    assert np.all(m.geom_contype == 0) and np.all(m.geom_conaffinity == 0)


def test_rotational_inertia_total_matches_paper_J():
    """At qpos = 0 with every mass at O' = d, the system inertia about C (from MuJoCo's bodies)
    equals J (incl. Remark 1's ring inertia) + Σ m_i (|d|² I - d dᵀ)."""
    scene = paper_scene("paper_example1")
    assert scene.has(Effect.MASS_INERTIA)
    m = build_spec(scene).compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    I_tot = np.zeros((3, 3))
    for b in range(1, m.nbody):
        R = d.ximat[b].reshape(3, 3)
        r = d.xipos[b]
        I_tot += R @ np.diag(m.body_inertia[b]) @ R.T
        I_tot += m.body_mass[b] * (r @ r * np.eye(3) - np.outer(r, r))
    dv = np.asarray(scene.rod.offset)
    J = np.diag(scene.body.inertia) + scene.masses.inertia.sum(axis=0)
    ref = J + scene.masses.mass.sum() * (dv @ dv * np.eye(3) - np.outer(dv, dv))
    np.testing.assert_allclose(I_tot, ref, rtol=0, atol=th.INERTIA_SUM_REL.value * np.max(ref))


def test_effects_map_onto_the_model():
    scene = paper_scene("paper_example1")
    m = build_spec(scene).compile()
    np.testing.assert_array_equal(m.opt.gravity, scene.gravity)
    assert m.nu == 0  # uncontrolled: no actuators
    np.testing.assert_array_equal(m.tendon_stiffness, scene.springs.k_linear)
    np.testing.assert_array_equal(m.tendon_stiffnesspoly[:, 1], scene.springs.k_cubic)
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    assert m.opt.timestep == scene.mujoco.timestep

    off = build_spec(scene.with_effects({Effect.SPRINGS_LINEAR})).compile()
    np.testing.assert_array_equal(off.opt.gravity, np.zeros(3))
    np.testing.assert_array_equal(off.tendon_stiffness, scene.springs.k_linear)
    np.testing.assert_array_equal(off.tendon_stiffnesspoly, 0.0)
    # no mass_inertia: the mass bodies carry only the tiny isotropic padding, taken off BR
    pad = off.body_inertia[off.body("mass1").id]
    assert np.all(pad < 1e-8 * scene.body.inertia.min())
    np.testing.assert_allclose(
        off.body_inertia[off.body("BR").id] + scene.n * pad[0],
        scene.body.inertia,
        rtol=th.ULP_REL.value,
    )

    bare = build_spec(scene.with_effects(set())).compile()
    assert bare.ntendon == 0 and bare.nu == 0

    torque_only = random_scene(np.random.default_rng(1), 2, controlled=False, external_torque=True)
    mt = build_spec(torque_only).compile()
    assert [mt.actuator(k).name for k in range(mt.nu)] == list(TORQUE_ACTUATORS)


def test_tendon_springs_follow_eq38():
    """Tendon forces and MuJoCo's spring energy against the closed form of Eq. (38)."""
    scene = paper_scene("paper_example2")
    no_gravity = scene.with_effects(scene.effects - {Effect.GRAVITY})
    m = build_spec(no_gravity).compile()
    d = mujoco.MjData(m)
    rng = np.random.default_rng(0)
    p = np.asarray(scene.masses.p_e) + rng.normal(scale=0.5, size=scene.n)
    d.qpos[3] = 1.0
    d.qpos[7:] = p
    mujoco.mj_forward(m, d)
    x = np.concatenate([[0.0], p - scene.masses.p_e, [0.0]])
    ext = np.diff(x)
    kl, kn = scene.springs.k_linear, scene.springs.k_cubic
    f = kl * ext + kn * ext**3
    F_ref = f[1:] - f[:-1]  # -∂U/∂p
    tol = th.SPRING_CLOSED_FORM_REL.value
    np.testing.assert_allclose(d.qfrc_passive[6:], F_ref, rtol=0, atol=tol * np.abs(f).max())
    U_ref = np.sum(0.5 * kl * ext**2 + 0.25 * kn * ext**4)
    assert d.energy[0] == pytest.approx(U_ref, rel=tol)


def test_rest_length_minus_one_is_not_mujocos_sentinel():
    """springlength = -1 means "length at qpos0" to MuJoCo; the builder flips such a tendon."""
    rng = np.random.default_rng(5)
    scene = random_scene(rng, 2, controlled=False)
    masses = scene.masses.__class__(
        mass=scene.masses.mass, p_e=np.array([-1.0, 0.5]), inertia=scene.masses.inertia
    )
    scene = scene.replace(masses=masses, initial=scene.initial)
    m = build_spec(scene).compile()
    assert np.all(m.tendon_lengthspring != -1.0)
    d = mujoco.MjData(m)
    d.qpos[3] = 1.0
    d.qpos[7:] = [-1.0, 0.5]  # at equilibrium: no spring force (exact: these are exact binary
    # fractions, so every tendon length equals its rest length exactly, on any machine)
    mujoco.mj_forward(m, d)
    assert np.max(np.abs(d.qfrc_passive[6:])) == 0.0


def test_spring_actuators_agree_with_tendon_springs():
    """The "spring actuator" form (affine bias + user-bias cubic term) vs native tendon springs."""
    rng = np.random.default_rng(11)
    for k in range(3):
        scene = random_scene(rng, controlled=bool(k % 2))
        alt = scene.replace(mujoco=MujocoSettings(spring_model=SpringModel.ACTUATOR))
        tw_t, tw_a = Twin(scene), Twin(alt)
        assert tw_a.m.nu == tw_t.m.nu + scene.n + 1
        for _ in range(3):
            t, q, qd = random_state(rng, scene)
            a1 = tw_t.acceleration(t, q, qd)
            a2 = tw_a.acceleration(t, q, qd)
            assert np.max(np.abs(a1 - a2)) <= th.SPRING_ACTUATOR_VS_TENDON_REL.value * np.max(
                np.abs(a1)
            )


def test_body_frame_option_moves_only_the_frame():
    """A BR body frame away from C: same inertial frame, masses, joint axes (in world)."""
    scene = paper_scene("paper_example1")
    bf = BodyFrame(pos=np.array([1.0, -2.0, 0.5]), quat=np.array([0.5, 0.5, 0.5, 0.5]))
    m = build_spec(scene, bf).compile()
    b = m.body("BR").id
    assert np.linalg.norm(m.body_ipos[b]) == pytest.approx(
        np.linalg.norm(bf.pos), rel=th.ULP_REL.value
    )
    assert m.body_mass[b] == scene.body.mass


def test_primitives_reproduce_example1_mass_properties():
    """Block + rod in aluminium: MuJoCo's mass and principal moments equal the paper's (4 digits);
    the rod line in principal axes gives the paper's a and d (to 1e-3)."""
    prims, rod = paper_example1_primitives()
    props = mass_properties(prims)
    assert props.mass == pytest.approx(4.597e5, rel=th.PRIMITIVE_SIG_DIGITS_REL.value)
    paper_J = np.array([1.3626e7, 1.5333e7, 0.3848e7])
    A = match_axes(props, paper_J, reference_axis=np.array([-0.3985, -0.1481, 0.9051]))
    moments = np.array([A[:, k] @ _inertia_in_design(props) @ A[:, k] for k in range(3)])
    np.testing.assert_allclose(moments, paper_J, rtol=th.PRIMITIVE_SIG_DIGITS_REL.value)
    a, d = rod_in_principal(props, rod["point"], rod["direction"], A)
    np.testing.assert_allclose(a, [-0.3985, -0.1481, 0.9051], atol=th.PRIMITIVE_ROD_ABS.value)
    np.testing.assert_allclose(d, [3.2616, 1.4196, -0.1623], atol=th.PRIMITIVE_ROD_ABS.value)
    # independent closed form for the mass: ρ (box volume + rod volume)
    assert props.mass == pytest.approx(
        2700 * (10 * 6 * 2 + np.pi * 16), rel=th.MASS_FORMULA_REL.value
    )


def _inertia_in_design(props):
    return props.axes @ np.diag(props.moments) @ props.axes.T


def test_closed_shell_cylinder_is_thin_wall_limit():
    """A closed thin shell (hollow cylinder with end caps): mass = ρ t (2πrh + 2πr²)."""
    r, h, t, rho = 4.0, 12.0, 0.02, 7000.0
    props = mass_properties(
        [Primitive(PrimitiveKind.CLOSED_SHELL, (r, h / 2), density=rho, thickness=t)]
    )
    assert props.mass == pytest.approx(
        rho * t * (2 * np.pi * r * h + 2 * np.pi * r * r), rel=th.MASS_FORMULA_REL.value
    )
    # axial moment of the lateral surface (m r²) and the two caps (m r²/2 each)
    m_lat, m_cap = rho * t * 2 * np.pi * r * h, rho * t * np.pi * r * r
    I = _inertia_in_design(props)
    assert I[2, 2] == pytest.approx(
        m_lat * r * r + 2 * m_cap * r * r / 2, rel=th.SHELL_CLOSED_FORM_REL.value
    )
    # transverse: lateral surface m (r²/2 + h²/12), each cap m (r²/4 + (h/2)²)
    I_t = m_lat * (r * r / 2 + h * h / 12) + 2 * m_cap * (r * r / 4 + h * h / 4)
    assert I[0, 0] == pytest.approx(I_t, rel=th.SHELL_CLOSED_FORM_REL.value)


def test_thick_tube_matches_closed_form():
    """Open thick-walled tube (exact mesh inertia) + two solid end caps vs closed forms."""
    R, t, h, rho = 4.0, 0.3, 12.0, 7000.0
    r = R - t
    tube = Primitive(PrimitiveKind.TUBE, (R, h / 2), density=rho, thickness=t)
    props = mass_properties([tube])
    m = rho * np.pi * (R * R - r * r) * h
    assert props.mass == pytest.approx(m, rel=th.TUBE_MESH_REL.value)
    I = _inertia_in_design(props)
    assert I[2, 2] == pytest.approx(m * (R * R + r * r) / 2, rel=th.TUBE_MESH_REL.value)
    assert I[0, 0] == pytest.approx(
        m * (3 * (R * R + r * r) + h * h) / 12, rel=th.TUBE_MESH_REL.value
    )
    np.testing.assert_allclose(props.com, 0.0, atol=th.KINEMATICS_REL.value * R)
    # with end caps (discs of radius r inside the ends): parallel-axis closed form
    caps = [
        Primitive(PrimitiveKind.CYLINDER, (r, t / 2), np.array([0, 0, z]), density=rho)
        for z in (-(h / 2 - t / 2), h / 2 - t / 2)
    ]
    props2 = mass_properties([tube, *caps])
    mc = rho * np.pi * r * r * t
    assert props2.mass == pytest.approx(m + 2 * mc, rel=th.TUBE_MESH_REL.value)
    I2 = _inertia_in_design(props2)
    Ic_t = mc * (3 * r * r + t * t) / 12 + mc * (h / 2 - t / 2) ** 2
    assert I2[0, 0] == pytest.approx(I[0, 0] + 2 * Ic_t, rel=th.TUBE_MESH_REL.value)


def test_bad_primitive_raises_naming_field():
    with pytest.raises(ValueError, match=r"Primitive\.size"):
        Primitive(PrimitiveKind.BOX, (1.0, 2.0))
    with pytest.raises(ValueError, match=r"Primitive\.thickness"):
        Primitive(PrimitiveKind.CYLINDER, (1.0, 2.0), thickness=0.1)
    with pytest.raises(ValueError, match=r"BodyFrame\.quat"):
        BodyFrame(quat=np.array([1.0, 1.0, 0.0, 0.0]))
