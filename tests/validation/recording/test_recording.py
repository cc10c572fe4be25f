"""run.rrd and demo.rrd read back with RrdReader: entities, sample counts, quaternion order, Z up,
log10 plots one unit each, the exaggerated difference view, a trail whose cost is linear in the
run, a blueprint in every file that opens as the active one under the artefact's own application
id, and every string in characters the viewer's fonts have."""

from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from hypothesis import given, settings
from hypothesis import strategies as st
from rerun.chunk import RrdReader
from scipy.spatial.transform import Rotation

from analytic.scene import load_scene
from analytic.simulate import simulate
from analytic.trajectory import Engine, Trajectory
from validation.compare.checks import Group, compare
from validation.recording.layout import difference_title, legend_markdown, overlay_title
from validation.recording.plots import Tab, key_path, plot_of, series_path
from validation.recording.recording import (
    TIMELINE,
    AppId,
    log_run,
    narrative_for,
    new_stream,
    write_recording,
)
from validation.recording.style import (
    VIEWER_CHARACTERS,
    color_word,
    plant_color,
    power_of_ten,
    unit_text,
    viewer_text,
)
from validation.recording.world import DIFFERENCE_TARGET, body_size, exaggerate
from validation.studies.demo import write_demo
from validation.studies.sweep.config import Outcome
from validation.studies.sweep.figure import FigureData, Line, Mark, Point
from validation.studies.sweep.rrd import write_rrd

SCENES = Path(__file__).resolve().parents[3] / "analytic" / "scenes"
T_END = 0.4
D_POSITION = 1e-9  # m: the second plant's C is moved by this times t / T_END along x ...
D_ANGLE = 1e-9  # rad: ... and its attitude turned by this times t / T_END about body z
TRAIL_GROWTH = 2.3
"""Largest ratio of a recording's trail bytes (and file bytes) for twice the horizon: linear growth
gives 2 (less with the fixed costs); the path-so-far re-logged at every sample gave ~4 here."""


@pytest.fixture(autouse=True, scope="module")
def strict():
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(False)


def perturbed(tr: Trajectory) -> Trajectory:
    """``tr`` relabelled as the MuJoCo plant, C moved and the body turned by amounts growing
    linearly from zero (exactly zero at t = 0); velocities untouched (their differences are exact
    zeros)."""
    s = (tr.t / tr.t[-1])[:, None]
    q = tr.q.copy()
    q[:, :3] += D_POSITION * s * np.array([1.0, 0.0, 0.0])
    turn = Rotation.from_rotvec(D_ANGLE * s * np.array([0.0, 0.0, 1.0]))
    u = Rotation.from_quat(tr.q[:, 3:7], scalar_first=True) * turn
    q[:, 3:7] = u.as_quat(scalar_first=True)
    return dataclasses.replace(tr, engine=Engine.MUJOCO, q=q)


@pytest.fixture(scope="module")
def ex1(tmp_path_factory):
    scene = load_scene(SCENES / "paper_example1_controlled.toml")
    tr = simulate(scene, t_end=T_END, rtol=1e-10)
    other = perturbed(tr)
    cmp = compare(tr, other, scene, t_end=T_END)
    path = tmp_path_factory.mktemp("rrd") / "run.rrd"
    info = write_recording(path, scene, [tr, other], cmp)
    return scene, tr, cmp, info


def rows(store, entity: str) -> int:
    chunks = store.stream().filter(content=entity, is_static=False).to_chunks()
    return sum(c.num_rows for c in chunks)


def static_rows(store, entity: str) -> int:
    chunks = store.stream().filter(content=entity, is_static=True).to_chunks()
    return sum(c.num_rows for c in chunks)


def column(store, entity: str, suffix: str, static: bool = False) -> list:
    out = []
    for c in store.stream().filter(content=entity, is_static=static).to_chunks():
        rb = c.to_record_batch()
        name = next(n for n in rb.schema.names if n.endswith(suffix))
        out += rb.column(name).to_pylist()
    return out


def narrative(store, entity: str) -> str:
    return column(store, entity, "TextDocument:text", static=True)[0][0]


def blueprint_views(path: Path) -> dict[str, dict]:
    """The stored blueprint's views: view entity -> {kind, name, origin}."""
    reader = RrdReader(path)
    bps = reader.blueprints()
    assert len(bps) == 1
    views: dict[str, dict] = {}
    for c in RrdReader(path).store(store=bps[0]).stream().to_chunks():
        rb = c.to_record_batch()
        if "ViewBlueprint:class_identifier" in rb.schema.names:
            views[c.entity_path] = {
                "kind": rb.column("ViewBlueprint:class_identifier").to_pylist()[0][0],
                "name": rb.column("ViewBlueprint:display_name").to_pylist()[0][0],
                "origin": rb.column("ViewBlueprint:space_origin").to_pylist()[0][0],
            }
    return views


def blueprint_components(path: Path, suffix: str) -> dict[str, list]:
    """Blueprint entity -> values of its component ending in ``suffix``."""
    reader = RrdReader(path)
    out = {}
    for c in RrdReader(path).store(store=reader.blueprints()[0]).stream().to_chunks():
        rb = c.to_record_batch()
        for n in rb.schema.names:
            if n.endswith(suffix):
                out[c.entity_path] = rb.column(n).to_pylist()[0]
    return out


def test_run_rrd_holds_both_plants_and_every_plot(ex1):
    _scene, _tr, cmp, info = ex1
    store = RrdReader(info.path).store()
    ents = set(store.schema().entity_paths())
    for plant in ("analytic", "mujoco"):
        for e in ("body", "body/shape", "body/rod", "body/masses", "body/omega", "body/torque"):
            assert f"/world/{plant}/{e}" in ents
        assert f"/world/{plant}/trail" in ents
        assert f"/plots/control/torque/{plant}" in ents
        assert f"/plots/control/rod_forces/{plant}" in ents
    for e in ("body", "body/shape", "body/masses", "offset"):
        assert f"/world/exaggerated/mujoco/{e}" in ents
    for s in cmp.series:
        if s.group is not Group.CONTROL:
            assert series_path("", s) in ents, s.key
    assert "/narrative" in ents
    assert set(info.entities) <= ents


def test_every_time_series_has_one_row_per_sample(ex1):
    _, tr, _, info = ex1
    store = RrdReader(info.path).store()
    N = tr.t.shape[0]
    for e in (
        "/world/analytic/body",
        "/world/mujoco/body",
        "/world/analytic/body/masses",
        "/world/analytic/body/omega",
        "/world/exaggerated/mujoco/body",
        "/plots/tracking/rad_per_s/e_omega/mujoco",
        "/plots/control/torque/analytic",
    ):
        assert rows(store, e) == N, e
    assert rows(store, "/world/analytic/trail") == N - 1  # one segment between two samples
    assert static_rows(store, "/narrative") == 1
    assert static_rows(store, "/world/analytic/body/shape") == 1


def test_masses_and_torque_have_one_value_per_element(ex1):
    _, tr, _, info = ex1
    store = RrdReader(info.path).store()
    pos = column(store, "/world/analytic/body/masses", "positions")
    assert len(pos) == tr.t.shape[0] and all(len(p) == tr.n for p in pos)
    tau = column(store, "/plots/control/torque/analytic", "scalars")
    assert all(len(v) == 3 for v in tau)
    np.testing.assert_allclose(np.array(tau), tr.torque, rtol=1e-12)  # Scalars are float64


def test_quaternions_are_written_x_y_z_w(ex1):
    _, tr, _, info = ex1
    store = RrdReader(info.path).store()
    q = np.array([np.ravel(v) for v in column(store, "/world/analytic/body", "quaternion")])
    u = tr.q[:, 3:7] / np.linalg.norm(tr.q[:, 3:7], axis=1, keepdims=True)
    np.testing.assert_allclose(
        q, np.concatenate([u[:, 1:], u[:, :1]], axis=1), atol=1e-6
    )  # float32
    R = np.array([np.ravel(v) for v in column(store, "/world/analytic/body", "translation")])
    np.testing.assert_allclose(R, tr.q[:, :3], rtol=1e-6, atol=1e-5)


def test_the_3d_space_is_z_up(ex1):
    """Gravity is −Z in every scene: the world's view coordinates make Z the up axis
    (Rerun's codes: Up = 1, Right = 3, Forward = 5)."""
    scene, _, _, info = ex1
    assert np.asarray(scene.gravity)[2] < 0
    store = RrdReader(info.path).store()
    xyz = np.ravel(column(store, "/world", "ViewCoordinates:xyz", static=True))
    assert xyz.tolist() == [3, 5, 1]  # RIGHT_HAND_Z_UP: x right, y forward, z up


def test_errors_are_log10_and_exact_zeros_are_left_out(ex1):
    _, tr, cmp, info = ex1
    store = RrdReader(info.path).store()
    # C moved by D_POSITION t / T: an exact zero at t = 0 (left out), then log10 of the distance
    err = np.ravel(column(store, "/plots/errors/m/position_C/analytic_vs_mujoco", "scalars"))
    assert err.shape == (tr.t.shape[0] - 1,)
    np.testing.assert_allclose(err, np.log10(D_POSITION * tr.t[1:] / tr.t[-1]), atol=1e-6)
    np.testing.assert_allclose(err, np.log10(cmp.get("diff.position_C").values[1:]), rtol=1e-12)
    # velocities untouched: every difference is an exact zero, so nothing is plotted
    path = "/plots/errors/m_per_s/velocity_C/analytic_vs_mujoco"
    assert rows(store, path) == 0 and static_rows(store, path) == 1
    e = np.ravel(column(store, "/plots/tracking/rad_per_s/e_omega/analytic", "scalars"))
    np.testing.assert_allclose(e, np.log10(cmp.get("analytic.e_omega").values), rtol=1e-12)
    for s in cmp.series:  # every plotted series: one row per sample that is not an exact zero
        if s.group is not Group.CONTROL:
            assert rows(store, series_path("", s)) == np.count_nonzero(s.values), s.key


def test_one_plot_per_unit_each_titled_with_its_unit(ex1):
    """Every logged series lies under exactly one time-series view of the stored blueprint,
    the series under a view share one unit, and the view's title states it (with log10 for a
    logarithm)."""
    _, _, cmp, info = ex1
    views = [v for v in blueprint_views(info.path).values() if v["kind"] == "TimeSeries"]
    by_origin = {v["origin"]: v["name"] for v in views}
    units: dict[str, set[str]] = {}
    for s in cmp.series:
        if s.group is Group.CONTROL:
            continue
        path = series_path("", s)
        homes = [o for o in by_origin if path.startswith(o + "/")]
        assert len(homes) == 1, (path, homes)
        units.setdefault(homes[0], set()).add(s.unit)
        title = by_origin[homes[0]]
        assert title.startswith("log10 ") and title.endswith(unit_text(s.unit)), title
        assert viewer_text(plot_of("", s).title) == title
    assert all(len(u) == 1 for u in units.values()), units
    assert len({next(iter(u)) for o, u in units.items() if "/errors/" in o}) == len(
        [o for o in units if "/errors/" in o]
    )  # the differences: one plot per unit, no two plots of one unit


def test_no_legend_covers_a_plot_and_each_tab_has_its_key(ex1):
    """Every time-series view of the stored layout hides its legend (at the designed size a
    legend covers most of a plot's curves); each plot tab has a key view above its plots, whose
    text names every plant or pair with the colour its curves are drawn in, and every quantity of
    a plot with several."""
    _, _, cmp, info = ex1
    views = blueprint_views(info.path)
    plots = [e for e, v in views.items() if v["kind"] == "TimeSeries"]
    hidden = blueprint_components(info.path, "PlotLegend:visible")
    assert plots and all(hidden.get(f"{e}/PlotLegend") == [False] for e in plots), hidden
    keys = {v["origin"] for v in views.values() if v["kind"] == "TextDocument"} - {"/narrative"}
    assert keys == {
        key_path("", tab)
        for tab in {plot_of("", s).tab for s in cmp.series if plot_of("", s)} | {Tab.CONTROL}
    }
    store = RrdReader(info.path).store()
    text = narrative(store, key_path("", Tab.DIFFERENCES))
    for s in cmp.series:
        if s.group is Group.DIFFERENCE:
            assert f"{color_word(plant_color(s.subject.value))}: {s.subject.value}" in text
    assert "position of C" in text and "rod positions" in text, text  # the shades of (m)


def test_difference_view_exaggerates_by_the_stated_factor(ex1):
    """The second plant's difference (D_POSITION along x, D_ANGLE about body z, both growing
    linearly) is drawn multiplied by a power of ten k that makes it visible (between a tenth and
    all of DIFFERENCE_TARGET times BR's size) and that the view's name and the narrative state."""
    scene, tr, _, info = ex1
    k = info.legend.factors["mujoco"]
    size = body_size(scene)
    largest = max(D_POSITION, size * D_ANGLE)
    assert k == 10.0 ** round(math.log10(k)) and k > 1
    assert 0.1 * DIFFERENCE_TARGET * size < k * largest <= DIFFERENCE_TARGET * size
    title = difference_title("analytic", "mujoco", k)
    assert f"×{power_of_ten(k)}" in title
    views = blueprint_views(info.path).values()
    assert {overlay_title(["analytic", "mujoco"]), title} <= {v["name"] for v in views}
    store = RrdReader(info.path).store()
    assert f'"{title}"' in narrative(store, "/narrative")

    s = tr.t / tr.t[-1]
    off = np.array(
        [np.ravel(v) for v in column(store, "/world/exaggerated/mujoco/offset", "vectors")]
    )
    np.testing.assert_allclose(off[:, 0], k * D_POSITION * s, rtol=1e-5, atol=1e-7)  # float32
    np.testing.assert_allclose(off[:, 1:], 0.0, atol=1e-7)
    qx = np.array(
        [np.ravel(v) for v in column(store, "/world/exaggerated/mujoco/body", "quaternion")]
    )
    ref = Rotation.from_quat(tr.q[:, 3:7], scalar_first=True)
    rel = (ref.inv() * Rotation.from_quat(qx)).as_rotvec()  # rerun's x, y, z, w
    np.testing.assert_allclose(rel[:, 2], k * D_ANGLE * s, atol=1e-5)
    np.testing.assert_allclose(rel[:, :2], 0.0, atol=1e-5)


def test_exaggerate_scales_position_angle_and_rod_positions():
    rng = np.random.default_rng(3)
    N, n = 50, 2
    q_ref = np.zeros((N, 7 + n))
    q_ref[:, :3] = rng.normal(size=(N, 3))
    q_ref[:, 3:7] = Rotation.random(N, random_state=4).as_quat(scalar_first=True)
    q_ref[:, 7:] = rng.normal(size=(N, n))
    axis = rng.normal(size=(N, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = 1e-7 * rng.uniform(size=N)
    q = q_ref.copy()
    q[:, :3] += 1e-8 * rng.normal(size=(N, 3))
    q[:, 7:] += 1e-8 * rng.normal(size=(N, n))
    u = Rotation.from_quat(q_ref[:, 3:7], scalar_first=True) * Rotation.from_rotvec(
        angle[:, None] * axis
    )
    q[:, 3:7] = u.as_quat(scalar_first=True)
    k = 1e5
    qx = exaggerate(q_ref, q, k)
    np.testing.assert_allclose(qx[:, :3] - q_ref[:, :3], k * (q[:, :3] - q_ref[:, :3]), atol=1e-9)
    np.testing.assert_allclose(qx[:, 7:] - q_ref[:, 7:], k * (q[:, 7:] - q_ref[:, 7:]), atol=1e-9)
    rel = (
        Rotation.from_quat(q_ref[:, 3:7], scalar_first=True).inv()
        * Rotation.from_quat(qx[:, 3:7], scalar_first=True)
    ).as_rotvec()
    np.testing.assert_allclose(rel, k * angle[:, None] * axis, atol=1e-8)  # same axis, k × angle
    np.testing.assert_allclose(np.linalg.norm(qx[:, 3:7], axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(exaggerate(q_ref, q_ref, k)[:, :3], q_ref[:, :3])


def test_trail_cost_grows_linearly_with_the_horizon(ex1, tmp_path):
    """Twice the horizon, at most about twice the bytes: the trail is one segment per sample,
    not the path so far at every sample (which grows with the square of the samples)."""
    scene, _, _, info = ex1
    tr2 = simulate(scene, t_end=2 * T_END, rtol=1e-10)
    other = perturbed(tr2)
    info2 = write_recording(
        tmp_path / "run2.rrd", scene, [tr2, other], compare(tr2, other, scene, t_end=2 * T_END)
    )

    def trail_bytes(path: Path) -> int:
        store = RrdReader(path).store()
        chunks = store.stream().filter(content="/world/analytic/trail", is_static=False)
        return sum(c.to_record_batch().nbytes for c in chunks.to_chunks())

    assert trail_bytes(info2.path) / trail_bytes(info.path) < TRAIL_GROWTH
    assert info2.path.stat().st_size / info.path.stat().st_size < TRAIL_GROWTH


def _overrides(blueprint_entity: str, entity: str) -> bool:
    """Whether a blueprint entity holds a view's overrides of ``entity`` (Rerun stores them at
    ``…/ViewContents/overrides/<entity>/visualizers``)."""
    return (
        re.search(rf"/overrides/{re.escape(entity)}(/visualizers)?$", blueprint_entity) is not None
    )


def test_trail_shows_the_path_from_the_start_to_the_cursor(ex1):
    """Each plant's trail entity has a visible time range from the start to the time cursor in
    the 3D view, and each plant's root a visibility toggle."""
    _, _, _, info = ex1
    ranges = blueprint_components(info.path, ":ranges")
    visible = blueprint_components(info.path, "EntityBehavior:visible")
    for plant in ("analytic", "mujoco"):
        (r,) = next(v for e, v in ranges.items() if _overrides(e, f"world/{plant}/trail"))
        assert r["timeline"] == TIMELINE and r["range"]["start"] is None  # from the start
        assert r["range"]["end"] == 0  # to the cursor
        assert [v for e, v in visible.items() if _overrides(e, f"world/{plant}")] == [[True]]


def test_only_the_simulation_timeline_and_a_stored_blueprint(ex1):
    _, _, _, info = ex1
    reader = RrdReader(info.path)
    store = reader.store()
    for c in store.stream().filter(is_static=False).to_chunks():
        assert set(c.timeline_names) == {TIMELINE}
    bps = reader.blueprints()
    assert len(bps) == 1
    bp_ents = RrdReader(info.path).store(store=bps[0]).schema().entity_paths()
    assert any(p.startswith("/view/") for p in bp_ents)


def test_writing_is_columnar_whatever_the_number_of_samples(ex1, tmp_path, monkeypatch):
    """Writing stays a small fraction of the simulation because every time series goes out in
    columns (send_columns): the number of logging calls does not grow with the samples.

    This replaces a wall-clock assert (writing < max(1 s, the run's wall time)), whose outcome
    depended on the machine's speed and load; speed goals are not asserted by timed tests."""
    scene, tr, cmp, _ = ex1
    calls = dict.fromkeys(("log", "send_columns"), 0)
    for name in calls:
        real = getattr(rr.RecordingStream, name)

        def spy(self, *a, _real=real, _name=name, **k):
            calls[_name] += 1
            return _real(self, *a, **k)

        monkeypatch.setattr(rr.RecordingStream, name, spy)
    short = simulate(scene, t_end=0.1, rtol=1e-10)
    counts = []
    for run, c, t_end in ((short, None, 0.1), (tr, cmp, T_END)):
        other = perturbed(run)
        c = c or compare(run, other, scene, t_end=t_end)
        for k in calls:
            calls[k] = 0
        write_recording(tmp_path / f"run_{t_end}.rrd", scene, [run, other], c)
        counts.append(dict(calls))
    assert len(short.t) < len(tr.t)
    assert counts[0] == counts[1] and counts[0]["send_columns"] > 0, counts


def test_a_given_narrative_is_followed_by_the_legend(ex1, tmp_path):
    """A caller's own narrative (the demo's) still states the arrow scales and the difference
    view's factor: log_run appends the legend to it."""
    scene, tr, cmp, _ = ex1
    rec = new_stream()
    path = tmp_path / "given.rrd"
    rec.save(str(path))
    _, legend = log_run(rec, scene, [tr, perturbed(tr)], cmp, narrative="# My text", prefix="s")
    rec.flush()
    rec.disconnect()
    text = narrative(RrdReader(path).store(), "/s/narrative")
    assert text.startswith("# My text") and text.endswith(legend_markdown(legend))
    assert f"{legend.arrows.omega:.3g} m per rad/s" in text
    assert f"{legend.arrows.torque:.3g} m per N·m" in text
    assert f"×{power_of_ten(legend.factors['mujoco'])}" in text


def test_hollow_cylinder_shape_for_example_2(tmp_path):
    scene = load_scene(SCENES / "paper_example2_controlled.toml")
    tr = simulate(scene, t_end=0.1, rtol=1e-8)
    info = write_recording(tmp_path / "ex2.rrd", scene, [tr], compare(tr, None, scene, t_end=0.1))
    store = RrdReader(info.path).store()
    ents = set(store.schema().entity_paths())
    assert "/world/analytic/body/shape" in ents and "/world/mujoco/body" not in ents
    assert not any(e.startswith("/world/exaggerated") for e in ents)  # nothing to compare with
    chunk = (
        store.stream().filter(content="/world/analytic/body/shape", is_static=True).to_chunks()[0]
    )
    names = chunk.to_record_batch().schema.names
    assert any("Cylinders3D:radii" in n for n in names)
    assert rows(store, "/world/analytic/body/masses") == tr.t.shape[0]
    pos = column(store, "/world/analytic/body/masses", "positions")
    assert all(len(p) == 5 for p in pos)
    assert "m per rad/s" in narrative(store, "/narrative")
    assert len(RrdReader(info.path).blueprints()) == 1


def test_demo_has_four_narrated_steps(tmp_path):
    res = write_demo(tmp_path, t_end=0.2)
    assert Path(res) / "demo.rrd" == res.rrd
    store = RrdReader(res.rrd).store()
    ents = set(store.schema().entity_paths())
    assert len(res.steps) == 4
    for step in res.steps:
        assert f"/{step.prefix}/narrative" in ents
        assert f"/{step.prefix}/world/analytic/body" in ents
        assert "Eq." in step.narrative
        text = narrative(store, f"/{step.prefix}/narrative")
        assert text.startswith(viewer_text(step.narrative, newlines=True))
        # the demo's recording states its arrow scales and its difference view's factor
        assert "m per rad/s" in text and "difference ×" in text
        uncontrolled = step.scene == "paper_example1"  # steps 1 and 4: no control at all
        assert ("no control torque arrow (τ = 0 throughout)" in text) == uncontrolled
        assert ("m per N·m" in text) != uncontrolled
        xyz = np.ravel(column(store, f"/{step.prefix}/world", "ViewCoordinates:xyz", static=True))
        assert xyz.tolist() == [3, 5, 1]
    assert rows(store, "/step1_uncontrolled/world/analytic/body") == 21
    assert "/step4_no_cubic_springs/plots/mass_positions/with" in ents
    assert "/step4_no_cubic_springs/plots/mass_positions/without" in ents
    # the uncontrolled step has no control: its torque is identically zero
    tau = np.array(column(store, "/step1_uncontrolled/plots/control/torque/analytic", "scalars"))
    assert np.all(tau == 0.0)
    md = res.markdown.read_text()
    assert md.startswith("# ") and md.count("## ") == 4
    # the MuJoCo twin rides along in every step, and agrees with the analytic plant under the
    # report's thresholds (validation/compare/thresholds.py)
    assert len(res.comparisons) == 4
    for step, cmp in zip(res.steps, res.comparisons, strict=True):
        assert f"/{step.prefix}/world/mujoco/body" in ents
        assert f"/{step.prefix}/world/exaggerated/mujoco/body" in ents
        assert cmp.passed, [c.label for c in cmp.failed_checks]
    assert rows(store, "/step1_uncontrolled/world/mujoco/body") == 21
    assert "wireframe" in md and "difference ×" in md  # the MuJoCo twin, and how to see it
    names = [v["name"] for v in blueprint_views(res.rrd).values()]
    assert sum(n.startswith("mujoco − analytic, difference ×") for n in names) == 4


def test_a_diverged_plant_is_drawn_as_is(ex1, tmp_path):
    """A plant whose coordinates turn to NaN (a diverged run) still gets its recording; its
    difference is not finite, so its difference view draws it unscaled (×1)."""
    scene, tr, _, _ = ex1
    bad = perturbed(tr)
    q = bad.q.copy()
    q[-5:] = np.nan
    bad = dataclasses.replace(bad, q=q)
    info = write_recording(
        tmp_path / "nan.rrd", scene, [tr, bad], compare(tr, bad, scene, t_end=T_END)
    )
    assert info.legend.factors == {"mujoco": 1.0}
    store = RrdReader(info.path).store()
    assert rows(store, "/world/exaggerated/mujoco/body") == tr.t.shape[0]
    assert f'"{difference_title("analytic", "mujoco", 1.0)}"' in narrative(store, "/narrative")


def test_narrative_for_is_what_the_recording_carries(ex1):
    """The text a document showing the same run can embed (the demo's markdown) is the logged
    narrative; without its heading, it adds no heading to the document."""
    scene, tr, cmp, info = ex1
    plants = [tr, perturbed(tr)]
    store = RrdReader(info.path).store()
    assert narrative_for(scene, plants, cmp) == narrative(store, "/narrative")
    text = narrative_for(scene, plants, cmp, "# Step\n\nBody.", heading=None)
    assert text.count("#") == 1 and "m per rad/s" in text


# ----------------------------------------------------------------------------------------------
# How the viewer opens a file, and the characters it can draw
# ----------------------------------------------------------------------------------------------


def _strings(value) -> list[str]:
    """Every string inside a value read from an Arrow column (lists, structs, maps)."""
    if isinstance(value, str):
        return [value]
    if isinstance(value, dict):
        return [x for v in value.values() for x in _strings(v)]
    if isinstance(value, list | tuple):
        return [x for v in value for x in _strings(v)]
    return []


def _is_text(t: pa.DataType) -> bool:
    if pa.types.is_string(t) or pa.types.is_large_string(t):
        return True
    if pa.types.is_list(t) or pa.types.is_large_list(t) or pa.types.is_fixed_size_list(t):
        return _is_text(t.value_type)
    if pa.types.is_struct(t):
        return any(_is_text(t.field(i).type) for i in range(t.num_fields))
    return False


def rrd_strings(path: Path) -> dict[str, set[str]]:
    """Every string a recording file carries, read back with Rerun's reader, from its
    recordings and its blueprints: entity paths, and each text-valued component (labels, series
    names, text documents, view and container names, entity filters) -> its values."""
    reader = RrdReader(path)
    out: dict[str, set[str]] = {}
    for entry in [*reader.recordings(), *reader.blueprints()]:
        for c in RrdReader(path).store(store=entry).stream().to_chunks():
            out.setdefault("entity path", set()).add(c.entity_path)
            rb = c.to_record_batch()
            for f in rb.schema:
                if f.metadata and f.metadata.get(b"rerun:kind") == b"data" and _is_text(f.type):
                    values = out.setdefault(f.name, set())
                    values.update(_strings(rb.column(f.name).to_pylist()))
    return out


def outside_the_fonts(strings: dict[str, set[str]]) -> dict[str, list[str]]:
    """Per component, the characters of its strings the viewer cannot draw (a text document
    may hold newlines)."""
    bad: dict[str, list[str]] = {}
    for name, values in strings.items():
        extra = {"\n"} if name.startswith("TextDocument") else set()
        chars = {ch for v in values for ch in v} - VIEWER_CHARACTERS - extra
        if chars:
            bad[name] = sorted(
                f"{ch!r} U+{ord(ch):04X} {unicodedata.name(ch, '?')}" for ch in chars
            )
    return bad


def rrd_commands(path: Path) -> list[str]:
    """The blueprint activation commands of a file, as ``rerun rrd print`` shows them."""
    out = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "print", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    ).stdout
    return re.findall(r"BlueprintActivationCommand\(.*\)", out)


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return write_demo(tmp_path_factory.mktemp("demo"), t_end=0.2)


@pytest.fixture(scope="module")
def sweep_rrd(tmp_path_factory):
    """A sweep.rrd of two series, one failed run and one too slow (labels with their marks)."""
    pts = tuple(
        Point(i, dt, 1e-3 * 2**-i, 0.9e-3 * 2**-i, 1.1e-3 * 2**-i, 3, 10.0 ** (-4 - 2 * i), False)
        for i, dt in enumerate((0.01, 0.005, 0.0025))
    )
    data = FigureData(
        "work–precision of uᵀu − 1 ≤ 10⁻¹²",
        1.0,
        (Line("analytic", "DOP853", pts), Line("mujoco", "RK4", pts[:2])),
        (
            Mark("mujoco", "RK4", 9, Outcome.DIVERGED, None, None, "dt 0.02: diverged ✕"),
            Mark("mujoco", "RK4", 10, Outcome.TOO_SLOW, 0.5, None, "dt 1e-5: too slow"),
        ),
        1e-13,
    )
    path = tmp_path_factory.mktemp("sweep") / "sweep.rrd"
    text = "# Sweep\n\n`φ = uᵀu − 1` obeys φ̈ + δ1 φ̇ + δ2 φ = 0; ✕ a failed run, ★ the cheapest."
    write_rrd(path, data, b"", text, recording_id="sweep-test")
    return path


def test_every_file_opens_in_its_blueprint_under_its_own_application_id(ex1, demo, sweep_rrd):
    """The viewer remembers a layout per application id and applies it to the next file with
    that id unless the file makes its blueprint the active one: each kind of file has an id of
    its own, and its blueprint is sent active (and default, for Blueprint -> Reset)."""
    files = {AppId.VALIDATE: ex1[3].path, AppId.DEMO: demo.rrd, AppId.SWEEP: sweep_rrd}
    assert len({a.value for a in files}) == 3
    for app_id, path in files.items():
        reader = RrdReader(path)
        stores = [*reader.recordings(), *reader.blueprints()]
        assert [s.kind for s in stores] == ["recording", "blueprint"], path.name
        assert {s.application_id for s in stores} == {app_id.value}, path.name
        commands = rrd_commands(path)
        assert len(commands) == 1, (path.name, commands)
        assert "make_active: true" in commands[0] and "make_default: true" in commands[0]
        assert f'"{app_id.value}"' in commands[0]


def test_every_string_the_recordings_carry_is_in_the_viewers_fonts(ex1, demo, sweep_rrd):
    """Labels, series names, view and tab names, entity paths and the text documents of
    run.rrd, demo.rrd and sweep.rrd use only characters the viewer's bundled fonts have (the
    headless viewer stops on any other)."""
    for path in (ex1[3].path, demo.rrd, sweep_rrd):
        strings = rrd_strings(path)
        # the reader sees what is checked: view names, series names, documents, labels
        assert "ViewBlueprint:display_name" in strings, path.name
        assert ("SeriesLines:names" in strings) == (path != sweep_rrd), path.name
        assert ("Points2D:labels" in strings) == (path == sweep_rrd), path.name
        assert any(k.startswith("TextDocument") for k in strings), path.name
        assert outside_the_fonts(strings) == {}, path.name
    views = [v["name"] for v in blueprint_views(ex1[3].path).values()]
    assert "log10 quaternion norm error |u^T u − 1|" in views  # ᵀ spelled, not dropped


def test_viewer_text_spells_what_the_fonts_lack():
    assert viewer_text("|uᵀu − 1|") == "|u^T u − 1|"
    assert viewer_text("10⁻¹² s") == "10^−12 s"
    assert viewer_text("ω̄_x and p̄_i") == "ωbar_x and pbar_i"
    assert viewer_text("u ⊗ (0, ω), ✕") == "u (x) (0, ω), ×"
    plain = "mujoco − analytic, difference ×1e8 (N·m, kg·m²/s, 10⁶, ≤ 1e-9, Δ, τ)"
    assert viewer_text(plain) == plain  # already drawable: unchanged
    assert viewer_text("a\nb") == "a?b" and viewer_text("a\nb", newlines=True) == "a\nb"


@settings(max_examples=300, deadline=None)
@given(st.text())
def test_viewer_text_is_always_drawable(text):
    out = viewer_text(text, newlines=True)
    assert set(out) <= VIEWER_CHARACTERS | {"\n"}
    assert viewer_text(out, newlines=True) == out
