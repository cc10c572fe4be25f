"""The timing loop's bookkeeping, on a planted clock: which clock a batch reads, how batches are
sized and alternated, and the CPU share of a run (nothing real is timed here)."""

from __future__ import annotations

import pytest

from validation.bench import timing
from validation.bench.timing import Batch, CpuMeter


class PlantedClock:
    """Stands in for the ``time`` module: ``work(cpu_s)`` advances the thread CPU clock by
    ``cpu_s`` and the wall clock by ``cpu_s / share`` (the thread had ``share`` of a CPU)."""

    def __init__(self) -> None:
        self.cpu_ns = 0
        self.wall_ns = 0
        self.share = 1.0

    def thread_time_ns(self) -> int:
        return self.cpu_ns

    def perf_counter_ns(self) -> int:
        return self.wall_ns

    def work(self, cpu_s: float) -> None:
        self.cpu_ns += round(cpu_s * 1e9)
        self.wall_ns += round(cpu_s / self.share * 1e9)


@pytest.fixture
def clock(monkeypatch) -> PlantedClock:
    c = PlantedClock()
    monkeypatch.setattr(timing, "time", c)
    monkeypatch.setattr(timing, "_switches", lambda: 0)
    return c


def test_a_batch_costs_its_thread_cpu_time_not_the_wall(clock):
    """A thread that had a third of a CPU: the wall is three times the work, the cost is the work."""
    clock.share = 1 / 3
    b = timing.time_batch(lambda: clock.work(2e-6), 1000)
    assert b.calls == 1000
    assert b.per_call_s == pytest.approx(2e-6, rel=1e-9)
    assert b.wall_s == pytest.approx(6e-3, rel=1e-9)
    assert b.cpu_share == pytest.approx(1 / 3, rel=1e-9)


def test_batches_are_sized_in_cpu_time_whatever_the_load(clock):
    """5 ms of thread CPU time per batch: 2500 calls of 2 µs, on an idle machine or a busy one."""
    clock.share = 1.0
    idle = timing.calls_per_batch(lambda: clock.work(2e-6), 5e-3)
    clock.share = 0.25
    busy = timing.calls_per_batch(lambda: clock.work(2e-6), 5e-3)
    assert idle == busy == 2500
    assert timing.calls_per_batch(lambda: clock.work(0.02), 5e-3) == 1  # a call longer than a batch


def test_interleaved_alternates_the_order_and_keeps_every_batch(clock, monkeypatch):
    """Even rounds in the given order, odd rounds reversed; each side's cost per call is its own,
    however the load changed between the rounds (a third of the CPU in every other round)."""
    order: list[str] = []
    cost = {"analytic": 1.3e-6, "mj_forward": 2.3e-6}

    def fn(name: str):
        def call() -> None:
            order.append(name)
            clock.work(cost[name])

        return call

    fns = {k: fn(k) for k in cost}
    rounds = 4
    # the load changes with the batch: planted by wrapping time_batch
    real = timing.time_batch
    seen = {"n": 0}

    def loaded(f, calls):
        seen["n"] += 1
        clock.share = 1 / 3 if seen["n"] % 2 else 1.0
        return real(f, calls)

    monkeypatch.setattr(timing, "time_batch", loaded)
    s = timing.interleaved(fns, rounds=rounds, batch_s=1e-3)
    assert list(s) == ["analytic", "mj_forward"]
    assert all(len(v) == rounds for v in s.values())
    for k, v in s.items():
        assert all(b.per_call_s == pytest.approx(cost[k], rel=1e-3) for b in v)
    # the timed batches, in order: a run of one name per batch
    firsts = []
    i = len(order) - sum(b.calls for v in s.values() for b in v)
    for r in range(rounds):
        a = order[i]
        firsts.append(a)
        i += s[a][r].calls
        b = order[i]
        assert b != a
        i += s[b][r].calls
    assert firsts == ["analytic", "mj_forward", "analytic", "mj_forward"]
    shares = sorted({round(b.cpu_share, 6) for v in s.values() for b in v})
    assert shares == [pytest.approx(1 / 3), 1.0]
    assert timing.median_per_call(s["analytic"]) == pytest.approx(1.3e-6, rel=1e-3)


def test_median_share_over_every_batch():
    b = [Batch(1, 1.0, 1.0, 0), Batch(1, 1.0, 2.0, 3), Batch(1, 1.0, 4.0, 9)]
    assert timing.median_share({"a": b[:2], "b": b[2:]}) == 0.5


def test_cpu_meter_uses_the_share_during_the_integration(clock):
    """Setup at full speed, then an integration with half a CPU reporting progress: the run's CPU
    time is its wall times the share between the first and the last report."""
    meter = CpuMeter()
    with meter:
        clock.work(0.1)  # setup, a CPU to itself
        clock.share = 0.5
        for t in range(5):
            clock.work(0.01)
            meter(float(t))
    assert meter.share == pytest.approx(0.5, rel=1e-9)
    assert meter.cpu_of(0.1) == pytest.approx(0.05, rel=1e-9)


def test_cpu_meter_without_reports_uses_the_whole_call(clock):
    meter = CpuMeter()
    clock.share = 0.8
    with meter:
        clock.work(0.2)
        meter(0.0)  # one report: no span
    assert meter.share == pytest.approx(0.8, rel=1e-9)
    assert CpuMeter().share == 1.0  # never used: no evidence of a busy machine
