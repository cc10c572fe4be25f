"""A drawing rendered: equal figures give equal files, the PNG is matplotlib's picture, formats parsed
and bad ones named (before any work)."""

from __future__ import annotations

import io

import matplotlib as mpl
import numpy as np
import pytest

from validation.report.figures import (
    PNG_DPI,
    TEXT_RASTER,
    FigureContext,
    FigureFormat,
    figure_invariants,
    parse_formats,
)


def test_equal_figures_give_equal_files(run):
    """No time stamp and no random SVG ids: the same figure drawn twice gives the same bytes in
    every format."""
    _, _, cmp, meta = run
    ctx = FigureContext.from_meta(meta)
    a, b = figure_invariants(cmp, ctx), figure_invariants(cmp, ctx)
    for fmt in FigureFormat:
        assert a.render(fmt) == b.render(fmt), fmt


def test_png_is_the_picture_matplotlib_draws(run):
    """The PNG written as RGB (every pixel opaque) holds exactly the pixels of matplotlib's own
    RGBA ``savefig`` at the same resolution, and records that resolution."""
    from PIL import Image

    _, _, cmp, meta = run
    d = figure_invariants(cmp, FigureContext.from_meta(meta))
    ours = Image.open(io.BytesIO(d.render(FigureFormat.PNG)))
    buf = io.BytesIO()
    with mpl.rc_context(TEXT_RASTER):
        d.figure.savefig(buf, format="png", dpi=PNG_DPI)
    theirs = np.asarray(Image.open(io.BytesIO(buf.getvalue())))
    assert ours.mode == "RGB" and (theirs[..., 3] == 255).all()
    assert np.array_equal(np.asarray(ours), theirs[..., :3])
    # PNG stores whole pixels per metre: within half of one (0.0127 dpi) of the figure's dpi
    assert ours.info["dpi"] == pytest.approx((PNG_DPI, PNG_DPI), abs=0.5 * 0.0254)


def test_figure_formats_are_parsed_and_bad_ones_named():
    assert parse_formats("png, SVG,png") == (FigureFormat.PNG, FigureFormat.SVG)
    with pytest.raises(ValueError, match="figure_format: unknown format 'bmp'"):
        parse_formats("png,bmp")


def test_cli_refuses_a_bad_figure_format_before_any_work(tmp_path, capsys):
    from validation.cli import EXIT_USAGE, main

    out = tmp_path / "v"
    assert main(["validate", "--figure-format", "gif", "--out", str(out)]) == EXIT_USAGE
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "figure_format" in err[0] and "gif" in err[0]
    assert not out.exists()
