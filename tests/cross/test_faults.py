"""Faults: a run that fails part way keeps what it reached, marked failed with when and why; the
hard-case table is written atomically and survives an interrupted suite."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from analytic import RunStatus, load_scene, simulate
from tests.support.guards import forbid_plant_runs
from validation.studies import hard_cases as hc


def _interrupt_after(t_stop):
    def progress(t):
        if t > t_stop:
            raise KeyboardInterrupt

    return progress


def test_interrupted_run_returns_partial_interrupted_trajectory(tmp_path):
    scene = load_scene(hc.HARD_DIR / "rod_through_C.toml")
    tr = simulate(scene, t_end=2.0, progress=_interrupt_after(0.5))
    assert tr.status is RunStatus.INTERRUPTED
    assert "interrupted at t =" in tr.message
    assert 0.5 <= tr.t[-1] < 2.0 and np.all(np.isfinite(tr.q))
    # what it reached is still physics: masses at C, invariants closed
    assert np.max(np.abs(tr.p)) <= 1e-12
    path = tr.save_npz(tmp_path / "partial.npz")
    with np.load(path) as z:
        meta = json.loads(str(z["meta_json"]))
        assert meta["status"] == "interrupted" and "interrupted" in meta["message"]
        assert z["t"][-1] == tr.t[-1]


def test_interrupted_suite_leaves_a_valid_partial_table(tmp_path):
    def progress(case, i, n):
        if i == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        hc.run_hard_cases(tmp_path, names=["rod_through_C", "pass_through"], progress=progress)
    data = json.loads((tmp_path / "hard_cases.json").read_text())
    assert data["complete"] is False and data["passed"] is False
    assert [r["case"] for r in data["rows"]] == ["rod_through_C"]
    assert "INCOMPLETE" in (tmp_path / "hard_cases.md").read_text()
    assert not list(tmp_path.glob(".*.tmp"))


def test_crash_during_write_keeps_previous_file(tmp_path, monkeypatch):
    table = hc.HardCaseTable((), complete=True, message="first")
    hc.write_table(table, tmp_path)
    before = (tmp_path / "hard_cases.json").read_text()

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr("validation.runs.atomic.os.replace", boom)
    with pytest.raises(OSError):
        hc.write_table(hc.HardCaseTable((), complete=False, message="second"), tmp_path)
    assert (tmp_path / "hard_cases.json").read_text() == before
    assert not list(tmp_path.glob(".*.tmp"))


def test_case_that_raises_is_an_error_row(monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("boom")

    monkeypatch.setattr(hc.references.euler, "torque_free", broken)  # the case's reference
    row = hc.run_case("rod_through_C")
    assert row.verdict == hc.ERROR and row.error == "RuntimeError: boom"
    assert all(row.plant_verdict(e) == hc.ERROR for e in row.plants)
    table = hc.HardCaseTable((row,), plants=row.plants)
    assert "RuntimeError: boom" in table.to_markdown()
    assert table.to_dict()["rows"][0]["error"] == "RuntimeError: boom"


@pytest.mark.parametrize("engine", ["analytic", "mujoco", "pinocchio"])
def test_ctrl_c_in_any_plant_stops_the_suite(tmp_path, monkeypatch, engine):
    """Each plant keeps what it reached when interrupted and returns it (status interrupted); the
    suite turns that back into KeyboardInterrupt, so Ctrl-C stops the whole suite (not only the
    current case, which would otherwise become a FAIL row), leaving an incomplete table."""
    from mj_bridge.plants import PLANTS

    cls = PLANTS[engine]
    if cls.unavailable():
        pytest.skip(cls.unavailable())
    original = cls.simulate

    def interrupted(self, scene, settings=None, t_end=None, progress=None):
        return original(self, scene, settings, t_end=t_end, progress=_interrupt_after(0.05))

    monkeypatch.setattr(cls, "simulate", interrupted)
    with pytest.raises(KeyboardInterrupt, match="interrupted at t ="):
        hc.run_hard_cases(tmp_path, names=["pass_through", "zero_gravity"])
    data = json.loads((tmp_path / "hard_cases.json").read_text(encoding="utf-8"))
    assert data["complete"] is False and data["rows"] == []
    assert "interrupted during pass_through" in data["message"]


@pytest.mark.parametrize("arg", ["no/such/scene.toml", "hard/nope"])
def test_cli_bad_scene_one_line_no_traceback(arg):
    r = subprocess.run(
        [sys.executable, "-m", "validation.cli", "simulate", arg],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode != 0
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


# ------------------------------------------------------------------------------------------------
# Injected faults in the right-hand side: the run stops there, says when and why, keeps the rest.
# ------------------------------------------------------------------------------------------------


def _faulty_after(monkeypatch, t_fault, fault):
    """Make the numpy model's acceleration misbehave from ``t_fault`` on (fault: 'nan' or 'linalg')."""
    from analytic.model import TumblingModel

    original = TumblingModel.acceleration

    def accel(self, t, q, qdot):
        qdd, c = original(self, t, q, qdot)
        if t > t_fault:
            if fault == "nan":
                qdd = qdd.copy()
                qdd[0] = np.nan
            else:
                raise np.linalg.LinAlgError("Matrix is not positive definite")
        return qdd, c

    monkeypatch.setattr(TumblingModel, "acceleration", accel)


@pytest.mark.parametrize(
    ("fault", "needle"),
    [("nan", "non-finite acceleration at t ="), ("linalg", "mass matrix not positive definite")],
)
def test_fault_part_way_keeps_samples_before_it(monkeypatch, tmp_path, fault, needle):
    scene = load_scene(hc.HARD_DIR / "zero_gravity.toml")
    clean = simulate(scene, t_end=1.0, backend="numpy")
    _faulty_after(monkeypatch, 0.4, fault)
    tr = simulate(scene, t_end=1.0, backend="numpy")
    assert tr.status is RunStatus.FAILED and needle in tr.message
    # the samples before the fault are kept, finite, and identical to the clean run's
    assert 0.2 <= tr.t[-1] <= 0.4
    k = len(tr.t)
    assert np.all(np.isfinite(tr.q))
    assert np.array_equal(tr.q, clean.q[:k])
    path = tr.save_npz(tmp_path / "failed.npz")
    with np.load(path) as z:
        assert json.loads(str(z["meta_json"]))["status"] == "failed"


# ------------------------------------------------------------------------------------------------
# Bad input is refused before any plant runs, naming the field
# ------------------------------------------------------------------------------------------------




@pytest.mark.parametrize(
    ("kwargs", "thresholds", "field"),
    [
        ({}, {"positon_C": 1e-6}, "thresholds.positon_C: unknown threshold"),
        ({"t_end": 1e-4}, None, "t_end: shorter than one MuJoCo step"),
        ({"t_end": 0.0041}, None, "t_end: not a whole number of MuJoCo steps"),
        ({"t_end": math.inf}, None, "t_end: must be finite"),
        ({"t_end": 1e300}, None, "t_end: too large"),
        ({"dt": 3e-3}, None, "dt: "),
        ({"dt": -1.0}, None, "dt: must be a positive"),
        ({"dt": 1e-15, "t_end": 0.01}, None, "dt: "),  # 1e13 MuJoCo steps
        ({"integrator": "RK5"}, None, "integrator: unknown value 'RK5'"),
    ],
)
def test_run_validation_refuses_bad_input_before_any_plant(
    tmp_path, monkeypatch, kwargs, thresholds, field
):
    from validation.validate import run_validation

    scene = load_scene(hc.SCENES_DIR / "paper_example1.toml")
    if thresholds is not None:
        scene = scene.replace(extra={"thresholds": thresholds})
    forbid_plant_runs(monkeypatch)
    out = tmp_path / "out"
    with pytest.raises(ValueError) as exc:
        run_validation(scene, out, **kwargs)
    assert str(exc.value).startswith(field), str(exc.value)
    assert "\n" not in str(exc.value)
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("t_end", [-1.0, math.nan, math.inf, 0.0, 10**400, "1"])
def test_plants_name_a_bad_t_end(t_end):
    import mj_bridge

    scene = load_scene(hc.SCENES_DIR / "paper_example1.toml")
    for sim in (simulate, mj_bridge.simulate):
        with pytest.raises(ValueError, match=r"^t_end: must be"):
            sim(scene, t_end=t_end)


def test_both_plants_sample_t0_and_t_end_of_a_short_horizon():
    """0.004 s at 100 Hz: the t = 0 sample and the t_end sample, on both plants, not one sample
    labelled t_end that holds the initial state."""
    import mj_bridge

    scene = load_scene(hc.SCENES_DIR / "paper_example1.toml")
    ana = simulate(scene, t_end=0.004)
    mj = mj_bridge.simulate(scene, t_end=0.004)
    for tr in (ana, mj):
        assert tr.status is RunStatus.OK
        assert tr.t.tolist() == [0.0, 0.004]
        assert np.array_equal(tr.q[0], scene.initial.q0())
        assert not np.allclose(tr.q[1], tr.q[0])  # moved: Ṙ(0) = (1, 2, 20) m/s
    np.testing.assert_allclose(mj.q[1, :3], ana.q[1, :3], rtol=0, atol=1e-9)
    # t_end shorter than one MuJoCo step, or not a whole number of them
    with pytest.raises(ValueError, match=r"^t_end: shorter than one MuJoCo step"):
        mj_bridge.simulate(scene, t_end=1e-4)
    with pytest.raises(ValueError, match=r"^t_end: not a whole number of MuJoCo steps"):
        mj_bridge.simulate(scene, t_end=0.0041)


def test_mujoco_warnings_are_collapsed(capfd):
    """An unstable run warns at every MuJoCo step; it is reported as a few lines with counts."""
    import warnings

    import mj_bridge
    from mj_bridge.callbacks import MAX_WARNING_LINES

    scene = load_scene(hc.SCENES_DIR / "paper_example1.toml")
    scene = scene.replace(gravity=np.array([0.0, 0.0, -1e300]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        tr = mj_bridge.simulate(scene, t_end=0.05)
    assert tr.status is RunStatus.FAILED
    mj = [str(w.message) for w in caught if str(w.message).startswith("MuJoCo:")]
    assert 1 <= len(mj) <= MAX_WARNING_LINES + 1, mj
    assert all("\n" not in m for m in mj)
    assert any(" times, first at Time = " in m for m in mj), mj
    assert "WARNING" not in capfd.readouterr().err  # MuJoCo's own printer is not used


def test_save_npz_error_names_the_path_not_a_temporary_file(tmp_path, monkeypatch):
    scene = load_scene(hc.HARD_DIR / "zero_gravity.toml")
    tr = simulate(scene, t_end=0.02)

    def refuse(src, dst):
        raise OSError(28, "No space left on device", str(src))

    monkeypatch.setattr("analytic.trajectory.os.replace", refuse)
    target = tmp_path / "x.npz"
    with pytest.raises(OSError) as exc:
        tr.save_npz(target)
    assert exc.value.filename == str(target)
    assert not list(tmp_path.iterdir())
