"""The built-in scenes shipped with the package (``analytic/scenes/*.toml``), found by name.

A built-in scene is a commented TOML file in ``analytic/scenes/``: the paper's two examples
(uncontrolled and controlled) and the spacecraft with propellant slosh, a worked example of a system
beyond the paper. Its name is the file's stem (``paper_example1``); :func:`analytic.load_scene` and
the command line accept it wherever they accept a path. A name is looked up in the list of files,
never joined onto a path, so no name can reach outside this directory.

The hard-case suite's scenes (``hard/<name>``) belong to the validation layer, which adds them to
the names its command line accepts (``validation.scenes``).
"""

from __future__ import annotations

from pathlib import Path

BUILTIN_DIR = Path(__file__).resolve().parent.parent / "scenes"
"""Where the built-in scenes live (package data, ``pyproject.toml``)."""


def builtin_scene_names() -> list[str]:
    """Names of the built-in scenes, sorted (``paper_example1``, ...)."""
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.toml"))


def builtin_scene_path(name: str) -> Path | None:
    """The file of the built-in scene ``name`` (``"paper_example1"`` or ``"paper_example1.toml"``),
    or None when there is no built-in scene of that name."""
    stem = name.removesuffix(".toml")
    for p in BUILTIN_DIR.glob("*.toml"):
        if p.stem == stem:
            return p
    return None


__all__ = ["BUILTIN_DIR", "builtin_scene_names", "builtin_scene_path"]
