"""Regenerate the checked-in MJCF files of the paper scenes: ``python -m model_xml.regenerate``.

Each built-in scene ``analytic/scenes/<name>.toml`` listed in :data:`PAPER_SCENES` becomes
``model_xml/<name>.xml`` (full precision, see :mod:`model_xml.mjcf_text`).
"""

from __future__ import annotations

import sys
from pathlib import Path

from analytic.scene import load_scene
from analytic.scene.builtin import BUILTIN_DIR
from model_xml.mjcf_text import to_mjcf

PAPER_SCENES = (
    "paper_example1",
    "paper_example1_controlled",
    "paper_example2",
    "paper_example2_controlled",
)
XML_DIR = Path(__file__).resolve().parent


def scene_path(name: str) -> Path:
    return BUILTIN_DIR / f"{name}.toml"


def xml_path(name: str) -> Path:
    return XML_DIR / f"{name}.xml"


def generate(name: str) -> str:
    """The MJCF text for one paper scene."""
    return to_mjcf(load_scene(scene_path(name)))


def regenerate(names: tuple[str, ...] = PAPER_SCENES) -> list[Path]:
    """Write the MJCF files; returns their paths."""
    out = []
    for name in names:
        p = xml_path(name)
        p.write_text(generate(name), encoding="utf-8")
        out.append(p)
    return out


def main(argv: list[str] | None = None) -> int:
    for p in regenerate():
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
