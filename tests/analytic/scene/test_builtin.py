"""The built-in scenes, found by name (never a path joined from a name).

Every bad input must raise ValueError whose message starts with the dotted field name.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from analytic.scene import load_scene
from validation.scenes import scene_path

# ------------------------------------------------------------------------------------------------
# Built-in scenes by name
# ------------------------------------------------------------------------------------------------


def test_load_scene_accepts_every_builtin_name_the_command_line_lists():
    """``analytic.load_scene(name)`` loads the same file as the command line's lookup, for every
    built-in name outside the hard-case suite (which is the validation layer's, ``hard/<name>``)."""
    from analytic import load_scene as api_load_scene
    from analytic.scene.builtin import builtin_scene_names
    from validation.scenes import HARD_PREFIX, builtin_names

    names = builtin_scene_names()
    assert {"paper_example1", "paper_example2_controlled", "spacecraft_slosh"} <= set(names)
    assert [n for n in builtin_names() if not n.startswith(HARD_PREFIX)] == names
    for name in names:
        by_name = api_load_scene(name)
        assert by_name.name == name
        assert Path(by_name.source) == scene_path(name)  # the file the CLI resolves
        assert api_load_scene(f"{name}.toml").name == name
        assert api_load_scene(Path(name)).name == name  # validation.validate passes a Path
    with pytest.raises(ValueError, match=r"^scene: file not found and no built-in scene") as exc:
        load_scene("hard/zero_gravity")
    assert "paper_example1" in str(exc.value) and "\n" not in str(exc.value)
    assert scene_path("hard/zero_gravity").name == "zero_gravity.toml"  # the CLI's


def test_builtin_names_are_looked_up_never_joined_onto_a_path(tmp_path, monkeypatch):
    """A name that walks out of the scenes' directory is no built-in scene; a file at the given
    path wins over a built-in of the same name."""
    from analytic.scene.builtin import BUILTIN_DIR, builtin_scene_path

    monkeypatch.chdir(tmp_path)
    for name in ("../scenes/paper_example1", "scenes/paper_example1", str(BUILTIN_DIR), "a\0b"):
        assert builtin_scene_path(name) is None
        with pytest.raises(ValueError, match=r"^scene: "):
            load_scene(name)
    text = scene_path("paper_example2").read_text(encoding="utf-8")
    Path("paper_example1").write_text(text, encoding="utf-8")
    assert load_scene("paper_example1").name == "paper_example2"
