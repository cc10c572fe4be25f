"""The figures of a run as the report writes them: drawn without warnings, nothing empty, every one
captioned, a figure not drawn named with its reason (:mod:`validation.report.figures`; each figure's
own tests are under ``tests/validation/report/figures/``, on the same planted runs,
:mod:`tests.support.figure_runs`)."""

from __future__ import annotations

import json
import math
import re
import warnings

import pytest

from tests.support.figure_runs import (
    PNG,
    SCENES,
    T_END,
    TORQUE_SCALE,
    controlled,
    masses_only_run,
    planted_run,
)
from validation.report.figures import (
    FigureContext,
    figure_errors,
)
from validation.report.report import write_report


@pytest.fixture(scope="module", params=SCENES)
def run(request):
    """(scene, plants, comparison, meta) of a controlled and of an uncontrolled scene."""
    return planted_run(request.param)


@pytest.fixture(scope="module")
def masses_only():
    """(scene, plants, comparison) of Example 1 with the masses controlled and ω not."""
    return masses_only_run()


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
    expected = {"errors", "invariants"} | ({"tracking", "control"} if controlled(sc) else set())
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
    if controlled(sc):
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
