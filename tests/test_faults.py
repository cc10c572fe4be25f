"""Faults: a run that fails part way keeps what it reached, marked failed with when and why; the
hard-case table is written atomically and survives an interrupted suite."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from analytic import RunStatus, load_scene, simulate
from validation import hard_cases as hc


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

    monkeypatch.setattr("validation.atomic.os.replace", boom)
    with pytest.raises(OSError):
        hc.write_table(hc.HardCaseTable((), complete=False, message="second"), tmp_path)
    assert (tmp_path / "hard_cases.json").read_text() == before
    assert not list(tmp_path.glob(".*.tmp"))


def test_case_that_raises_is_an_error_row(monkeypatch):
    def broken(scene, th):
        raise RuntimeError("boom")

    monkeypatch.setitem(hc.CASES, "rod_through_C", (broken, True))
    row = hc.run_case("rod_through_C")
    assert row.verdict == hc.ERROR and "RuntimeError: boom" in row.analytic["error"]


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
