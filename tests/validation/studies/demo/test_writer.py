"""What ``tumble demo`` writes: the files a teacher reads without a viewer, each named in the
guide."""

from __future__ import annotations

from pathlib import Path

from validation.studies.demo import STEPS

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _section(md: str, title: str) -> str:
    return md.split(f"## {title}")[1].split("\n## ")[0].split("\n# ")[0]


def test_each_step_has_a_figure_the_guide_embeds(demo_dir):
    """One PNG per step, a valid image, embedded in that step's section of demo.md; every file
    of the demo is named in the guide."""
    from PIL import Image

    out = Path(demo_dir)
    md = (out / "demo.md").read_text()
    assert [f.name for f in demo_dir.figures] == [f"{s.prefix}.png" for s in STEPS]
    for step, fig in zip(STEPS, demo_dir.figures, strict=True):
        assert fig.is_file() and fig.parent == out
        data = fig.read_bytes()
        assert data.startswith(PNG_SIGNATURE)
        with Image.open(fig) as im:
            im.verify()
        with Image.open(fig) as im:
            w, h = im.size
            assert im.format == "PNG" and w >= 800 and h >= 600
        assert f"]({fig.name})" in _section(md, step.title), step.prefix
    made = {p.name for p in out.iterdir()} - {"manifest.json", "demo.md"}
    assert all(name in md for name in made), made
