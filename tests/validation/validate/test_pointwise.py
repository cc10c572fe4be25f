"""The pointwise check before a run: a plant that leaves a term out of its model is found, with the
term named, before any plant runs; an exact one is not; a refusal is check_scene's."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import mj_bridge.plants as plants_mod
from analytic.effects import Effect
from analytic.scene import load_scene
from tests.support.pointwise_plants import DROPPED, POINTWISE_PLANTS, REFUSAL, PointwiseSettings
from validation.compare.pointwise import Case
from validation.compare.thresholds import pointwise_threshold
from validation.validate import run_validation, validation_request
from validation.validate.pointwise import (
    PointwiseWarning,
    check_pointwise,
    pointwise_states,
    precision_of,
    uncontrolled,
)


@pytest.fixture
def fakes(monkeypatch):
    """The registry with the pointwise plants of tests/support/pointwise_plants.py as plugins."""
    known = dict(plants_mod.PLANTS) | POINTWISE_PLANTS
    monkeypatch.setattr(plants_mod, "_load", lambda: (known, ()))
    return known


def _check(scene, engines):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = check_pointwise(scene, engines, lambda e: plants_mod.plant(e).default_settings(scene))
    return out, [str(w.message) for w in caught if issubclass(w.category, PointwiseWarning)]


def test_states_are_valid_near_the_motion_and_reproducible():
    sc = load_scene("paper_example1")
    names, t, q, qdot = pointwise_states(sc, 5, seed=3)
    assert names[0] == "the initial state" and len(names) == t.shape[0] == 6
    np.testing.assert_array_equal(q[0], sc.initial.q0())
    u, udot = q[:, 3:7], qdot[:, 3:7]
    np.testing.assert_allclose(np.sum(u * u, axis=1), 1.0, rtol=0, atol=1e-14)  # unit quaternion
    np.testing.assert_allclose(np.sum(u * udot, axis=1), 0.0, atol=1e-14)  # u̇ tangent
    assert np.all((t >= 0) & (t <= sc.output.t_end))
    again = pointwise_states(sc, 5, seed=3)
    np.testing.assert_array_equal(again[2], q)


def test_a_dropped_term_is_found_and_named_before_any_run(fakes):
    sc = load_scene("paper_example1")
    out, said = _check(sc, ["analytic", "mujoco", "dropterm"])
    assert not out.refused and not out.check.not_checked
    [found] = out.check.findings  # the plants without pointwise are not compared
    assert found.plant == "dropterm" and found.case is Case.UNCONTROLLED
    assert found.state == "the initial state"
    assert found.vs_mujoco > 1e3 * found.bound and found.vs_analytic > 1e3 * found.bound
    assert found.references <= pointwise_threshold("float64").value  # C and analytic agree
    assert found.cause == DROPPED.value
    assert said == [found.text()]
    assert "the models differ, not the integration" in said[0]
    assert f"the difference is in {DROPPED.value}" in said[0]
    assert [p.plant for p in out.check.plants] == ["dropterm"]


def test_a_term_at_another_strength_is_found_by_switching_it_off_in_the_plant(fakes):
    out, said = _check(load_scene("paper_example2"), ["halfterm"])
    [found] = out.check.findings
    assert found.cause == DROPPED.value
    assert f"the difference is in {DROPPED.value} (halfterm applies 0.5 of" in said[0]


def test_a_controlled_scene_is_checked_controlled_and_not(fakes):
    sc = load_scene("paper_example2_controlled")
    out, said = _check(sc, ["dropterm"])
    cases = {c.case for c in out.check.plants[0].cases}
    assert cases == {Case.CONTROLLED, Case.UNCONTROLLED}
    by_case = {f.case: f for f in out.check.findings}
    assert by_case[Case.UNCONTROLLED].cause == DROPPED.value
    if Case.CONTROLLED in by_case:  # masses under partial control: the missing term shows too
        assert by_case[Case.CONTROLLED].cause == DROPPED.value
    assert len(said) == len(out.check.findings)


def test_an_exact_plant_has_no_finding(fakes):
    sc = load_scene("paper_example1_controlled")
    out, said = _check(sc, ["exact"])
    assert not out.check.findings and not said
    [pp] = out.check.plants
    assert pp.precision == "float64" and len(pp.cases) == 2
    for c in pp.cases:
        assert max(c.vs_mujoco) <= min(c.bounds) and max(c.vs_analytic) <= min(c.bounds)


def test_a_scene_without_the_term_has_no_finding(fakes):
    sc = load_scene("spacecraft_slosh")  # linear springs only
    assert DROPPED not in sc.effects
    out, said = _check(sc, ["dropterm"])
    assert not out.check.findings and not said


def test_a_plant_without_pointwise_costs_nothing(fakes):
    out, said = _check(load_scene("paper_example1"), ["analytic", "mujoco"])
    assert out.check.empty and not said
    assert out.check.wall_time_s < 1.0


def test_precision_is_the_settings_and_its_bound_is_its_epsilon():
    assert precision_of(object()) == "float64"
    assert precision_of(PointwiseSettings("float32")) == "float32"
    eps32, eps64 = np.finfo(np.float32).eps, np.finfo(np.float64).eps
    assert pointwise_threshold("float32").value / pointwise_threshold(
        "float64"
    ).value == pytest.approx(eps32 / eps64)
    with pytest.raises(ValueError, match=r"settings\.precision"):
        precision_of(PointwiseSettings("int8"))


def test_a_float32_plant_is_judged_at_float32(fakes):
    """The same exact q̈ with a float32-sized perturbation passes at float32, fails at float64."""
    sc = load_scene("paper_example1")
    base = POINTWISE_PLANTS["exact"]

    class Rounded(base):
        def pointwise(self, scene, settings, t, q, qdot):
            got = super().pointwise(scene, settings, t, q, qdot)
            return got * (1 + 10 * float(np.finfo(np.float32).eps))

    fakes["exact"] = Rounded
    for precision, found in (("float32", False), ("float64", True)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = check_pointwise(sc, ["exact"], lambda e, p=precision: PointwiseSettings(p))
        assert bool(out.check.findings) is found, precision


def test_a_named_plant_that_refuses_pointwise_refuses_the_run(fakes):
    with pytest.raises(ValueError) as err:
        validation_request("paper_example1", plants="analytic,refusing")
    assert str(err.value) == f"refusing: {REFUSAL}"


def test_a_set_leaves_a_refusing_plant_out_with_one_warning(fakes):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        req = validation_request("paper_example1", plants="all")
    assert "refusing" not in req.plants and {"analytic", "mujoco", "dropterm"} <= set(req.plants)
    assert [x.engine for x in req.left_out if x.engine == "refusing"] == ["refusing"]
    lines = [str(w.message) for w in caught]
    assert lines.count(f"refusing plant left out: {REFUSAL}") == 1
    assert sum(1 for x in lines if x.startswith("dropterm: q̈ differs")) == 1


def test_a_plant_whose_pointwise_breaks_is_not_checked_and_said(fakes):
    class Broken(POINTWISE_PLANTS["exact"]):
        def pointwise(self, scene, settings, t, q, qdot):
            return np.zeros(3)

    fakes["exact"] = Broken
    out, said = _check(load_scene("paper_example1"), ["exact"])
    assert not out.refused and not out.check.plants
    assert out.check.not_checked == (said[0],) and "shape (3,)" in said[0]


def test_uncontrolled_turns_only_the_controller_off():
    sc = load_scene("paper_example1_controlled")
    plain = uncontrolled(sc)
    assert set(plain.effects) == set(sc.effects) - {Effect.CONTROL_OMEGA, Effect.CONTROL_MASSES}
    assert uncontrolled(plain) is plain


def _report_files(tmp_path, pointwise):
    """report.md and report.json of a run that failed before a comparison, with ``pointwise``."""
    from validation.report.report import write_report

    meta = {"run_id": "r", "horizon_s": 1.0, "plants": [], "wall_times_s": {}}
    if pointwise is not None:
        meta["pointwise"] = pointwise.to_dict()
    scene = load_scene("paper_example1")
    rep = write_report(tmp_path, None, [], meta, failure="no run", scene=scene)
    return rep.markdown.read_text(encoding="utf-8"), json.loads(rep.json.read_text("utf-8"))


def test_report_md_and_json_state_the_findings(fakes, tmp_path):
    from tests.validation.report.test_provenance import validator

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        req = validation_request("paper_example1", plants="analytic,dropterm")
    md, doc = _report_files(tmp_path, req.pointwise)
    assert "## Pointwise check before the run" in md
    assert f"the difference is in {DROPPED.value}" in md and "**differs**" in md
    validator("report").validate(doc)
    [f] = doc["pointwise"]["findings"]
    assert f["plant"] == "dropterm" and f["cause"] == DROPPED.value
    assert f["text"] == req.pointwise.findings[0].text()
    assert "pointwise" not in doc["run"]


def test_a_run_without_a_pointwise_plant_has_no_section(tmp_path):
    from tests.validation.report.test_provenance import validator

    md, doc = _report_files(tmp_path, None)
    assert "Pointwise" not in md and "pointwise" not in doc
    validator("report").validate(doc)


@pytest.mark.slow
def test_a_validation_reports_the_findings(fakes, tmp_path):
    """The whole job: the check's findings reach report.md and report.json of the run."""
    from tests.validation.report.test_provenance import validator

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run_validation(
            "paper_example1",
            tmp_path / "out",
            t_end=0.02,
            plants="analytic,dropterm",
            concurrent=False,
        )
    md = res.files["report.md"].read_text(encoding="utf-8")
    assert md.index("## Pointwise check") < md.index("## Checks")
    assert f"the difference is in {DROPPED.value}" in md
    doc = json.loads(res.files["report.json"].read_text(encoding="utf-8"))
    validator("report").validate(doc)
    assert doc["pointwise"]["findings"][0]["cause"] == DROPPED.value


@pytest.mark.slow
def test_mjx_drops_the_cubic_tendon_stiffness_and_this_process_never_imports_jax(tmp_path):
    """MJX 3.17 reads tendon_stiffness, never tendon_stiffnesspoly (mjx/_src/passive.py): the
    check finds it at the initial state and names springs.cubic, and finds nothing in a scene of
    linear springs only. The check runs in a fresh interpreter that must not import jax or warp
    (the plant evaluates in a spawned process of its own)."""
    import subprocess
    import sys

    mjx_plugin = pytest.importorskip("mj_bridge.mjx_plugin")
    if mjx_plugin.MjxPlant.unavailable():
        pytest.skip(mjx_plugin.MjxPlant.unavailable())
    code = """
import json, sys, warnings
warnings.simplefilter("ignore")
import mj_bridge.plants as plants
from analytic.scene import load_scene
from mj_bridge.mjx_plugin import MjxPlant
from validation.validate.pointwise import check_pointwise
known = plants.registered()
if "mjx" not in known:  # an installation whose entry points predate the plugin
    plants._load = lambda: ({**known, "mjx": MjxPlant}, ())
plant = plants.plant
out = {}
for name in ("paper_example1", "spacecraft_slosh"):
    sc = load_scene(name)
    got = check_pointwise(sc, ["mjx"], lambda e: plant(e).default_settings(sc), count=1)
    out[name] = [f.to_dict() for f in got.check.findings]
out["imported"] = sorted(m for m in ("jax", "warp", "mujoco_warp") if m in sys.modules)
print(json.dumps(out))
"""
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True
    )
    out = json.loads(run.stdout.splitlines()[-1])
    assert out["imported"] == []
    [found] = out["paper_example1"]
    assert found["state"] == "the initial state" and found["cause"] == Effect.SPRINGS_CUBIC.value
    assert out["spacecraft_slosh"] == []
