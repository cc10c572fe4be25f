"""A figure as the report writes it: :class:`Drawing` (a matplotlib figure and its caption, or
only the caption saying why nothing was drawn), rendered to PNG, SVG or PDF (:class:`FigureFormat`)
without a time stamp in the file, so equal figures give equal files."""

from __future__ import annotations

import io
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np


class FigureFormat(StrEnum):
    """A file format a figure is written in (the file's extension)."""

    PNG = "png"
    SVG = "svg"
    PDF = "pdf"


DEFAULT_FORMATS = (FigureFormat.PNG,)
PNG_DPI = 150  # pixels per inch of the PNG files (10 in wide: 1500 px)
PNG_COMPRESS_LEVEL = 3  # zlib level of the PNGs (below Pillow's 6: docs/performance.md)
SVG_HASH_SALT = "validation.report.figures"  # salt of the SVG ids (matplotlib: a random uuid)
TEXT_RASTER = {"text.hinting": "no_hinting"}
"""How Agg rasterises text: glyphs unhinted. Matplotlib's default (FreeType hinting each glyph to
the pixel grid) looks the same at 150 dpi and costs drawing time (``docs/performance.md``)."""


@dataclass(frozen=True)
class Drawing:
    """One figure and its caption; ``figure`` is None when there was nothing to draw, and the
    caption then says why (a sentence, ``The scene has no control requirement, ...``)."""

    name: str
    caption: str
    figure: Any = None

    @property
    def drawn(self) -> bool:
        return self.figure is not None

    def render(self, fmt: FigureFormat | str = FigureFormat.PNG) -> bytes:
        """The figure's file content in ``fmt``: no time stamp, and SVG element ids drawn from a
        fixed salt rather than a random one, so equal figures give equal files; text rasterised
        as :data:`TEXT_RASTER` says."""
        # deferred: matplotlib ~0.4 s (python -X importtime): the report imports this module, a worker draws
        import matplotlib as mpl

        if self.figure is None:
            raise ValueError(f"figure {self.name!r}: not drawn ({self.caption})")
        fmt = FigureFormat(fmt)
        if fmt is FigureFormat.PNG:
            return _png(self.figure)
        metadata = {FigureFormat.SVG: {"Date": None}, FigureFormat.PDF: {"CreationDate": None}}[fmt]
        buf = io.BytesIO()
        with mpl.rc_context({"svg.hashsalt": SVG_HASH_SALT, **TEXT_RASTER}):
            self.figure.savefig(buf, format=fmt.value, dpi=PNG_DPI, metadata=metadata)
        return buf.getvalue()


def _png(figure: Any) -> bytes:
    """``figure`` as PNG: the pixels matplotlib's Agg renderer draws at :data:`PNG_DPI`, written as
    RGB when every pixel is opaque (the figures have an opaque background), else RGBA.

    matplotlib's ``savefig`` always writes RGBA, whose PNG row filters cost more than those of the
    RGB that carries the same picture when the alpha channel is all 255 (``docs/performance.md``);
    the file records the resolution and no time stamp or software version."""
    import matplotlib as mpl
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    with mpl.rc_context(TEXT_RASTER):
        canvas = FigureCanvasAgg(figure)
        canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())
    image = Image.fromarray(rgba[..., :3] if (rgba[..., 3] == 255).all() else rgba)
    buf = io.BytesIO()
    image.save(buf, format="png", compress_level=PNG_COMPRESS_LEVEL, dpi=(PNG_DPI, PNG_DPI))
    return buf.getvalue()


def parse_formats(text: str) -> tuple[FigureFormat, ...]:
    """``"png,svg"`` -> the formats, in order, once each; ValueError naming ``figure_format``."""
    out: list[FigureFormat] = []
    for part in str(text).split(","):
        name = part.strip().lower()
        try:
            fmt = FigureFormat(name)
        except ValueError:
            known = ", ".join(f.value for f in FigureFormat)
            raise ValueError(
                f"figure_format: unknown format {part.strip()!r} (known: {known})"
            ) from None
        if fmt not in out:
            out.append(fmt)
    return tuple(out)


__all__ = ["DEFAULT_FORMATS", "PNG_DPI", "TEXT_RASTER", "Drawing", "FigureFormat", "parse_formats"]
