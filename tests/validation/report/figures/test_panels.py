"""The panels: log ticks naming their decades inside the view; the throw-away figure changing no figure."""

from __future__ import annotations

import re

import pytest

from validation.report.figures import (
    FigureContext,
    FigureFormat,
    figure_invariants,
    prepare_drawing,
)

_SUPERSCRIPT_DIGITS = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def test_log_ticks_name_their_decades_inside_the_view(drawn):
    """Every log panel labels at least one tick; each label, ``10⁻¹²`` in plain text, names the
    power of ten it stands at, and every tick lies inside the panel's limits."""
    for d, _ in drawn:
        for ax in d.figure.axes:
            if ax.get_yscale() != "log":
                continue
            lo, hi = ax.get_ylim()
            locs = ax.yaxis.get_majorticklocs()
            labels = ax.yaxis.get_major_formatter().format_ticks(locs)
            assert len(locs) >= 1, d.name
            for loc, text in zip(locs, labels, strict=True):
                m = re.fullmatch("10([⁻]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)", text)
                assert m, (d.name, text)
                assert loc == pytest.approx(10.0 ** int(m.group(1).translate(_SUPERSCRIPT_DIGITS)))
                assert lo <= loc <= hi, (d.name, text)


def test_preparing_the_drawing_changes_no_figure(run):
    """The throw-away figure drawn to load fonts and caches before the evidence workers fork
    leaves no setting behind: a figure renders to the same bytes before and after it."""
    _, _, cmp, meta = run
    ctx = FigureContext.from_meta(meta)
    before = figure_invariants(cmp, ctx).render(FigureFormat.PNG)
    prepare_drawing()
    assert figure_invariants(cmp, ctx).render(FigureFormat.PNG) == before
