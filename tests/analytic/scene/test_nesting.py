"""Nesting of any depth (hypothesis): one named ValueError, never a RecursionError.

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analytic import scene as S
from analytic.scene import load_scene

_CONTROLLED = S.builtin_scene_path("paper_example1_controlled").read_text(encoding="utf-8")


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    depth=st.integers(S.MAX_SCENE_NESTING + 1, 4000),
    how=st.sampled_from(["array", "inline_table", "dotted", "header"]),
    where=st.sampled_from(["top", "thresholds", "hard_case", "masses"]),
)
def test_nesting_of_any_depth_is_one_named_value_error(tmp_path, depth, how, where):
    """Lists, inline tables, dotted keys or headers nested beyond the bound, anywhere: a one-line
    ValueError naming the file or the key, never a RecursionError."""
    if how == "array":
        value = "[" * depth + "]" * depth
    elif how == "inline_table":
        value = "{ k = " * depth + "1" + " }" * depth
    else:
        value = None
    key = ".".join(["k"] * depth)
    if how == "dotted":
        line = f"{key}.k = 1"  # depth tables, the last one holding k = 1
    elif how == "header":
        line = f"[{where}.{key}]" if where != "top" else f"[{key}]"
    else:
        line = f"x = {value}"
    if where == "top" or how == "header":
        text = line + "\n" + _CONTROLLED if how != "header" else _CONTROLLED + "\n" + line + "\n"
    else:
        text = _CONTROLLED + f"\n[{where}.deep]\n{line}\n"
    path = tmp_path / "deep.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError) as exc:
        load_scene(path)
    msg = str(exc.value)
    assert "nested deeper than" in msg and "\n" not in msg, msg
