"""``report.md``'s sections: in the order of :data:`SECTIONS`, each saying nothing it has nothing
for (no comparison: the verdict, the failure, the figures, the thresholds' heading and the run)."""

from __future__ import annotations

from validation.report.markdown import SECTIONS, render_markdown
from validation.report.records import FigureEntry, RunVerdict


def test_a_run_without_a_comparison_says_what_it_has_in_order():
    meta = {"scene": {"name": "s"}, "redone": ["the recording"]}
    figures = [FigureEntry("control", "No plant produced a sample.")]
    md = render_markdown(None, RunVerdict.FAILED, "plant `x` | failed", figures, meta, code="c")
    lines = md.splitlines()
    assert lines[0] == "# s: FAILED"
    assert lines[2] == "**The run failed:** plant \\`x\\` \\| failed"
    assert lines[4] == "**Redone:** the recording"
    heads = [x for x in lines if x.startswith("## ")]
    assert heads == ["## Figures", "## Thresholds", "## Run"]
    assert "*No control figure.* No plant produced a sample." in lines
    assert md.endswith("```\n")


def test_every_section_is_a_function_of_the_page():
    assert len(SECTIONS) == len(set(SECTIONS)) and all(callable(s) for s in SECTIONS)


def test_the_pointwise_check_comes_first_with_its_findings():
    case = {
        "case": "uncontrolled",
        "states": ["the initial state"],
        "vs_mujoco": [3e-2],
        "vs_analytic": [3e-2],
        "mujoco_vs_analytic": [1e-16],
        "bounds": [2e-12],
    }
    finding = {"plant": "mjx", "text": "mjx: q̈ differs from MuJoCo C by 3.0e-02 relative"}
    pw = {
        "states": 1,
        "seed": 0,
        "plants": [{"plant": "mjx", "precision": "float64", "threshold": 2e-12, "cases": [case]}],
        "findings": [finding],
        "not_checked": ["warp: q̈ not checked pointwise: pointwise raised RuntimeError: x"],
    }
    meta = {"scene": {"name": "s"}, "pointwise": pw}
    md = render_markdown(None, RunVerdict.FAILED, "", [], meta)
    heads = [x for x in md.splitlines() if x.startswith("## ")]
    assert heads[0] == "## Pointwise check before the run"
    assert f"- **mjx:** {finding['text']}" in md and "warp: q̈ not checked" in md
    assert "| mjx | float64 | uncontrolled | 3.000e-02 |" in md and "**differs**" in md
    run = md[md.index("## Run") :]
    assert "pointwise" not in run  # stated once, in its section


def test_an_outlier_the_pointwise_check_found_is_explained_by_it():
    from types import SimpleNamespace

    from validation.report.markdown import _outliers_explained

    finding = {
        "plant": "mjx",
        "state": "the initial state",
        "vs_mujoco": 0.1,
        "bound": 2e-12,
        "cause": "springs.cubic",
    }
    meta = {"pointwise": {"findings": [finding]}}
    out = SimpleNamespace(outliers=[SimpleNamespace(plant="mjx")])
    other = SimpleNamespace(outliers=[SimpleNamespace(plant="pinocchio")])
    [line] = _outliers_explained([out, out, other], meta)
    assert line.startswith("why mjx is the outlier (2 quantities): its q̈ already differed")
    assert line.endswith(
        "the models differ, not the integration; the difference is in springs.cubic"
    )
    assert _outliers_explained([out], {}) == []
    case = {"vs_mujoco": [3e-7, 5e-7]}
    agreed = {
        "plants": [{"plant": "mjx", "precision": "float32", "threshold": 1e-3, "cases": [case]}]
    }
    [line] = _outliers_explained([out], {"pointwise": agreed})
    assert "agreed with MuJoCo C's to 5.0e-07 relative at every state" in line
    assert line.endswith(
        "the difference grew in the integration (its float32 arithmetic, its step and scheme)"
    )
