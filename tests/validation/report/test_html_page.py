"""The pieces of every HTML report: well-formed, self-contained (the checker finds any external
reference), values escaped, numbers readable and sorted by their exact values."""

from __future__ import annotations

import base64
import hashlib
import math

import pytest

from tests.support.html_checks import assert_report_page, external_references, parse, rows
from validation.report.html_page import (
    CSP,
    SCRIPT,
    STYLE,
    Banner,
    Column,
    Row,
    Tone,
    figure,
    num,
    page,
    readable,
    recording,
    relative_link,
    section,
    state,
    table,
    text,
)

HOSTILE = '<script>alert("x")</script> & <img src="http://example.com/t.png">'
PNG = b"\x89PNG\r\n\x1a\n" + b"\0" * 16


def _page(*body: str, banner: Banner | None = None) -> str:
    return page(HOSTILE, banner or Banner("FAILED", Tone.FAIL, [HOSTILE], [HOSTILE]), body)


def test_numbers_are_readable_and_the_exact_value_is_kept():
    assert readable(2.645e-13) == "2.6e-13"
    assert readable(0.0123) == "0.0123"
    assert readable(12.34) == "12.3"
    assert readable(0) == "0" and readable(42) == "42"
    assert readable(math.nan) == "–" and readable(None) == "–" and readable(math.inf) == "∞"
    c = num(2.645e-13, "m")
    assert c.key == 2.645e-13 and c.title == "2.645e-13 m" and c.text == "2.6e-13"
    assert num(math.nan).key != num(math.nan).key  # NaN: sorted last by the script, not equal


def test_hostile_text_is_text_everywhere():
    markup = _page(
        section(HOSTILE, table("t", [Column(HOSTILE)], [[text(HOSTILE)]])),
    )
    doc = assert_report_page(markup)
    assert len(doc.find("script")) == 1  # the page's own, nothing from the text
    assert doc.find("img") == []
    assert rows(doc, "t") == [[HOSTILE]]
    assert doc.find("title")[0].text() == HOSTILE
    assert HOSTILE in doc.find(id="verdict")[0].text()


def test_a_page_is_self_contained_and_its_policy_admits_only_itself():
    markup = _page(figure("f", PNG, "png", "cap"), recording("run.rrd"))
    doc = assert_report_page(markup)
    [img] = doc.find("img")
    assert img.attrs["src"] == "data:image/png;base64," + base64.b64encode(PNG).decode()
    [style] = doc.find("style")
    [script] = doc.find("script")
    assert style.text() == STYLE and script.text() == SCRIPT
    for body in (STYLE, SCRIPT):
        digest = base64.b64encode(hashlib.sha256(body.encode()).digest()).decode()
        assert f"'sha256-{digest}'" in CSP
    links = [a.attrs["href"] for a in doc.find("a")]
    assert links == ["run.rrd"]
    assert "rerun run.rrd" in doc.text()


@pytest.mark.parametrize(
    "tag",
    [
        '<img src="https://example.com/x.png">',
        '<script src="http://cdn.example.com/x.js"></script>',
        '<link rel="stylesheet" href="x.css">',
        '<a href="//example.com/">x</a>',
        '<div style="background:url(x.png)"></div>',
        "<style>@import 'x.css';</style>",
    ],
)
def test_the_checker_finds_every_external_reference(tag):
    markup = _page(tag)
    assert external_references(parse(markup)) != []


def test_links_are_only_relative():
    assert relative_link("counterexamples/a.toml").startswith('<a href="counterexamples/a.toml"')
    for bad in ("http://example.com/x", "/etc/passwd", "../x", "a/../../x"):
        with pytest.raises(ValueError, match="name"):
            relative_link(bad)


def test_tables_refuse_ragged_rows_and_bad_ids():
    with pytest.raises(ValueError, match="2 cells under 1 columns"):
        table("t", ["a"], [[text(1), text(2)]])
    with pytest.raises(ValueError, match="table_id"):
        table("a b", ["a"], [])


def test_a_row_and_a_cell_carry_their_tone():
    markup = _page(table("t", ["v"], [Row([state("FAIL", Tone.FAIL)], Tone.FAIL.value)]))
    doc = parse(markup)
    [tr] = doc.find("table")[0].find("tbody")[0].find("tr")
    assert tr.attrs["class"] == "fail" and tr.find("td")[0].attrs["class"] == "state fail"


def test_a_figure_format_that_cannot_be_embedded_is_refused():
    with pytest.raises(ValueError, match="suffix"):
        figure("f", b"%PDF", "pdf", "")
