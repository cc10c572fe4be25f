"""``campaign.html``: a new finding fails the campaign first, with the plant the referee blames;
every counterexample in the sortable table with its section, cause, minimal scene (a relative
link) and reproduce command; every string text."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from tests.support.html_checks import assert_report_page, parse, rows
from validation.studies.fuzz.html_report import FINDING_COLUMNS, campaign_html

HOSTILE = "<script>alert(1)</script>"
PNG = b"\x89PNG\r\n\x1a\n" + b"\0" * 16


def _finding(key: str, known: str = "", settlement=None, outlier: str = "shifted") -> dict:
    return {
        "key": key,
        "kind": "check",
        "what": "position_C",
        "plant": outlier,
        "known": known,
        "file": f"counterexamples/{key.replace(':', '_')}.toml",
        "found_in": 0,
        "occurrences": 2,
        "evaluations": 30,
        "horizon": 0.05,
        "drivers": {"spin": 0.5, "mass_ratio": 1.0, "stiffness": 0.0, "n": 0},
        "verdicts": [
            {"quantity": "position_C", "verdict": "outlier", "outlier": outlier},
            {"quantity": "attitude", "verdict": "agree", "outlier": ""},
        ],
        "command": f"tumble validate counterexamples/{key}.toml --plants analytic,{outlier}",
        "settlement": settlement,
    }


def _campaign(new: bool = True, complete: bool = True):
    settings = {
        "cause": "settings",
        "text": "gone at tightened settings " + HOSTILE,
        "culprit": "mujoco",
    }
    findings = [_finding("check:rod_positions", settlement=settings, outlier="mujoco")]
    findings.append(_finding("check:energy", known="a known one " + HOSTILE))
    if new:
        findings.insert(0, _finding("check:position_C" + HOSTILE, outlier="shifted" + HOSTILE))
    doc = {
        "scenes_per_plant": {"analytic": 2, "shifted": 2},
        "with_disagreement": 2,
        "refused": {"mujoco": {"a reason " + HOSTILE: 1}},
        "timeouts": {},
        "pass_rates": {"position_C": {"run": 2, "passed": 0}, "attitude": {"run": 2, "passed": 2}},
        "counterexamples": findings,
    }
    config = SimpleNamespace(seed=0, plants=("analytic", "shifted"), horizon=0.5)
    res = SimpleNamespace(
        config=config, scenes=(1, 2), wall_s=3.2, complete=complete, out_dir=Path(".")
    )
    return res, doc


def test_a_new_finding_fails_the_campaign_first_naming_the_plant_blamed():
    res, doc = _campaign()
    markup = campaign_html(res, doc, PNG)
    assert HOSTILE not in markup
    page = assert_report_page(markup)
    banner = page.find(id="verdict")[0]
    assert banner.attrs["class"] == "banner fail"
    said = banner.text()
    assert said.startswith("FAILED") and "1 new findings" in said
    assert (
        f"check:position_C{HOSTILE}: blamed shifted{HOSTILE}; referee: position_C: outlier "
        f"shifted{HOSTILE}; in 2 scene(s); cause unsettled" in said
    )


def test_every_counterexample_is_in_the_table_with_its_cause_and_scene():
    res, doc = _campaign()
    page = parse(campaign_html(res, doc, PNG))
    got = rows(page, "findings")
    assert len(got) == 3 and len(got[0]) == len(FINDING_COLUMNS)
    by = {r[0]: r for r in got}
    limit = by["check:rod_positions"]
    assert limit[1] == "Numerical limits of the settings" and limit[2] == "mujoco"
    assert limit[3] == "position_C: outlier mujoco" and limit[4] == "settings"
    details = page.find("ul", **{"class": "details"})[0].text()
    assert f"Cause settings: gone at tightened settings {HOSTILE}." in details
    assert by[f"check:energy (a known one {HOSTILE})"][1] == "Known findings"
    hrefs = [a.attrs["href"] for a in page.find("a")]
    assert hrefs == [e["file"] for e in doc["counterexamples"]]
    assert [c.text() for c in page.find("code")][1].startswith("tumble validate")
    assert page.find("img")[0].attrs["src"].startswith("data:image/png;base64,")
    rates = {r[0]: r for r in rows(page, "pass-rates")}
    assert rates["position_C"][1:] == ["0", "2", "0"]


def test_without_a_referee_the_table_says_why():
    res, doc = _campaign()
    doc["counterexamples"][0]["verdicts"] = []
    doc["counterexamples"][0]["plant"] = ""
    row = rows(parse(campaign_html(res, doc, None)), "findings")[0]
    assert row[2:4] == ["none named", "no ruling (the referee rules on three plants or more)"]


def test_no_new_finding_passes_and_an_interrupted_campaign_says_so():
    res, doc = _campaign(new=False)
    assert parse(campaign_html(res, doc, None)).find(id="verdict")[0].text().startswith("PASSED")
    res, doc = _campaign(new=False, complete=False)
    banner = assert_report_page(campaign_html(res, doc, None)).find(id="verdict")[0]
    assert banner.text().startswith("INTERRUPTED") and banner.attrs["class"] == "banner stop"
