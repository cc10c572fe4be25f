"""The accelerated series in the sweep's outputs: each series' floor read off its rows, said in
``sweep.md``, ``sweep.json`` and ringed in the figure; an accelerated plant that cannot run is
skipped with one line (no engine runs here: rows are made up)."""

from __future__ import annotations

import pytest

from validation.studies.sweep import accelerated, figure, rows, study, timing
from validation.studies.sweep.config import MJWARP, MJX, Outcome, SweepConfig


def _row(engine, method, dt, error, rid, floor=False, status=Outcome.OK, cfg=None):
    r = rows.blank_row(engine, method, dt, cfg or SweepConfig())
    r.update(run_id=rid, status=status, error=error, at_reference_floor=False)
    r.update(timing.summary([0.5 / dt * 1e-3]), at_precision_floor=floor)
    return r


def _runs():
    cfg = SweepConfig()
    d = cfg.accelerated_dts
    return [
        _row(MJX, "float32", d[0], 1e-3, 0),
        _row(MJX, "float32", d[1], 4e-6, 1, floor=True),
        _row(MJX, "float32", d[2], 3e-6, 2),
        _row(MJX, "float32", d[3], None, 3, status=Outcome.SKIPPED),
        _row(MJX, "float64", d[0], 1e-3, 4),
        _row(MJX, "float64", d[1], 4e-6, 5),
        _row(MJWARP, "float32", d[0], 2e-4, 6),
    ]


def test_floors_name_the_smallest_step_that_helped_or_say_there_was_none():
    found = {(f.engine, f.precision): f for f in accelerated.floors(_runs())}
    f32 = found[(MJX, "float32")]
    assert (f32.dt, f32.error, f32.run_id, f32.best_error) == (2.5e-3, 4e-6, 1, 3e-6)
    assert "floor at dt 0.0025 s" in f32.words
    f64 = found[(MJX, "float64")]
    assert f64.dt is None and "no floor within the grid" in f64.words
    assert found[(MJWARP, "float32")].horizon_s == SweepConfig().warp_t_end


def test_the_text_states_warps_short_horizon_and_why():
    cfg = SweepConfig()
    words = accelerated.grid_words(cfg, MJWARP)
    assert f"over {cfg.warp_t_end:g} s" in words and "19 ms per step" in words
    assert "not 20 s" in words
    md = "\n".join(accelerated.floors_markdown(_runs(), cfg))
    assert "## Precision" in md and "| mjx float32 | 20 s | 0.0025 s | 4e-06 |" in md
    assert accelerated.floors_markdown([], cfg) == []


def test_the_figure_rings_the_floor_and_draws_every_series():
    data = figure.figure_data(_runs(), 1e-12, "s", 20.0)
    lines = {(ln.engine, ln.method): ln for ln in data.lines}
    assert set(lines) == {(MJX, "float32"), (MJX, "float64"), (MJWARP, "float32")}
    assert [p.at_precision_floor for p in lines[(MJX, "float32")].points] == [False, True, False]
    # per simulated second: the runs' wall times over their horizons (Warp's is shorter)
    warp = lines[(MJWARP, "float32")].points[0]
    assert warp.wall == pytest.approx(0.5 / 1e-2 * 1e-3 / SweepConfig().warp_t_end)
    assert any("mjwarp float32: horizon" in h for h in data.horizons)
    assert figure.render_png(data)[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_accelerated_plant_that_cannot_run_is_skipped_in_one_line(monkeypatch):
    said = []
    monkeypatch.setattr(study.running, "pinocchio_unavailable", lambda: "")
    monkeypatch.setattr(
        study.running,
        "accelerated_unavailable",
        lambda e: "mujoco-mjx is not installed [test]" if e == MJX else "",
    )
    skipped: dict[str, str] = {}
    study._skip_unavailable(SweepConfig(), skipped, said.append)
    assert skipped == {MJX: "mujoco-mjx is not installed [test]"}
    assert said == ["  mjx series skipped: mujoco-mjx is not installed [test]"]
    series = study._series_of(SweepConfig(), skipped)
    assert (MJWARP, "float32") in series and not any(e == MJX for e, _ in series)
    # the accelerated series go first (a process and a compilation per run)
    assert study._expense_rank(MJWARP, "float32") < study._expense_rank("analytic", "Radau")


def test_an_unregistered_plant_is_unavailable_with_its_reason(monkeypatch):
    monkeypatch.setattr(study.running, "registered", lambda: {})
    assert "not a registered plant" in study.running.accelerated_unavailable(MJX)


@pytest.mark.parametrize(
    "control_error, kind",
    [(1e-9, accelerated.FloorKind.ROUND_OFF), (3e-6, accelerated.FloorKind.MODEL), (None, "none")],
)
def test_a_float64_control_tells_round_off_from_a_model_difference(control_error, kind):
    """MJX float32 stops at 3e-6: round-off when MJX float64 goes on to 1e-9 at the same step,
    the model when it stops there too (MJX without the cubic stiffness), unconfirmed without it."""
    runs = _runs()
    if control_error is not None:
        d = SweepConfig().accelerated_dts
        runs.append(_row(MJX, "float64", d[2], control_error, len(runs)))
    (f32,) = [f for f in accelerated.floors(runs) if f.precision == "float32" and f.engine == MJX]
    expected = accelerated.FloorKind.UNCONFIRMED if kind == "none" else kind
    assert f32.kind is expected and expected.value in f32.to_dict()["kind"]
    assert f32.words.startswith("mjx float32: floor at dt 0.0025 s")


@pytest.mark.slow
def test_a_sweep_with_the_accelerated_plants_installed(tmp_path):
    """End to end on the real plants (slow: a process and a compilation per run): MJX float32 and
    MuJoCo Warp over two steps and 0.1 s, beside MuJoCo's RK4; every run ends ok with a finite
    error below the sweep's divergence limit, and the files carry the precision and the floors."""
    import json

    from analytic.effects import Precision
    from validation.studies.sweep import run_sweep
    from validation.studies.sweep.running import accelerated_unavailable

    wanted = [(e, Precision.FLOAT32) for e in (MJX, MJWARP) if not accelerated_unavailable(e)]
    if not wanted:
        pytest.skip("neither mjx nor mjwarp can run here")
    cfg = SweepConfig(
        t_end=0.1, solvers=(), integrators=("RK4",), dts=(1e-2, 2.5e-3), deltas=(),
        effects_repeats=1, accelerated=tuple(wanted), accelerated_dts=(1e-2, 2.5e-3),
        warp_dts=(1e-2, 2.5e-3), warp_t_end=0.05,
    )  # fmt: skip
    res = run_sweep("paper_example1_controlled", tmp_path / "out", config=cfg)
    acc = [r for r in res.runs if r["engine"] in (MJX, MJWARP)]
    assert acc and all(r["status"] in (Outcome.OK, Outcome.SKIPPED) for r in acc)
    assert all(0 < r["error"] < cfg.diverge_error for r in acc if r["status"] == Outcome.OK)
    doc = json.loads((res.out_dir / "sweep.json").read_text())
    assert {f["engine"] for f in doc["precision_floors"]} == {e for e, _ in wanted}
    assert "## Precision" in (res.out_dir / "sweep.md").read_text()
