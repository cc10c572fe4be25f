"""The float32 drift of MuJoCo's accelerated plants (MJX in float32, MuJoCo Warp) from the C
plant and the analytic plant, judged against bounds derived from float32 round-off.

Scenes: Paper Example 1 and its controlled form over 2 s and 20 s. MJX 3.17 drops MuJoCo 4's
cubic tendon stiffness (``springs.cubic``; a model difference, docs/performance.md), so MJX is
judged on the scenes with linear springs only; MuJoCo Warp, which keeps it, on the scenes as given.
Warp on a CPU takes ~19 ms per step (2 s at dt 2.5e-4 s: ~150 s), so its runs are the 2 s ones.

The bound on the largest difference of a quantity after N steps is
``FLOAT32_DRIFT_FACTOR x sqrt(N) x eps32 x S`` (``tests/support/tolerances.py``, the reason
there), S the quantity's reach over the run (:func:`reach`); a difference below
``FLOAT32_FLOOR_FRACTION x eps32 x max |R|`` would mean the plant did not run in float32. Every
test is ``slow`` (minutes of JIT compilation and Warp's CPU steps).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest

from analytic.effects import Effect, Precision
from mj_bridge.plants import plant, registered
from tests.support import tolerances as tol
from validation.compare.checks import difference_series
from validation.scenes import resolve_scene

pytestmark = pytest.mark.slow

UNCONTROLLED, CONTROLLED = "paper_example1", "paper_example1_controlled"
QUANTITIES = ("position_C", "rod_positions", "attitude")


def _unavailable(name: str) -> str:
    cls = registered().get(name)
    return "not registered" if cls is None else cls.unavailable()


def _needs(name: str):
    why = _unavailable(name)
    return pytest.mark.skipif(bool(why), reason=f"{name}: {why}")


def scene_of(name: str, linear_only: bool):
    sc = resolve_scene(name)
    return sc.with_effects(sc.effects - {Effect.SPRINGS_CUBIC}) if linear_only else sc


@functools.cache
def run(engine: str, name: str, linear_only: bool, t_end: float, precision: str = ""):
    """One run, made once per session: ``engine`` on the scene over ``t_end`` s (its default
    settings; an accelerated plant's ``precision`` when given)."""
    sc = scene_of(name, linear_only)
    pl = plant(engine)
    settings = pl.default_settings(sc)
    if precision and "precision" in {f.name for f in dataclasses.fields(settings)}:
        settings = dataclasses.replace(settings, precision=Precision(precision))
    tr = pl.simulate(sc, settings, t_end=t_end)
    assert tr.status.value == "ok", f"{engine} {name}: {tr.message}"
    return tr


def _upto(t: np.ndarray, horizon: float) -> int:
    return int(np.searchsorted(np.asarray(t, float), horizon + 1e-9, side="right"))


def differences(ref, tr, horizon: float) -> dict[str, float]:
    """The largest difference of each quantity (m, m, rad) over the common samples up to
    ``horizon`` s."""
    by_name = {s.name: s for s in difference_series(ref, tr)}
    return {q: float(np.max(by_name[q].values[: _upto(by_name[q].t, horizon)])) for q in QUANTITIES}


def reach(ref, t_end: float) -> dict[str, float]:
    """S of each quantity over the float64 run ``ref`` up to ``t_end`` s: its magnitude plus what
    a velocity error integrates to over ``t_end`` (m, m, rad)."""
    k = _upto(ref.t, t_end)
    R = float(np.max(np.linalg.norm(ref.R[:k], axis=1)))
    v = float(np.max(np.linalg.norm(ref.qdot[:k, 0:3], axis=1)))
    p = float(np.max(np.abs(ref.p[:k])))
    pdot = float(np.max(np.abs(ref.qdot[:k, 7:])))
    w = float(np.max(np.linalg.norm(ref.omega[:k], axis=1)))
    return {
        "position_C": R + v * t_end,
        "rod_positions": p + pdot * t_end,
        "attitude": 1.0 + w * t_end,
    }


def judge_drift(tr, ref, t_end: float, dt: float) -> dict[str, tuple[float, float]]:
    """{quantity: (largest difference up to ``t_end`` s, its float32 bound)}, and the float32
    floor checked."""
    n = round(t_end / dt)
    d = differences(ref, tr, t_end)
    s = reach(ref, t_end)
    bound = {q: tol.FLOAT32_DRIFT_FACTOR.value * math.sqrt(n) * tol.EPS32 * s[q] for q in s}
    R = float(np.max(np.linalg.norm(ref.R[: _upto(ref.t, t_end)], axis=1)))
    floor = tol.FLOAT32_FLOOR_FRACTION.value * tol.EPS32 * R
    assert d["position_C"] >= floor, (
        f"position of C within {d['position_C']:.2e} m of float64: below float32's floor "
        f"{floor:.2e} m (did the plant run in float32?)"
    )
    return {q: (d[q], bound[q]) for q in QUANTITIES}


def _assert_within(found: dict[str, tuple[float, float]], what: str) -> None:
    over = {q: v for q, v in found.items() if not v[0] <= v[1]}
    assert not over, f"{what}: beyond float32 round-off: " + ", ".join(
        f"{q} {d:.2e} > {b:.2e}" for q, (d, b) in over.items()
    )


CASES = [
    pytest.param(name, t_end, id=f"{name}-{t_end:g}s")
    for name in (UNCONTROLLED, CONTROLLED)
    for t_end in (2.0, 20.0)
]


@_needs("mjx")
@pytest.mark.parametrize("name, t_end", CASES)
@pytest.mark.parametrize("against", ["mujoco", "analytic"])
def test_mjx_float32_drifts_within_float32_round_off_on_linear_springs(name, t_end, against):
    """MJX float32 against a float64 plant on the linear-springs scene: round-off only (one 20 s
    run of each plant, judged over its first 2 s and over the whole)."""
    dt = scene_of(name, True).mujoco.timestep
    tr = run("mjx", name, True, 20.0, Precision.FLOAT32)
    ref = run(against, name, True, 20.0)
    _assert_within(judge_drift(tr, ref, t_end, dt), f"mjx float32 vs {against}, {name}")


@_needs("mjwarp")
@pytest.mark.parametrize("name", [UNCONTROLLED, CONTROLLED])
@pytest.mark.parametrize("against", ["mujoco", "analytic"])
def test_warp_drifts_within_float32_round_off_over_2_s(name, against):
    """MuJoCo Warp (float32) against a float64 plant on the scene as given (cubic springs on)."""
    t_end = 2.0
    dt = scene_of(name, False).mujoco.timestep
    tr = run("mjwarp", name, False, t_end)
    ref = run(against, name, False, t_end)
    _assert_within(judge_drift(tr, ref, t_end, dt), f"mjwarp vs {against}, {name}")
