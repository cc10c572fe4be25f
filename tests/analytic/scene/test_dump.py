"""A resolved scene written in the scene file's conventions loads back to the same scene.

``analytic.scene.dump.scene_to_toml`` is what ``tumble validate`` writes beside its report as
``scene.toml``, and ``scene_to_dict`` the ``provenance.scene`` block of the JSON outputs: both in the
TOML's own keys (``lambda``, 1-based ``indices``). Loaded back, every field is equal, arrays bit for
bit (the loader keeps a unit axis, a unit quaternion and a rotation matrix it is given as they are,
so nothing is re-rounded).
"""

from __future__ import annotations

import dataclasses
import json
import tomllib
import warnings
from typing import Any

import numpy as np
import pytest

from analytic.scene import Scene, load_scene, random_scenes, scene_from_dict
from analytic.scene.dump import scene_to_dict, scene_to_toml
from validation.report.provenance import FileKind, dumps, provenance
from validation.scenes import builtin_names, resolve_scene


def _differences(a: Any, b: Any, where: str = "scene") -> list[str]:
    """Where ``a`` and ``b`` differ: dataclass fields (``source`` aside: where a scene was read
    from), arrays (shape, dtype and every bit), mappings, sequences and plain values."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return [f"{where}: {type(a).__name__} vs {type(b).__name__}"]
        out = []
        for f in dataclasses.fields(a):
            if f.name != "source":
                out += _differences(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
        return out
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        same = a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b)
        return [] if same else [f"{where}: {a.tolist()!r} vs {b.tolist()!r}"]
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return [f"{where}: keys {sorted(a)} vs {sorted(b)}"]
        return [d for k in a for d in _differences(a[k], b[k], f"{where}.{k}")]
    return (
        []
        if (type(a) is type(b) or isinstance(a, str)) and a == b
        else [f"{where}: {a!r} vs {b!r}"]
    )


def _load_quietly(text: str) -> tuple[Scene, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = scene_from_dict(tomllib.loads(text))
    return scene, [str(w.message) for w in caught]


def _assert_round_trip(scene: Scene, warned: list[str]) -> None:
    text = scene_to_toml(scene)
    back, rewarned = _load_quietly(text)
    assert _differences(scene, back) == []
    # what loaded without a warning reloads without one (a unit axis is not normalised again)
    assert set(rewarned) <= set(warned), rewarned
    # and dumping the reloaded scene writes the same text (the dump is a fixed point)
    assert scene_to_toml(dataclasses.replace(back, source=scene.source)) == text


@pytest.mark.parametrize("name", builtin_names())
def test_every_builtin_scene_round_trips_through_toml(name, tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = resolve_scene(name)
    _assert_round_trip(scene, [str(w.message) for w in caught])
    # through a file too, as `tumble validate` writes it beside the report
    path = tmp_path / "scene.toml"
    path.write_text(scene_to_toml(scene), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _differences(scene, load_scene(path)) == []


RANDOM_OPTIONS = [
    {},
    {"n": 0},
    {"n": 1, "track_all": True},
    {"controlled": False},
    {"external_torque": True},
    {"mass_inertia": "body"},
    {"spring_model": "actuator"},
]


@pytest.mark.parametrize("seed", range(12))
def test_random_scenes_round_trip_through_toml(seed):
    rng = np.random.default_rng(1000 + seed)
    options = RANDOM_OPTIONS[seed % len(RANDOM_OPTIONS)]
    raw = random_scenes.random_scene_dict(rng, **options)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = scene_from_dict(raw)
    _assert_round_trip(scene, [str(w.message) for w in caught])


def test_the_dump_uses_the_files_conventions():
    """Example 2 controls masses 1, 2 and 4 (Sec. VII.B): the dump says 1, 2, 4, under the file's
    key names; the record holds them 0-based."""
    scene = resolve_scene("paper_example2_controlled")
    assert scene.control.masses.indices == (0, 1, 3)
    d = scene_to_dict(scene)
    masses = d["control"]["masses"]
    assert masses["indices"] == [1, 2, 4]
    assert set(masses) == {"indices", "l", "lambda", "alpha", "beta"}
    assert d["control"]["omega"]["components"] == [1, 2, 3]
    with open(scene.source, "rb") as f:
        given = tomllib.load(f)
    assert masses["lambda"] == pytest.approx(given["control"]["masses"]["lambda"])
    # every table is one the file format declares (the loader refuses anything else)
    assert scene_from_dict(d) is not None


def test_the_provenance_scene_is_the_files_tables_and_loads_back():
    scene = resolve_scene("paper_example2_controlled")
    block = json.loads(dumps(provenance(FileKind.REPORT, scene, argv=["tumble"])))
    assert block["scene"]["control"]["masses"]["indices"] == [1, 2, 4]
    assert "lam" not in block["scene"]["control"]["masses"]
    assert _differences(scene, scene_from_dict(block["scene"])) == []


def test_scene_text_that_could_break_toml_is_written_as_data():
    """A name or description with quotes, backslashes, newlines and control characters, and a
    source path with a newline, stay data: the text loads back to the same strings."""
    scene = resolve_scene("paper_example1")
    odd = 'a "quoted" \\ name\nwith [scene]\x7f and\ttabs\x01 é'
    scene = dataclasses.replace(scene, name=odd, description=odd, source="dir\n[body]\nx.toml")
    text = scene_to_toml(scene, header="first\n[second]")
    back, _ = _load_quietly(text)
    assert back.name == odd and back.description == odd
    assert _differences(scene, back) == []


def test_a_scene_off_the_unit_sphere_on_purpose_keeps_its_quaternion():
    raw = random_scenes.random_scene_dict(np.random.default_rng(7), 2)
    raw["initial"]["attitude"] = {"quaternion": [1.01, 0.0, 0.0, 0.0], "allow_off_manifold": True}
    scene = scene_from_dict(raw)
    assert scene_to_dict(scene)["initial"]["attitude"]["allow_off_manifold"] is True
    _assert_round_trip(scene, [])


def test_validate_writes_the_scene_it_ran_beside_the_report(tmp_path):
    """``scene.toml`` in the run directory (named in its manifest) is the report's provenance
    scene and loads back to the scene that ran."""
    from validation.validate import run_validation

    res = run_validation("paper_example2_controlled", tmp_path / "v", t_end=0.05)
    path = res.out_dir / "scene.toml"
    assert res.files["scene.toml"] == path
    manifest = json.loads((res.out_dir / "manifest.json").read_text(encoding="utf-8"))
    assert "scene.toml" in json.dumps(manifest)
    ran = resolve_scene("paper_example2_controlled")
    assert _differences(ran, load_scene(path)) == []
    with open(path, "rb") as f:
        toml = tomllib.load(f)
    report = json.loads((res.out_dir / "report.json").read_text(encoding="utf-8"))
    assert report["provenance"]["scene"] == json.loads(dumps(toml))
    assert toml["control"]["masses"]["indices"] == [1, 2, 4]  # Sec. VII.B: masses 1, 2 and 4


def test_modified_scene_changes_the_keys_given_and_validates_again():
    """``modified_scene`` lays the changes over the scene's own tables: the keys given change,
    every other field stays equal; a change the loader refuses is a ValueError naming the field
    (``dataclasses.replace`` would have kept it)."""
    from analytic.scene import modified_scene

    sc = load_scene("paper_example1_controlled")
    new = modified_scene(sc, {"body": {"inertia": [1.0e7, 1.2e7, 4.0e6]}, "output": {"t_end": 5.0}})
    assert isinstance(new, Scene)
    assert new.body.inertia.tolist() == [1.0e7, 1.2e7, 4.0e6] and new.output.t_end == 5.0
    same = dataclasses.replace(new, body=sc.body, output=sc.output, source=sc.source)
    assert _differences(same, sc) == []
    with pytest.raises(ValueError, match=r"^body\.inertia"):
        modified_scene(sc, {"body": {"inertia": [1.0, -2.0, 3.0]}})
    with pytest.raises(ValueError, match=r"^changes"):
        modified_scene(sc, [("body", {})])
