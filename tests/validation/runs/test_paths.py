"""Default output paths and run ids (``validation/runs/paths.py``), and the split of
:mod:`validation.runs.outputs` into modules of one job each, every public name still found there."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from validation.runs import locks, manifest, outputs, paths, staging


@pytest.mark.parametrize("part", [paths, manifest, locks, staging])
def test_outputs_keeps_every_public_name_of_its_parts(part):
    """Importers of ``validation.runs.outputs`` keep working: each name its parts export that
    outputs exported before the split is the very same object there."""
    for name in set(part.__all__) & set(outputs.__all__):
        assert getattr(outputs, name) is getattr(part, name), name


def test_outputs_public_names_are_unchanged():
    assert set(outputs.__all__) == {
        "DEFAULT_ROOT", "KNOWN_OUTPUT_NAMES", "MANIFEST", "MANIFEST_SCHEMA", "RUN_ID_PATTERN",
        "SLUG_MAX_LEN", "STAGING_MARKER", "CommitMode", "ManifestEntry", "NotOurs", "OutputBusy",
        "OutputRun", "Owned", "RunState", "default_out_dir", "default_out_file", "new_run_id",
        "output_run", "parse_manifest", "prove_owned", "slug",
    }  # fmt: skip


def test_a_run_id_is_utc_time_and_eight_hex_digits():
    rid = paths.new_run_id()
    assert re.fullmatch(r"\d{8}T\d{6}Z-[0-9a-f]{8}", rid) and paths.is_run_id(rid)
    for bad in (None, 20240101, "20240101T000000Z-0123abc", "20240101T000000Z-0123abcd\n", ""):
        assert not paths.is_run_id(bad)


def test_default_paths_stay_under_out():
    assert paths.default_out_dir("validate_", "../../etc") == Path("out") / "validate_etc"
    assert paths.default_out_file("a b/c", ".xml") == Path("out") / "a_b_c.xml"
