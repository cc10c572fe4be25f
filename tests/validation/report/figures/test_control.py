"""The control figure: the other plant as its distance from the reference; no empty torque panel."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.figure_runs import TORQUE_SCALE, controlled
from validation.report.figures import (
    FigureContext,
    figure_control,
)


def test_control_figure_shows_the_other_plant_as_its_distance(run):
    """A reference panel per force and one panel for the other plant, whose torque curve is the
    planted relative difference: the copy is visible, not hidden under the reference's line."""
    sc, plants, _, meta = run
    drawing = figure_control(plants, FigureContext.from_meta(meta))
    if not controlled(sc):
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
