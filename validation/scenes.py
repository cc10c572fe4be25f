"""Scenes by name or by path: the built-in scenes and the hard-case suite's.

The built-in scenes (the paper's examples, the spacecraft with propellant slosh) live with the
scene format in ``analytic/scenes/`` (:mod:`analytic.scene.builtin`), so
``analytic.load_scene("paper_example1")`` finds them too. The hard-case suite's scenes are this
layer's (``validation/scenes/hard/``, with the criteria of :mod:`validation.studies.hard_cases`); the
command line also accepts them, as ``hard/<name>``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from analytic.scene import Scene, load_scene
from analytic.scene.builtin import BUILTIN_DIR, builtin_scene_names, builtin_scene_path
from validation.compare.thresholds import thresholds_for

SCENES_DIR = BUILTIN_DIR
"""The built-in scenes (``analytic/scenes``)."""
HARD_DIR = Path(__file__).resolve().parent / "scenes" / "hard"
"""The hard-case suite's scenes."""
HARD_PREFIX = "hard/"
DEFAULT_SCENE = "paper_example1_controlled"
"""The scene of every command run without one (``simulate``, ``validate``, ``export-mjcf``,
``sweep``, :func:`validation.run_validation`): Example 1 under control, so that the tracking errors
and the control's checks have something to show."""


def _hard_files() -> list[Path]:
    return sorted(HARD_DIR.glob("*.toml"))


def builtin_names() -> list[str]:
    """Names the command line accepts: the built-in scenes, then ``hard/<name>`` for each hard case."""
    return builtin_scene_names() + [f"{HARD_PREFIX}{p.stem}" for p in _hard_files()]


def scene_path(name_or_path: str) -> Path:
    """A path as given if it exists, else the built-in or hard-case scene of that name.

    A name is matched against the list of scene files, never joined onto a directory.
    """
    p = Path(name_or_path)
    try:
        if p.exists():
            return p
    except (OSError, ValueError) as exc:  # a name too long for the file system, a NUL byte
        raise ValueError(f"scene: cannot look up {name_or_path!r} ({exc})") from None
    found = builtin_scene_path(name_or_path)
    if found is not None:
        return found
    stem = name_or_path.removesuffix(".toml")
    if stem.startswith(HARD_PREFIX):
        for h in _hard_files():
            if h.stem == stem.removeprefix(HARD_PREFIX):
                return h
    raise ValueError(
        f"scene: no file and no built-in scene named {name_or_path!r} "
        f"(built-in: {', '.join(builtin_names())})"
    )


def resolve_scene(
    name_or_path: Scene | str | Path | None,
    default: str = DEFAULT_SCENE,
    *,
    check_thresholds: bool = True,
) -> Scene:
    """The one resolver of a scene: a :class:`Scene` as given, else a file by path or a built-in
    or hard-case scene by name (:func:`scene_path`; ``default`` when None or empty), loaded.

    Everything in it is checked here, before any work: its fields by the loader, and the names
    and values of its ``[thresholds]`` against :data:`validation.compare.thresholds.DEFAULTS`.
    Messages name a file as the user gave it. ``check_thresholds=False`` leaves the thresholds
    to a caller that checks them itself, once (:func:`validation.validate.request.validation_request`).

    Raises:
        ValueError: naming the field (``scene``, ``thresholds.<name>``, the loader's) and the value.
    """
    if isinstance(name_or_path, Scene):
        scene = name_or_path
    else:
        given = str(name_or_path) if name_or_path else default
        p = scene_path(given)
        scene = load_scene(given if p == Path(given) else p)
    if check_thresholds:
        thresholds_for(scene)
    return scene


def with_threshold_overrides(scene: Scene, overrides: Mapping[str, Any] | None) -> Scene:
    """``scene`` with ``overrides`` (name -> number or ``{value, reason}``) laid over its
    ``[thresholds]`` table; not checked here (:func:`validation.compare.thresholds.thresholds_for`
    of the result checks every entry)."""
    if not overrides:
        return scene
    extra = dict(scene.extra or {})
    extra["thresholds"] = {**dict(extra.get("thresholds") or {}), **dict(overrides)}
    return scene.replace(extra=extra)
