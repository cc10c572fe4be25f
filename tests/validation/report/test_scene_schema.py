"""The scene format's JSON Schema (``validation/report/scene_schema.py``) against the loader.

* the shipped ``validation/scenes/scene.schema.json`` is what the generator produces now (parsed
  JSON), a valid draft-07 schema, printed and written by ``tumble scene-reference --json-schema``;
* never stricter than the loader: every built-in scene, every hard case, each of them written back
  as the resolved ``scene.toml``, and random valid scenes (hypothesis) validate;
* every refusal the schema can express is the loader's too, systematically from the declarations:
  for every declared key (the generic ``[thresholds]`` entries as every name of the comparison) in
  a scene that reads it, an unknown sibling, a missing required key, every wrong type and every
  violation of the key's own schema (enum, bound, length, distinct entries, each entry's) is
  refused by the loader, with a message naming that key, and by the schema, at that key's path.

"The loader" here is the scene loader and, for the names of ``[thresholds]`` and their rtol, the
comparison that resolves them (``thresholds_for``): the loader checks the entries' shape, the
comparison their names, and every command that compares does both before any plant runs.
"""

from __future__ import annotations

import copy
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jsonschema import Draft7Validator, ValidationError

from analytic import scene as S
from analytic.scene.builtin import BUILTIN_DIR
from analytic.scene.dump import scene_to_toml
from analytic.scene.random_scenes import MassInertia, random_scene_dict, unit_scene_dict
from analytic.scene.schema import KEYS, VERBATIM_TABLES, Kind, Need
from tests.support.scene_variants import variant
from validation.cli import main
from validation.compare.thresholds import DEFAULTS, SCALED, thresholds_for
from validation.report.scene_reference import DIRECTIVE_EXAMPLE, TAPLO_CONFIG, TOMBI_CONFIG
from validation.report.scene_schema import (
    DRAFT,
    LOADER_ONLY,
    SHIPPED,
    bounds_keywords,
    render_json,
    scene_schema,
)

ROOT = Path(__file__).resolve().parents[3]
HARD_DIR = ROOT / "validation" / "scenes" / "hard"
SCENE_FILES = sorted(BUILTIN_DIR.glob("*.toml")) + sorted(HARD_DIR.glob("*.toml"))
SCHEMA = scene_schema()
VALIDATOR = Draft7Validator(SCHEMA)
UNKNOWN = "zz_not_a_key"
HARD_NAME = "hard_criterion_x"  # an instance of thresholds.hard_<criterion>

Path_ = tuple[str | int, ...]


def _load(raw: dict) -> None:
    """The loader, then the comparison's resolution of ``[thresholds]`` (see the docstring)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (data of unlisted effects, rounded axes: warnings)
        thresholds_for(S.scene_from_dict(raw))


def _errors(instance: Any) -> list[ValidationError]:
    """Every error of ``instance``, with those inside ``anyOf`` branches."""
    out, todo = [], list(VALIDATOR.iter_errors(instance))
    while todo:
        e = todo.pop()
        out.append(e)
        todo.extend(e.context or ())
    return out


def _raw(path: Path) -> dict:
    with open(path, "rb") as f:
        return tomllib.load(f)


# ------------------------------------------------------------------------------------------------
# The shipped file, the draft, the command
# ------------------------------------------------------------------------------------------------


def test_the_shipped_schema_is_what_the_generator_produces():
    assert json.loads(SHIPPED.read_text(encoding="utf-8")) == scene_schema(), (
        "validation/scenes/scene.schema.json is stale: regenerate it with "
        "`tumble scene-reference --json-schema --out validation/scenes/scene.schema.json`"
    )


def test_the_schema_is_draft07_with_every_table_closed():
    Draft7Validator.check_schema(SCHEMA)
    assert SCHEMA["$schema"] == DRAFT == "http://json-schema.org/draft-07/schema#"
    assert "$ref" not in json.dumps(SCHEMA)  # (Taplo drops its x-taplo docs beside a $ref)

    def tables(node: Any, path: str) -> Iterator[tuple[str, dict]]:
        if isinstance(node, dict):
            if node.get("type") == "object":
                yield path, node
            for key, sub in node.items():
                yield from tables(sub, f"{path}/{key}")
        elif isinstance(node, list):
            for i, sub in enumerate(node):
                yield from tables(sub, f"{path}/{i}")

    found = list(tables(SCHEMA, ""))
    assert len(found) >= len([k for k in KEYS if k.kind is Kind.TABLE])
    for path, node in found:
        verbatim = path.split("/")[-1] in VERBATIM_TABLES
        assert node["additionalProperties"] is verbatim, path  # (explicit: Tombi's strict mode)


def test_the_command_prints_and_writes_the_schema(tmp_path, capsys):
    assert main(["scene-reference", "--json-schema"]) == 0
    assert json.loads(capsys.readouterr().out) == SCHEMA
    out = tmp_path / "scene.schema.json"
    assert main(["scene-reference", "--json-schema", "--out", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == render_json()


def test_every_bounds_clause_is_expressed_or_the_loaders():
    """The generator refuses a clause it neither expresses nor lists as the loader's; each clause
    listed as the loader's is still declared somewhere (the list only holds what is there)."""
    clauses = set()
    for k in KEYS:
        bounds_keywords(k)  # raises LookupError for an unknown clause
        clauses |= {c.strip() for part in k.bounds.split(";") for c in part.split(",")}
    assert set(LOADER_ONLY) <= clauses


# ------------------------------------------------------------------------------------------------
# Never stricter than the loader
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_every_builtin_and_hard_scene_validates(path):
    raw = _raw(path)
    _load(raw)
    assert _errors(raw) == []
    # written back as the resolved scene (every default filled in, inertia_body, ...)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        resolved = tomllib.loads(scene_to_toml(S.scene_from_dict(raw)))
    assert _errors(resolved) == []


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_every_builtin_and_hard_scene_names_the_shipped_schema(path):
    """Line 1 is ``#:schema <relative path>`` (Taplo and Tombi read it; the loader skips it as a
    comment), resolving to the shipped file; line 2 is blank, as Tombi requires."""
    first, second = path.read_text(encoding="utf-8").splitlines()[:2]
    m = re.fullmatch(r"#:schema (\S+)", first)
    assert m and not m.group(1).startswith("/"), first
    assert (path.parent / m.group(1)).resolve() == SHIPPED.resolve()
    assert second == ""


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(0, 6),
    controlled=st.booleans(),
    track_all=st.booleans(),
    external_torque=st.booleans(),
    mass_inertia=st.sampled_from(list(MassInertia)),
    spring_model=st.sampled_from(["tendon", "actuator"]),
)
def test_random_valid_scenes_validate(
    seed, n, controlled, track_all, external_torque, mass_inertia, spring_model
):
    raw = random_scene_dict(
        np.random.default_rng(seed),
        n,
        controlled=controlled,
        track_all=track_all,
        external_torque=external_torque,
        mass_inertia=mass_inertia,
        spring_model=spring_model,
    )
    raw = json.loads(json.dumps(raw))  # as a file holds it: plain lists, floats, ints
    _load(raw)
    assert _errors(raw) == []


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 5))
def test_random_unit_scenes_validate(seed, n):
    raw = json.loads(json.dumps(unit_scene_dict(np.random.default_rng(seed), n)))
    _load(raw)
    assert _errors(raw) == []


# ------------------------------------------------------------------------------------------------
# Every refusal the schema expresses is the loader's, key by key
# ------------------------------------------------------------------------------------------------


def _bases() -> list[dict]:
    """Scenes that together read every declared key: the built-in scenes, variants of the
    controlled Example 1 for the keys none of them gives, then the hard cases (``[hard_case]``)."""
    base = _raw(BUILTIN_DIR / "paper_example1_controlled.toml")
    effects = base["scene"]["effects"]
    J = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]
    n = len(base["masses"]["mass"])
    every_threshold = {
        name: {"value": 1e-6, "rtol": 1e-7 if name in SCALED else 0.0, "reason": "a test"}
        for name in DEFAULTS
    }
    variants = [
        variant(base, masses__ring_radius=None, masses__inertia_axial=[1.0] * n, masses__inertia_transverse=[1.0] * n),
        variant(base, masses__ring_radius=None, masses__inertia_body=[J] * n),
        variant(base, initial__attitude={"quaternion": [1.0, 0.0, 0.0, 0.0], "allow_off_manifold": False}),
        variant(base, initial__attitude={"axis": [0.0, 0.0, 1.0], "angle": 0.3}),
        variant(base, initial__pdot=[0.1] * n, control__masses__indices=list(range(1, n + 1))),
        variant(base, control__omega__gamma=None, control__omega__components=[1, 2, 3], control__omega__gain=J),
        variant(base, scene__effects=[*effects, "external_torque"], external_torque={"constant": [0.0, 0.0, 1.0], "amplitude": [1.0, 0.0, 0.0], "frequency": 2.0}),
        variant(base, scene__effects=[*effects, "springs.damping"], springs__c_damping=[0.1] * (n + 1)),
        variant(base, solver={"method": "RK45", "rtol": 1e-9, "atol": 1e-10, "max_step": 0.01}),
        variant(base, stabilization={"delta1": 1.0, "delta2": 4.0}, mujoco={"integrator": "RK4", "timestep": 2.5e-4, "spring_model": "tendon"}, output={"t_end": 1.0, "rate": 10.0}),
        variant(base, control__weighting="M^-2", thresholds={**every_threshold, HARD_NAME: 1.0}, mjx={"precision": "float64"}),
    ]  # fmt: skip
    builtins = [_raw(p) for p in sorted(BUILTIN_DIR.glob("*.toml"))]
    return [*builtins, *variants, *(_raw(p) for p in sorted(HARD_DIR.glob("*.toml")))]


BASES = _bases()


def _instances() -> list[tuple[Path_, Any]]:
    """Every declared key as the paths it takes in a file (``thresholds.<name>``: each name of
    the comparison; ``thresholds.hard_<criterion>``: :data:`HARD_NAME`), with its declaration."""

    def expand(part: str) -> list[str]:
        if part == "<name>":
            return list(DEFAULTS)
        return [HARD_NAME] if part.startswith("hard_<") else [part]

    out = []
    for k in KEYS:
        paths: list[Path_] = [()]
        for part in [*(k.table.split(".") if k.table else []), k.key]:
            paths = [(*p, name) for p in paths for name in expand(part)]
        out += [(p, k) for p in paths]
    return out


INSTANCES = _instances()


def _get(raw: Any, path: Path_) -> Any:
    for part in path:
        if not isinstance(raw, dict) or part not in raw:
            raise KeyError(path)
        raw = raw[part]
    return raw


def _base_for(path: Path_) -> dict:
    for raw in BASES:
        try:
            _get(raw, path)
        except KeyError:
            continue
        return raw
    raise LookupError(f"{'.'.join(map(str, path))}: no base scene gives it (add a variant)")


def _is(value: Any, json_type: str) -> bool:
    """Whether a TOML value is of a JSON Schema type (bool is no number, as in JSON)."""
    number = isinstance(value, int | float) and not isinstance(value, bool)
    return {
        "number": number,
        "string": isinstance(value, str),
        "boolean": isinstance(value, bool),
        "array": isinstance(value, list),
        "object": isinstance(value, dict),
    }[json_type]


_POOL = ("1.0", True, 1, [1.0], {"a": 1.0})
"""Values of every TOML type; a key's wrong types are those its kind excludes."""

_LISTS = {
    # kind: (the entries' kind, a fixed length, the longest list any scene can hold)
    Kind.VECTOR3: (Kind.NUMBER, 3, 3),
    Kind.VECTOR4: (Kind.NUMBER, 4, 4),
    Kind.VECTOR_N: (Kind.NUMBER, None, S.MAX_MASSES),  # n ≤ MAX_MASSES
    Kind.VECTOR_N1: (Kind.NUMBER, None, S.MAX_MASSES + 1),  # n + 1 springs
    Kind.VECTOR_K: (Kind.NUMBER, None, S.MAX_MASSES),  # k ≤ n
    Kind.MATRIX3: (Kind.VECTOR3, 3, 3),
    Kind.MATRIX_K: (Kind.VECTOR_K, None, 3),  # k ≤ 3 body axes
    Kind.MATRICES_N: (Kind.MATRIX3, None, S.MAX_MASSES),
    Kind.INDICES: (Kind.NUMBER, None, None),
    Kind.CHOICES: (Kind.CHOICE, None, None),
}
_TYPES = {
    Kind.NUMBER: {"number"},
    Kind.STRING: {"string"},
    Kind.BOOLEAN: {"boolean"},
    Kind.CHOICE: {"string"},
    Kind.TABLE: {"object"},
    Kind.NUMBER_OR_VALUE_TABLE: {"number", "object"},
    Kind.NUMBER_OR_STRING: {"number", "string"},
    **{kind: {"array"} for kind in _LISTS},
}


def _violations(key: Any, value: Any, kind: Kind | None = None) -> Iterator[tuple[str, Any]]:
    """``(what, value)`` for each way of breaking the declaration of ``key`` (its ``kind``, or
    that of an entry of it): a wrong type, a choice outside the enum, a value beyond a declared
    bound (:func:`bounds_keywords`: the declaration's prose, not the schema built from it), a list
    of a wrong length or too long for any scene, repeated indices; then the same for its first
    entry. Built from the declarations alone, so a bound the schema fails to carry is caught."""
    top = kind is None
    kind = key.kind if kind is None else kind
    number, array = bounds_keywords(key)
    if not top:
        array = {}  # (the count and distinctness a declaration states are of the list itself)
    types = _TYPES[kind]
    for v in _POOL:
        if not any(_is(v, t) for t in types):
            yield f"wrong type {v!r}", v
    if kind is Kind.CHOICE:
        yield "not a choice", "zz_not_a_choice"
    if kind in (Kind.NUMBER, Kind.NUMBER_OR_VALUE_TABLE, Kind.NUMBER_OR_STRING):
        if key.kind is Kind.INDICES:
            yield "not an integer", 1.5
        if "exclusiveMinimum" in number:
            yield "at the exclusive minimum", number["exclusiveMinimum"]
        if "minimum" in number:
            lo = number["minimum"]
            if key.kind is Kind.INDICES:
                yield "below the minimum", lo - 1
            else:  # (halfway to 0 above it, twice as far from 0 below it)
                yield "below the minimum", lo / 2 if lo > 0 else lo - max(abs(lo), 1)
        if "maximum" in number:
            hi = number["maximum"]
            yield "above the maximum", hi + max(abs(hi), 1)
    if kind in _LISTS and isinstance(value, list) and value:
        entry, length, longest = _LISTS[kind]
        if length is not None:
            yield "too short", value[:-1]
            yield "too long", [*value, value[-1]]
        if longest is not None:
            yield "longer than any scene's", [value[0]] * (longest + 1)
        if kind in (Kind.INDICES, Kind.MATRIX_K):  # (no effects at all is a scene)
            yield "empty", []
        if array.get("uniqueItems"):
            yield "an entry repeated", [value[0], *value]
        if array.get("maxItems"):
            yield "beyond the declared count", [value[0]] * (array["maxItems"] + 1)
        for what, v in _violations(key, value[0], entry):
            yield f"[0] {what}", [v, *value[1:]]


def _refused(raw: dict, name: str) -> str:
    """'' when the loader refuses ``raw`` naming ``name`` first; else what it did."""
    try:
        _load(raw)
    except ValueError as exc:
        return "" if str(exc).startswith(name) else f"refused naming another field: {exc}"
    return "accepted by the loader"


def _schema_refuses_at(raw: dict, path: Path_, needle: str = "") -> bool:
    """Whether the schema reports an error at ``path`` or inside it (``needle`` in its message);
    stops at the first (the errors are generated lazily)."""
    for top in VALIDATOR.iter_errors(raw):
        todo = [top]
        while todo:
            e = todo.pop()
            if tuple(e.absolute_path)[: len(path)] == path and needle in e.message:
                return True
            todo.extend(e.context or ())
    return False


def test_every_declared_key_has_a_base_scene_that_validates():
    missing = []
    for path, _ in INSTANCES:
        try:
            _base_for(path)
        except LookupError as exc:
            missing.append(str(exc))
    assert missing == []
    for raw in BASES:
        _load(raw)
        assert _errors(raw) == [], raw["scene"]["name"]


@pytest.mark.parametrize(
    ("path", "key"), INSTANCES, ids=[".".join(map(str, p)) for p, _ in INSTANCES]
)
def test_every_refusal_the_schema_expresses_is_the_loaders(path, key):
    base = _base_for(path)
    *parent_path, last = path
    dotted = ".".join(map(str, path))
    failures = []

    def check(what: str, raw: dict, name: str, at: Path_, needle: str = "") -> None:
        loader = _refused(raw, name)
        schema = _schema_refuses_at(raw, at, needle)
        if loader or not schema:
            failures.append(f"{what}: loader: {loader or 'refused'}; schema: {schema}")

    if key.kind is Kind.TABLE and key.dotted not in VERBATIM_TABLES:
        raw = copy.deepcopy(base)
        _get(raw, path)[UNKNOWN] = 1.0
        check("an unknown key", raw, f"{dotted}.{UNKNOWN}", path, repr(UNKNOWN))
    if not parent_path:  # the document's own unknown table
        raw = copy.deepcopy(base)
        raw[UNKNOWN] = {"a": 1.0}
        check("an unknown table", raw, UNKNOWN, (), repr(UNKNOWN))
    if key.need is Need.REQUIRED:
        raw = copy.deepcopy(base)
        del _get(raw, tuple(parent_path))[last]
        check("missing", raw, dotted, tuple(parent_path), repr(last))
    value = _get(base, path)
    count = 0
    for what, bad in _violations(key, value):
        raw = copy.deepcopy(base)
        _get(raw, tuple(parent_path))[last] = bad
        check(what, raw, dotted, path)
        count += 1
    assert count >= 1  # (every key has a type to break)
    assert failures == [], f"{dotted}:\n" + "\n".join(failures)


# ------------------------------------------------------------------------------------------------
# The editors' own checkers read it as docs/scene-format.md says
# ------------------------------------------------------------------------------------------------

TOOLS = {
    # the command that checks files against their schema, offline, with no user configuration
    "taplo": ["check"],
    "tombi": ["lint", "--offline"],
}


def _tool(name: str, args: list[str], cwd: Path, home: Path) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).with_name(name)
    exe = str(exe) if exe.exists() else shutil.which(name)
    if exe is None:
        pytest.skip(f"{name} is not installed (pip install '.[test]' installs it)")
    env = {**os.environ, "HOME": str(home), "XDG_CACHE_HOME": str(home / "cache"), "NO_COLOR": "1"}
    return subprocess.run(
        [exe, *TOOLS[name], *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=60
    )


@pytest.mark.parametrize("name", list(TOOLS))
def test_the_editors_checkers_read_the_builtin_scenes_directive(name, tmp_path):
    """Taplo (Even Better TOML's engine) and Tombi find the shipped schema through each built-in
    scene's and hard case's ``#:schema`` line, and accept every one of them."""
    proc = _tool(name, [str(p) for p in SCENE_FILES], ROOT, tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.parametrize("name", list(TOOLS))
@pytest.mark.parametrize("setup", ["directive", "configuration"])
def test_the_editors_checkers_refuse_what_the_schema_refuses(name, setup, tmp_path):
    """A project set up as docs/scene-format.md says (the schema written by the command, then a
    ``#:schema`` line or the tool's configuration file): a scene passes, and one with an unknown
    key, a choice outside the enum and a value below its bound fails, naming each."""
    assert (
        main(["scene-reference", "--json-schema", "--out", str(tmp_path / "scene.schema.json")])
        == 0
    )
    (tmp_path / "scenes").mkdir()
    text = (BUILTIN_DIR / "paper_example2.toml").read_text(encoding="utf-8").split("\n", 2)[2]
    bad = text.replace('integrator = "RK4"', 'integrator = "RK5"\nintegrater = "RK4"', 1)
    bad = bad.replace("\ndelta1 = ", "\ndelta1 = -1.0 #", 1)
    assert bad.count("RK5") == 1 and "delta1 = -1.0" in bad
    header = ""
    if setup == "directive":
        header = DIRECTIVE_EXAMPLE.split("\n", 1)[0].replace("./", "../") + "\n\n"
    else:
        (tmp_path / ".taplo.toml").write_text(TAPLO_CONFIG, encoding="utf-8")
        (tmp_path / "tombi.toml").write_text(TOMBI_CONFIG, encoding="utf-8")
    (tmp_path / "scenes" / "good.toml").write_text(header + text, encoding="utf-8")
    (tmp_path / "scenes" / "bad.toml").write_text(header + bad, encoding="utf-8")
    home = tmp_path / "home"
    good = _tool(name, ["scenes/good.toml"], tmp_path, home)
    assert good.returncode == 0, good.stdout + good.stderr
    proc = _tool(name, ["scenes/bad.toml"], tmp_path, home)
    said = proc.stdout + proc.stderr
    assert proc.returncode != 0, said
    for needle in ("RK5", "integrater", "-1"):
        assert needle in said, (needle, said)


_RANGE_REFUSALS = ("must be positive (got", "must be non-negative (got", "must be at least", "must be at most", "entries must be at most", "must be an integer in 1..")  # fmt: skip
"""How the loader words a refusal of a number's range (``analytic/scene/values.py``, ``twin.py``,
the parsers): what a schema's bounds express."""
_PROBES = (0, 0.0, -0.5, -1e300, 1e-16, 1e300, 1e45)
_INDEX_PROBES = (0, -1, 4, S.MAX_MASSES + 1)
_NUMBERED = {
    # kind: where its first number sits (a number, a list's first entry, a matrix's first entry)
    Kind.NUMBER: (),
    Kind.NUMBER_OR_VALUE_TABLE: (),
    Kind.NUMBER_OR_STRING: (),
    Kind.VECTOR3: (0,),
    Kind.VECTOR4: (0,),
    Kind.VECTOR_N: (0,),
    Kind.VECTOR_N1: (0,),
    Kind.VECTOR_K: (0,),
    Kind.INDICES: (0,),
    Kind.MATRIX3: (0, 0),
    Kind.MATRIX_K: (0, 0),
    Kind.MATRICES_N: (0, 0, 0),
}
NUMBERED = [(p, k) for p, k in INSTANCES if k.kind in _NUMBERED]


@pytest.mark.parametrize(
    ("path", "key"), NUMBERED, ids=[".".join(map(str, p)) for p, _ in NUMBERED]
)
def test_every_range_the_loader_refuses_the_schema_refuses(path, key):
    """The loader as the oracle, independent of the declarations' prose: a number probed at
    zero, negative, tiny and huge values in a key's first number; where the loader refuses its
    range (naming the key), the schema refuses it there; where the loader accepts it, the schema
    reports nothing there (never stricter at a bound)."""
    base = _base_for(path)
    dotted = ".".join(map(str, path))
    where = _NUMBERED[key.kind]
    failures = []
    for probe in _INDEX_PROBES if key.kind is Kind.INDICES else _PROBES:
        raw = copy.deepcopy(base)
        node = _get(raw, path[:-1])
        target, last = (node, path[-1])
        for i in where:
            target, last = target[last], i
        if not isinstance(target[last], int | float) or isinstance(target[last], bool):
            continue  # (a [thresholds] entry given as a table: its value is its own key)
        target[last] = probe
        at = (*path, *where)
        try:
            _load(raw)
        except ValueError as exc:
            message = str(exc)
            n_bound = (
                f"in 1..{len(_get(raw, ('masses', 'mass')))} " if "1..n" in key.bounds else "-"
            )
            if n_bound in message:
                continue  # (indices up to n: a bound of this scene, not of every scene)
            if message.startswith(dotted) and any(w in message for w in _RANGE_REFUSALS):
                if not _schema_refuses_at(raw, at):
                    failures.append(f"{probe!r}: refused by the loader ({message}), not the schema")
            continue
        if _schema_refuses_at(raw, at):
            failures.append(f"{probe!r}: accepted by the loader, refused by the schema")
    assert failures == [], f"{dotted}:\n" + "\n".join(failures)
