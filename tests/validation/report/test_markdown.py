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
