"""What ``tumble fuzz``'s output directory and options survive: a user's directory or a link as
``--out``, records forged, edited, truncated, linked or replaced by FIFOs before a resume, two
campaigns at once, a Dask worker count or scheduler that cannot work.

The rule is :mod:`validation.studies.fuzz.directory`'s: a campaign writes only into a directory
its ``manifest.json`` proves its own, reads back only what that manifest lists unchanged, never
opens a link or a FIFO, and refuses in one line (exit 2) before any work.

Read as a table: each test's docstring is "<fault> -> <what the tool does>".
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.trees import tree as _tree
from validation.cli import EXIT_USAGE, main
from validation.runs.atomic import OutputError
from validation.studies.fuzz import campaign as campaign_mod
from validation.studies.fuzz.campaign import SerialExecutor, fuzz
from validation.studies.fuzz.directory import open_campaign
from validation.studies.fuzz.judge import Disagreement, Kind

pytestmark = pytest.mark.faults

PLANTS = ("analytic", "pinocchio")
HORIZON = 0.05
ARGS = ["fuzz", "--plants", ",".join(PLANTS), "--horizon", str(HORIZON), "--budget", "1"]
CONFIG = {"seed": 0, "plants": list(PLANTS), "horizon": HORIZON}
RECORD = "scenes/000000.json"
USERS = {"notes.txt": b"my notes\n", "campaign.md": b"# my own campaign plan\n"}


@pytest.fixture(scope="module")
def judged(tmp_path_factory) -> Path:
    """A finished campaign of one scene (the two plants agree on it), made once."""
    out = tmp_path_factory.mktemp("fuzz") / "campaign"
    fuzz(out, budget=1, seed=0, plants=PLANTS, horizon=HORIZON, executor=SerialExecutor())
    return out


@pytest.fixture
def campaign(judged, tmp_path) -> Path:
    """A copy of :func:`judged` of this test's own."""
    out = tmp_path / "campaign"
    shutil.copytree(judged, out, symlinks=True)
    return out


def _one_line_error(err: str, *words: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("tumble: error: "), err
    assert "Traceback" not in err
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


def _resume_cli(out: Path, capsys, *extra: str) -> tuple[int, str]:
    rc = main([*ARGS, "--out", str(out), *extra])
    return rc, capsys.readouterr().err


def _resume_subprocess(out: Path) -> subprocess.CompletedProcess:
    """The resume as a user runs it, in its own process: a FIFO that blocked would hang it."""
    return subprocess.run(
        [sys.executable, "-m", "validation", *ARGS, "--out", str(out)],
        capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL,
    )


def test_fuzz_out_holding_a_users_files_is_refused_and_left_untouched(tmp_path, capsys):
    """--out naming a user's directory holding notes.txt and their own campaign.md -> exit 2 before any plant runs, one line naming an entry; nothing there is replaced or added."""
    mine = tmp_path / "mine"
    mine.mkdir()
    for name, data in USERS.items():
        (mine / name).write_bytes(data)
    before = _tree(mine)
    rc, err = _resume_cli(mine, capsys)
    assert rc == EXIT_USAGE
    _one_line_error(err, str(mine), "no tumble campaign wrote")
    assert _tree(mine) == before
    assert sorted(os.listdir(tmp_path)) == ["mine"]  # no lock or anything else left beside it


def test_fuzz_out_a_link_to_a_users_directory_is_refused(tmp_path, capsys):
    """--out naming a symbolic link to a user's directory -> exit 2, one line saying it is a link; nothing written through it."""
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "notes.txt").write_bytes(USERS["notes.txt"])
    link = tmp_path / "link"
    link.symlink_to(theirs)
    rc, err = _resume_cli(link, capsys)
    assert rc == EXIT_USAGE
    _one_line_error(err, "symbolic link")
    assert _tree(theirs) == {"notes.txt": USERS["notes.txt"]}


def test_a_campaign_directory_from_before_manifests_is_refused(tmp_path, capsys):
    """--out holding an older campaign (campaign_config.json, scenes/, no manifest.json) -> exit 2, one line: it cannot prove it is one; left as it is."""
    old = tmp_path / "old"
    (old / "scenes").mkdir(parents=True)
    (old / "campaign_config.json").write_text(json.dumps(CONFIG))
    before = _tree(old)
    rc, err = _resume_cli(old, capsys)
    assert rc == EXIT_USAGE
    _one_line_error(err, "cannot prove")
    assert _tree(old) == before


def test_a_forged_scene_record_is_refused_on_resume_not_reported(campaign, capsys):
    """A resumed campaign whose scenes/000000.json was rewritten to claim a disagreement -> exit 2, one line naming the file (its SHA-256 is not the one the campaign wrote); no finding, nothing written."""
    rec = campaign / RECORD
    doc = json.loads(rec.read_text())
    assert doc["disagreements"] == []  # the two plants agreed on this scene
    doc["disagreements"] = [Disagreement(Kind.CHECK, "position_C").to_dict()]
    rec.write_text(json.dumps(doc, indent=2) + "\n")
    before = _tree(campaign)
    rc, err = _resume_cli(campaign, capsys)
    assert rc == EXIT_USAGE
    _one_line_error(err, str(rec), "changed after the campaign wrote it")
    assert _tree(campaign) == before  # no counterexample, no report


@pytest.mark.parametrize("edit", ["empty object", "symbolic link"])
def test_an_edited_or_linked_record_is_one_line_naming_it(campaign, tmp_path, capsys, edit):
    """A resumed campaign's scenes/000000.json edited to {} or replaced by a symbolic link to a copy -> exit 2, one line naming the file, no KeyError traceback; nothing written."""
    rec = campaign / RECORD
    if edit == "empty object":
        rec.write_text("{}")
    else:
        copy = tmp_path / "copy.json"
        copy.write_bytes(rec.read_bytes())
        rec.unlink()
        rec.symlink_to(copy)
    before = _tree(campaign)
    rc, err = _resume_cli(campaign, capsys)
    assert rc == EXIT_USAGE
    _one_line_error(err, str(rec))
    assert "KeyError" not in err
    assert _tree(campaign) == before


def test_a_truncated_campaign_config_is_one_line_naming_it(campaign, capsys):
    """A resumed campaign whose campaign_config.json was truncated -> exit 2, one line naming that file (not a bare JSON error)."""
    cfg = campaign / "campaign_config.json"
    cfg.write_bytes(cfg.read_bytes()[:10])
    rc, err = _resume_cli(campaign, capsys)
    assert rc == EXIT_USAGE
    _one_line_error(err, str(cfg))


@pytest.mark.parametrize("where", [RECORD, "campaign_config.json"])
def test_a_fifo_in_a_resumed_campaign_does_not_block(campaign, where):
    """A FIFO (no writer) at scenes/000000.json or campaign_config.json of a resumed campaign -> refused at once, exit 2, one line naming it; the FIFO is never opened."""
    path = campaign / where
    path.unlink()
    os.mkfifo(path)
    r = _resume_subprocess(campaign)
    assert r.returncode == EXIT_USAGE, r.stderr
    _one_line_error(r.stderr, str(path), "FIFO")
    assert path.is_fifo()


def test_a_deleted_record_is_judged_again(campaign, monkeypatch):
    """A resumed campaign whose scenes/000000.json was deleted (the way out a refusal names) -> that scene is judged again and written; the resume completes."""
    (campaign / RECORD).unlink()
    calls = []
    real = campaign_mod.scene_plant_task
    monkeypatch.setattr(campaign_mod, "scene_plant_task", lambda *a: calls.append(a[1]) or real(*a))
    res = fuzz(campaign, budget=1, seed=0, plants=PLANTS, horizon=HORIZON, executor=SerialExecutor())
    assert set(calls) == {0} and res.complete and len(res.scenes) == 1
    assert (campaign / RECORD).is_file()
    assert json.loads((campaign / "manifest.json").read_text())["state"] == "complete"


def test_two_campaigns_into_one_out_at_once_are_refused(campaign, capsys):
    """A second campaign into an --out a running campaign holds -> exit 2, one line saying another run is writing there; the running one's files untouched."""
    with open_campaign(campaign, CONFIG):
        before = _tree(campaign)
        rc, err = _resume_cli(campaign, capsys)
        assert _tree(campaign) == before
    assert rc == EXIT_USAGE
    _one_line_error(err, "another tumble run")


def test_a_file_put_where_the_campaign_writes_is_not_replaced(tmp_path):
    """A user's file put at a path the campaign writes (campaign.md) while it runs -> the write is refused naming it (OutputError), the user's file is left as it was."""
    out = tmp_path / "c"
    with pytest.raises(OutputError, match="not the file this campaign wrote"):
        with open_campaign(out, CONFIG) as cd:
            (out / "campaign.md").write_bytes(USERS["campaign.md"])
            cd.write("campaign.md", b"# report\n")
    assert (out / "campaign.md").read_bytes() == USERS["campaign.md"]
    assert json.loads((out / "manifest.json").read_text())["state"] == "failed"


@pytest.mark.parametrize("command", ["fuzz", "sweep"])
def test_a_thousand_dask_workers_are_refused_up_front(tmp_path, capsys, command):
    """--dask-workers 1000 on a small machine (fuzz, sweep) -> exit 2 at once, one line naming dask_workers, the value and the bound; nothing created."""
    out = tmp_path / "out"
    args = (
        [*ARGS, "--out", str(out)]
        if command == "fuzz"
        else ["sweep", "paper_example1", "--quick", "--out", str(out)]
    )
    rc = main([*args, "--dask-workers", "1000"])
    err = capsys.readouterr().err
    assert rc == EXIT_USAGE
    _one_line_error(err, "dask_workers", "1000", "at most")
    assert not out.exists()


def _silent_listener() -> socket.socket:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(4)
    return s


@pytest.mark.parametrize("kind", ["nothing there", "listens, says nothing"])
def test_a_scheduler_that_is_not_there_is_refused_before_anything_is_written(tmp_path, capsys, kind):
    """--scheduler at a closed port (tcp://127.0.0.1:9), or at a port that listens but is no Dask scheduler -> exit 2 within seconds (not after Dask's 30 s), one line naming the address; no campaign directory."""
    out = tmp_path / "out"
    listener = _silent_listener() if kind != "nothing there" else None
    address = (
        "tcp://127.0.0.1:9" if listener is None else f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    )
    try:
        t0 = time.monotonic()
        rc, err = _resume_cli(out, capsys, "--scheduler", address)
        took = time.monotonic() - t0
    finally:
        if listener is not None:
            listener.close()
    assert rc == EXIT_USAGE
    _one_line_error(err, address, "scheduler")
    assert took < 20.0  # the probe's 5 s and slack on a busy machine; Dask alone took 31 s
    assert not out.exists()
    assert sorted(os.listdir(tmp_path)) == []


def test_an_interrupted_campaign_is_marked_so_and_resumes(campaign, monkeypatch):
    """Ctrl-C (KeyboardInterrupt) while a campaign judges its second scene -> the manifest says interrupted and lists the first scene's record; the next run resumes it without judging that scene again."""
    real = campaign_mod.scene_plant_task

    def interrupted(*a):
        if a[1] == 1:
            raise KeyboardInterrupt
        return real(*a)

    monkeypatch.setattr(campaign_mod, "scene_plant_task", interrupted)
    with pytest.raises(KeyboardInterrupt):
        fuzz(campaign, budget=2, seed=0, plants=PLANTS, horizon=HORIZON, executor=SerialExecutor())
    manifest = json.loads((campaign / "manifest.json").read_text())
    assert manifest["state"] == "interrupted" and RECORD in manifest["files"]
    calls = []
    monkeypatch.setattr(campaign_mod, "scene_plant_task", lambda *a: calls.append(a[1]) or real(*a))
    res = fuzz(campaign, budget=2, seed=0, plants=PLANTS, horizon=HORIZON, executor=SerialExecutor())
    assert set(calls) == {1} and res.complete and [r.index for r in res.scenes] == [0, 1]
    assert json.loads((campaign / "manifest.json").read_text())["state"] == "complete"
