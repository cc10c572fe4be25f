"""The scene format's JSON Schema, generated from the loader's own key declarations.

:func:`scene_schema` builds it from :data:`analytic.scene.schema.KEYS` (the table the loader reads
every key through): one JSON Schema property per declared key, with its type, its enum (effects,
integrators, weightings, ...), the fixed length of its list, its numeric bounds, its meaning as the
description and its declared default; ``additionalProperties: false`` on every table the loader
checks, so an unknown key is an error in the editor as it is at load. ``[thresholds]`` lists the
comparison's names (:data:`validation.compare.thresholds.DEFAULTS`), which is why the generator sits
in ``validation`` (as the reference, :mod:`validation.report.scene_reference`, does).

The draft is **draft-07**, the one JSON Schema version both TOML language servers read: Taplo (and
VS Code's Even Better TOML, built on it) reads draft-04/06/07, Tombi draft-07 and 2020-12. Nothing
beyond draft-07 is used, and no ``$ref`` (Taplo ignores its ``x-taplo`` extension beside one).

A declaration's ``bounds`` is prose; each of its clauses (split at ``;`` and ``,``) is either one
the schema expresses (``> 0``, ``≥ 0``, ``{LO} … {HI}``, ``at most {HI}``, ``entries at most {HI}
in magnitude``, ``n ≤ {N}``, ``distinct``, ``in 1..3``; ``finite`` as a TOML number, ``a known name`` as the names of
``[thresholds]``) or one only the loader can check, listed with the reason (:data:`LOADER_ONLY`: a
norm, a rotation, a relation between entries or keys). A clause in neither
stops the generator (``LookupError``), so a new bound is either expressed or said to be the
loader's. The schema never refuses what the loader accepts (tested with the built-in scenes, the
hard cases and random scenes); what it cannot express stays the loader's alone (:data:`LOADER_ONLY`,
and the cross-field rules: ``docs/scene-format.md``, *Editors*).

The shipped copy is :data:`SHIPPED` (``validation/scenes/scene.schema.json``, package data), written
by :data:`GENERATOR`; ``tests/validation/report/test_scene_schema.py`` checks it is what this
module generates now.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from analytic import scene as S
from analytic.scene.schema import (
    CHOICE_MEANINGS,
    KEYS,
    NO_DEFAULT,
    VERBATIM_TABLES,
    Key,
    Kind,
    Need,
)
from validation.compare.thresholds import DEFAULTS, HARD_CASE_PREFIX, SCALED

DRAFT = "http://json-schema.org/draft-07/schema#"
"""The JSON Schema draft: draft-07, read by Taplo (draft-04/06/07) and Tombi (draft-07, 2020-12)."""

SHIPPED = Path(__file__).resolve().parents[1] / "scenes" / "scene.schema.json"
"""The schema as shipped in the package (``validation/scenes/scene.schema.json``)."""

GENERATOR = "tumble scene-reference --json-schema --out validation/scenes/scene.schema.json"
"""The command that writes :data:`SHIPPED`."""

TOML_VERSION = "v1.0.0"
"""The TOML version the loader parses (:mod:`tomllib`), told to Tombi (``x-tombi-toml-version``)."""

AXES = 3
"""Body axes: ``control.omega.components`` index them, so a gain over them is at most 3×3."""

_FIXED_LENGTH: Mapping[Kind, int] = {Kind.VECTOR3: 3, Kind.VECTOR4: 4}
_PER_MASS: Mapping[Kind, int] = {
    Kind.VECTOR_N: S.MAX_MASSES,  # n ≤ MAX_MASSES
    Kind.VECTOR_N1: S.MAX_MASSES + 1,  # one per spring: n + 1
    Kind.VECTOR_K: S.MAX_MASSES,  # k ≤ n
    Kind.MATRICES_N: S.MAX_MASSES,
}

_NAME = r"\{([A-Z_]+)\}"
_RANGE = re.compile(rf"^(each )?{_NAME} … {_NAME}( \S+)?$")
_AT_MOST = re.compile(rf"^at most {_NAME}( \S+)?$")
_MAGNITUDE = re.compile(rf"^entries at most {_NAME}( \S+)? in magnitude$")
_COUNT = re.compile(rf"^n ≤ {_NAME}$")
_INDEX = re.compile(r"^in 1\.\.(\d+|n)$")

WARNING_ONLY = "a repair with a warning, not a refusal"

LOADER_ONLY: Mapping[str, str] = {
    "A + B ≥ C": "the triangle inequality of principal moments, a relation between entries",
    "unit length within {AXIS_REFUSE_TOL}": "a vector's norm",
    "one off 1 by more than {AXIS_NORMALISE_TOL} is normalised with a one-line warning naming "
    "its norm": WARNING_ONLY,
    "within {ROTATION_REFUSE_TOL} of a rotation": "a matrix's singular values and determinant",
    "at most twice the transverse moment": "a relation between two keys",
    "symmetric": "a relation between a matrix's entries",
    "positive semidefinite": "a matrix's eigenvalues",
    "symmetric positive definite": "a matrix's eigenvalues",
    "norm within {QUAT_REFUSE_TOL} of 1": "a vector's norm, a bound `allow_off_manifold` lifts",
    "at least one MuJoCo step": "a relation to `mujoco.timestep`",
    "≤ {MAX_OUTPUT_SAMPLES} samples": "a product with `output.rate`",
    "≤ {MAX_MUJOCO_STEPS} steps per run": "a quotient of `output.t_end`",
}
"""The bounds clauses only the loader checks, each with what makes it inexpressible in a schema
(or :data:`WARNING_ONLY`: what the loader repairs with a warning)."""


def _constant(name: str) -> float:
    value = getattr(S, name, None)
    if not isinstance(value, int | float):
        raise LookupError(f"scene bound {{{name}}}: not a constant of analytic.scene")
    return value


def _fill(text: str) -> str:
    """``text`` with each ``{NAME}`` replaced by the constant of :mod:`analytic.scene`."""
    return (
        re.sub(_NAME, lambda m: f"{_constant(m.group(1)):g}", text)
        .replace("{{", "{")
        .replace("}}", "}")
    )


def bound_clauses(key: Key) -> list[str]:
    """The clauses of ``key``'s declared bounds (split at ``;`` and ``,``), unfilled."""
    return [c.strip() for part in key.bounds.split(";") for c in part.split(",") if c.strip()]


def bounds_keywords(key: Key) -> tuple[dict[str, Any], dict[str, Any]]:
    """The JSON Schema keywords of ``key``'s declared bounds: ``(on each number, on the list)``.

    Raises:
        LookupError: a clause of the bounds that is neither expressed here nor in
            :data:`LOADER_ONLY`, naming the key and the clause.
    """
    number: dict[str, Any] = {}
    array: dict[str, Any] = {}
    for clause in bound_clauses(key):
        if clause in LOADER_ONLY or clause in ("finite", "a known name"):
            continue
        if clause == "> 0":
            number["exclusiveMinimum"] = 0
        elif clause in ("≥ 0", "a number ≥ 0 or a string"):
            number["minimum"] = 0
        elif clause == "distinct":
            array["uniqueItems"] = True
        elif m := _RANGE.match(clause):
            number["minimum"], number["maximum"] = _constant(m.group(2)), _constant(m.group(3))
        elif m := _AT_MOST.match(clause):
            number["maximum"] = _constant(m.group(1))
        elif m := _MAGNITUDE.match(clause):
            number["minimum"], number["maximum"] = -_constant(m.group(1)), _constant(m.group(1))
        elif m := _COUNT.match(clause):
            array["maxItems"] = int(_constant(m.group(1)))
        elif m := _INDEX.match(clause):
            top = S.MAX_MASSES if m.group(1) == "n" else int(m.group(1))
            number.update(minimum=1, maximum=top)
        else:
            raise LookupError(
                f"{key.dotted}: bounds clause {clause!r} is neither expressed by the scene's JSON "
                "Schema nor listed as the loader's alone (validation/report/scene_schema.py)"
            )
    return number, array


def _description(key: Key) -> str:
    parts = [_fill(key.meaning)]
    if key.unit and not key.unit.startswith("the "):
        parts.append(f"Unit: {key.unit}.")
    if key.need is Need.CONDITIONAL:
        parts.append(f"When: {_fill(key.when)}.")
    if key.bounds:
        parts.append(f"Refused unless: {_fill(key.bounds)}.")
    if key.default is NO_DEFAULT and key.default_text:
        parts.append(f"When absent: {key.default_text}.")
    return " ".join(parts)


def _choices(key: Key) -> dict[str, Any]:
    assert key.choices is not None
    return {
        "type": "string",
        "enum": [c.value for c in key.choices],
        "x-taplo": {"docs": {"enumValues": [CHOICE_MEANINGS[c] for c in key.choices]}},
    }


def _number(bounds: Mapping[str, Any], integer: bool = False) -> dict[str, Any]:
    return {"type": "integer" if integer else "number", **bounds}


def _array(items: dict[str, Any], length: int | None = None, **more: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "array"}
    if length is not None:
        out.update(minItems=length, maxItems=length)
    out.update(more)
    out["items"] = items  # (after the lengths: a validator reports a wrong length first)
    return out


def _value(key: Key) -> dict[str, Any]:
    """The schema of a key's value (not a table), without its description."""
    number, array = bounds_keywords(key)
    kind = key.kind
    if kind is Kind.NUMBER:
        return _number(number)
    if kind is Kind.STRING:
        return {"type": "string"}
    if kind is Kind.BOOLEAN:
        return {"type": "boolean"}
    if kind is Kind.CHOICE:
        return _choices(key)
    if kind is Kind.CHOICES:
        return _array(_choices(key))
    if kind in _FIXED_LENGTH:
        return _array(_number(number), _FIXED_LENGTH[kind])
    if kind is Kind.MATRIX3:
        return _array(_array(_number(number), 3), 3)
    if kind is Kind.MATRIX_K:
        return _array(_array(_number(number), minItems=1, maxItems=AXES), minItems=1, maxItems=AXES)
    if kind is Kind.MATRICES_N:
        return _array(
            _array(_array(_number(number), 3), 3), **{"maxItems": _PER_MASS[kind], **array}
        )
    if kind in _PER_MASS:
        return _array(_number(number), **{"maxItems": _PER_MASS[kind], **array})
    if kind is Kind.INDICES:
        return _array(_number(number, integer=True), minItems=1, **array)
    if kind is Kind.NUMBER_OR_STRING:
        return {"anyOf": [_number(number), {"type": "string"}]}
    if kind is Kind.NUMBER_OR_VALUE_TABLE:
        return {"anyOf": [_number(number), _table(key.dotted)]}
    raise LookupError(f"{key.dotted}: no JSON Schema for the kind {kind.name}")


def _property(key: Key) -> dict[str, Any]:
    out: dict[str, Any] = {"description": _description(key)}
    out.update(_table(key.dotted) if key.kind is Kind.TABLE else _value(key))
    if key.default is not NO_DEFAULT:
        out["default"] = key.default
    return out


def _thresholds(key: Key) -> dict[str, Any]:
    """``[thresholds]``: the comparison's names, each a bound, and the hard-case suite's
    ``hard_*`` criteria; any other name is refused (by ``tumble validate``, the pytest plugin)."""
    entry = next(k for k in KEYS if k.table == key.dotted and k.key.startswith("<"))
    hard = next(k for k in KEYS if k.table == key.dotted and k.key.startswith(HARD_CASE_PREFIX))
    properties = {}
    for name, t in DEFAULTS.items():
        schema = _property(entry)
        default = f"{t.value:g}" + (f" + {t.rtol:g} × scale" if t.rtol else "")
        schema["description"] = f"{t.unit}, default {default}: {t.reason}. {schema['description']}"
        schema["default"] = t.value
        if name not in SCALED:  # no relative part: rtol may only be 0
            rtol = schema["anyOf"][1]["properties"]["rtol"]
            rtol["maximum"] = 0
            rtol["description"] += f" {name} has no relative part: 0 only."
        properties[name] = schema
    return {
        "type": "object",
        "properties": properties,
        "patternProperties": {f"^{re.escape(HARD_CASE_PREFIX)}": _property(hard)},
        "additionalProperties": False,
    }


def _table(dotted: str) -> dict[str, Any]:
    """The schema of the table ``dotted`` (generic name): its keys, the required ones, no other."""
    if dotted in VERBATIM_TABLES:  # checked by the layer that owns it, not by the loader
        return {"type": "object", "additionalProperties": True}
    if dotted == "thresholds":
        return _thresholds(next(k for k in KEYS if k.dotted == dotted))
    keys = [k for k in KEYS if k.table == dotted]
    out: dict[str, Any] = {
        "type": "object",
        "properties": {k.key: _property(k) for k in keys},
        "additionalProperties": False,
    }
    required = [k.key for k in keys if k.need is Need.REQUIRED]
    if required:
        out["required"] = required
    return out


def scene_schema() -> dict[str, Any]:
    """The JSON Schema (draft-07) of a scene file, as nested dicts."""
    return {
        "$schema": DRAFT,
        "title": "tumbling-testbed scene",
        "description": "A scene file of tumbling-testbed (docs/scene-format.md), generated from the "
        f"loader's key declarations by `{GENERATOR}`. The loader refuses more than this schema "
        "can express (norms, rotations, lengths of n, rules across keys).",
        "x-tombi-toml-version": TOML_VERSION,
        **_table(""),
    }


def render_json() -> str:
    """:func:`scene_schema` as the text of :data:`SHIPPED` (two-space indents, UTF-8, a final
    newline)."""
    return json.dumps(scene_schema(), indent=2, ensure_ascii=False) + "\n"


__all__ = [
    "AXES",
    "DRAFT",
    "GENERATOR",
    "LOADER_ONLY",
    "SHIPPED",
    "TOML_VERSION",
    "WARNING_ONLY",
    "bound_clauses",
    "bounds_keywords",
    "render_json",
    "scene_schema",
]
