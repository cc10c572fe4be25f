"""Every kind of HTML report, made by a real run, opened in headless Chromium with no network:
its script runs (``<body data-js="ready">``), a table sorts by the URL fragment (numbers as
numbers, descending), and its screenshot shows the verdict banner across the top in its colour.

The runs: ``tumble validate``'s ``report.html`` (three plants: the referee rules), the sweep's
``sweep.html`` (the quick grid), the hard cases' ``hard_cases.html`` (one fast case) and a
fuzzing campaign's ``campaign.html`` (a planted wrong plant: a new finding, FAILED).

Slow (the runs, about two minutes in all); skipped without Chromium (Debian: ``apt-get install
chromium``). The screenshots are left in pytest's temporary directory.
"""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import pytest

from tests.support.fuzz_plants import ShiftedPlant
from tests.support.html_checks import assert_report_page, chromium, open_in_chromium, parse
from validation.report.html_page import Tone

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(chromium() is None, reason="Chromium is not installed"),
]

WINDOW = (1280, 1400)
"""The browser window of the screenshots, px."""

BANNER_BACKGROUND = {
    Tone.PASS: (0xE9, 0xF7, 0xEC),
    Tone.FAIL: (0xFD, 0xEC, 0xEA),
    Tone.STOP: (0xFF, 0xF6, 0xE0),
}
"""The banner's background colour of each tone (``validation/report/html_page.py``'s STYLE)."""


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """Each kind of report, made by a real run: kind -> (its file, its main table's id and the
    numeric column to sort by, the tone its verdict must have)."""
    from validation.studies.fuzz.campaign import SerialExecutor, fuzz
    from validation.studies.hard_cases import case_names, run_hard_cases
    from validation.studies.sweep import run_sweep
    from validation.validate import DEFAULT_SCENE, run_validation

    root = tmp_path_factory.mktemp("reports")
    got = {}
    res = run_validation(
        DEFAULT_SCENE, root / "validate", t_end=1.0, plants="analytic,mujoco,pinocchio"
    )
    got["validate"] = (
        res.files["report.html"],
        "checks",
        3,
        Tone.PASS if res.passed else Tone.FAIL,
    )
    sw = run_sweep(DEFAULT_SCENE, root / "sweep", quick=True)
    got["sweep"] = (sw.files["html"], "runs", 5, None)
    name = case_names(fast_only=True)[0]
    tb = run_hard_cases(root / "hard", names=[name], plants=("analytic", "mujoco"))
    got["hard_cases"] = (
        root / "hard" / "hard_cases.html",
        "checks",
        5,
        Tone.PASS if tb.passed else Tone.FAIL,
    )
    camp = fuzz(
        root / "fuzz",
        budget=2,
        seed=0,
        plants=("analytic", ShiftedPlant()),
        executor=SerialExecutor(),
    )
    got["fuzz"] = (camp.files["html"], "pass-rates", 3, Tone.FAIL)
    return got


def _dom(dom: str):
    """The tree of the DOM Chromium dumped (its serialisation, with or without the doctype)."""
    return parse(dom if dom.lstrip().lower().startswith("<!doctype") else "<!DOCTYPE html>" + dom)


def _column(dom: str, table_id: str, col: int) -> tuple[str | None, list[float]]:
    """The sort state of column ``col`` of table ``table_id`` in the DOM Chromium dumped, and the
    column's values (``data-v``) in row order."""
    doc = _dom(dom)
    [t] = doc.find("table", id=table_id)
    th = t.find("th")[col]
    values = []
    for tr in t.find("tbody")[0].find("tr"):
        v = tr.find("td")[col].attrs.get("data-v", "nan")
        values.append(float(v) if v not in ("nan", "") else math.nan)
    return th.attrs.get("aria-sort"), values


def _first_band(png: bytes, colour: tuple[int, int, int]) -> tuple[int, int]:
    """The topmost row holding pixels of ``colour`` and how many of that row's pixels have it
    (``(-1, 0)`` when none does)."""
    import numpy as np
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    hit = np.all(rgb == np.array(colour, np.uint8), axis=-1)
    rows = np.nonzero(hit.any(axis=1))[0]
    if rows.size == 0:
        return -1, 0
    top = int(rows[0])
    return top, int(hit[top].sum())


@pytest.mark.parametrize("kind", ["validate", "sweep", "hard_cases", "fuzz"])
def test_each_report_renders_sorts_and_shows_its_verdict_first(pages, kind, tmp_path):
    path, table_id, col, tone = pages[kind]
    markup = path.read_text(encoding="utf-8")
    assert_report_page(markup)
    dom = open_in_chromium(path, f"sort={table_id}.{col}.desc")
    assert re.search(r'<body[^>]*data-js="ready"', dom), "the page's script did not run"
    sort, values = _column(dom, table_id, col)
    assert sort == "descending"
    finite = [v for v in values if not math.isnan(v)]
    assert finite == sorted(finite, reverse=True) and len(finite) >= 1
    assert all(math.isnan(v) for v in values[len(finite) :]), "a missing value sorted first"
    shot = tmp_path / f"{kind}.png"
    open_in_chromium(path, screenshot=shot, size=WINDOW)
    png = shot.read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    if tone is None:  # the sweep's tone follows how its runs ended: read it off the page
        cls = parse(markup).find(id="verdict")[0].attrs["class"]
        tone = Tone(cls.split()[-1])
    top, width = _first_band(png, BANNER_BACKGROUND[tone])
    assert top >= 0, f"no {tone.value} banner in the screenshot"
    assert top < WINDOW[1] // 3, "the banner is not at the top"
    assert width > WINDOW[0] // 2, "the first band of the verdict's colour does not span the page"


def test_the_page_script_sorts_text_columns_as_text(pages):
    path, table_id, _col, _tone = pages["validate"]
    dom = open_in_chromium(path, f"sort={table_id}.0.asc")
    doc = _dom(dom)
    [t] = doc.find("table", id=table_id)
    names = [tr.find("td")[0].text() for tr in t.find("tbody")[0].find("tr")]
    assert names == sorted(names, key=str.lower)
    assert Path(path).with_name("run.rrd").is_file()  # the recording the page links
