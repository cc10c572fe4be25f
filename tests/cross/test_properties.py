"""Property-based tests (hypothesis): random valid scenes agree across engines; random corruptions
of the paper's scene files are refused with a ValueError naming the field."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mj_bridge
from analytic import TumblingModel, scene_from_dict
from tests.support.scene_strategies import scene_and_state

SCENES = Path(__file__).resolve().parents[2] / "analytic" / "scenes"
PAPER = [
    "paper_example1",
    "paper_example1_controlled",
    "paper_example2",
    "paper_example2_controlled",
]
REL = 1e-8


def _rel(x, ref) -> float:
    x, ref = np.asarray(x), np.asarray(ref)
    nr = float(np.linalg.norm(ref))
    return float(np.linalg.norm(x - ref)) / nr if nr > 0 else float(np.linalg.norm(x))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene_and_state())
def test_random_scene_dynamics_and_controllers_agree(case):
    scene, t, q, qd = case
    model = TumblingModel(scene)
    qdd, c = model.acceleration(t, q, qd)
    assert np.all(np.isfinite(qdd))
    tw = mj_bridge.Twin(scene)
    qdd_mj = tw.acceleration(t, q, qd)
    # mass rows are compared on their own scale (a 1e-3 kg mass beside a 1e3 kg one)
    assert _rel(qdd_mj[:7], qdd[:7]) <= REL
    if scene.n:
        assert _rel(qdd_mj[7:], qdd[7:]) <= REL
    if scene.controlled:
        mc = tw.mujoco_control(t, q, qd)
        assert _rel(mc.torque, c.torque) <= REL
        if scene.n:
            assert _rel(mc.rod_forces, c.rod_forces) <= REL


# ----------------------------------------------------------------------------------------------
# Corruptions of the paper's scene files
# ----------------------------------------------------------------------------------------------


def _paper(name: str) -> dict:
    return tomllib.loads((SCENES / f"{name}.toml").read_text(encoding="utf-8"))


def _leaves(d: dict, path: tuple = ()):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _leaves(v, (*path, k))
        else:
            yield (*path, k), v


def _get(d, path):
    for k in path[:-1]:
        d = d[k]
    return d


def _dotted(path) -> str:
    return ".".join(path)


REQUIRED = [
    ("scene", "name"), ("scene", "effects"), ("body", "mass"), ("body", "inertia"),
    ("rod", "axis"), ("rod", "offset"), ("masses", "mass"), ("masses", "p_e"),
    ("initial", "p"),
]  # fmt: skip
"""Keys a paper scene cannot do without (the attitude can: it defaults to the identity)."""
POSITIVE = [("body", "mass"), ("body", "inertia"), ("masses", "mass")]
PER_MASS = [("masses", "p_e"), ("masses", "ring_radius"), ("initial", "p"), ("initial", "pdot"),
            ("springs", "k_linear"), ("springs", "k_cubic")]  # fmt: skip


def _wrong_type(v):
    if isinstance(v, bool):
        return "yes"
    if isinstance(v, int | float):
        return "1.0"
    if isinstance(v, str):
        return 123
    if isinstance(v, list):
        return "[1, 2]"
    return 0


@st.composite
def corruption(draw):
    """A paper scene dict, one corruption that must be refused, and the field it must name."""
    name = draw(st.sampled_from(PAPER))
    data = _paper(name)
    kind = draw(
        st.sampled_from(["type", "nan", "huge_int", "negative", "zero_axis", "length", "missing"])
    )
    if kind == "type":
        path, v = draw(st.sampled_from(sorted(_leaves(data))))
        if isinstance(v, list) and v and draw(st.booleans()):
            i = draw(st.integers(0, len(v) - 1))
            v = copy.deepcopy(v)
            v[i] = _wrong_type(v[i]) if not isinstance(v[i], list) else "x"
            _get(data, path)[path[-1]] = v
        else:
            _get(data, path)[path[-1]] = _wrong_type(v)
    elif kind in ("nan", "huge_int"):
        numeric = [
            (p, v)
            for p, v in _leaves(data)
            if (isinstance(v, float | int) and not isinstance(v, bool))
            or (isinstance(v, list) and v and all(isinstance(x, int | float) for x in v))
        ]
        path, v = draw(st.sampled_from(sorted(numeric)))
        if kind == "nan":
            bad = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        else:  # an integer literal no double holds (TOML integers are unbounded)
            bad = draw(st.sampled_from([1, -1])) * 10 ** draw(st.integers(309, 4000))
        if isinstance(v, list):
            v = list(v)
            v[draw(st.integers(0, len(v) - 1))] = bad
            _get(data, path)[path[-1]] = v
        else:
            _get(data, path)[path[-1]] = bad
    elif kind == "negative":
        path = draw(st.sampled_from(POSITIVE))
        v = _get(data, path)[path[-1]]
        if isinstance(v, list):
            v = list(v)
            v[draw(st.integers(0, len(v) - 1))] *= -1
        else:
            v = -v
        _get(data, path)[path[-1]] = v
    elif kind == "zero_axis":
        path = ("rod", "axis")
        data["rod"]["axis"] = [0.0, 0.0, 0.0]
    elif kind == "length":
        path = draw(st.sampled_from([p for p in PER_MASS if p[-1] in _get(data, p)]))
        v = list(_get(data, path)[path[-1]])
        v = v[:-1] if draw(st.booleans()) else [*v, v[-1]]
        _get(data, path)[path[-1]] = v
    else:
        path = draw(st.sampled_from(REQUIRED))
        del _get(data, path)[path[-1]]
    return name, kind, data, _dotted(path)


@settings(max_examples=200, deadline=None)
@given(corruption())
def test_corrupted_paper_scene_raises_value_error_naming_field(case):
    name, kind, data, field = case
    try:
        scene_from_dict(data)
    except ValueError as exc:
        msg = str(exc)
        assert msg.startswith(field), f"{name} {kind}: {msg!r} does not name {field!r}"
        assert "\n" not in msg
    except Exception as exc:  # pragma: no cover - the finding this test exists for
        pytest.fail(f"{name} {kind} {field}: {type(exc).__name__}: {exc}")
    else:
        pytest.fail(f"{name} {kind} {field}: accepted silently")


# ----------------------------------------------------------------------------------------------
# The output grid: t = 0 first, t_end last, every plant the same grid
# ----------------------------------------------------------------------------------------------


@settings(max_examples=300, deadline=None)
@given(
    t_end=st.floats(1e-6, 1e3, allow_nan=False, allow_infinity=False),
    rate=st.floats(1e-3, 1e4, allow_nan=False, allow_infinity=False),
)
def test_output_grid_starts_at_zero_and_ends_at_t_end(t_end, rate):
    from analytic.scene import MAX_OUTPUT_SAMPLES, OutputSettings

    if t_end * rate + 2 > MAX_OUTPUT_SAMPLES:
        with pytest.raises(ValueError, match=r"^output\.(t_end|rate): too large"):
            OutputSettings(t_end=t_end, rate=rate)
        return
    t = OutputSettings(t_end=t_end, rate=rate).times()
    assert t[0] == 0.0 and t[-1] == t_end
    assert np.all(np.diff(t) > 0)
    # every sample but the last is on the rate grid, and no interval is longer than 1/rate
    np.testing.assert_array_equal(t[:-1], np.arange(len(t) - 1) / rate)
    assert np.all(np.diff(t) <= (1 + 1e-9) / rate)


@settings(max_examples=200, deadline=None)
@given(
    steps_per_sample=st.integers(1, 400),
    samples=st.integers(1, 50),
    extra_steps=st.integers(0, 399),
    dt=st.sampled_from([1e-4, 2.5e-4, 5e-4, 1e-3]),
)
def test_mujoco_steps_land_on_the_output_grid(steps_per_sample, samples, extra_steps, dt):
    """t_end a whole number of steps: MuJoCo's steps between samples add up to the same grid."""
    from analytic.scene import OutputSettings
    from mj_bridge.plan import plan_steps

    extra_steps %= steps_per_sample
    base = scene_from_dict(_paper("paper_example1"))
    rate = 1.0 / (steps_per_sample * dt)
    t_end = (samples * steps_per_sample + extra_steps) * dt
    scene = base.replace(output=OutputSettings(t_end=t_end, rate=rate))
    _, h, times, k = plan_steps(scene, dt=dt)
    assert times[0] == 0.0 and times[-1] == t_end
    np.testing.assert_allclose(np.cumsum(k) * h, times[1:], rtol=1e-9, atol=0)
