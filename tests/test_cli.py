"""The ``tumble`` command line: outputs, exit codes, and one-line errors (never a traceback)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from validation.cli import EXIT_USAGE, main


def test_simulate_writes_trajectory_and_summary(tmp_path, capsys):
    rc = main(["simulate", "paper_example2", "--t-end", "0.5", "--out", str(tmp_path)])
    assert rc == 0
    data = np.load(tmp_path / "trajectory.npz")
    assert data["q"].shape == (51, 12)  # 0.5 s at 100 Hz, n = 5 -> 5 + 7 coordinates
    meta = json.loads(str(data["meta_json"]))
    assert meta["engine"] == "analytic" and meta["status"] == "ok"
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "ok"
    # No control in this scene: the work of the control is exactly zero.
    assert np.all(data["invariants.work"] == 0.0)
    out = capsys.readouterr().out
    assert "paper_example2" in out and "invariants" in out
    # no temporary files left behind by the atomic writes
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "manifest.json",
        "summary.json",
        "trajectory.npz",
    ]


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["simulate", "no_such_scene"], "no file and no built-in scene"),
        (["simulate", "paper_example1", "--rtol", "-1"], "must be a positive"),
    ],
)
def test_bad_input_one_line(argv, needle, capsys):
    with pytest.raises(SystemExit) if "--rtol" in argv else _NoRaise():
        rc = main(argv)
        assert rc == EXIT_USAGE
    err = capsys.readouterr().err.strip()
    assert needle in err
    assert "Traceback" not in err


class _NoRaise:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_bad_scene_file_in_a_subprocess(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[scene]\nname = "x"\neffects = ["gravity"]\n[body]\nmass = -1\ninertia = [1, 1, 1]\n'
    )
    proc = subprocess.run(
        [sys.executable, "-m", "validation.cli", "simulate", str(bad)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == EXIT_USAGE
    lines = proc.stderr.strip().splitlines()
    assert lines == ["tumble: error: body.mass: must be positive (got -1)"]
    assert proc.stdout == ""
