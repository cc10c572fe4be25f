"""The work-precision sweep (validation.studies.sweep): physics of the numbers it reports, the cheapest-setting
selection, file round trips, series stopping, user executors, the reference cache, the timing
summary and what the figure, the recording and the JSON show.

One quick sweep (``quick=True``, 0.5 s of the controlled Example 1) is shared by the module; every
expected value is computed here independently (integrator orders, the closed-form tracking and
norm-error dynamics, errors recomputed with rotation matrices), never copied from the sweep's output.
Every sweep here writes its reference cache under the test's temporary directory.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import re
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

import analytic
from mj_bridge.plants import PinocchioPlant
from validation.compare.summary import drift_figures
from validation.scenes import resolve_scene
from validation.studies import sweep
from validation.studies.sweep import figure, json_doc, reference, rows, running, series, timing

SCENE = "paper_example1_controlled"
HAS_PIN = not PinocchioPlant.unavailable()
needs_pin = pytest.mark.skipif(not HAS_PIN, reason="Pinocchio (pin) is not installed")


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("reference_cache")


@pytest.fixture(scope="module")
def result(tmp_path_factory, cache_dir):
    out = tmp_path_factory.mktemp("sweep")
    return sweep.run_sweep(SCENE, out, quick=True, cache_dir=cache_dir)


@pytest.fixture(scope="module")
def scene():
    return resolve_scene(SCENE)


def _ok(result, engine, method):
    rows = [
        r
        for r in result.runs
        if r["engine"] == engine and r["method"] == method and r["status"] == "ok"
    ]
    return sorted(rows, key=lambda r: -r["setting"])  # loose/large first


class _Clock:
    """A made-up ``time`` module for the budget tests: every reading 1 ms after the previous one,
    so a run's measured wall time does not depend on the machine's load."""

    now = 0.0

    def perf_counter(self):
        self.now += 1e-3
        return self.now


def test_every_setting_of_the_grid_is_reported(result):
    cfg = sweep.SweepConfig.quick()
    scipy_plants = 2 if HAS_PIN else 1  # the analytic engine and, when installed, Pinocchio
    expected = scipy_plants * len(cfg.solvers) * len(cfg.rtols) + len(cfg.integrators) * len(
        cfg.dts
    )
    assert len(result.runs) == expected
    assert [r["run_id"] for r in result.runs] == list(range(expected))
    for r in result.runs:
        assert r["status"] in {"ok", "diverged", "failed", "too_slow", "skipped", "degraded"}
        if r["status"] != "ok":
            assert r["note"], f"run {r['run_id']} {r['status']} without a reason"


def test_reference_self_convergence_below_every_sweep_error(result):
    est = result.reference["error_estimate"]
    assert 0 < est < 1e-11  # DOP853 at rtol 2.5e-14 over 0.5 s: round-off level
    errors = [r["error"] for r in result.runs if r["status"] == "ok"]
    assert est < min(errors)
    assert result.reference["rtol"] < min(sweep.SweepConfig.quick().rtols)


def test_rk4_error_falls_16x_per_halving(result):
    rows = _ok(result, "mujoco", "RK4")
    floor = 100 * result.reference["error_estimate"]
    ratios = [
        a["error"] / b["error"]
        for a, b in itertools.pairwise(rows)
        if math.isclose(a["dt"], 2 * b["dt"]) and b["error"] > floor
    ]
    assert len(ratios) >= 3
    for r in ratios:
        assert 16 / 1.5 < r < 16 * 1.5, ratios


def test_euler_error_falls_2x_per_halving(result):
    rows = _ok(result, "mujoco", "Euler")
    ratios = [a["error"] / b["error"] for a, b in itertools.pairwise(rows)]
    assert len(ratios) >= 3
    for r in ratios:
        assert 2 / 1.3 < r < 2 * 1.3, ratios


def test_dop853_error_decreases_with_rtol(result):
    rows = _ok(result, "analytic", "DOP853")
    assert len(rows) == len(sweep.SweepConfig.quick().rtols)
    errs = [r["error"] for r in rows]
    for a, b in itertools.pairwise(errs):
        assert b <= 2 * a, errs  # monotone within a factor 2
    # rtol spans 1e-3 … 1e-11: the error must fall by orders of magnitude too
    assert errs[-1] < 1e-5 * errs[0]


def test_errors_match_an_independent_computation(result, scene):
    """Recompute one row: own reference run, attitude angle from rotation matrices, own scales."""
    cfg = sweep.SweepConfig.quick()
    row = next(
        r
        for r in result.runs
        if r["engine"] == "analytic" and r["method"] == "DOP853" and r["rtol"] == 1e-5
    )
    ref = sweep.reference_run(scene, cfg.t_end, result.reference["max_step"])
    # the row's own atol (rtol x atol_ratio, 1.0000000000000002e-06): an ulp of atol moves a run
    # at round-off, which the energy balance's cancellation turns into ~1e-9 of its value
    tr = analytic.simulate(scene, method="DOP853", rtol=1e-5, atol=row["atol"], t_end=cfg.t_end)
    Ra = Rotation.from_quat(tr.u, scalar_first=True).as_matrix()
    Rb = Rotation.from_quat(ref.u, scalar_first=True).as_matrix()
    cosang = (np.einsum("nij,nij->n", Ra, Rb) - 1) / 2
    att = np.arccos(np.clip(cosang, -1, 1))
    pos = np.linalg.norm(tr.R - ref.R, axis=1) / np.max(np.linalg.norm(ref.R - ref.R[0], axis=1))
    rod = np.max(np.abs(tr.p - ref.p), axis=1) / np.max(np.abs(ref.p))
    assert row["err_att_max"] == pytest.approx(att.max(), rel=1e-4)
    assert row["err_pos_max"] == pytest.approx(pos.max(), rel=1e-6)
    assert row["err_rod_max"] == pytest.approx(rod.max(), rel=1e-6)
    assert row["err_pos_final"] == pytest.approx(pos[-1], rel=1e-6)
    assert row["error"] == pytest.approx(max(att.max(), pos.max(), rod.max()), rel=1e-4)
    for k, v in drift_figures(tr).items():
        assert row[k] == pytest.approx(v, rel=1e-9, abs=1e-300)


def test_tracking_error_follows_the_closed_form(result, scene):
    """docs/errata.md, item 3: e_ω(t) = exp(-P t) e_ω(0) exactly; accurate runs must report |e_ω(T)|."""
    ot = scene.control.omega
    comps = list(ot.components)
    e0 = scene.initial.omega[comps] - ot.b[comps]  # ω̄(0) = b cos 0
    T = sweep.SweepConfig.quick().t_end
    expected = float(np.max(np.abs(expm(-ot.gain * T) @ e0)))
    for r in result.runs:
        if r["status"] == "ok" and r["error"] < 1e-8:
            assert r["tracking_omega_final"] == pytest.approx(expected, rel=1e-6), r["run_id"]


def test_stabilization_norm_error_obeys_its_ode(result):
    """φ = uᵀu − 1 solves φ̈ + δ1 φ̇ + δ2 φ = 0 with φ̇(0) = 0 (u̇(0) = Hᵀω/… ⟂ u)."""
    rows = [s for s in result.stabilization if s["initial_norm_error"] > 0]
    assert {(s["delta1"], s["delta2"]) for s in rows} == set(sweep.SweepConfig.quick().deltas)
    for s in rows:
        d1, d2, phi0 = s["delta1"], s["delta2"], s["initial_norm_error"]
        sol = solve_ivp(
            lambda t, x, d1=d1, d2=d2: [x[1], -d1 * x[1] - d2 * x[0]],
            (0, s["t_end"]),
            [phi0, 0.0],
            rtol=1e-12,
            atol=1e-16,
        )
        assert s["quat_norm_error_final"] == pytest.approx(sol.y[0, -1], rel=1e-4, abs=1e-9)
    exact_start = [s for s in result.stabilization if s["initial_norm_error"] == 0]
    for s in exact_start:
        assert s["quat_norm_error_max"] < 1e-8  # stays on the sphere up to the tolerance


def test_cheapest_setting_table(result):
    """For each level: the pick is below the level and no cheaper qualifying run exists."""
    levels = sweep.SweepConfig.quick().levels
    assert levels == tuple(10.0**-k for k in range(3, 11))
    engines = ["analytic", "mujoco"] + (["pinocchio"] if HAS_PIN else [])
    assert list(result.cheapest) == engines
    for engine in engines:
        cands_all = [r for r in result.runs if r["engine"] == engine and r["status"] == "ok"]
        for lv in levels:
            pick = result.cheapest[engine][lv]
            qualifying = [r for r in cands_all if r["error"] <= lv]
            if not qualifying or lv <= sweep.FLOOR_FACTOR * result.reference["error_estimate"]:
                assert pick is None
                continue
            r = result.runs[pick]
            assert r["engine"] == engine and r["status"] == "ok" and r["error"] <= lv
            assert all(q["wall_time_s"] >= r["wall_time_s"] for q in qualifying)
    md_rows = {
        int(line.split("|")[1]): line
        for line in (result.out_dir / "sweep.md")
        .read_text()
        .split("## Every run")[1]
        .split("## Stabilisation")[0]
        .splitlines()
        if line.startswith("| ") and line.split("|")[1].strip().isdigit()
    }
    for engine in engines:
        for lv, rid in result.cheapest[engine].items():
            if rid is not None:
                assert "★" in md_rows[rid] and f"{lv:.0e}" in md_rows[rid]


def _json_number(v):
    """What JSON holds for ``v``: a number, or None where it is not a finite one."""
    return None if isinstance(v, float) and not math.isfinite(v) else v


def test_csv_and_json_round_trip(result):
    rows_csv = sweep.read_csv(result.files["csv"])
    doc = json.loads(result.files["json"].read_text())
    rows_json = doc["runs"]
    assert len(rows_csv) == len(rows_json) == len(result.runs)
    for a, b, c in zip(rows_csv, rows_json, result.runs, strict=True):
        assert set(a) == set(sweep.COLUMNS)
        for k in sweep.COLUMNS:
            assert _json_number(a[k]) == b[k] == _json_number(c[k]), (k, a[k], b[k], c[k])
        assert b["wall_time_samples_s"] == c["wall_time_samples_s"]  # every timing, whole
    assert doc["reference"]["error_estimate"] == result.reference["error_estimate"]


def test_files_complete_and_written_atomically(result):
    names = {p.name for p in result.out_dir.iterdir()}
    assert {"sweep.csv", "sweep.json", "sweep.md", "work_precision.png", "sweep.rrd"} <= names
    assert not [n for n in names if n.endswith(".tmp")]
    assert result.files["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from rerun.chunk import RrdReader

    store = RrdReader(str(result.files["rrd"])).store()  # raises without the footer
    ents = {str(e) for e in store.schema().entity_paths()}
    assert "/work_precision/mujoco/RK4" in ents and "/work_precision/analytic/DOP853" in ents
    if HAS_PIN:
        assert {f"/work_precision/pinocchio/{m}" for m in sweep.SweepConfig.quick().solvers} <= ents


@needs_pin
def test_pinocchio_series_errors_fall_with_rtol_like_the_analytic_ones(result):
    """The Pinocchio plant integrates the same motion in other coordinates: over the same solvers
    and rtols its error against the (analytic) reference falls with rtol by orders of magnitude, to
    the level the analytic engine reaches (no model difference left above ~1e-10), and with DOP853
    it stays within a small factor of the analytic engine's at every rtol."""
    cfg = sweep.SweepConfig.quick()
    for method in cfg.solvers:
        rows = _ok(result, "pinocchio", method)
        assert [r["rtol"] for r in rows] == list(cfg.rtols), method  # every setting ran ok
        errs = [r["error"] for r in rows]
        assert errs[-1] <= 1e-2 * errs[0], (method, errs)
        for a, b in itertools.pairwise(errs):
            assert b <= 2 * a, (method, errs)  # monotone within a factor 2
        assert errs[-1] < 1e-10, (method, errs)
        for r in rows:
            assert r["nfev"] > 0 and r["wall_time_s"] > 0 and r["wall_time_repeats"] >= 1
            assert r["setting_name"] == "rtol" and r["atol"] == pytest.approx(
                r["rtol"] * cfg.atol_ratio
            )
    dop_p = [r["error"] for r in _ok(result, "pinocchio", "DOP853")]
    dop_a = [r["error"] for r in _ok(result, "analytic", "DOP853")]
    assert dop_p[-1] < 1e-5 * dop_p[0]  # as for the analytic engine
    for ep, ea in zip(dop_p, dop_a, strict=True):
        assert ea / 5 < ep < 5 * ea, (dop_p, dop_a)
    # tracking: accurate Pinocchio runs report the same closed-form e_ω(T) as the analytic ones
    acc = [r for r in result.runs if r["status"] == "ok" and r["error"] < 1e-8]
    track = {r["engine"]: r["tracking_omega_final"] for r in acc}
    assert track["pinocchio"] == pytest.approx(track["analytic"], rel=1e-6)
    md = result.files["md"].read_text()
    assert "## Pinocchio and the analytic engine at the same setting" in md
    assert "| level | analytic | mujoco | pinocchio |" in md
    doc = json.loads(result.files["json"].read_text())
    assert doc["skipped_series"] == [] and result.skipped_series == {}
    assert {"engine": "pinocchio", "method": "DOP853"} in doc["series"]
    csv_engines = {r["engine"] for r in sweep.read_csv(result.files["csv"])}
    assert csv_engines == {"analytic", "mujoco", "pinocchio"}


def test_sweep_without_pinocchio_says_the_series_was_skipped(tmp_path, monkeypatch):
    """Without pin the sweep runs the other plants and says, in sweep.md and sweep.json, that the
    Pinocchio series was skipped and why."""
    reason = "the Pinocchio plant needs the 'pin' package (>= 4.1) [test]"
    monkeypatch.setattr(PinocchioPlant, "unavailable", classmethod(lambda cls: reason))

    def never(*_a, **_k):
        raise AssertionError("a Pinocchio run was attempted without pin")

    monkeypatch.setattr(running, "pinocchio_run", never)
    with ThreadPoolExecutor(max_workers=2) as ex:  # threads: the patches hold in the workers
        res = sweep.run_sweep(
            SCENE, tmp_path / "out", executor=ex, config=_tiny(), cache_dir=tmp_path / "cache"
        )
    assert {r["engine"] for r in res.runs} == {"analytic", "mujoco"}
    assert all(r["status"] == "ok" for r in res.runs)
    assert res.skipped_series == {"pinocchio": reason}
    assert list(res.cheapest) == ["analytic", "mujoco"]
    md = res.files["md"].read_text()
    assert f"Pinocchio series skipped: pin is not installed ({reason})" in md
    assert "| level | analytic | mujoco | pinocchio |" in md and "series skipped |" in md
    doc = json.loads(res.files["json"].read_text())
    assert doc["skipped_series"] == [
        {
            "engine": "pinocchio",
            "reason": reason,
            "note": f"Pinocchio series skipped: pin is not installed ({reason})",
        }
    ]
    assert all(s["engine"] != "pinocchio" for s in doc["series"])


def test_effects_rows(result, scene):
    offs = [r["off"] for r in result.effects]
    assert len(offs) == 1 + len(scene.effects)
    assert set(offs[1:]) == {e.value for e in scene.effects}
    for r in result.effects:
        if not r["note"]:
            for c in ("analytic_fast", "mj_forward", "mj_forward_ctrl"):
                assert r[c] is not None and r[c] > 0


def _tiny(**kw):
    return dataclasses.replace(
        sweep.SweepConfig.quick(),
        solvers=("DOP853",),
        rtols=(1e-5, 1e-9),
        integrators=("RK4",),
        dts=(1e-2, 5e-3),
        deltas=((0.5, 8.0),),
        effects_repeats=1,
        **kw,
    )


def test_series_stops_when_too_slow_and_reports_it(scene, result, monkeypatch):
    """The wall times are made up, so where a series stops does not depend on the machine's speed
    or load: a MuJoCo run costs 5e-5 s / dt, and the analytic engine's budget clock advances 1 ms
    at every reading (at the start and at each output sample passed: ~20 at rtol 1e-3, ~50 at
    tighter tolerances over these 0.5 s)."""
    ref = sweep.ref_samples(sweep.reference_run(scene, 0.5, result.reference["max_step"]))
    real = running.mujoco_run

    def costed(sc, integrator, dt, t_end, budget=None):
        tr = real(sc, integrator, dt, t_end)
        return dataclasses.replace(tr, info={**tr.info, "wall_time_s": 5e-5 / dt})

    monkeypatch.setattr(running, "mujoco_run", costed)
    cfg = dataclasses.replace(
        sweep.SweepConfig.quick(), dts=tuple(1e-2 / 2**k for k in range(8)), max_run_wall_s=0.05
    )
    rows = sweep.run_series(scene, "mujoco", "RK4", cfg, ref)
    assert [r["dt"] for r in rows] == list(cfg.dts)
    # predicted from the last two runs (cost a + b/dt, here a = 0): 0.04 s at dt = 1.25e-3, then
    # 0.08 s > 0.05 s at dt/2
    assert [r["status"] for r in rows] == ["ok"] * 4 + ["too_slow"] + ["skipped"] * 3
    assert all("too slow" in r["note"] for r in rows[4:])

    monkeypatch.setattr(running, "time", _Clock())
    cfg_a = dataclasses.replace(sweep.SweepConfig.quick(), max_run_wall_s=0.03)
    rows_a = sweep.run_series(scene, "analytic", "Radau", cfg_a, ref)
    assert [r["rtol"] for r in rows_a] == list(cfg_a.rtols)
    statuses = [r["status"] for r in rows_a]
    assert statuses == ["ok", "too_slow"] + ["skipped"] * (len(statuses) - 2), rows_a


@needs_pin
def test_pinocchio_series_keeps_the_budget_and_a_real_interrupt_stops_the_sweep(
    scene, result, monkeypatch
):
    """The Pinocchio series is stopped for its budget as the analytic one is (made-up clock, as
    above); a KeyboardInterrupt that is not the budget's (Ctrl-C) is not taken for 'too slow': it
    propagates out of the run and the series."""
    ref = sweep.ref_samples(sweep.reference_run(scene, 0.5, result.reference["max_step"]))

    monkeypatch.setattr(running, "time", _Clock())
    cfg = dataclasses.replace(sweep.SweepConfig.quick(), max_run_wall_s=0.03)
    rows = sweep.run_series(scene, "pinocchio", "Radau", cfg, ref)
    statuses = [r["status"] for r in rows]
    assert statuses == ["ok", "too_slow"] + ["skipped"] * (len(statuses) - 2), rows
    assert "stopped at its budget of 0.03 s" in rows[1]["note"]
    # the budget's stop is an ordinary exception: no handler of the user's interrupt can take it
    assert not issubclass(running.BudgetExceeded, KeyboardInterrupt)

    class CtrlC:
        """A user's Ctrl-C arriving inside the run (at the third clock reading: in progress)."""

        calls = 0

        def perf_counter(self):
            self.calls += 1
            if self.calls >= 3:
                raise KeyboardInterrupt
            return 0.0

    monkeypatch.setattr(running, "time", CtrlC())
    with pytest.raises(KeyboardInterrupt) as info:
        running.pinocchio_run(scene, "DOP853", 1e-6, 1e-7, 0.5, budget=100.0)
    assert not isinstance(info.value, running.BudgetExceeded)
    monkeypatch.setattr(running, "time", CtrlC())
    with pytest.raises(KeyboardInterrupt):
        sweep.run_series(scene, "pinocchio", "DOP853", cfg, ref)


def test_divergence_stops_a_series(scene, result, monkeypatch):
    """A run that blows up after a coarser one worked is 'diverged' and ends the series."""
    ref = sweep.ref_samples(sweep.reference_run(scene, 0.5, result.reference["max_step"]))
    real = running.mujoco_run

    def fake(sc, integrator, dt, t_end, budget=None):
        tr = real(sc, integrator, dt, t_end)
        if dt < 6e-3:  # pretend the run blew up: C thrown 1 km off
            q = tr.q.copy()
            q[:, :3] += 1e3
            return dataclasses.replace(tr, q=q)
        return tr

    monkeypatch.setattr(running, "mujoco_run", fake)
    cfg = dataclasses.replace(sweep.SweepConfig.quick(), dts=(1e-2, 5e-3, 2.5e-3))
    rows = sweep.run_series(scene, "mujoco", "RK4", cfg, ref)
    assert [r["status"] for r in rows] == ["ok", "diverged", "skipped"]


def _compare_with_quick(res, result):
    quick = {(r["engine"], r["method"], r["setting"]): r for r in result.runs}
    for r in res.runs:
        q = quick[(r["engine"], r["method"], r["setting"])]
        assert r["status"] == q["status"] == "ok"
        assert r["error"] == pytest.approx(q["error"], rel=1e-9)
        assert r["nfev"] == q["nfev"]


def test_user_thread_executor(tmp_path, result, cache_dir):
    with ThreadPoolExecutor(max_workers=2) as ex:
        res = sweep.run_sweep(SCENE, tmp_path, executor=ex, config=_tiny(), cache_dir=cache_dir)
    _compare_with_quick(res, result)


def test_dask_local_cluster(tmp_path, result, cache_dir):
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        res = sweep.run_sweep(
            SCENE, tmp_path, executor=client.get_executor(), config=_tiny(), cache_dir=cache_dir
        )
    _compare_with_quick(res, result)


RK4_COST_S = 1e-4  # made-up MuJoCo wall of a 1 s run at dt: RK4_COST_S / dt (0.1 s at dt = 1e-3)


def _goal_with_made_up_walls(monkeypatch, cap_s):
    """The 60 s goal's search over 1 s with MuJoCo's wall made up as ``RK4_COST_S / dt`` (exactly
    linear in the step count, so where the search stops and what it predicts do not depend on the
    machine's speed or load); the errors are the real ones."""
    import mj_bridge
    from validation.bench import example1_goal

    real = mj_bridge.simulate

    def costed(sc, *, dt, **kw):
        tr = real(sc, dt=dt, **kw)
        return dataclasses.replace(tr, info={**tr.info, "wall_time_s": RK4_COST_S / dt})

    monkeypatch.setattr(mj_bridge, "simulate", costed)
    # the goal counts each run's wall times the share of a CPU the thread had during it: with the
    # walls made up, the share is planted too (a whole CPU), so the costs are exactly those walls
    monkeypatch.setattr(example1_goal.CpuMeter, "share", property(lambda self: 1.0))
    return example1_goal.goal_example1_60s(t_end=1.0, cap_s=cap_s, progress=lambda _s: None)


def _dt_reaching(e_target, pts):
    """The dt at which the power law through the two (dt, error) points reaches ``e_target``,
    fitted here as a straight line in log-log (numpy's least squares on two points), and its
    order (the slope)."""
    (dt1, e1, _), (dt2, e2, _) = pts
    order, log_c = np.polyfit(np.log([dt1, dt2]), np.log([e1, e2]), 1)
    return float(np.exp((np.log(e_target) - log_c) / order)), float(order)


def test_goal_same_accuracy_search_interpolates_to_the_analytic_accuracy(monkeypatch):
    """Without a cap the search halves dt until RK4 is as accurate as the analytic run and stops
    at the first such run; the two last runs show RK4's order (the controller inside every stage),
    and the ratio uses MuJoCo's wall at exactly the analytic accuracy. With walls exactly
    ``RK4_COST_S / dt`` that wall is known independently: ``RK4_COST_S / dt_need``."""
    from validation.bench.goal import Goal

    g = _goal_with_made_up_walls(monkeypatch, cap_s=1e9)
    e_a, w_a = g.data["analytic"]
    pts = g.data["rk4"]
    assert not g.extrapolated
    assert len(pts) >= 2, pts  # RK4 at dt = 1e-3 is not as accurate as DOP853 at rtol 1e-12
    assert all(math.isclose(a[0], 2 * b[0]) for a, b in itertools.pairwise(pts))
    assert pts[-1][1] <= e_a < pts[-2][1]
    assert all(p[1] > e_a for p in pts[:-1])  # stopped at the first run as accurate
    dt_need, order = _dt_reaching(e_a, pts[-2:])
    assert 3.5 < order < 4.5, order  # RK4, with the controller evaluated in every stage
    assert pts[-1][0] <= dt_need <= pts[-2][0]
    assert g.value == pytest.approx(w_a / (RK4_COST_S / dt_need), rel=1e-9)
    # the first run found as accurate would have flattered MuJoCo less: it did more work than needed
    assert g.value > w_a / pts[-1][2]
    assert Goal("x", 1.0, 1.0).holds and not Goal("x", 1.01, 1.0).holds
    assert not Goal("x", math.nan, 1.0).holds


def test_goal_same_accuracy_search_extrapolates_when_capped(monkeypatch):
    """A cap that stops the search after two runs (0.1 s and 0.2 s of made-up wall: the next, 0.4 s,
    would pass 2 x 0.2 s > 0.3 s) before RK4 reaches the analytic accuracy: the goal says it is
    extrapolated and predicts MuJoCo's wall at the dt where RK4's observed power law reaches that
    accuracy, wall ∝ 1/dt from the last run, i.e. exactly ``RK4_COST_S / dt_need`` here."""
    g = _goal_with_made_up_walls(monkeypatch, cap_s=0.3)
    e_a, w_a = g.data["analytic"]
    pts = g.data["rk4"]
    assert g.extrapolated and "(extrapolated)" in g.line()
    assert [p[0] for p in pts] == pytest.approx([1e-3, 5e-4])
    assert all(p[1] > e_a for p in pts)  # the cap, not the accuracy, stopped the search
    dt_need, order = _dt_reaching(e_a, pts)
    assert 3.5 < order < 4.5, order
    assert dt_need < pts[-1][0]  # a finer step than any run made
    assert g.value == pytest.approx(w_a / (RK4_COST_S / dt_need), rel=1e-9)
    assert g.value < w_a / pts[-1][2]  # MuJoCo needs more than its last run's wall
    assert f"{order:.2f}" in g.detail and "did not reach it" in g.detail


def test_pinocchio_goal_is_skipped_with_its_reason_without_pin(monkeypatch, tmp_path):
    """No timing: the goal is skipped before anything runs; bench prints and writes it as
    skipped, neither holding nor failing, and names no issue numbers."""
    from validation.bench import command as bench
    from validation.bench import goals
    from validation.bench.goal import Goal
    from validation.bench.pinocchio_goal import goal_pinocchio

    monkeypatch.setattr(
        PinocchioPlant, "unavailable", classmethod(lambda cls: "no pin here [test]")
    )
    g = goal_pinocchio(progress=lambda _s: pytest.fail("nothing is measured"))
    assert g.skipped == "pin is not installed: no pin here [test]"
    assert g.verdict == "SKIPPED" and not g.holds and g.limit == 3.0
    assert g.line() == f"{g.name}: skipped (pin is not installed: no pin here [test])"

    done = Goal("a measured goal", 0.5, 1.0, "detail")
    monkeypatch.setattr(goals, "measure", lambda skip_long, progress: [done, g])
    monkeypatch.setattr(bench, "evaluation_table", lambda: [])
    lines: list[str] = []
    path = tmp_path / "bench.json"
    assert bench.run(True, str(path), out=lines.append)  # a skipped goal does not fail the run
    text = "\n".join(lines)
    assert "issue" not in text.lower()
    assert f"SKIPPED  {g.name}: pin is not installed" in text
    assert "HOLDS  a measured goal: 0.5" in text
    doc = json.loads(path.read_text())
    by_name = {d["name"]: d for d in doc["goals"]}
    assert by_name[g.name]["verdict"] == "SKIPPED" and by_name[g.name]["ratio"] is None
    assert by_name[g.name]["skipped"].startswith("pin is not installed")
    assert by_name["a measured goal"]["verdict"] == "HOLDS"


@needs_pin
def test_pinocchio_goal_structure():
    """The goal's bookkeeping on a short horizon (speeds are not asserted): warm run first, then
    interleaved rounds alternating who goes first, ratio = the median of the rounds' ratios, and
    both plants ran the same motion."""
    from validation.bench.pinocchio_goal import goal_pinocchio

    g = goal_pinocchio(t_end=0.5, rounds=3, progress=lambda _s: None)
    d = g.data
    assert not g.skipped and g.limit == 3.0
    assert len(d["analytic_s"]) == len(d["pinocchio_s"]) == 3
    a_first, p_first = ["analytic", "pinocchio"], ["pinocchio", "analytic"]
    assert d["order"] == [a_first, p_first, a_first]
    assert d["analytic_median_s"] == sorted(d["analytic_s"])[1]
    # the ratio: the median of the rounds' ratios of CPU time, each at most the round's wall
    assert d["ratios"] == pytest.approx(
        [p / a for p, a in zip(d["pinocchio_cpu_s"], d["analytic_cpu_s"], strict=True)]
    )
    assert g.value == sorted(d["ratios"])[1] and g.spread.rounds == 3
    assert all(c <= w for c, w in zip(d["analytic_cpu_s"], d["analytic_s"], strict=True))
    assert d["max_distance_C_m"] < 1e-9  # same motion (C falls ~1.2 m in 0.5 s)
    assert g.verdict != "SKIPPED"  # HOLDS, FAILS or (three short rounds, a busy machine) TOO_BUSY


# ----------------------------------------------------------------------------------------------
# The recording, the figure, the JSON
# ----------------------------------------------------------------------------------------------


def _rrd_views(path) -> dict[str, tuple[str, str]]:
    """``{view name: (view class, origin)}`` of the blueprint stored in a recording."""
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    (bp,) = reader.blueprints()
    views: dict[str, tuple[str, str]] = {}
    for chunk in reader.store(store=bp).stream().to_chunks():
        rb = chunk.to_record_batch()
        if "ViewBlueprint:display_name" in rb.schema.names:
            for name, cls, origin in zip(
                rb.column("ViewBlueprint:display_name").to_pylist(),
                rb.column("ViewBlueprint:class_identifier").to_pylist(),
                rb.column("ViewBlueprint:space_origin").to_pylist(),
                strict=True,
            ):
                views[name[0]] = (cls[0], origin[0])
    return views


def test_recording_shows_the_work_precision_plot_without_a_timeline_or_a_png_link(result):
    """The recording's blueprint has the work-precision plot as a 2D view of its own entities and
    the text beside it; nothing is on a timeline (no wall-time axis); its text names the PNG file
    but links to no file the viewer cannot open."""
    from rerun.chunk import RrdReader

    views = _rrd_views(result.files["rrd"])
    assert views["work-precision"] == ("2D", "/work_precision")
    assert views["sweep.md"] == ("TextDocument", "/report")
    store = RrdReader(str(result.files["rrd"])).store()
    assert store.schema().index_columns() == []  # static only: no wall_time (or any) timeline
    (chunk,) = store.stream().filter(content="/report").to_chunks()
    text = chunk.to_record_batch().column("TextDocument:text").to_pylist()[0][0]
    assert "# What accuracy costs in time" in text and "**Figure: work-precision" in text
    assert ".png)" not in text and "](" not in text  # no markdown link or image
    assert "![work-precision](work_precision.png)" in result.files["md"].read_text()


def test_sweep_json_has_numbers_not_nan_strings(result):
    """Every number of sweep.json is a JSON number or null: no NaN/Infinity tokens (which strict
    parsers refuse), no 'nan' / 'inf' strings, no abbreviated arrays."""
    text = result.files["json"].read_text()

    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")

    doc = json.loads(text, parse_constant=refuse)

    def strings(x):
        if isinstance(x, dict):
            for v in x.values():
                yield from strings(v)
        elif isinstance(x, list):
            for v in x:
                yield from strings(v)
        elif isinstance(x, str):
            yield x

    bad = {s for s in strings(doc) if s.lower() in {"nan", "inf", "-inf", "infinity"}}
    bad |= {s for s in strings(doc) if s.startswith("<") and s.endswith("values>")}
    assert not bad
    for r in doc["runs"]:
        if r["status"] == "ok":
            assert len(r["wall_time_samples_s"]) == r["wall_time_repeats"] >= 1
    # a row with a non-finite error (a diverged run) is written with null, not a string
    row = dict(result.runs[0], error=math.nan, error_final=math.inf, status="diverged")
    res = dataclasses.replace(result, runs=(row,))
    out = json.loads(json_doc.sweep_json(res, sweep.SweepConfig.quick()), parse_constant=refuse)
    assert out["runs"][0]["error"] is None and out["runs"][0]["error_final"] is None


def _row(engine, method, setting, status, error=None, walls=(), note="", rid=0, predicted=None):
    row = rows.blank_row(engine, method, setting, sweep.SweepConfig.quick())
    row.update(run_id=rid, status=status, error=error, note=note, wall_time_predicted_s=predicted)
    row.update(timing.summary(list(walls)), at_reference_floor=False, horizon_s=20.0)
    return row


def test_failed_and_cut_series_are_marks_in_the_figure(tmp_path):
    """A series whose every run failed has no line but one labelled mark per failed run; a series
    cut as too slow keeps its line and gets a mark at the predicted wall time and its last error;
    the PNG is drawn with both."""
    runs = [
        _row("analytic", "DOP853", 1e-4, "ok", 1e-3, [0.02, 0.01, 0.03], rid=0),
        _row("analytic", "DOP853", 1e-6, "ok", 1e-5, [0.05], rid=1),
        _row("analytic", "DOP853", 1e-8, "too_slow", predicted=9.0, note="too slow", rid=2),
        _row("analytic", "DOP853", 1e-10, "skipped", note="series stopped", rid=3),
        _row("mujoco", "implicit", 1e-2, "failed", note="MuJoCo warning", rid=4),
        _row("mujoco", "implicit", 5e-3, "failed", walls=[0.2], note="non-finite", rid=5),
    ]
    data = figure.figure_data(runs, 1e-12, "a scene", 20.0)
    assert [(ln.engine, ln.method) for ln in data.lines] == [("analytic", "DOP853")]
    (line,) = data.lines
    per_s = 1 / 20.0  # wall times per simulated second: the runs' over their 20 s horizon
    assert [p.wall for p in line.points] == pytest.approx([0.02 * per_s, 0.05 * per_s])
    first = line.points[0]
    assert (first.wall_min, first.wall_max, first.n) == pytest.approx((0.01 * per_s, 0.03 * per_s, 3))
    by_run = {m.run_id: m for m in data.marks}
    assert set(by_run) == {2, 4, 5}  # every run that is not ok and was attempted
    cut = by_run[2]
    assert cut.outcome == "too_slow" and (cut.wall, cut.error) == pytest.approx((9.0 * per_s, 1e-5))
    assert "too slow" in cut.label and "1 skipped" in cut.label
    for rid in (4, 5):
        m = by_run[rid]
        assert (m.engine, m.method, m.outcome) == ("mujoco", "implicit", "failed")
        assert "mujoco implicit" in m.label and "failed" in m.label and m.error is None
    assert by_run[4].wall is None and by_run[5].wall == pytest.approx(0.2 * per_s)
    assert "horizon 20 s" in data.title and "attitude angle" in data.error_measure
    assert figure.render_png(data)[:8] == b"\x89PNG\r\n\x1a\n"


# ----------------------------------------------------------------------------------------------
# Timing: medians and spread
# ----------------------------------------------------------------------------------------------


def test_timing_summary_is_the_median_and_the_spread():
    s = timing.summary([0.3, 0.1, 0.2, 0.25])
    assert s == {
        "wall_time_s": pytest.approx(0.225),  # the mean of the middle two: an even count
        "wall_time_min_s": 0.1,
        "wall_time_max_s": 0.3,
        "wall_time_repeats": 4,
    }
    assert timing.summary([])["wall_time_s"] is None


def test_a_series_reports_the_median_of_its_repeats(scene, result, monkeypatch):
    """Made-up walls (so the test does not depend on the machine): the MuJoCo runs of the series
    take 3, 1, 2 ms, then 0.3, 0.4 s (after an untimed warm-up run); a setting is timed up to ``repeats`` times while its
    timings add up to less than ``repeat_budget_s``, and reports their median, min and max."""
    ref = sweep.ref_samples(sweep.reference_run(scene, 0.5, result.reference["max_step"]))
    real = running.mujoco_run
    walls = iter([9.0, 3e-3, 1e-3, 2e-3, 0.3, 0.4, 0.2])  # the first: the untimed warm-up

    def costed(sc, integrator, dt, t_end, budget=None):
        tr = real(sc, integrator, dt, t_end)
        return dataclasses.replace(tr, info={**tr.info, "wall_time_s": next(walls)})

    monkeypatch.setattr(running, "mujoco_run", costed)
    cfg = dataclasses.replace(
        sweep.SweepConfig.quick(), dts=(1e-2, 5e-3), repeats=3, repeat_budget_s=0.5
    )
    rows = series.run_series(scene, "mujoco", "RK4", cfg, ref)
    assert [r["status"] for r in rows] == ["ok", "ok"]
    first, second = rows
    assert first["wall_time_samples_s"] == [3e-3, 1e-3, 2e-3]
    assert (first["wall_time_s"], first["wall_time_min_s"], first["wall_time_max_s"]) == (
        2e-3,
        1e-3,
        3e-3,
    )
    # 0.3 s: one repeat (0.3 < 0.5), then 0.7 s ≥ 0.5: no third
    assert second["wall_time_samples_s"] == [0.3, 0.4] and second["wall_time_repeats"] == 2
    assert second["wall_time_s"] == pytest.approx(0.35)


# ----------------------------------------------------------------------------------------------
# The reference cache
# ----------------------------------------------------------------------------------------------


class _Inline(Executor):
    """Runs each task at once, in this thread, and counts the reference runs."""

    def __init__(self):
        self.reference_runs = 0

    def submit(self, fn, /, *args, **kwargs):
        if fn is reference.reference_task:
            self.reference_runs += 1
        f = Future()
        f.set_result(fn(*args, **kwargs))
        return f


T_CACHE = 0.2  # s: the cache tests' horizon (two reference runs of 0.2 s each)


def test_reference_cache_hit_on_the_same_scene(scene, tmp_path):
    ex = _Inline()
    first = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    assert ex.reference_runs == 2 and first.info["cache"]["status"].startswith("computed")
    path = first.info["cache"]["path"]
    assert path.startswith(str(tmp_path)) and path.endswith(".npz")
    again = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    assert ex.reference_runs == 2  # nothing recomputed
    assert again.info["cache"]["status"] == "cached" and again.info["cache"]["path"] == path
    for k in ("t", "R", "u", "p"):
        assert np.array_equal(getattr(again.samples, k), getattr(first.samples, k))
    assert again.error_estimate == first.error_estimate
    # the scene's name, description and source path do not change the motion: still a hit
    renamed = scene.replace(name="another_name", description="", source="")
    reference.obtain_reference(renamed, T_CACHE, ex, tmp_path)
    assert ex.reference_runs == 2


def test_reference_cache_misses_after_a_scene_or_horizon_change(scene, tmp_path):
    ex = _Inline()
    base = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    spun = scene.replace(
        initial=dataclasses.replace(scene.initial, omega=scene.initial.omega * 1.001)
    )
    other = reference.obtain_reference(spun, T_CACHE, ex, tmp_path)
    assert ex.reference_runs == 4 and other.info["cache"]["status"].startswith("computed")
    assert other.info["cache"]["key"] != base.info["cache"]["key"]
    assert not np.array_equal(other.samples.u, base.samples.u)  # another motion
    longer = reference.obtain_reference(scene, 2 * T_CACHE, ex, tmp_path)
    assert ex.reference_runs == 6 and len(longer.samples.t) > len(base.samples.t)
    assert len(list(tmp_path.glob("reference-*.npz"))) == 3


@pytest.mark.parametrize(
    "damage", ["garbage", "truncated", "flipped byte", "another scene's file", "empty"]
)
def test_a_damaged_reference_cache_file_is_refused_and_recomputed(scene, tmp_path, damage):
    ex = _Inline()
    good = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    path = Path(good.info["cache"]["path"])
    data = path.read_bytes()
    if damage == "garbage":
        path.write_bytes(b"not a cache file" * 10)
    elif damage == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "flipped byte":  # inside a member's data: the zip CRC no longer matches
        k = data.index(b"\x93NUMPY") + 200
        path.write_bytes(data[:k] + bytes([data[k] ^ 0xFF]) + data[k + 1 :])
    elif damage == "another scene's file":
        spun = scene.replace(initial=dataclasses.replace(scene.initial, p=scene.initial.p + 0.01))
        other = reference.obtain_reference(spun, T_CACHE, ex, tmp_path / "elsewhere")
        path.write_bytes(Path(other.info["cache"]["path"]).read_bytes())
    else:
        path.write_bytes(b"")
    runs_before = ex.reference_runs
    again = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    assert ex.reference_runs == runs_before + 2  # refused, recomputed
    assert "cache file refused" in again.info["cache"]["status"]
    assert np.array_equal(again.samples.u, good.samples.u)
    # and stored again, whole: the next sweep reads it
    final = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    assert final.info["cache"]["status"] == "cached" and ex.reference_runs == runs_before + 2


def test_the_sweep_reads_its_reference_from_the_cache(result, cache_dir):
    """The module's quick sweep stored its reference; the key names the scene, horizon, reference
    settings and code, and a sweep of the same scene finds it."""
    key = reference.cache_key(resolve_scene(SCENE), sweep.SweepConfig.quick().t_end)
    assert result.reference["cache"]["key"] == key
    assert (cache_dir / f"reference-{key}.npz").is_file()
    assert result.reference["cache"]["status"] in {"cached", "computed (not in the cache)"}


def test_python_m_validation_sweep_is_the_tumble_sweep_command_line():
    """One parser: ``python -m validation.studies.sweep`` is ``tumble sweep`` (same usage, same options)."""
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-m", "validation.studies.sweep", "--help"],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    ).stdout
    assert out.startswith("usage: tumble sweep")
    assert "--t-end" in out and "--quick" in out and "--out" in out
    from validation.cli import build_parser

    args = build_parser().parse_args(["sweep"])
    assert args.scene is None and args.t_end is None  # the defaults: DEFAULT_SCENE, 20 s
    assert sweep.DEFAULT_SCENE == SCENE and sweep.SweepConfig().t_end == 20.0


def _poison_rotation(path: Path, delta: float = 1e-4) -> None:
    """Rewrite the cache file at ``path`` with ``delta`` added to every rotation sample: the same
    members, shapes and finiteness (and the stored digest left as it was)."""
    with np.load(path, allow_pickle=False) as z:
        members = {k: np.array(z[k]) for k in z.files}
    members["R"] = members["R"] + delta
    with open(path, "wb") as f:
        np.savez(f, **members)


def test_a_poisoned_reference_cache_file_fails_its_content_check(scene, tmp_path):
    """A cache file whose rotation samples were shifted (still a well-formed, finite file of the
    right key and shapes) is refused by its content check, said in one line, and recomputed."""
    ex = _Inline()
    good = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    path = Path(good.info["cache"]["path"])
    _poison_rotation(path)
    with pytest.warns(reference.ReferenceCacheWarning) as record:
        again = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    lines = [str(w.message) for w in record]
    assert ex.reference_runs == 4  # refused, recomputed
    assert again.info["cache"]["status"] != "cached"
    assert np.array_equal(again.samples.R, good.samples.R)  # the true samples, not the poisoned
    said = [ln for ln in lines if "failed its content check" in ln]
    assert len(said) == 1 and str(path) in said[0] and "recomputing" in said[0]
    # replaced by a whole entry: the next sweep reads it, and it holds the true samples
    final = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    assert final.info["cache"]["status"] == "cached" and ex.reference_runs == 4
    assert np.array_equal(final.samples.R, good.samples.R)


def _obtain_unblocked(scene, cache_dir: Path, path: Path, ex: Executor, lines: list[str]):
    """``obtain_reference`` in a thread (its one-line warnings into ``lines``); should it block on
    the FIFO at ``path``, a writer is opened there to release it and the test fails."""
    import os
    import threading
    import warnings

    box: dict = {}

    def work():
        with warnings.catch_warnings(record=True) as record:
            warnings.simplefilter("always")
            box["ref"] = reference.obtain_reference(scene, T_CACHE, ex, cache_dir)
        lines.extend(str(w.message) for w in record)

    th = threading.Thread(target=work, daemon=True)
    th.start()
    th.join(120)
    if th.is_alive():
        fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK)  # release the blocked reader
        os.close(fd)
        th.join(30)
        pytest.fail(f"obtain_reference blocked on the FIFO at {path}")
    return box["ref"]


def test_a_fifo_at_the_reference_cache_path_is_not_read(scene, tmp_path):
    """A FIFO at the cache file's name is not read (no hang): one line says so, the reference is
    computed, and the FIFO, which the tool did not create, is left as it is (not stored)."""
    import os
    import stat

    key = reference.cache_key(scene, T_CACHE)
    path = reference.cache_path(tmp_path, key)
    os.mkfifo(path)
    ex, lines = _Inline(), []
    ref = _obtain_unblocked(scene, tmp_path, path, ex, lines)
    assert ex.reference_runs == 2 and ref.info["cache"]["status"].startswith("computed")
    said = [ln for ln in lines if "FIFO" in ln]
    assert len(said) == 1 and "not read" in said[0]
    assert stat.S_ISFIFO(os.lstat(path).st_mode)
    assert "not stored" in ref.info["cache"]["status"]
    assert sum("not stored" in ln for ln in lines) == 1
    # the next sweep does the same, again without blocking
    _obtain_unblocked(scene, tmp_path, path, ex, [])
    assert ex.reference_runs == 4


def test_a_directory_or_link_at_the_reference_cache_path_is_left_alone(scene, tmp_path):
    """A directory at the cache file's name is neither read nor replaced (the reference is computed
    and not stored, said in one line); a symbolic link there is not followed."""
    import os

    key = reference.cache_key(scene, T_CACHE)
    path = reference.cache_path(tmp_path, key)
    path.mkdir()
    (path / "user-file").write_text("kept")
    ex = _Inline()
    with pytest.warns(reference.ReferenceCacheWarning) as record:
        ref = reference.obtain_reference(scene, T_CACHE, ex, tmp_path)
    lines = [str(w.message) for w in record]
    assert ex.reference_runs == 2 and "not stored" in ref.info["cache"]["status"]
    assert (path / "user-file").read_text() == "kept"
    assert sum("directory" in ln and "not read" in ln for ln in lines) == 1
    assert sum("not stored" in ln for ln in lines) == 1
    # a link to a good entry elsewhere is not followed: it is computed here
    elsewhere = tmp_path / "elsewhere"
    reference.obtain_reference(scene, T_CACHE, ex, elsewhere)
    linked = tmp_path / "linked"
    linked.mkdir()
    target = reference.cache_path(elsewhere, key)
    os.symlink(target, reference.cache_path(linked, key))
    runs = ex.reference_runs
    with pytest.warns(reference.ReferenceCacheWarning):
        via_link = reference.obtain_reference(scene, T_CACHE, ex, linked)
    assert ex.reference_runs == runs + 2 and via_link.info["cache"]["status"] != "cached"
    assert target.is_file()  # the link's target is untouched


# ----------------------------------------------------------------------------------------------
# What sweep.md says, and what it claims from timings
# ----------------------------------------------------------------------------------------------


def test_sweep_text_says_what_was_done(result):
    """No 'up to 1 timings', no doubled 'computed'; the timing rule as the config has it."""
    from validation.studies.sweep.markdown import reference_origin

    md = (result.out_dir / "sweep.md").read_text()
    assert not re.search(r"up to 1 timings", md)
    assert "computed (computed" not in md and "Computed by this sweep (computed" not in md
    assert reference_origin({"status": "computed (not in the cache)"}) == (
        "Computed by this sweep (not in the cache)."
    )
    assert reference_origin({"status": "cached"}).startswith("Read from the cache")
    once = dataclasses.replace(sweep.SweepConfig.quick(), repeats=1)
    from validation.studies.sweep.markdown import _timing_words

    assert "timed once" in _timing_words(once, 2) and "up to" not in _timing_words(once, 2)


def test_quick_help_states_its_measured_duration():
    """The --quick help names a duration in seconds, not 'minutes'."""
    import argparse

    from validation.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    quick = next(a for a in sub.choices["sweep"]._actions if "--quick" in a.option_strings)
    assert "minutes" not in quick.help and "s on" in quick.help


def test_the_cheapest_pick_is_ranked_only_by_timings_that_separate(tmp_path):
    """Non-monotone single timings (a coarser step slower than a finer one) are not ranked;
    overlapping repeated timings name the rivals; separated ones are ranked."""
    from validation.studies.sweep.selection import cheapest_settings, ranking

    runs = [
        _row("mujoco", "RK4", 5e-3, "ok", 1e-7, [7.08e-3], rid=0),
        _row("mujoco", "RK4", 2.5e-3, "ok", 5e-9, [3.91e-3], rid=1),
    ]
    pick = cheapest_settings(runs, (1e-6,))["mujoco"][1e-6]
    assert pick == 1 and not ranking(runs, pick, 1e-6).ranked  # one timing each: no spread
    overlapping = [
        _row("mujoco", "RK4", 5e-3, "ok", 1e-7, [7e-3, 4e-3, 9e-3], rid=0),
        _row("mujoco", "RK4", 2.5e-3, "ok", 5e-9, [3.9e-3, 3.5e-3, 5e-3], rid=1),
    ]
    rank = ranking(overlapping, 1, 1e-6)
    assert rank.rivals == (0,) and not rank.ranked
    apart = [
        _row("mujoco", "RK4", 5e-3, "ok", 1e-7, [7e-3, 6.5e-3, 7.5e-3], rid=0),
        _row("mujoco", "RK4", 2.5e-3, "ok", 5e-9, [3.9e-3, 3.5e-3, 4.2e-3], rid=1),
        _row("mujoco", "RK4", 1e-2, "degraded", 1e-8, [1e-3, 1e-3, 1e-3], rid=2),
    ]
    assert cheapest_settings(apart, (1e-6,))["mujoco"][1e-6] == 1  # never the degraded run
    assert ranking(apart, 1, 1e-6).ranked


def test_every_cheapest_cell_states_its_timings(result):
    """Each pick in sweep.md carries its timings and says when they do not rank it."""
    from validation.studies.sweep.selection import ranking

    md = (result.out_dir / "sweep.md").read_text()
    table = md.split("## Cheapest setting per accuracy level")[1].split("\n## ")[0]
    for by_level in result.cheapest.values():
        for lv, rid in by_level.items():
            if rid is None:
                continue
            line = next(ln for ln in table.splitlines() if ln.startswith(f"| {lv:.0e} |"))
            cell = next(c for c in line.split("|") if c.strip().startswith(f"#{rid} "))
            assert "ms (" in cell and "timing" in cell
            assert ("not ranked" in cell) == (not ranking(result.runs, rid, lv).ranked)


def test_a_dropped_control_is_degraded_not_ok(scene, result, monkeypatch):
    """A MuJoCo run in which a sampled control reached MJ_MAXVAL is 'degraded' (measured, drawn
    as a mark, never picked), not 'ok'."""
    ref = sweep.ref_samples(sweep.reference_run(scene, 0.5, result.reference["max_step"]))
    real = running.mujoco_run

    def loud(sc, integrator, dt, t_end, budget=None):
        tr = real(sc, integrator, dt, t_end)
        torque = tr.torque.copy()
        torque[-1, 0] = 2 * series.MJ_MAXVAL
        return dataclasses.replace(tr, torque=torque)

    monkeypatch.setattr(running, "mujoco_run", loud)
    cfg = dataclasses.replace(sweep.SweepConfig.quick(), dts=(1e-2,))
    (row,) = sweep.run_series(scene, "mujoco", "RK4", cfg, ref)
    assert row["status"] == "degraded" and "drops it for that step" in row["note"]
    assert row["wall_time_s"] is not None and row["error"] is not None
    row["run_id"] = 0  # numbered by the sweep
    assert sweep.cheapest_settings([row], (1.0,))["mujoco"][1.0] is None
    (mark,) = figure.figure_data([row], 0.0, "s", cfg.t_end).marks
    assert mark.outcome == "degraded" and "degraded" in mark.label


def test_coincident_series_are_both_visible_and_said_so():
    """Two series of one plant with the same errors (MuJoCo's Euler and implicitfast) are both
    in the legend, each naming the other, and the second is drawn with its own markers."""
    runs = [
        _row("mujoco", "Euler", 1e-2, "ok", 3e-3, [0.010, 0.011], rid=0),
        _row("mujoco", "Euler", 5e-3, "ok", 1.5e-3, [0.020, 0.021], rid=1),
        _row("mujoco", "implicitfast", 1e-2, "ok", 3e-3, [0.012, 0.013], rid=2),
        _row("mujoco", "implicitfast", 5e-3, "ok", 1.5e-3, [0.022, 0.024], rid=3),
        _row("mujoco", "RK4", 1e-2, "ok", 1e-6, [0.03, 0.031], rid=4),
        _row("mujoco", "RK4", 5e-3, "ok", 6e-8, [0.06, 0.061], rid=5),
    ]
    data = figure.figure_data(runs, 0.0, "s", 1.0)
    same = {ln.method: ln.same_as for ln in data.lines}
    assert same == {"Euler": ("implicitfast",), "implicitfast": ("Euler",), "RK4": ()}
    assert figure.render_png(data)[:8] == b"\x89PNG\r\n\x1a\n"


def test_effect_costs_claim_no_ratio_the_spread_does_not_support(result):
    """Each effect cost carries its spread and rounds; a ratio to the full scene is printed only
    where the two timing ranges do not meet."""
    from validation.studies.effects_cost import effects_markdown

    full = result.effects[0]
    lines = effects_markdown(list(result.effects))
    assert f"over {full['repeats']} rounds" in lines[0]
    for r in result.effects[1:]:
        if r["note"]:
            continue
        row = next(ln for ln in lines if ln.startswith(f"| {r['off']} |"))
        for c in ("analytic_fast", "mj_forward", "mj_forward_ctrl"):
            apart = r[f"{c}_max"] < full[f"{c}_min"] or r[f"{c}_min"] > full[f"{c}_max"]
            assert r[f"{c}_resolved"] == apart
        assert row.count("×") == sum(
            bool(r[f"{c}_resolved"]) for c in ("analytic_numpy", "analytic_fast", "mj_forward",
                                                "mj_forward_ctrl")
        )  # fmt: skip


def test_the_grid_counts_its_series_and_logs_each(monkeypatch, scene, caplog):
    """Under a plain display the series done are counted (``2/2 series``) and each series' line
    is logged at INFO (the command line prints it as ``tumble: ...``); fast fakes for the runs."""
    import io
    import logging

    from validation.runs.display import Display, Mode, showing
    from validation.studies.sweep import study

    def fake_series(sc, e, m, cfg, samples, floor):
        return [{"status": "ok", "engine": e, "method": m}]

    monkeypatch.setattr(study, "run_series", fake_series)
    monkeypatch.setattr(study, "stabilization_row", lambda *a: {})
    cfg = dataclasses.replace(_tiny(), deltas=(), delta_rtols=())
    buf = io.StringIO()
    series = [("analytic", "DOP853"), ("mujoco", "RK4")]
    with (
        ThreadPoolExecutor(max_workers=2) as ex,
        showing(Display(Mode.PLAIN, buf, delay_s=0.0)),
        caplog.at_level(logging.INFO, logger="tumbling_testbed"),
    ):
        runs, _ = study._grid(ex, scene, cfg, series, None, 0.0, study.log.info)
    assert [r["method"] for r in runs] == ["DOP853", "RK4"]  # rows in the series' order
    lines = buf.getvalue().splitlines()
    assert lines[0].startswith(f"tumble: sweep {scene.name}: ") and "/2 series" in lines[0]
    assert lines[-1].startswith(f"tumble: sweep {scene.name}: 2/2 series, done in ")
    said = [r.getMessage() for r in caplog.records if r.name == study.log.name]
    assert "  analytic DOP853: 1/1 ok" in said and "  mujoco RK4: 1/1 ok" in said
