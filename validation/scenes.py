"""Built-in scenes shipped with the package, found by name or by path."""

from __future__ import annotations

from pathlib import Path

from analytic.scene import Scene, load_scene
from validation.thresholds import thresholds_for

SCENES_DIR = Path(__file__).resolve().parent / "scenes"
DEFAULT_SIMULATE_SCENE = "paper_example1"
DEFAULT_VALIDATE_SCENE = "paper_example1_controlled"


def builtin_names() -> list[str]:
    """Names of the built-in scenes (``validation/scenes/*.toml`` and ``hard/*.toml``)."""
    names = [p.stem for p in sorted(SCENES_DIR.glob("*.toml"))]
    names += [f"hard/{p.stem}" for p in sorted((SCENES_DIR / "hard").glob("*.toml"))]
    return names


def scene_path(name_or_path: str) -> Path:
    """A path as given if it exists, else the built-in scene of that name."""
    p = Path(name_or_path)
    try:
        if p.exists():
            return p
    except (OSError, ValueError) as exc:  # a name too long for the file system, a NUL byte
        raise ValueError(f"scene: cannot look up {name_or_path!r} ({exc})") from None
    candidate = SCENES_DIR / f"{name_or_path.removesuffix('.toml')}.toml"
    if candidate.exists():
        return candidate
    raise ValueError(
        f"scene: no file and no built-in scene named {name_or_path!r} "
        f"(built-in: {', '.join(builtin_names())})"
    )


def resolve_scene(name_or_path: str | None, default: str = DEFAULT_SIMULATE_SCENE) -> Scene:
    """Load a scene given by path or built-in name (``default`` when None).

    Everything in it is checked here, before any work: its fields by the loader, and the names
    and values of its ``[thresholds]`` against :data:`validation.thresholds.DEFAULTS`. Messages
    name a file as the user gave it.
    """
    given = name_or_path or default
    p = scene_path(given)
    scene = load_scene(given if p == Path(given) else p)
    thresholds_for(scene)
    return scene
