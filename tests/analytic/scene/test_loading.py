"""Scene loading: the paper's data, the attitude conventions, effects, and bad input.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import copy
import json
import math
import tomllib
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from analytic.model import TumblingModel
from analytic.scene import load_scene, scene_from_dict
from analytic.scene.rules import EFFECT_DATA
from validation.scenes import resolve_scene, scene_path

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
    """docs/errata.md, item 6: S(u(0)) = Rot(ν, π/3)·P reproduces the printed u(0) and u̇(0) to their 4 digits."""
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
    # printed u̇(0) with its transposed digits fixed (third entry -0.5774; docs/errata.md, item 12)
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
    with pytest.warns(UserWarning, match=r"^springs\.k_cubic: given but effect 'springs.cubic'"):
        sc = scene_from_dict(raw)
    model = TumblingModel(sc)
    assert "springs.cubic" not in model.force_terms
    raw2 = copy.deepcopy(raw)
    raw2["springs"]["k_cubic"] = [1e30, 1e30, 1e30]
    with pytest.warns(UserWarning, match=r"^springs\.k_cubic:"):
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
    with pytest.warns(UserWarning, match=r"^masses\.ring_radius: given but effect 'mass_inertia'"):
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
    # an effect's constants must be given
    ("paper_example1", "springs.k_cubic", _DELETE, "springs.k_cubic"),
    ("paper_example1", "springs.k_linear", _DELETE, "springs.k_linear"),
    # sizes that cannot be held: output samples, MuJoCo steps, integer literals beyond a double
    ("paper_example1", "output.rate", 1e12, "output.rate"),
    ("paper_example1", "output.t_end", 1e300, "output.t_end"),
    ("paper_example1", "mujoco.timestep", 1e-12, "mujoco.timestep"),
    ("paper_example1", "stabilization.delta1", 10**400, "stabilization.delta1"),
    ("paper_example1", "body.inertia", [10**400, 1.0, 1.0], "body.inertia[0]"),
    ("paper_example1", "initial.omega", [1.0, -(10**400), 0.5], "initial.omega[1]"),
    # a horizon shorter than one MuJoCo step
    ("paper_example1", "output.t_end", 1e-4, "output.t_end"),
    # what MuJoCo's compiler refuses (mjMINVAL, A + B >= C) and what does not fit a double
    ("paper_example1", "masses.mass", [5e5, 1e-20], "masses.mass[1]"),
    ("paper_example1", "masses.mass", [5e5, 1e300], "masses.mass[1]"),
    ("paper_example1", "body.mass", 1e-20, "body.mass"),
    ("paper_example1", "body.mass", 1e300, "body.mass"),
    ("paper_example1", "body.inertia", [1e-20, 1e-20, 1e-20], "body.inertia[0]"),
    ("paper_example1", "body.inertia", [1e300, 1e300, 1e300], "body.inertia[0]"),
    ("paper_example1", "masses.ring_radius", [1e200, 1.0], "masses.ring_radius[0]"),
    # a flat BR (A + B = C) cannot give up the point masses' inertia padding (MuJoCo refuses it)
    ("paper_example2", "body.inertia", [1.0, 1.0, 2.0], "body.inertia"),
    # [thresholds]: a table of finite non-negative numbers (or {value, reason})
    ("paper_example1", "thresholds", {"position_C": "1e-6"}, "thresholds.position_C"),
    ("paper_example1", "thresholds", {"position_C": float("nan")}, "thresholds.position_C"),
    ("paper_example1", "thresholds", {"position_C": -1e-6}, "thresholds.position_C"),
    ("paper_example1", "thresholds", {"position_C": float("inf")}, "thresholds.position_C"),
    ("paper_example1", "thresholds", {"position_C": 10**400}, "thresholds.position_C"),
    ("paper_example1", "thresholds", {"attitude": {"valu": 1e-6}}, "thresholds.attitude.valu"),
    ("paper_example1", "thresholds", {"attitude": {"value": 1e-6, "reason": 3}}, "thresholds.attitude.reason"),
    ("paper_example1", "thresholds", {"hard_x": float("nan")}, "thresholds.hard_x"),
    ("paper_example1", "thresholds", [1e-6], "thresholds"),
]  # fmt: skip


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


def test_threshold_names_are_checked_where_they_are_resolved(tmp_path):
    """The loader checks the table's shape; the comparison's names are refused by resolve_scene
    (the CLI's loader) and run_validation (tests/cross/test_faults.py) before any plant runs."""
    text = scene_path("paper_example1").read_text(encoding="utf-8")
    bad = tmp_path / "typo.toml"
    bad.write_text(text + "\n[thresholds]\npositon_C = 1e-6\n", encoding="utf-8")
    load_scene(bad)  # a table of numbers: the analytic layer keeps it
    with pytest.raises(ValueError) as exc:
        resolve_scene(str(bad))
    msg = str(exc.value)
    assert msg.startswith("thresholds.positon_C: unknown threshold (did you mean 'position_C'?")
    assert "\n" not in msg
    # the hard-case suite's entries, and its stated criterion as a sentence, are kept
    ok = tmp_path / "ok.toml"
    ok.write_text(text + '\n[thresholds]\nhard_criterion = "a sentence"\nhard_x = 1e-9\n')
    sc = resolve_scene(str(ok))
    assert sc.extra["thresholds"] == {"hard_criterion": "a sentence", "hard_x": 1e-9}


def test_axis_angle_attitude_is_the_rotation_it_names_and_scipys_quaternion():
    """u(0) from an axis, an angle and a reference-from-principal matrix: S(u) equals Rodrigues'
    rotation times the reference, and u equals scipy's composed quaternion (sign included), for
    random rotations and the awkward ones (half turns, identity, a permutation)."""
    from scipy.spatial.transform import Rotation

    from analytic.kinematics import S, axis_angle_quat, matrix_quat, quat_mul

    rng = np.random.default_rng(11)
    refs = [np.eye(3), np.diag([1.0, -1.0, -1.0]), np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0.0]])]
    refs += [Rotation.random(random_state=int(s)).as_matrix() for s in rng.integers(0, 2**31, 40)]
    for ref in refs:
        axis = rng.standard_normal(3)
        axis /= np.linalg.norm(axis)
        for angle in (0.0, np.pi, -2.5, float(rng.uniform(-7, 7))):
            u = quat_mul(axis_angle_quat(axis, angle), matrix_quat(ref))
            k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            rodrigues = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
            np.testing.assert_allclose(S(u), rodrigues @ ref, atol=1e-14)
            want = Rotation.from_rotvec(axis * angle) * Rotation.from_matrix(ref)
            np.testing.assert_allclose(u, want.as_quat(scalar_first=True), atol=1e-14)


# ------------------------------------------------------------------------------------------------
# Writing a scene without guessing: unknown names first, every optional key optional
# ------------------------------------------------------------------------------------------------


def _drop(raw: dict, dotted: str) -> None:
    *head, last = dotted.split(".")
    node = raw
    for key in head:
        node = node[key]
    node.pop(last)


def _full_scene() -> dict:
    """Example 1 under control with every optional key of its tables that has a declared default
    written at that default (so that leaving the key out must load the same scene)."""
    from analytic.scene.schema import KEYS, NO_DEFAULT, Kind, Need

    raw = _raw("paper_example1_controlled")
    raw["stabilization"] = {}
    raw["control"]["masses"]["indices"] = [1, 2]
    for k in KEYS:
        if k.need is not Need.OPTIONAL or k.default is NO_DEFAULT or k.kind is Kind.TABLE:
            continue
        node = raw
        for part in k.table.split(".") if k.table else []:
            node = node.get(part) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node[k.key] = copy.deepcopy(k.default)
    return raw


# Leaving out a table of optional data also leaves out what only it describes: the effects whose
# data it holds (the loader's own list) and, for [masses], the masses' state and requirement.
_MASS_DATA = ("initial.p", "initial.pdot", "springs", "control.masses")


def _without(raw: dict, dotted: str) -> dict:
    raw = copy.deepcopy(raw)
    _drop(raw, dotted)
    gone = [dotted, *(_MASS_DATA if dotted == "masses" else ())]
    for extra in gone[1:]:
        _drop(raw, extra)
    if "effects" not in raw.get("scene", {}):
        return raw
    raw["scene"]["effects"] = [
        e
        for e in raw["scene"]["effects"]
        if not any(
            d == g or d.startswith(g + ".")
            for d, eff in EFFECT_DATA
            if eff.value == e
            for g in gone
        )
    ]
    return raw


def test_every_optional_key_can_be_left_out_and_takes_its_declared_default():
    """From the declarations: a scene without any one optional key loads, and when the key has a
    declared default the scene is the one that gives it; a scene without a required key is refused
    naming it."""
    from analytic.scene.schema import KEYS, NO_DEFAULT, Need
    from tests.analytic.scene.test_dump import _differences

    full = _full_scene()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reference = scene_from_dict(full)
        checked = 0
        for k in KEYS:
            if "<" in k.dotted or k.table == "hard_case":
                continue
            node = full
            for part in k.dotted.split("."):
                node = node.get(part) if isinstance(node, dict) else None
            if node is None:
                continue  # not in this scene (a conditional table, another shape's key)
            if k.need is Need.REQUIRED:
                with pytest.raises(ValueError) as exc:
                    scene_from_dict(_without(full, k.dotted))
                assert str(exc.value).startswith(k.dotted + ":"), str(exc.value)
            elif k.need is Need.OPTIONAL:
                sc = scene_from_dict(_without(full, k.dotted))
                if k.default is not NO_DEFAULT:
                    assert _differences(reference, sc) == [], k.dotted
            checked += 1
    assert checked > 30


def test_a_scene_needs_no_attitude_and_without_masses_no_initial_state():
    raw = {
        "scene": {"name": "x", "effects": []},
        "body": {"mass": 2.0, "inertia": [1.0, 2.0, 2.5]},
        "rod": {"axis": [1.0, 0.0, 0.0], "offset": [0.0, 0.0, 0.0]},
    }
    sc = scene_from_dict(raw)
    np.testing.assert_array_equal(sc.initial.u, [1.0, 0.0, 0.0, 0.0])
    for name in ("R", "Rdot", "omega"):
        np.testing.assert_array_equal(getattr(sc.initial, name), np.zeros(3))
    raw["masses"] = {"mass": [1.0], "p_e": [0.0]}
    with pytest.raises(ValueError, match=r"^initial\.p: missing required key"):
        scene_from_dict(raw)


def test_a_rounded_rod_axis_is_normalised_with_one_warning_naming_its_norm():
    raw = _raw("paper_example2")
    raw["rod"]["axis"] = [0.9997, 0.0, 0.0]
    with pytest.warns(UserWarning, match=r"^rod\.axis: norm 0\.9997 normalised to 1") as rec:
        sc = scene_from_dict(raw)
    assert len([w for w in rec if "rod.axis" in str(w.message)]) == 1
    np.testing.assert_allclose(sc.rod.axis, [1.0, 0.0, 0.0], rtol=0, atol=1e-15)
    raw["rod"]["axis"] = [1.002, 0.0, 0.0]
    with pytest.raises(ValueError, match=r"^rod\.axis: must be a unit vector.*got norm 1\.002"):
        scene_from_dict(raw)
    raw["rod"]["axis"] = [0.6, 0.8, 0.0]  # a unit vector: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene_from_dict(raw)


# ------------------------------------------------------------------------------------------------
# One default scene for every command
# ------------------------------------------------------------------------------------------------


def test_every_command_defaults_to_the_one_default_scene():
    from validation import scenes, validate
    from validation.cli import build_parser
    from validation.studies import sweep

    assert scenes.DEFAULT_SCENE == "paper_example1_controlled"  # controlled: tracking to show
    assert sweep.DEFAULT_SCENE is scenes.DEFAULT_SCENE
    assert validate.DEFAULT_SCENE is scenes.DEFAULT_SCENE
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for command in ("simulate", "validate", "export-mjcf", "sweep"):
        text = " ".join(sub.choices[command].format_help().split())
        assert f"(default: {scenes.DEFAULT_SCENE})" in text, command
    assert resolve_scene(None).name == scenes.DEFAULT_SCENE


def test_simulate_without_a_scene_prints_the_tracking_errors(tmp_path, capsys):
    from validation.cli import main

    out = tmp_path / "sim"
    # (the numpy right-hand side: no compilation; the default scene is the point here)
    assert main(["simulate", "--t-end", "0.05", "--backend", "numpy", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "|e_omega|" in printed and "|e_p| (masses 1,2)" in printed
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["scene"] == "paper_example1_controlled"
    assert len(summary["final_tracking_error"]["e_p"]) == 2  # both masses are controlled
