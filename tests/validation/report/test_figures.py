"""Figures and their captions: drawn without warnings, as checked, nothing empty, every one captioned.

The plants here are the analytic run and a copy labelled MuJoCo with planted differences (C moved
by 5e-9 m, the control torque scaled by 1 + 1e-9), so what each figure draws is known exactly.
"""

from __future__ import annotations

import dataclasses
import io
import itertools
import json
import math
import re
import warnings

import matplotlib as mpl
import numpy as np
import pytest

from analytic.simulate import simulate
from analytic.trajectory import Engine
from validation.compare.checks import compare
from validation.report.figures import (
    PNG_DPI,
    TEXT_RASTER,
    FigureContext,
    FigureFormat,
    figure_control,
    figure_errors,
    figure_invariants,
    figure_tracking,
    parse_formats,
    prepare_drawing,
)
from validation.report.report import write_report
from validation.scenes import resolve_scene

T_END = 0.3
C_OFFSET = 5e-9  # m, planted in the copy's position of C
TORQUE_SCALE = 1e-9  # planted relative error of the copy's control torque
PNG = b"\x89PNG\r\n\x1a\n"


def _copy(tr):
    q = tr.q.copy()
    q[:, 0] += C_OFFSET
    return dataclasses.replace(
        tr, engine=Engine.MUJOCO, q=q, torque=tr.torque * (1.0 + TORQUE_SCALE)
    )


@pytest.fixture(scope="module", params=["paper_example1_controlled", "paper_example1"])
def run(request):
    """(scene, plants, comparison, meta) of a controlled and of an uncontrolled scene."""
    sc = resolve_scene(request.param)
    tr = simulate(sc, t_end=T_END, rtol=1e-10)
    plants = [tr, _copy(tr)]
    meta = {
        "scene": {"name": sc.name, "effects": sorted(e.value for e in sc.effects)},
        "horizon_s": T_END,
        "output_rate_hz": sc.output.rate,
        "plants": [
            {"engine": "analytic", "settings": "analytic DOP853 rtol 1e-10"},
            {"engine": "mujoco", "settings": "a planted copy"},
        ],
    }
    return sc, plants, compare(plants[0], plants[1], sc, t_end=T_END), meta


def _controlled(sc) -> bool:
    return any(e.value.startswith("control.") for e in sc.effects)


def test_figures_are_drawn_without_warnings(run, tmp_path):
    """Every figure, in every format, for a controlled and an uncontrolled scene: no warning
    (a constant series on a log axis, a missing glyph, a layout that does not fit)."""
    sc, plants, cmp, meta = run
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        files = write_report(tmp_path, cmp, plants, meta, formats=("png", "svg", "pdf"))
    doc = json.loads((tmp_path / "report.json").read_text())
    assert "figure_errors" not in doc["run"]
    names = {f.name for f in files.figures}
    expected = {"errors", "invariants"} | ({"tracking", "control"} if _controlled(sc) else set())
    assert names == {f"{n}.{x}" for n in expected for x in ("png", "svg", "pdf")}
    assert (tmp_path / "errors.png").read_bytes().startswith(PNG)
    assert b"<svg" in (tmp_path / "errors.svg").read_bytes()[:400]
    assert (tmp_path / "errors.pdf").read_bytes().startswith(b"%PDF")


def test_every_referenced_figure_has_a_caption(run, tmp_path):
    """report.md: each embedded figure is followed by its numbered caption naming the file,
    the solver settings and the horizon; every other format is linked from the caption."""
    _, plants, cmp, meta = run
    write_report(tmp_path, cmp, plants, meta, formats=("png", "svg"))
    md = (tmp_path / "report.md").read_text()
    lines = md.splitlines()
    embedded = [
        (i, m.group(1)) for i, x in enumerate(lines) if (m := re.match(r"!\[.*\]\((.+)\)$", x))
    ]
    assert embedded
    for number, (i, name) in enumerate(embedded, 1):
        caption = next(x for x in lines[i + 1 :] if x.strip())
        assert caption.startswith(f"*Figure {number} (`{name}`).*"), caption
        assert "DOP853 rtol 1e-10" in caption and f"Horizon {T_END:g} s" in caption
        assert f"[{name.replace('.png', '.svg')}]" in caption
        assert (tmp_path / name).exists()
    doc = json.loads((tmp_path / "report.json").read_text())
    assert set(doc["captions"]) == {"errors", "tracking", "invariants", "control"}


def test_uncontrolled_scene_has_no_control_figure_and_says_why(run, tmp_path):
    sc, plants, cmp, meta = run
    if _controlled(sc):
        pytest.skip("the controlled scene has a control figure")
    files = write_report(tmp_path, cmp, plants, meta)
    assert not (tmp_path / "control.png").exists() and not (tmp_path / "tracking.png").exists()
    md = (tmp_path / "report.md").read_text()
    assert "*No control figure.* The scene has no control requirement" in md
    assert "*No tracking figure.* The scene has no control requirement" in md
    errors = next(e for e in files.entries if e.name == "errors")
    assert "Left out: control torque, rod forces (the scene has no control requirement" in (
        errors.caption
    )
    # no empty panel: the errors figure has one panel per quantity that is not identically zero
    drawing = figure_errors(cmp, FigureContext.from_meta(meta))
    titles = [ax.get_title(loc="left") for ax in drawing.figure.axes]
    assert not any(t.startswith(("control torque", "rod forces")) for t in titles)


def test_errors_are_drawn_as_checked_with_their_thresholds(run):
    """The planted offset of C is the position panel's curve; the torque panel draws the relative
    difference (the planted 1e-9), at the level its check reports, under its threshold line."""
    sc, _, cmp, meta = run
    fig = figure_errors(cmp, FigureContext.from_meta(meta)).figure
    by_title = {ax.get_title(loc="left").split(":")[0]: ax for ax in fig.axes}
    pos = by_title["position of C"]
    curve, threshold = pos.lines[0].get_ydata(), pos.lines[-1].get_ydata()
    assert np.nanmax(curve) == pytest.approx(C_OFFSET, rel=1e-6)
    assert threshold[0] == cmp.thresholds["position_C"].value
    if _controlled(sc):
        tq = by_title["control torque"]
        drawn = np.nanmax(tq.lines[0].get_ydata())
        assert drawn == pytest.approx(cmp.check("control_torque").value, rel=1e-12)
        assert drawn == pytest.approx(TORQUE_SCALE, rel=1e-3)
        assert tq.lines[-1].get_ydata()[0] == cmp.thresholds["control_torque"].value


def test_invariants_are_drawn_relative_with_their_thresholds(run):
    """Each relative balance is drawn divided by its scale: the curve's maximum is the check's
    value, and the threshold line is the relative threshold of validation/compare/thresholds.py."""
    _, _, cmp, meta = run
    fig = figure_invariants(cmp, FigureContext.from_meta(meta)).figure
    names = ("quat_norm", "linear_momentum", "angular_momentum", "energy")
    assert len(fig.axes) == len(names)
    for ax, name in zip(fig.axes, names, strict=True):
        check = cmp.check(f"analytic.{name}")
        th = cmp.thresholds[name]
        assert th.relative == (name != "quat_norm")
        assert np.nanmax(ax.lines[0].get_ydata()) == pytest.approx(check.value, rel=1e-12)
        assert ax.lines[-1].get_ydata()[0] == th.value
        assert ("relative" in ax.get_ylabel()) == th.relative


def test_control_figure_shows_the_other_plant_as_its_distance(run):
    """A reference panel per force and one panel for the other plant, whose torque curve is the
    planted relative difference: the copy is visible, not hidden under the reference's line."""
    sc, plants, _, meta = run
    drawing = figure_control(plants, FigureContext.from_meta(meta))
    if not _controlled(sc):
        assert not drawing.drawn and "no control requirement" in drawing.caption
        return
    axes = drawing.figure.axes
    assert len(axes) == 4  # torque, rod forces, mujoco − analytic: torque, rod forces
    assert "GN·m" in axes[0].get_ylabel() and "MN" in axes[1].get_ylabel()
    diff = axes[2]
    assert diff.get_yscale() == "log" and "mujoco − analytic" in diff.get_title(loc="left")
    # the torque distance has its panel to itself: no rod-force curve drawn over it
    curves = [ln for ln in diff.lines if ln.get_label() != "threshold"]
    assert [ln.get_label() for ln in curves] == ["‖Δτ‖₂ / max‖τ‖₂"]
    assert np.nanmax(curves[0].get_ydata()) == pytest.approx(TORQUE_SCALE, rel=1e-3)
    assert all("ΔF" in ln.get_label() for ln in axes[3].lines if ln.get_label() != "threshold")
    for ax in axes:  # legends stand outside the data, to the right of the panel
        legend = ax.get_legend()
        right_edge = ax.transAxes.transform((1.0, 1.0))[0]
        assert legend is not None and legend.get_bbox_to_anchor().x0 > right_edge


@pytest.fixture(scope="module")
def drawn(run):
    """Every figure drawn for the run (as its PNG is: Agg at the figure's dpi), with the renderer
    that drew it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    _, plants, cmp, meta = run
    ctx = FigureContext.from_meta(meta)
    drawings = (
        figure_errors(cmp, ctx),
        figure_tracking(cmp, ctx),
        figure_invariants(cmp, ctx),
        figure_control(plants, ctx, cmp.thresholds),
    )
    out = []
    for d in drawings:
        if d.drawn:
            canvas = FigureCanvasAgg(d.figure)
            canvas.draw()
            out.append((d, canvas.get_renderer()))
    return out


PX = 0.5  # px: rounding of text extents


def _inside(box, page) -> bool:
    return (
        box.x0 >= page.x0 - PX
        and box.x1 <= page.x1 + PX
        and box.y0 >= page.y0 - PX
        and box.y1 <= page.y1 + PX
    )


def _apart(a, b) -> bool:
    return a.x1 <= b.x0 + PX or b.x1 <= a.x0 + PX or a.y1 <= b.y0 + PX or b.y1 <= a.y0 + PX


def test_nothing_is_clipped_or_overlapping(drawn):
    """The layout is fixed in inches, not searched for: every panel with its title, tick labels
    and axis labels lies inside the figure, below the figure's title and clear of the panels next
    to it; every legend lies inside the figure and outside every panel's data area."""
    for d, renderer in drawn:
        fig, page = d.figure, d.figure.bbox
        panels = [ax.get_tightbbox(renderer) for ax in fig.axes]  # with title, labels, legend
        for ax, box in zip(fig.axes, panels, strict=True):
            assert _inside(box, page), (d.name, ax.get_title(loc="left"))
        for upper, lower in itertools.pairwise(panels):
            assert lower.y1 <= upper.y0 + PX, d.name
        title = next(
            t
            for t in fig.get_children()
            if getattr(t, "get_text", None) and t.get_text() == fig.get_suptitle()
        ).get_window_extent(renderer)
        assert _inside(title, page) and panels[0].y1 <= title.y0 + PX, d.name
        legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
        assert legends, d.name
        for legend in legends:
            box = legend.get_window_extent(renderer)
            assert _inside(box, page), d.name
            assert all(_apart(box, ax.bbox) for ax in fig.axes), d.name
        for legend in fig.legends:  # below the panels, their tick and axis labels
            assert legend.get_window_extent(renderer).y1 <= panels[-1].y0 + PX, d.name


def test_every_panel_shows_its_curves_and_thresholds_whole(drawn):
    """Each panel's y limits enclose every curve it draws and its threshold lines (a log panel's
    limits are set from them, not autoscaled)."""
    for d, _ in drawn:
        for ax in d.figure.axes:
            lo, hi = ax.get_ylim()
            for line in ax.lines:
                y = np.asarray(line.get_ydata(), float)
                y = y[np.isfinite(y) & ((y > 0) if ax.get_yscale() == "log" else True)]
                if line.get_label() == "threshold" or ax.get_yscale() == "log":
                    assert y.size, (d.name, line.get_label())
                if y.size:
                    assert lo <= y.min() and y.max() <= hi, (d.name, line.get_label())


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


def test_preparing_the_drawing_changes_no_figure(run):
    """The throw-away figure drawn to load fonts and caches before the evidence workers fork
    leaves no setting behind: a figure renders to the same bytes before and after it."""
    _, _, cmp, meta = run
    ctx = FigureContext.from_meta(meta)
    before = figure_invariants(cmp, ctx).render(FigureFormat.PNG)
    prepare_drawing()
    assert figure_invariants(cmp, ctx).render(FigureFormat.PNG) == before


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


@pytest.fixture(scope="module")
def masses_only():
    """(scene, plants, comparison) of Example 1 with the masses controlled and ω not: no control
    torque in either plant, rod forces in both (the copy's forces scaled by 1 + 1e-9)."""
    from analytic.effects import Effect

    sc = resolve_scene("paper_example1_controlled")
    sc = sc.with_effects(sc.effects - {Effect.CONTROL_OMEGA})
    tr = simulate(sc, t_end=T_END, rtol=1e-10)
    copy = dataclasses.replace(_copy(tr), rod_forces=tr.rod_forces * (1.0 + TORQUE_SCALE))
    return sc, [tr, copy], compare(tr, copy, sc, t_end=T_END)


def test_a_scene_without_torque_control_draws_no_torque_panel(masses_only):
    """No empty τ panel: the rod forces and their distance only, and the caption says why."""
    _, plants, cmp = masses_only
    assert not any(np.any(p.torque) for p in plants)
    drawing = figure_control(plants, FigureContext(plants[0].scene), cmp.thresholds)
    titles = [ax.get_title(loc="left") for ax in drawing.figure.axes]
    assert len(titles) == 2 and not any("torque" in t for t in titles), titles
    assert "neither plant applies one" in drawing.caption
    for ax in drawing.figure.axes:
        assert any(np.any(np.nan_to_num(np.asarray(l.get_ydata(), float))) for l in ax.lines)


def test_a_check_that_does_not_apply_says_so(masses_only, tmp_path):
    """The control_torque check of a scene without torque control is NOT_APPLICABLE in the record,
    report.json and report.md, never a pass with value 0."""
    from validation.compare.checks import CheckState
    from validation.compare.summary import check_sentence

    sc, plants, cmp = masses_only
    (check,) = [c for c in cmp.checks if c.name == "control_torque"]
    assert check.state is CheckState.NOT_APPLICABLE and not check.applicable
    assert math.isnan(check.value)
    assert "not applicable" in check_sentence(check)
    (rod,) = [c for c in cmp.checks if c.name == "rod_forces"]
    assert rod.state is CheckState.PASS and rod.value == pytest.approx(TORQUE_SCALE, rel=1e-3)
    files = write_report(tmp_path, cmp, plants, {"scene": {"name": sc.name}})
    doc = json.loads(files.json.read_text())
    (js,) = [c for c in doc["checks"] if c["name"] == "control_torque"]
    assert js["verdict"] == "not applicable" and js["applicable"] is False
    assert js["value"] is None and js["t_max"] is None
    md = files.markdown.read_text()
    row = next(ln for ln in md.splitlines() if ln.startswith("| control_torque |"))
    assert "not applicable" in row and "pass" not in row
    assert "Not applicable: control\\_torque" in md or "Not applicable: control_torque" in md
    applicable = len(cmp.applicable_checks)
    assert f"{applicable} of {applicable} checks pass." in md
