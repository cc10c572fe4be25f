"""The scene format's reference (``docs/scene-format.md``) and the loader's key declarations.

The loader reads every key through :data:`analytic.scene.schema.KEYS`, and the reference is rendered
from it. These tests close the loop:

* every key the loader reads is declared, and every declared key is read by the loader (found
  statically in its source, and recorded while it loads scenes that take every branch);
* every declared key is in the reference, in its table's section;
* the committed ``docs/scene-format.md`` is what the generator renders now (text rendered by our
  own code from our own declarations, so an exact comparison is meaningful);
* the records' own defaults (``SolverSettings()``, ...) are the declared ones;
* the reference's TOML examples load as scenes.
"""

from __future__ import annotations

import ast
import re
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

from analytic import scene as S
from analytic.scene import loading, parsers
from analytic.scene.builtin import builtin_scene_names
from analytic.scene.schema import CHOICE_MEANINGS, KEYS, NO_DEFAULT, Kind, key_spec
from analytic.scene.table import Table
from tests.support.scene_variants import variant as scene_variant
from validation.cli import main
from validation.report.scene_reference import GENERATOR, LIMIT_NAMES, MINIMAL_SCENE, render
from validation.scenes import builtin_names, scene_path

ROOT = Path(__file__).resolve().parents[3]
DOC = ROOT / "docs" / "scene-format.md"
READERS = {
    "raw",
    "has",
    "number",
    "vector",
    "string",
    "boolean",
    "enum",
    "table",
    "table_or_empty",
    "required_table",
}
WILDCARD = re.compile(r"<[a-z]+>")


def _raw(name: str) -> dict:
    with open(scene_path(name), "rb") as f:
        return tomllib.load(f)


def test_committed_reference_is_what_the_generator_renders():
    assert DOC.read_text(encoding="utf-8") == render(), (
        f"docs/scene-format.md is stale: regenerate it with `{GENERATOR}`"
    )


def test_cli_prints_and_writes_the_reference(tmp_path, capsys):
    assert main(["scene-reference"]) == 0
    assert capsys.readouterr().out == render()
    out = tmp_path / "ref.md"
    assert main(["scene-reference", "--out", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == render()


def _literal_keys_read_by_the_loader() -> set[str]:
    """Every string literal the loader passes as a key to one of ``Table``'s readers (in the
    modules that read the tables: the top level and the per-table parsers)."""
    keys = set()
    nodes = (
        node
        for module in (loading, parsers)
        for node in ast.walk(ast.parse(Path(module.__file__).read_text(encoding="utf-8")))
    )
    for node in nodes:
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in READERS
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            keys.add(node.args[0].value)
    return keys


def _spring_law_keys_read_by_the_loader() -> set[str]:
    """The spring laws' keys, each checked to be read: a ``[springs]`` table giving only that
    law's coefficients loads them, and the others stay zero."""
    from analytic.effects.registry import SPRING_LAWS
    from analytic.scene import scene_from_dict

    keys = set()
    for law in SPRING_LAWS:
        data = _raw("paper_example1")
        data["scene"]["effects"] = [law.effect.value]
        n = len(data["masses"]["mass"])
        data["springs"] = {law.key.key: [1.5] * (n + 1)}
        springs = scene_from_dict(data).springs
        assert springs.of(law).tolist() == [1.5] * (n + 1) and springs.given == {law.key.key}
        keys.add(law.key.key)
    return keys


def test_every_key_the_loader_reads_is_declared_and_in_the_reference():
    declared = {k.key for k in KEYS}
    # the spring laws' coefficients are read by iteration over their declarations (parse_springs)
    read = _literal_keys_read_by_the_loader() | _spring_law_keys_read_by_the_loader()
    assert len(read) > 60
    assert read - declared == set(), "keys the loader reads but KEYS does not declare"
    # and nothing is declared that the loader never reads (wildcards are read by iteration)
    assert {k for k in declared if not WILDCARD.search(k)} - read == set()
    sections = {s.split("\n", 1)[0]: s for s in re.split(r"^### ", render(), flags=re.M)}
    for k in KEYS:
        if k.kind is Kind.TABLE:
            assert f"`[{k.dotted}]`" in sections, k.dotted
            continue
        table = k.table.split(".<name>")[0]  # a threshold's table is listed under [thresholds]
        assert f"| `{k.key}` |" in sections[f"`[{table}]`"], k.dotted


def _branch_corpus() -> list[dict]:
    """Scenes that together take every branch of the loader: each built-in scene, each hard case,
    and variants for the keys none of them uses."""
    corpus = [_raw(name) for name in builtin_names()]
    base = _raw("paper_example1_controlled")

    def variant(**changes) -> dict:
        return scene_variant(base, **changes)

    J = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]
    corpus += [
        variant(masses__ring_radius=None, masses__inertia_axial=[1.0, 1.0], masses__inertia_transverse=[1.0, 1.0]),
        variant(masses__ring_radius=None, masses__inertia_body=[J, J]),
        variant(initial__attitude={"quaternion": [1.0, 0.0, 0.0, 0.0], "allow_off_manifold": False}),
        variant(initial__attitude={"axis": [0.0, 0.0, 1.0], "angle": 0.3}),
        variant(control__omega__gamma=None, control__omega__gain=[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], control__omega__components=[1, 2, 3]),
        variant(control__masses__indices=None),
        variant(external_torque={"constant": [0.0, 0.0, 1.0], "amplitude": [1.0, 0.0, 0.0], "frequency": 2.0}, scene__effects=[*base["scene"]["effects"], "external_torque"]),
        variant(solver={"method": "RK45", "rtol": 1e-9, "atol": 1e-10, "max_step": 0.01}),
        variant(stabilization={"delta1": 1.0, "delta2": 4.0}),
        variant(thresholds={"position_C": {"value": 1e-7, "reason": "tighter"}, "attitude": 1e-7, "hard_x": 1.0}),
        variant(gravity=None, scene__effects=[e for e in base["scene"]["effects"] if e != "gravity"]),
    ]  # fmt: skip
    return corpus


def test_every_declared_key_is_read_while_loading_the_corpus(monkeypatch):
    """Recorded at run time: every (table, key) the loader looks up is declared (else it raises),
    and loading the corpus looks up every declared key."""
    seen: set[tuple[str, str]] = set()
    spec = Table.spec

    def recording(self, key, *kinds):
        k = spec(self, key, *kinds)
        seen.add((k.table, k.key))
        return k

    monkeypatch.setattr(Table, "spec", recording)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the corpus has an off-manifold start and the like
        for raw in _branch_corpus():
            S.scene_from_dict(raw)
    assert {(k.table, k.key) for k in KEYS} - seen == set()


def test_reading_an_undeclared_key_or_as_another_kind_is_a_programming_error():
    t = Table({"mass": 1.0, "colour": "red"}, "body")
    with pytest.raises(LookupError, match=r"body\.colour"):
        t.number("colour")
    with pytest.raises(TypeError, match=r"body\.mass"):
        t.vector("mass")
    with pytest.raises(LookupError, match="declared default"):
        Table({}, "solver").number("rtol", 1e-6)
    assert key_spec("thresholds", "position_C").key == "<name>"
    assert key_spec("thresholds", "hard_x").key == "hard_<criterion>"


def test_declared_defaults_are_the_records_defaults():
    """A scene that gives only what is required loads with the records' own defaults."""
    raw = {
        "scene": {"name": "x", "effects": []},
        "body": {"mass": 1.0, "inertia": [1.0, 1.0, 1.0], "shape": {"kind": "box_and_rod", "box_half_sizes": [1.0, 1.0, 1.0]}},
        "rod": {"axis": [1.0, 0.0, 0.0], "offset": [0.0, 0.0, 0.0]},
        "initial": {"attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]}},
    }  # fmt: skip
    sc = S.scene_from_dict(raw)
    assert sc.solver == S.SolverSettings()
    assert sc.output == S.OutputSettings()
    assert sc.mujoco == S.MujocoSettings()
    assert sc.stabilization == S.Stabilization()
    assert sc.control == S.Control()
    assert sc.description == ""
    np.testing.assert_array_equal(sc.gravity, [0.0, 0.0, -9.81])
    default_shape = S.BodyShape()
    for name in ("rod_radius", "rod_start", "rod_length"):
        assert getattr(sc.body.shape, name) == getattr(default_shape, name), name
    np.testing.assert_array_equal(sc.body.shape.box_center, default_shape.box_center)
    for name in ("R", "Rdot", "omega"):
        np.testing.assert_array_equal(getattr(sc.initial, name), np.zeros(3))


def test_every_choice_has_a_meaning_and_every_bound_quoted_exists():
    assert all(k.default is NO_DEFAULT or k.kind is not Kind.TABLE for k in KEYS)
    for k in KEYS:
        if k.choices is not None:
            for c in k.choices:
                assert CHOICE_MEANINGS.get(c), f"{k.dotted} = {c.value!r} has no meaning"
    for name in LIMIT_NAMES:
        assert isinstance(getattr(S, name), int | float)
    assert not re.search(r"\{[A-Z_]+\}", render())  # every quoted bound filled in


def _toml_blocks(text: str) -> list[str]:
    return re.findall(r"^```toml\n(.*?)^```", text, flags=re.S | re.M)


def test_the_references_toml_examples_load_as_scenes():
    blocks = _toml_blocks(render())
    assert blocks == [MINIMAL_SCENE]
    for block in blocks:
        sc = S.scene_from_dict(tomllib.loads(block))
        assert sc.n == 1 and sc.output.t_end == 2.0


def test_the_reference_lists_every_builtin_scene():
    doc = render()
    for name in builtin_scene_names():
        assert f"| `{name}` |" in doc
