"""Scene loading: the paper's data, the attitude conventions, effects, and bad input.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import copy
import math
import tomllib
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analytic.model import TumblingModel
from analytic.scene import load_scene, scene_from_dict
from validation.scenes import scene_path

PAPER = [
    "paper_example1",
    "paper_example1_controlled",
    "paper_example2",
    "paper_example2_controlled",
]


def _raw(name: str) -> dict:
    with open(scene_path(name), "rb") as f:
        return tomllib.load(f)


@pytest.mark.parametrize("name", PAPER)
def test_paper_scenes_load_with_unit_quaternion(name):
    sc = load_scene(scene_path(name))
    assert abs(np.linalg.norm(sc.initial.u) - 1) < 1e-15
    # u̇(0) = ¼ Hᵀ ω(0) is tangent to the sphere and reproduces ω(0) (Eq. 12).
    u, ud = sc.initial.u, sc.initial.udot
    assert abs(u @ ud) < 1e-15
    H = 2 * np.array(
        [[-u[1], u[0], u[3], -u[2]], [-u[2], -u[3], u[0], u[1]], [-u[3], u[2], -u[1], u[0]]]
    )
    np.testing.assert_allclose(H @ ud, sc.initial.omega, atol=1e-14)


def test_example1_attitude_matches_printed_values():
    """ERRATA: S(u(0)) = Rot(ν, π/3)·P reproduces the printed u(0) and u̇(0) to their 4 digits."""
    sc = load_scene(scene_path("paper_example1"))
    np.testing.assert_allclose(sc.initial.u, [0.8034, 0.1600, 0.4272, 0.3828], atol=1e-4)
    np.testing.assert_allclose(sc.initial.udot, [0.0379, 0.6999, -0.2503, -0.0927], atol=1.5e-4)


def test_example2_attitude_closed_form():
    sc = load_scene(scene_path("paper_example2"))
    th = math.pi / 3
    nu = np.ones(3) / math.sqrt(3)
    np.testing.assert_allclose(
        sc.initial.u, np.r_[math.cos(th / 2), math.sin(th / 2) * nu], atol=1e-15
    )
    # printed u̇(0) with ERRATA's transposed digits fixed (third entry -0.5774)
    np.testing.assert_allclose(sc.initial.udot, [-0.2887, 0.8660, -0.5774, 0.5774], atol=1e-4)


def test_example1_ring_inertia_is_remark1_closed_form():
    sc = load_scene(scene_path("paper_example1"))
    a = sc.rod.axis
    for i, m in enumerate(sc.masses.mass):
        np.testing.assert_allclose(
            sc.masses.inertia[i], m * 1.0**2 / 2 * (np.eye(3) + np.outer(a, a))
        )


def test_example2_equilibria_uniform():
    sc = load_scene(scene_path("paper_example2"))
    np.testing.assert_allclose(np.diff(sc.masses.p_e), 11.96 / 6, rtol=1e-15)
    assert sc.masses.p_e[2] == 0.0


def test_effect_off_removes_its_term():
    """No springs.cubic: the model has no cubic term (Q does not depend on k_n at all)."""
    raw = _raw("paper_example1")
    raw["scene"]["effects"] = ["gravity", "springs.linear", "mass_inertia"]
    sc = scene_from_dict(raw)
    model = TumblingModel(sc)
    assert "springs.cubic" not in model.force_terms
    raw2 = copy.deepcopy(raw)
    raw2["springs"]["k_cubic"] = [1e30, 1e30, 1e30]
    model2 = TumblingModel(scene_from_dict(raw2))
    q, qd = sc.initial.q0(), sc.initial.qdot0()
    assert np.array_equal(model.generalized_force(0.0, q, qd), model2.generalized_force(0.0, q, qd))
    # and with it on, the huge stiffness shows
    raw2["scene"]["effects"].append("springs.cubic")
    model3 = TumblingModel(scene_from_dict(raw2))
    assert not np.allclose(
        model3.generalized_force(0.0, q, qd), model.generalized_force(0.0, q, qd)
    )


def test_mass_inertia_effect_switches_J():
    raw = _raw("paper_example1")
    on = TumblingModel(scene_from_dict(raw))
    raw["scene"]["effects"].remove("mass_inertia")
    off = TumblingModel(scene_from_dict(raw))
    np.testing.assert_allclose(on.J - off.J, on.scene.masses.inertia.sum(axis=0))
    assert np.array_equal(off.J, np.diag(off.scene.body.inertia))


def _set(d: dict, path: str, value):
    keys = path.split(".")
    for k in keys[:-1]:
        d = d[k]
    if value is _DELETE:
        del d[keys[-1]]
    else:
        d[keys[-1]] = value


_DELETE = object()

# (scene, dotted key, new value, field named in the message)
CORRUPTIONS = [
    ("paper_example1", "body.mass", -3.0, "body.mass"),
    ("paper_example1", "body.mass", 0.0, "body.mass"),
    ("paper_example1", "body.mass", float("nan"), "body.mass"),
    ("paper_example1", "body.mass", "4.6e5", "body.mass"),
    ("paper_example1", "body.mass", "__import__('os').system('true')", "body.mass"),
    ("paper_example1", "body.mass", _DELETE, "body.mass"),
    ("paper_example1", "body.inertia", [1.0, 2.0], "body.inertia"),
    ("paper_example1", "body.inertia", [1.0, 1.0, 5.0], "body.inertia"),
    ("paper_example1", "body.inertia", [1.0, float("inf"), 1.0], "body.inertia[1]"),
    ("paper_example1", "rod.axis", [0.0, 0.0, 0.0], "rod.axis"),
    ("paper_example1", "rod.axis", [1.0, 1.0, 0.0], "rod.axis"),
    ("paper_example1", "masses.mass", [5e5, -4e5], "masses.mass[1]"),
    ("paper_example1", "masses.p_e", [4.0], "masses.p_e"),
    ("paper_example1", "springs.k_linear", [6e6, 7.5e6], "springs.k_linear"),
    ("paper_example1", "springs.k_cubic", [1.0, -1.0, 1.0], "springs.k_cubic[1]"),
    ("paper_example1", "initial.p", [5.0, 11.0, 1.0], "initial.p"),
    ("paper_example1", "initial.Rdot", [1.0, 2.0], "initial.Rdot"),
    ("paper_example1", "scene.effects", ["gravity", "magnetism"], "scene.effects[1]"),
    ("paper_example1", "scene.colour", "red", "scene.colour"),
    ("paper_example1", "solver.method", "Euler", "solver.method"),
    ("paper_example1", "solver.rtol", -1.0, "solver.rtol"),
    ("paper_example1", "output.t_end", 0.0, "output.t_end"),
    ("paper_example1", "mujoco.integrator", "leapfrog", "mujoco.integrator"),
    (
        "paper_example1",
        "initial.attitude.reference_from_principal",
        [[1, 0, 0], [0, 1, 0], [0, 0, 2]],
        "initial.attitude.reference_from_principal",
    ),
    ("paper_example2_controlled", "control.masses.indices", [1, 2, 6], "control.masses.indices[2]"),
    ("paper_example2_controlled", "control.masses.indices", [1, 1, 2], "control.masses.indices"),
    ("paper_example2_controlled", "control.masses.l", [0.8, -1.0], "control.masses.l"),
    (
        "paper_example2_controlled",
        "control.masses.alpha",
        [2.0, 0.0, 2.0],
        "control.masses.alpha[1]",
    ),
    ("paper_example2_controlled", "control.omega.gamma", -0.4, "control.omega.gamma"),
    (
        "paper_example2_controlled",
        "control.omega.components",
        [0, 1],
        "control.omega.components[0]",
    ),
    ("paper_example2_controlled", "control.weighting", "M^-3", "control.weighting"),
    ("paper_example2_controlled", "control.omega", _DELETE, "control.omega"),
]


@pytest.mark.parametrize(("name", "key", "value", "field"), CORRUPTIONS)
def test_bad_input_names_the_field(name, key, value, field):
    raw = _raw(name)
    _set(raw, key, value)
    with pytest.raises(ValueError) as exc:
        scene_from_dict(raw)
    assert str(exc.value).startswith(field + ":"), str(exc.value)


def test_quaternion_normalised_refused_or_allowed():
    raw = _raw("paper_example2")
    u = [0.8660254037844387, 0.28867513459481287, 0.28867513459481287, 0.28867513459481287]
    raw["initial"]["attitude"] = {"quaternion": [x * (1 + 1e-8) for x in u]}
    with pytest.warns(UserWarning, match="initial.attitude.quaternion"):
        sc = scene_from_dict(raw)
    assert abs(np.linalg.norm(sc.initial.u) - 1) < 1e-15
    raw["initial"]["attitude"] = {"quaternion": [x * 1.1 for x in u]}
    with pytest.raises(ValueError, match=r"^initial\.attitude\.quaternion:"):
        scene_from_dict(raw)
    raw["initial"]["attitude"] = {"quaternion": [x * 1.1 for x in u], "allow_off_manifold": True}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc = scene_from_dict(raw)
    assert abs(np.linalg.norm(sc.initial.u) - 1.1) < 1e-14
    # u̇ still reproduces ω off the sphere (u̇ = Hᵀω / 4|u|²)
    u0 = sc.initial.u
    H = 2 * np.array(
        [
            [-u0[1], u0[0], u0[3], -u0[2]],
            [-u0[2], -u0[3], u0[0], u0[1]],
            [-u0[3], u0[2], -u0[1], u0[0]],
        ]
    )
    np.testing.assert_allclose(H @ sc.initial.udot, sc.initial.omega, atol=1e-14)


def test_axis_angle_equals_scipy_rotation():
    raw = _raw("paper_example2")
    raw["initial"]["attitude"] = {"axis": [0.0, 0.0, 2.0], "angle_deg": 90.0}
    sc = scene_from_dict(raw)
    ref = Rotation.from_euler("z", 90, degrees=True).as_quat(scalar_first=True)
    np.testing.assert_allclose(sc.initial.u, ref, atol=1e-15)


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(ValueError, match=r"^scene: file not found"):
        load_scene(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene\nname = 1")
    with pytest.raises(ValueError, match=r"^scene: not valid TOML"):
        load_scene(bad)
