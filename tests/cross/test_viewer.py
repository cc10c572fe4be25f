"""The recordings in a real viewer: run.rrd and demo.rrd opened in Rerun's web viewer in headless
Chromium show their designed layout (its view and tab titles, read off the screenshot with
Tesseract), no legend covers the plots' curves (the words only a legend shows are absent, the
curves' colours are on screen), and the characters recordings may use are in the fonts the viewer
bundles.

Slow (a viewer drawn on the CPU per file); skipped without Chromium or Tesseract (Debian:
``apt-get install chromium tesseract-ocr``).
"""

from __future__ import annotations

import importlib.util
import io
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

from validation.recording.style import VIEWER_CHARACTERS

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


def _images():
    spec = importlib.util.spec_from_file_location(
        "make_images", ROOT / "docs/images/make_images.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _words(png: Path) -> str:
    """The text Tesseract reads in a screenshot, lower case, one space between words."""
    out = subprocess.run(
        ["tesseract", str(png), "-", "--psm", "11"],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    ).stdout
    return " ".join(out.lower().split())


@pytest.fixture(scope="module")
def images():
    module = _images()
    if module.chromium() is None or shutil.which("tesseract") is None:
        pytest.skip("needs Chromium and Tesseract (apt-get install chromium tesseract-ocr)")
    return module


def test_run_rrd_opens_in_its_designed_layout(images, tmp_path):
    """The designed views' titles are on screen: the 3D view with every plant, the narrative
    "what this is" and the plot tabs; the automatic layout names views after entity paths."""
    from analytic.scene import load_scene
    from analytic.simulate import simulate
    from validation.compare.checks import compare
    from validation.recording.recording import write_recording

    scene = load_scene("paper_example1_controlled")
    tr = simulate(scene, t_end=0.5, rtol=1e-10)
    path = write_recording(tmp_path / "run.rrd", scene, [tr], compare(tr, None, scene)).path
    words = _words(images.viewer_screenshot(path, tmp_path / "run.png"))
    assert "what this is" in words, words
    assert "tracking errors" in words, words
    assert "analytic plant" in words, words


MIN_CURVE_PIXELS = 2000
"""Pixels in the colours of the pairs' curves (within :data:`CURVE_COLOUR_DISTANCE`) the plot
column must show: six difference plots about 180 px wide, three pairs each, are well over this
when their curves are drawn; the legend dots and key words alone are a few hundred."""

CURVE_COLOUR_DISTANCE = 40.0
"""How far (RGB, 0-255 each) a pixel may be from a curve's colour: the anti-aliased line on the
plot's dark background."""


def _curve_pixels(png: Path, colours) -> int:
    """The pixels of the plot column (the right half of the window, left of the selection panel)
    within :data:`CURVE_COLOUR_DISTANCE` of one of ``colours``."""
    import numpy as np
    from PIL import Image

    rgb = np.asarray(Image.open(png).convert("RGB"), float)
    width = rgb.shape[1]
    column = rgb[:, width // 2 : int(0.8 * width)]
    ref = np.array([c[:3] for c in colours], float)
    dist = np.linalg.norm(column[:, :, None, :] - ref[None, None], axis=3).min(axis=2)
    return int((dist < CURVE_COLOUR_DISTANCE).sum())


def test_difference_plots_show_their_curves_not_legends(images, tmp_path):
    """Three plants' run.rrd at the designed size: no legend covers the difference plots (the
    words only a legend shows are absent: each difference plot's legend lists "threshold of
    <quantity>" and "<pair>: <quantity>" per curve; the tab's key names each pair once), and the
    plot column shows the pairs' curves, in their colours."""
    import re

    from validation.recording.style import plant_color, shade
    from validation.validate import run_validation

    res = run_validation("paper_example1_controlled", tmp_path / "v", t_end=2.0)
    shot = images.viewer_screenshot(res.files["run.rrd"], tmp_path / "plots.png")
    words = _words(shot)
    pairs = ("analytic vs mujoco", "analytic vs pinocchio", "mujoco vs pinocchio")
    assert "colours" in words and "shades, darkest first" in words, words  # the key is shown
    assert "threshold of" not in words, words
    assert len(re.findall(r"\bvs\b", words)) <= len(pairs), words  # the key's, once per pair
    colours = [shade(plant_color(p), j) for p in pairs for j in range(3)]
    assert _curve_pixels(shot, colours) >= MIN_CURVE_PIXELS


def test_demo_rrd_opens_in_its_designed_layout(images, tmp_path):
    """The demo opens on its first step's tab, the other steps as tabs beside it (one step's
    body per tab, not four drawn over each other), with the step's narrative view."""
    from validation.studies.demo import STEPS, write_demo

    res = write_demo(tmp_path / "demo", t_end=0.2)
    words = _words(images.viewer_screenshot(res.rrd, tmp_path / "demo.png"))
    assert "what to look at" in words, words
    assert sum(s.title.split(" ", 1)[1].lower()[:12] in words for s in STEPS) >= 2, words


def _embedded_fonts(binary: Path) -> list[set[int]]:
    """The character maps of the TrueType/OpenType fonts inside the ``rerun`` executable."""
    from fontTools.ttLib import TTFont

    data = binary.read_bytes()
    fonts: list[set[int]] = []
    for sig in (b"\x00\x01\x00\x00", b"OTTO"):
        i = data.find(sig)
        while i >= 0:
            try:
                n = struct.unpack(">H", data[i + 4 : i + 6])[0]
                tags = [data[i + 12 + 16 * k : i + 16 + 16 * k] for k in range(n if n <= 40 else 0)]
                if 4 <= n and b"cmap" in tags and all(t.isascii() for t in tags):
                    ends = [
                        sum(struct.unpack(">II", data[i + 20 + 16 * k : i + 28 + 16 * k]))
                        for k in range(n)
                    ]
                    font = TTFont(io.BytesIO(data[i : i + max(ends)]))
                    fonts.append(set(font.getBestCmap()))
            except Exception:  # not a font: a byte pattern that only looks like a header
                pass
            i = data.find(sig, i + 1)
    return fonts


def test_the_allowed_characters_are_in_every_font_the_viewer_bundles():
    """VIEWER_CHARACTERS lies in each distinct font embedded in the installed viewer (Inter and
    JetBrains Mono in 0.41): a new rerun with other fonts fails here, not in a user's viewer."""
    pytest.importorskip("fontTools")
    import rerun_cli

    binary = Path(rerun_cli.__file__).parent / "rerun"
    if not binary.exists():
        pytest.skip("no rerun executable in rerun_cli")
    fonts = {frozenset(f) for f in _embedded_fonts(binary)}
    assert len(fonts) >= 2  # a proportional and a monospace font
    for cmap in fonts:
        missing = sorted(c for c in map(ord, VIEWER_CHARACTERS) if c not in cmap)
        assert not missing, [f"U+{c:04X} {chr(c)}" for c in missing]
