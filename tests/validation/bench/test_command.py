"""``tumble bench``'s summary and ``bench.json`` content with planted goals (the file's validation
against its schema is in tests/validation/report/test_provenance.py)."""

from __future__ import annotations

import json
import math

import pytest

from validation.bench import command, goals
from validation.bench.goal import Goal
from validation.bench.verdicts import SPREAD_BOUND, Spread


@pytest.fixture
def planted(monkeypatch):
    measured = [
        Goal("quiet goal", 0.57, 1.0, spread=Spread(0.56, 0.57, 0.58, 21, 0.98)),
        Goal("busy goal", 0.6, 1.0, spread=Spread(0.3, 0.6, 1.2, 21, 0.31)),
        Goal("once", 0.03, 1.0),
        Goal("pin", math.nan, 3.0, skipped="pin is not installed"),
    ]
    monkeypatch.setattr(goals, "measure", lambda skip_long, progress: measured)
    monkeypatch.setattr(command, "evaluation_table", lambda: [])
    monkeypatch.setattr(command, "load_average", iter([0.4, 2.6]).__next__)
    return measured


def test_summary_names_each_verdict_and_says_when_the_machine_was_too_busy(planted):
    lines: list[str] = []
    holds, _ = command.measure_and_print(True, lines.append)
    assert not holds  # a goal without a verdict is not a goal that holds
    text = "\n".join(lines)
    assert "HOLDS  quiet goal: 0.57 (≤ 1; interquartile 0.56-0.58 over 21 rounds" in text
    assert "TOO_BUSY  busy goal: 0.6 (≤ 1; interquartile 0.3-1.2 over 21 rounds" in text
    assert "HOLDS  once: 0.03 (≤ 1)" in text
    assert "SKIPPED  pin: pin is not installed" in text
    busy = [x for x in lines if x.startswith("the machine was too busy for a verdict")]
    assert len(busy) == 1
    assert "on 1 goal(s)" in busy[0] and "load average 0.40 before, 2.60 after" in busy[0]
    assert f"wider than {SPREAD_BOUND:g} of the limit" in busy[0]


def test_bench_document_carries_spread_verdict_and_load(planted):
    _, doc = command.measure_and_print(True, lambda _s: None)
    assert doc["spread_bound"] == SPREAD_BOUND
    assert doc["machine"]["load_average_1min"] == {"before": 0.4, "after": 2.6}
    by = {g["name"]: g for g in doc["goals"]}
    assert [g["verdict"] for g in doc["goals"]] == ["HOLDS", "TOO_BUSY", "HOLDS", "SKIPPED"]
    assert by["busy goal"]["spread"] == {
        "low": 0.3, "median": 0.6, "high": 1.2, "rounds": 21, "cpu_share": 0.31
    }  # fmt: skip
    assert by["busy goal"]["holds"] is False and by["busy goal"]["ratio"] == 0.6
    assert by["once"]["spread"] is None and by["pin"]["spread"] is None


def test_no_too_busy_line_when_every_goal_has_a_verdict(monkeypatch):
    monkeypatch.setattr(goals, "measure", lambda skip_long, progress: [Goal("g", 0.5, 1.0)])
    monkeypatch.setattr(command, "evaluation_table", lambda: [])
    lines: list[str] = []
    assert command.measure_and_print(True, lines.append)[0]
    assert not any("too busy" in x for x in lines)


def _planted_batched(monkeypatch, seen):
    from validation.bench import batch_throughput

    def fake(plants=None, sizes=(), horizon=0.0, progress=print, **_kw):
        seen.append((tuple(sizes), horizon))
        progress("  devices: JAX cpu:0 (planted)")
        return (Goal("fake batched", 0.5, 1.0),)

    monkeypatch.setattr(batch_throughput, "goal_batched_throughput", fake)
    monkeypatch.setattr(command, "evaluation_table", lambda: pytest.fail("not with --batched"))


def test_batched_measures_the_batched_plants_only_with_its_sizes(monkeypatch, capsys, tmp_path):
    seen: list = []
    _planted_batched(monkeypatch, seen)
    assert command.main(["--batched", "--batch-sizes", "1,4", "--batch-horizon", "0.02"]) == 0
    assert command.main(["--batched", "--out", str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    assert seen == [((1, 4), 0.02), ((1, 16, 256), 0.01)]  # given; then the defaults
    assert "devices: JAX cpu:0 (planted)" in out and "HOLDS  fake batched: 0.5 (≤ 1)" in out
    doc = json.loads((tmp_path / "b" / "bench.json").read_text())
    assert doc["evaluation_us"] == [] and [g["name"] for g in doc["goals"]] == ["fake batched"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--batch-sizes", "1,2"], "--batch-sizes: needs --batched"),
        (["--batched", "--batch-sizes", "0,2"], "--batch-sizes: must be whole numbers"),
        (["--batched", "--batch-horizon", "-1"], "--batch-horizon: must be a positive number"),
    ],
)
def test_batched_options_are_checked(argv, message, capsys):
    with pytest.raises(SystemExit) as exc:
        command.main(argv)
    assert exc.value.code == 2 and message in capsys.readouterr().err
