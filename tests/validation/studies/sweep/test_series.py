"""An accelerated plant's series: its precision floor found, marked and ended on; its horizon and
budget its own (no engine runs here: the runs are stubs with made-up errors)."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

from validation.studies.sweep import config, metrics, rows, series
from validation.studies.sweep.config import MJWARP, MJX, Outcome, SweepConfig


def _ref(t_end: float = 1.0) -> metrics.RefSamples:
    t = np.linspace(0.0, t_end, 11)
    R = np.stack([t, 2 * t, 0 * t], axis=1)
    u = np.tile([1.0, 0.0, 0.0, 0.0], (len(t), 1))
    return metrics.ref_samples(types.SimpleNamespace(t=t, R=R, u=u, p=np.ones((len(t), 2))))


def _stub(monkeypatch, errors: dict[float, float], seen: list | None = None):
    """run_series over stub runs: ``errors[dt]`` is the error of the run at dt."""

    def run_setting(scene, engine, method, s, cfg, t_end=None, budget=None):
        if seen is not None:
            seen.append((engine, method, s, cfg.horizon(engine), budget))
        return types.SimpleNamespace(
            status=types.SimpleNamespace(value="ok"), message="", info={"wall_time_s": 1e-3 / s}
        )

    def fill_row(row, tr, ref):
        row.update(error=errors[row["setting"]], nsteps=round(1.0 / row["setting"]))

    monkeypatch.setattr(series.running, "run_setting", run_setting)
    monkeypatch.setattr(series.timing, "warm_up", lambda *a, **k: None)
    monkeypatch.setattr(series, "fill_row", fill_row)


def test_a_float32_series_marks_its_floor_and_stops_past_it(monkeypatch):
    """RK4's error falls 256x per quartered step until float32's round-off: the smallest step that
    helped is marked, the run that showed the floor kept with its note, the rest skipped."""
    cfg = SweepConfig()
    dts = cfg.accelerated_dts
    errors = {dts[0]: 1e-3, dts[1]: 4e-6, dts[2]: 3e-6, dts[3]: 5e-6}
    _stub(monkeypatch, errors)
    out = series.run_series(None, MJX, "float32", cfg, _ref(), floor=1e-12)
    assert [r["status"] for r in out] == [Outcome.OK, Outcome.OK, Outcome.OK, Outcome.SKIPPED]
    assert [r["at_precision_floor"] for r in out] == [False, True, False, False]
    assert (
        "error floor" in out[2]["note"]
        and "smallest step that helped is dt 0.0025 s" in out[2]["note"]
    )
    assert "past its float32 error floor" in out[3]["note"]
    assert all(r["precision"] == "float32" for r in out)


def test_a_series_whose_error_keeps_falling_has_no_floor(monkeypatch):
    cfg = SweepConfig()
    errors = {dt: 1e-3 * (dt / 1e-2) ** 4 + 1e-11 for dt in cfg.accelerated_dts}
    _stub(monkeypatch, errors)
    out = series.run_series(None, MJX, "float64", cfg, _ref(), floor=1e-13)
    assert [r["status"] for r in out] == [Outcome.OK] * len(cfg.accelerated_dts)
    assert not any(r["at_precision_floor"] for r in out)


def test_the_floor_rule_is_a_factor_per_smaller_step():
    prev = {"setting": 1e-2, "error": 1e-4, "precision": "float32"}
    ok = {
        "setting": 2.5e-3,
        "error": 1e-4 / (config.PRECISION_FLOOR_GAIN * 1.01),
        "precision": "float32",
    }
    flat = {
        "setting": 2.5e-3,
        "error": 1e-4 / (config.PRECISION_FLOOR_GAIN * 0.99),
        "precision": "float32",
    }
    rising = {"setting": 2.5e-3, "error": 2e-4, "precision": "float32"}
    assert series.precision_floor(prev, ok) == ""
    assert "error floor" in series.precision_floor(prev, flat)
    assert "error floor" in series.precision_floor(prev, rising)
    assert series.precision_floor(prev, {**rising, "error": math.nan}) == ""


def test_warp_runs_over_its_own_horizon_and_budget(monkeypatch):
    """MuJoCo Warp's series: its steps, its (shorter) horizon, the accelerated budget."""
    cfg = SweepConfig(t_end=20.0, warp_t_end=0.5)
    seen: list = []
    _stub(monkeypatch, {dt: 1e-3 * (dt / 1e-2) ** 4 + 1e-11 for dt in cfg.warp_dts}, seen)
    out = series.run_series(None, MJWARP, "float32", cfg, _ref(20.0), floor=0.0)
    assert [s for _, _, s, _, _ in seen] == list(cfg.warp_dts)
    assert {(h, b) for *_, h, b in seen} == {(0.5, cfg.accelerated_max_run_wall_s)}
    assert all(r["horizon_s"] == 0.5 for r in out)


def test_the_reference_up_to_a_shorter_horizon_has_that_parts_scales():
    ref = _ref(20.0)
    part = metrics.ref_until(ref, 4.0)
    assert part.t[-1] == pytest.approx(4.0) and len(part.t) == 3
    assert part.R_scale == pytest.approx(np.hypot(4.0, 8.0))
    assert metrics.ref_until(ref, 20.0) is ref


@pytest.mark.parametrize(
    "entry, field",
    [
        (("mjx", "float16"), "accelerated[0]"),
        (("mujoco", "float32"), "accelerated[0]"),
        (("mjwarp", "float64"), "accelerated[0]"),
        (("mjx",), "accelerated[0]"),
    ],
)
def test_a_bad_accelerated_series_is_refused_naming_it(entry, field):
    with pytest.raises(ValueError, match=field.replace("[", r"\[").replace("]", r"\]")):
        SweepConfig(accelerated=(entry,))


def test_rows_of_the_accelerated_series_say_their_precision_and_horizon():
    cfg = SweepConfig(warp_t_end=0.25)
    r = rows.blank_row(MJWARP, "float32", 1e-2, cfg)
    assert (r["precision"], r["horizon_s"], r["setting_name"]) == ("float32", 0.25, "dt")
    assert rows.blank_row("mujoco", "RK4", 1e-2, cfg)["precision"] == "float64"
    assert SweepConfig.quick().accelerated == ()


def test_an_accelerated_runs_budget_starts_at_its_first_sample(monkeypatch):
    """Compilation before the first sample is not the setting's cost; after it, the budget holds."""
    from validation.studies.sweep import running

    clock = iter([100.0, 100.0, 100.5, 200.0])  # the first sample comes after 100 s of compiling
    monkeypatch.setattr(running.time, "perf_counter", lambda: next(clock))

    def plant_run(progress):
        progress(0.0)  # the initial sample, before compiling: not counted
        progress(0.01)  # first sample at 100 s: the clock starts here
        progress(0.02)  # 0.5 s later: within 1 s
        progress(0.03)  # 100 s later: over
        raise AssertionError("not stopped")

    with pytest.raises(running.BudgetExceeded) as exc:
        running.within_budget(plant_run, 1.0, from_first_sample=True)
    assert exc.value.t_reached == 0.03
