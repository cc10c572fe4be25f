"""The hard-case suite: each case's stated criterion, judged against independent references,
on every installed plant (the analytic plant, MuJoCo and, with ``pin``, Pinocchio).

The default run covers the fast subset (short horizons); ``pytest -m hard`` runs every case.
"""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from analytic import load_scene, scene_from_dict, simulate
from mj_bridge.plants import PinocchioPlant, installed_plants
from tests import tolerances as tol
from validation import hard_cases as hc

INSTALLED = tuple(e.value for e in installed_plants())

KNOWN_FAILURES: dict[tuple[str, str], tuple[set[str], str]] = {
    ("rod_through_C", "pinocchio"): (
        {"pinocchio: max |p_i|, m"},
        "Pinocchio's masses leave C: max |p| 2.1e-11 m > 1e-12 m. pin.aba returns p'' ~ 1e-14 - "
        "3e-13 m/s^2 of round-off at p = 0 (exactly 0 in the analytic plant), which seeds the spring "
        "modes; DOP853 at the scene's rtol 1e-12 takes ~0.15 s steps there and lets it grow "
        "(a recorded finding; the criterion is not loosened)",
    ),
}
"""(case, plant) -> (the labels of the checks known to fail, why): findings, not test bugs. Where
one shows, it must fail exactly so (nothing else of that plant fails, every other plant passes) and
the test xfails with the reason. The failure grows out of round-off, whose last bits differ between
CPUs and library builds, so a machine on which the plant passes the case passes the test too (no
test may depend on bit-level behaviour across machines)."""


def _failed(row: hc.HardCaseRow) -> str:
    bad = [f"{c.label} = {c.value:.3e} > {c.bound:.1e}" for c in row.checks if not c.passed]
    return f"{row.case}: {row.verdict} {row.error} " + "; ".join(bad)


def _assert_row(name: str) -> hc.HardCaseRow:
    row = hc.run_case(name)
    assert row.verdict != hc.ERROR, _failed(row)
    assert row.plants == INSTALLED, row.plants
    assert row.checks, f"{name}: no check was made"
    known = []
    for e in row.plants:
        verdict = row.plant_verdict(e)
        if verdict == hc.NA:
            # not applicable, said by name: the reason names the plant
            assert hc.label(e) in row.not_applicable[e], row.not_applicable
            assert e not in row.figures
            continue
        assert any(c.plant == e for c in row.checks), f"{name}: nothing judged on {e}"
        if (name, e) in KNOWN_FAILURES:
            labels, why = KNOWN_FAILURES[(name, e)]
            failed = {c.label for c in row.failed_checks(e)}
            if failed:
                assert failed == labels, _failed(row)
                known.append(f"{e}: {why}")
                continue
        assert verdict == hc.PASS, _failed(row)
    if known:
        pytest.xfail("; ".join(known))
    assert row.passed, _failed(row)
    return row


FAST = list(hc.FAST_CASES)
SLOW = [n for n in hc.CASES if n not in hc.FAST_CASES]


@pytest.mark.parametrize("name", FAST)
def test_fast_hard_case(name):
    _assert_row(name)


@pytest.mark.hard
@pytest.mark.parametrize("name", SLOW)
def test_slow_hard_case(name):
    _assert_row(name)


def test_every_hard_scene_states_its_criterion():
    """Each scene file has a CRITERION comment and a machine-readable hard_criterion + bounds."""
    files = sorted(hc.HARD_DIR.glob("*.toml"))
    assert {f.stem for f in files} == set(hc.CASES)
    for f in files:
        text = f.read_text(encoding="utf-8")
        assert "CRITERION" in text, f.name
        th = tomllib.loads(text)["thresholds"]
        assert isinstance(th.get("hard_criterion"), str) and th["hard_criterion"], f.name
        bounds = {k: v for k, v in th.items() if k != "hard_criterion"}
        assert bounds and all(isinstance(v, int | float) and v > 0 for v in bounds.values()), f.name


def test_off_manifold_start_refused_unless_allowed():
    data = tomllib.loads((hc.HARD_DIR / "off_manifold.toml").read_text(encoding="utf-8"))
    u = np.array(data["initial"]["attitude"]["quaternion"])
    assert abs(np.linalg.norm(u) - 1.1) < 1e-12
    del data["initial"]["attitude"]["allow_off_manifold"]
    with pytest.raises(ValueError, match=r"^initial\.attitude\.quaternion"):
        scene_from_dict(data)


def test_euler_reference_against_closed_form():
    """The reference integrator itself: an axisymmetric body (J1 = J2) precesses in closed form,
    ω̇1 = -Ω ω2, ω̇2 = Ω ω1 with Ω = (J3 - J1)/J1 ω3, ω3 constant."""
    J = np.diag([2.0, 2.0, 3.5])
    w0 = np.array([0.7, -0.4, 2.0])
    t = np.linspace(0, 10, 201)
    w, u = hc.euler_reference(J, w0, np.array([1.0, 0, 0, 0]), t)
    Om = (3.5 - 2.0) / 2.0 * w0[2]
    c, s = np.cos(Om * t), np.sin(Om * t)
    ref = np.stack([w0[0] * c - w0[1] * s, w0[0] * s + w0[1] * c, np.full_like(t, w0[2])], 1)
    np.testing.assert_allclose(w, ref, rtol=0, atol=tol.EULER_REFERENCE_OMEGA_ABS.value)
    np.testing.assert_allclose(
        np.linalg.norm(u, axis=1), 1.0, rtol=0, atol=tol.EULER_REFERENCE_QUAT_NORM_ABS.value
    )
    # angular momentum in the inertial frame is constant
    L = np.stack([hc.rotation(u[k]) @ (J @ w[k]) for k in range(len(t))])
    np.testing.assert_allclose(
        L, np.repeat(L[:1], len(t), 0), rtol=0, atol=tol.EULER_REFERENCE_MOMENTUM_ABS.value
    )


def test_run_hard_cases_writes_table(tmp_path):
    seen = []
    table = hc.run_hard_cases(
        tmp_path,
        names=["pass_through", "long_horizon"],
        fast_only=True,
        progress=lambda case, i, n: seen.append((case, i, n)),
    )
    assert seen == [("pass_through", 0, 1)]
    assert [r.case for r in table.rows] == ["pass_through"]
    assert table.passed and table.complete
    assert table.plants == INSTALLED
    data = json.loads((tmp_path / "hard_cases.json").read_text(encoding="utf-8"))
    assert data["passed"] is True and data["rows"][0]["case"] == "pass_through"
    assert data["plants"] == list(INSTALLED)
    # a mapping plant -> verdict and figures, for every plant
    per_plant = data["rows"][0]["plants"]
    assert list(per_plant) == list(INSTALLED)
    for e in INSTALLED:
        assert per_plant[e]["verdict"] == "PASS"
        assert per_plant[e]["figures"]["crossings"] > 0
    assert {c["plant"] for c in data["rows"][0]["checks"]} == set(INSTALLED)
    md = (tmp_path / "hard_cases.md").read_text(encoding="utf-8")
    assert md.startswith("# Hard cases: PASSED") and "| pass_through |" in md
    header = next(line for line in md.splitlines() if line.startswith("| case |"))
    assert header == (
        "| case | criterion | "
        + " | ".join(hc.label(e) for e in INSTALLED)
        + " | verdict | wall s |"
    )
    assert not list(tmp_path.glob(".*.tmp"))


def test_suite_without_pinocchio_runs_on_two_plants(tmp_path, monkeypatch):
    """Without ``pin`` the suite runs on the analytic plant and MuJoCo and says Pinocchio was not
    installed (with the reason); the other plants are judged as before."""
    why = "the Pinocchio plant needs the 'pin' package (>= 4.1): pip install it"
    monkeypatch.setattr(PinocchioPlant, "unavailable", classmethod(lambda cls: why))
    table = hc.run_hard_cases(tmp_path, names=["pass_through", "off_manifold"])
    assert table.plants == ("analytic", "mujoco")
    assert dict(table.not_installed) == {"pinocchio": why}
    assert table.passed, [hc.HardCaseRow.to_dict(r) for r in table.rows]
    pt, om = table.row("pass_through"), table.row("off_manifold")
    assert set(pt.figures) == {"analytic", "mujoco"}
    assert {c.plant for c in pt.checks} == {"analytic", "mujoco"}
    assert set(om.not_applicable) == {"mujoco"}
    data = json.loads((tmp_path / "hard_cases.json").read_text(encoding="utf-8"))
    assert data["plants"] == ["analytic", "mujoco"]
    assert data["not_installed"] == {"pinocchio": why}
    assert all(list(r["plants"]) == ["analytic", "mujoco"] for r in data["rows"])
    md = (tmp_path / "hard_cases.md").read_text(encoding="utf-8")
    assert f"Pinocchio was not run: not installed ({why})." in md
    assert "| case | criterion | analytic | MuJoCo | verdict | wall s |" in md


def test_off_manifold_not_applicable_by_name():
    """MuJoCo and Pinocchio cannot represent |u| = 1.1: the row says so, naming each; the analytic
    plant is judged."""
    row = hc.run_case("off_manifold")
    others = [e for e in INSTALLED if e != "analytic"]
    assert list(row.not_applicable) == others
    for e in others:
        assert row.plant_verdict(e) == hc.NA
        assert hc.label(e) in row.not_applicable[e] and "not representable" in row.not_applicable[e]
    assert row.plant_verdict("analytic") == hc.PASS and row.passed
    d = row.to_dict()["plants"]
    for e in others:
        assert d[e] == {"verdict": "N/A", "not applicable": row.not_applicable[e]}


def test_plant_verdicts_and_markdown_columns():
    """A failing check fails its own plant's column and the case, not the other plants."""
    checks = (
        hc.Check("analytic: drift", 1e-12, 1e-10, "analytic"),
        hc.Check("mujoco: drift", 1e-9, 1e-10, "mujoco"),
        hc.Check("mujoco vs analytic dR_m", 1e-9, 1e-6, "mujoco"),
    )
    row = hc.HardCaseRow(
        case="x",
        criterion="c",
        plants=("analytic", "mujoco", "pinocchio"),
        figures={"analytic": {"drift": 1e-12}, "mujoco": {"drift": 1e-9}},
        not_applicable={"pinocchio": "Pinocchio cannot"},
        checks=checks,
        verdict=hc.FAIL,
        wall_time_s=0.1,
    )
    assert [row.plant_verdict(e) for e in row.plants] == ["PASS", "FAIL", "N/A"]
    assert [c.label for c in row.failed_checks()] == ["mujoco: drift"]
    d = row.to_dict()["plants"]
    assert d["mujoco"]["failed"] == ["mujoco: drift"] and "failed" not in d["analytic"]
    table = hc.HardCaseTable((row,), plants=row.plants)
    md = table.to_markdown()
    line = next(s for s in md.splitlines() if s.startswith("| x |"))
    cells = [s.strip() for s in line.split(" | ")]
    assert cells[2].startswith("**PASS**") and cells[3].startswith("**FAIL**")
    assert cells[4] == "n/a: Pinocchio cannot" and "**FAIL**" in cells[5]
    assert "- FAIL: mujoco: drift" in md


def test_plant_specific_bound_overrides_the_general_one():
    """``hard_<plant>_<x>`` is that plant's alone; every other plant gets ``hard_<x>``."""
    th = {"hard_reference_rel": 1e-9, "hard_mujoco_reference_rel": 1e-8}
    assert hc._bound(th, "hard_reference_rel", "mujoco") == 1e-8
    assert hc._bound(th, "hard_reference_rel", "analytic") == 1e-9
    assert hc._bound(th, "hard_reference_rel", "pinocchio") == 1e-9


def test_suite_plants_need_the_analytic_plant(tmp_path):
    with pytest.raises(ValueError, match=r"^plants: the hard cases need the analytic plant"):
        hc.run_hard_cases(tmp_path, names=["pass_through"], plants=["mujoco"])
    with pytest.raises(ValueError, match=r"^plants: unknown plant 'nope'"):
        hc.run_hard_cases(tmp_path, names=["pass_through"], plants=["analytic", "nope"])


def test_run_hard_cases_refuses_unknown_name(tmp_path):
    with pytest.raises(ValueError, match=r"^names: unknown hard case 'nope'"):
        hc.run_hard_cases(tmp_path, names=["nope"])


def test_energy_split_adds_up_to_the_total():
    """E = E_int + ½ m_T |ċ|² - m_T g·c: the centre-of-mass decomposition used by the long-horizon
    case, checked against the total energy of the invariants (computed independently)."""
    from analytic.model import TumblingModel
    from validation.scenes import scene_path

    scene = load_scene(scene_path("paper_example1"))
    tr = simulate(scene, t_end=2.0)
    E_int, c, cd = hc.split_energy(scene, tr)
    m = TumblingModel(scene)
    E = E_int + 0.5 * m.m_T * np.sum(cd * cd, axis=1) - m.m_T * (c @ m.g)
    np.testing.assert_allclose(E, tr.invariants.energy, rtol=1e-12)
    # and the centre of mass follows its parabola (uniform gravity, no external force)
    par = c[0] + np.outer(tr.t, cd[0]) + 0.5 * np.outer(tr.t**2, m.g)
    assert np.max(np.abs(c - par)) < tol.COM_PARABOLA_ABS_M.value
