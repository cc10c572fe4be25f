"""Built-in scenes shipped with the package, found by name or by path."""

from __future__ import annotations

from pathlib import Path

from analytic.scene import Scene, load_scene

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
    if p.exists():
        return p
    candidate = SCENES_DIR / f"{name_or_path.removesuffix('.toml')}.toml"
    if candidate.exists():
        return candidate
    raise ValueError(
        f"scene: no file and no built-in scene named {name_or_path!r} "
        f"(built-in: {', '.join(builtin_names())})"
    )


def resolve_scene(name_or_path: str | None, default: str = DEFAULT_SIMULATE_SCENE) -> Scene:
    """Load a scene given by path or built-in name (``default`` when None)."""
    return load_scene(scene_path(name_or_path or default))
