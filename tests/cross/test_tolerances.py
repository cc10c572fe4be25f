"""Every named bound of the project is one record type with a value, a unit and a reason.

The comparison's thresholds (``validation/compare/thresholds.py``, and what the shipped scenes make of them)
and the tests' tolerances (``tests/support/tolerances.py``) are :class:`analytic.threshold.Threshold`
records: each must say in which unit it counts and why it has its number, its value must be a
finite non-negative number, and no two share a name (a report or a failing test names a bound by
its name alone).
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

from analytic.threshold import Threshold, ThresholdSource
from tests.support import tolerances
from validation.compare.thresholds import DEFAULTS, thresholds_for
from validation.scenes import builtin_names, resolve_scene

ROOT = Path(__file__).resolve().parents[2]


def _all_records() -> list[tuple[str, Threshold]]:
    """(where, record) for every threshold the project defines or a shipped scene puts in force."""
    out = [("validation.compare.thresholds.DEFAULTS", t) for t in DEFAULTS.values()]
    out += [("tests.support.tolerances", t) for t in tolerances.TOLERANCES.values()]
    for name in builtin_names():
        out += [(f"scene {name}", t) for t in thresholds_for(resolve_scene(name)).values()]
    return out


def _problems(t: Threshold) -> list[str]:
    out = []
    if not (isinstance(t.reason, str) and t.reason.strip()):
        out.append("no reason")
    if not (isinstance(t.unit, str) and t.unit.strip()):
        out.append("no unit")
    if isinstance(t.value, bool) or not isinstance(t.value, int | float):
        out.append(f"value {t.value!r} is not a number")
    elif not (math.isfinite(t.value) and t.value >= 0):
        out.append(f"value {t.value!r} is not finite and non-negative")
    if t.source not in ThresholdSource:
        out.append(f"unknown source {t.source!r}")
    return out


def test_every_threshold_has_a_unit_a_reason_and_a_finite_non_negative_value():
    records = _all_records()
    assert {where for where, _ in records} >= {"validation.compare.thresholds.DEFAULTS", "tests.support.tolerances"}
    bad = [f"{where}: {t.name}: {', '.join(p)}" for where, t in records if (p := _problems(t))]
    assert not bad, "\n".join(bad)


def test_the_check_finds_a_bound_without_a_meaning():
    """Not vacuous: records that slipped past the constructor are reported."""
    t = Threshold("x", 1e-9, "m", "why")
    assert _problems(t) == []
    for field, bad in [("reason", ""), ("unit", " "), ("value", math.nan), ("value", True)]:
        broken = Threshold("x", 1e-9, "m", "why")
        object.__setattr__(broken, field, bad)
        assert _problems(broken), (field, bad)


def test_threshold_names_are_unique():
    """Across the comparison's defaults and the tests' tolerances; each mapping is keyed by its
    records' names, and each tolerance is bound in its module under its own name."""
    for key, t in DEFAULTS.items():
        assert t.name == key
    for key, t in tolerances.TOLERANCES.items():
        assert t.name == key and getattr(tolerances, key) is t
    names = [t.name for t in DEFAULTS.values()] + [t.name for t in tolerances.TOLERANCES.values()]
    assert len(names) == len(set(names)), sorted(n for n in set(names) if names.count(n) > 1)
    # every record the module defines is in its registry (none hidden from the checks above)
    defined = [v for v in vars(tolerances).values() if isinstance(v, Threshold)]
    assert len(defined) == len(tolerances.TOLERANCES) and len(defined) > 30


def test_the_record_refuses_a_bound_without_a_meaning():
    ok = {"name": "x", "value": 1e-9, "unit": "m", "reason": "why"}
    assert Threshold(**ok).source is ThresholdSource.DEFAULT
    assert Threshold(**ok, source="scene").source is ThresholdSource.SCENE
    for field, bad in [
        ("value", -1e-9),
        ("value", math.nan),
        ("value", math.inf),
        ("value", "1e-9"),
        ("unit", ""),
        ("reason", "  "),
        ("name", ""),
        ("source", "elsewhere"),
    ]:
        with pytest.raises(ValueError, match=r"^thresholds\.") as e:
            Threshold(**{**ok, field: bad})
        assert field == "value" or f".{field}:" in str(e.value)
    with pytest.raises(ValueError, match=r"^thresholds\.x\.floor: must be positive"):
        Threshold(**ok, relative=True)


def test_one_record_type():
    """No other module of the packages or the tests defines a class named ``Threshold``."""
    found = []
    for pkg in ("analytic", "model_xml", "mj_bridge", "validation", "tests"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            found += [
                path.relative_to(ROOT).as_posix()
                for node in ast.walk(tree)
                if isinstance(node, ast.ClassDef) and node.name == "Threshold"
            ]
    assert found == ["analytic/threshold.py"]
