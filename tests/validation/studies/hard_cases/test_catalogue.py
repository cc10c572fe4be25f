"""The catalogue of measures: ``docs/hard_cases.md`` lists every entry a scene file may name."""

from __future__ import annotations

from pathlib import Path

from validation.studies.hard_cases.catalogue import IMPLICIT, MEASURES


def test_docs_list_every_measure():
    """``docs/hard_cases.md`` documents every (reference, measure) a scene file may name."""
    doc = (Path(__file__).resolve().parents[4] / "docs" / "hard_cases.md").read_text("utf-8")
    for (m, r), info in MEASURES.items():
        if (m, r) not in IMPLICIT:
            assert f"| `{r.value}` | `{m.value}` | {info.unit} |" in doc, (r, m)
