"""The tests' paper scenes, and the random scenes and on-manifold states the MuJoCo-twin,
Pinocchio, coordinate and MJCF tests draw: :func:`random_scene` and :func:`random_state` are the
one random-scene generator, :mod:`analytic.scene.random_scenes` (same seeded draws as before it moved
there)."""

from __future__ import annotations

from pathlib import Path

from analytic.scene import Scene, load_scene
from analytic.scene.random_scenes import random_scene, random_state

SCENE_DIR = Path(__file__).resolve().parents[2] / "analytic" / "scenes"
PAPER = (
    "paper_example1",
    "paper_example1_controlled",
    "paper_example2",
    "paper_example2_controlled",
)


def paper_scene(name: str) -> Scene:
    return load_scene(SCENE_DIR / f"{name}.toml")


__all__ = ["PAPER", "SCENE_DIR", "paper_scene", "random_scene", "random_state"]
