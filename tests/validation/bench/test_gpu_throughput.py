"""The GPU throughput script (:mod:`validation.bench.gpu_throughput`): its GPU defaults reach the
measurement, a machine without a GPU is warned about, and only batched plants are taken."""

from __future__ import annotations

import pytest

from validation.bench import batch_throughput as bt
from validation.bench import gpu_throughput as gpu
from validation.bench.goal import Goal


def test_a_gpu_is_told_from_a_cpu_by_its_device_name():
    assert gpu.sees_gpu({"JAX": "cuda:0 (NVIDIA H100)", "Warp": "cpu (x86_64)"})
    assert gpu.sees_gpu({"JAX": "gpu:0 (Tesla T4)"})
    assert not gpu.sees_gpu({"JAX": "cpu:0 (cpu; 1 device(s))", "Warp": "cpu (x86_64)"})
    assert not gpu.sees_gpu({})


def _plant(monkeypatch, devices):
    seen = []

    def fake(plants=None, sizes=(), horizon=0.0, progress=print, devices=None, **_kw):
        seen.append((plants, tuple(sizes), horizon, devices))
        return (Goal("fake batched", 2.0, 1.0),)

    monkeypatch.setattr(bt, "accelerator_devices", lambda: devices)
    monkeypatch.setattr(bt, "goal_batched_throughput", fake)
    return seen


def test_the_gpu_defaults_and_the_warning_without_a_gpu(monkeypatch, capsys):
    seen = _plant(monkeypatch, {"JAX": "cpu:0 (cpu; 1 device(s))"})
    assert gpu.main([]) == 0
    out = capsys.readouterr().out
    assert seen == [
        (None, gpu.GPU_BATCH_SIZES, gpu.GPU_HORIZON_S, {"JAX": "cpu:0 (cpu; 1 device(s))"})
    ]
    assert out.startswith(
        "warning: no GPU seen (JAX cpu:0 (cpu; 1 device(s))): measuring on the CPU"
    )
    assert "FAILS  fake batched: 2 (≤ 1)" in out


def test_on_a_gpu_there_is_no_warning_and_sizes_are_taken(monkeypatch, capsys):
    seen = _plant(monkeypatch, {"Warp": "cuda:0 (NVIDIA A100)"})
    assert gpu.main(["--sizes", "8,64", "--horizon", "0.5"]) == 0
    assert seen[0][1:3] == ((8, 64), 0.5)
    assert "warning" not in capsys.readouterr().out


def test_only_batched_plants_are_taken(monkeypatch, capsys):
    _plant(monkeypatch, {})
    with pytest.raises(SystemExit) as exc:
        gpu.main(["--plants", "analytic"])
    assert exc.value.code == 2
    assert "--plants: not batched plants: analytic" in capsys.readouterr().err
