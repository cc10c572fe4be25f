"""Finite values whose products overflow (hypothesis): refused naming the field, or finite initial
quantities.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import tomllib
import warnings

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from analytic import scene as S
from analytic.scene import scene_from_dict
from analytic.scene.overflow import derived_quantities, initial_fields

_CONTROLLED = S.builtin_scene_path("paper_example1_controlled").read_text(encoding="utf-8")

_NUMERIC = [
    ("initial", "omega"),
    ("initial", "Rdot"),
    ("initial", "R"),
    ("initial", "p"),
    ("initial", "pdot"),
    ("rod", "offset"),
    ("masses", "p_e"),
    ("springs", "k_linear"),
    ("springs", "k_cubic"),
    ("gravity", "vector"),
    ("control.omega", "b"),
    ("control.omega", "sigma"),
    ("control.omega", "gamma"),
    ("control.masses", "l"),
    ("control.masses", "lambda"),
    ("control.masses", "alpha"),
    ("control.masses", "beta"),
    ("stabilization", "delta1"),
    ("stabilization", "delta2"),
]


@settings(max_examples=300, deadline=None)
@given(
    field=st.sampled_from(_NUMERIC),
    exponent=st.integers(40, 308),
    mantissa=st.floats(1.0, 1.79),
    sign=st.sampled_from([1.0, -1.0]),
    entry=st.integers(0, 2),
)
def test_huge_finite_values_load_with_finite_initial_quantities_or_are_named(
    field, exponent, mantissa, sign, entry
):
    """A finite value up to 1.79e308 in any numeric field: either refused by a one-line ValueError
    naming a field, or loaded with every derived initial quantity finite (so no plant meets a
    non-finite initial state)."""
    data = tomllib.loads(_CONTROLLED)
    table = data
    for part in field[0].split("."):
        table = table.setdefault(part, {})
    big = sign * mantissa * 10.0**exponent if exponent < 308 else sign * min(mantissa, 1.79) * 1e308
    old = table.get(field[1])
    if isinstance(old, list):
        new = list(old)
        new[entry % len(new)] = big
        table[field[1]] = new
    else:
        table[field[1]] = big
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            sc = scene_from_dict(data)
        except ValueError as exc:
            msg = str(exc)
            assert "\n" not in msg and msg.split(":")[0].split("[")[0] in _FIELD_NAMES, msg
            return
    with np.errstate(all="ignore"):
        quantities = derived_quantities(sc, initial_fields(sc))
    assert all(np.all(np.isfinite(v)) for _, v in quantities.values())
    assert np.all(np.isfinite(sc.initial.q0())) and np.all(np.isfinite(sc.initial.qdot0()))


_FIELD_NAMES = {f"{t}.{k}" for t, k in _NUMERIC} | {
    "output.t_end",
    "output.rate",
    "initial.attitude.quaternion",
    "rod.axis",
    "body.mass",
    "body.inertia",
    "masses.mass",
}
