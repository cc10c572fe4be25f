"""The ``tumble`` command line: outputs, exit codes, and one-line errors (never a traceback)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.guards import forbid_plant_runs
from validation.cli import EXIT_USAGE, main, user_warnings


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
    """Refused with the usage exit code (argparse's own for an argument it converts) and one line."""
    try:
        rc = main(argv)
    except SystemExit as e:  # argparse refuses a bad --rtol by exiting with its own code
        rc = e.code
    assert rc == EXIT_USAGE
    err = capsys.readouterr().err.strip()
    assert needle in err
    assert "Traceback" not in err


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


# ------------------------------------------------------------------------------------------------
# Bad input is caught before any work: one line naming the field, exit 2, no output directory
# ------------------------------------------------------------------------------------------------

PAPER1 = Path(__file__).resolve().parents[2] / "analytic" / "scenes" / "paper_example1.toml"


def _scene_file(tmp_path, replace=(), append="") -> str:
    text = PAPER1.read_text(encoding="utf-8")
    for old, new in replace:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "scene.toml"
    path.write_text(text + append, encoding="utf-8")
    return str(path)




@pytest.mark.parametrize(
    ("replace", "append", "args", "line"),
    [
        ((), "\n[thresholds]\npositon_C = 1e-6\n", (), "thresholds.positon_C: unknown threshold"),
        (
            (),
            '\n[thresholds]\nposition_C = "1e-6"\n',
            (),
            "thresholds.position_C: must be a number",
        ),
        ((), "\n[thresholds]\nposition_C = nan\n", (), "thresholds.position_C: must be finite"),
        ((), "\n[thresholds]\nposition_C = -1e-6\n", (), "thresholds.position_C: must be non-neg"),
        ((), "\n[thresholds]\nposition_C = inf\n", (), "thresholds.position_C: must be finite"),
        ((), "", ("--t-end", "0.0001"), "t_end: shorter than one MuJoCo step"),
        ((), "", ("--t-end", "1e300"), "t_end: too large"),
        ((("rate = 100.0 ", "rate = 1e12 "),), "", (), "output.rate: too large"),
        ((("t_end = 20.0 ", "t_end = 1e300 "),), "", (), "output.t_end: too large"),
        ((("delta1 = 0.5", "delta1 = " + "9" * 400),), "", (), "stabilization.delta1: must be"),
        ((("[5.0e5, 4.0e5]", "[5.0e5, 1e-20]"),), "", (), "masses.mass[1]: must be at least 1e-15"),
        ((("[5.0e5, 4.0e5]", "[5.0e5, 1e300]"),), "", (), "masses.mass[1]: must be at most"),
        ((("k_cubic = [", "# k_cubic = ["),), "", (), "springs.k_cubic: required by effect"),
    ],
)
def test_validate_refuses_bad_input_before_any_plant(
    tmp_path, monkeypatch, capsys, replace, append, args, line
):
    scene = _scene_file(tmp_path, replace, append)
    forbid_plant_runs(monkeypatch)
    out = tmp_path / "out"
    rc = main(["validate", scene, "--out", str(out), *args])
    err = capsys.readouterr().err.splitlines()
    assert rc == EXIT_USAGE
    assert len(err) == 1 and err[0].startswith(f"tumble: error: {line}"), err
    assert not out.exists()


def test_table_for_an_unlisted_effect_is_one_warning_line(tmp_path, capsys):
    scene = _scene_file(tmp_path, append="\n[external_torque]\nconstant = [1.0, 0.0, 0.0]\n")
    rc = main(["simulate", scene, "--t-end", "0.01", "--out", str(tmp_path / "out")])
    assert rc == 0
    assert capsys.readouterr().err.splitlines() == [
        "tumble: warning: external_torque: given but effect 'external_torque' is not listed in "
        "scene.effects, so ignored"
    ]


def test_short_horizon_has_t0_and_t_end(tmp_path, capsys):
    rc = main(["simulate", "paper_example1", "--t-end", "0.004", "--out", str(tmp_path)])
    assert rc == 0
    with np.load(tmp_path / "trajectory.npz") as z:
        assert z["t"].tolist() == [0.0, 0.004]
        assert not np.allclose(z["q"][1], z["q"][0])


def _cli(*args, timeout=120):
    return subprocess.run(
        [sys.executable, "-m", "validation.cli", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_fifo_scene_is_refused_without_reading_it(tmp_path):
    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    proc = _cli("simulate", str(fifo), timeout=60)  # reading it would wait for a writer forever
    assert proc.returncode == EXIT_USAGE
    assert proc.stderr.splitlines() == [
        f"tumble: error: scene: not a regular file (got {str(fifo)!r})"
    ]


def test_unstable_run_keeps_stderr_readable(tmp_path):
    """g = 1e300: MuJoCo warns at every step and numpy overflows; stderr stays a few one-line
    warnings, without colour codes (it is a pipe here), and the run fails with exit 1."""
    scene = _scene_file(tmp_path, (("[0.0, 0.0, -9.81]", "[0.0, 0.0, -1e300]"),))
    proc = _cli("validate", scene, "--t-end", "0.01", "--out", str(tmp_path / "out"))
    lines = proc.stderr.splitlines()
    assert proc.returncode == 1, proc.stderr
    assert "\x1b" not in proc.stderr and "\r" not in proc.stderr and "Traceback" not in proc.stderr
    warnings = [line for line in lines if line.startswith("tumble: warning: ")]
    progress = [line for line in lines if line not in warnings]
    assert len(warnings) <= 12, proc.stderr
    assert any(line.startswith("tumble: warning: MuJoCo: ") for line in warnings), proc.stderr
    # the rest is progress, one plain line per stage (a pipe is not a terminal)
    assert all(line.startswith("tumble: ") for line in progress), proc.stderr
    assert len(progress) <= 12, proc.stderr


def test_user_warnings_one_line_each_resource_warnings_hidden(capsys):
    """What a user sees of warnings: one line per warning and place, no source line; a
    ResourceWarning (a SIGTERM landing inside an import leaves its .pyc open) shows nothing."""
    import warnings

    with user_warnings():
        for _ in range(3):
            warnings.warn("x is odd\nsecond line", UserWarning, stacklevel=1)
        warnings.warn("unclosed file <_io.BufferedReader>", ResourceWarning, stacklevel=1)
    assert capsys.readouterr().err.splitlines() == ["tumble: warning: x is odd"]


def test_no_colour_codes_when_stderr_is_not_a_terminal():
    """Rerun's logger colours its lines unless NO_COLOR is set when rerun is first imported: the
    tool's import of rerun sets it for that import only, when stderr is not a terminal, and
    leaves the environment as it was."""
    code = (
        "import os\n"
        "from validation.runs.environment import import_rerun\n"
        "import_rerun()\n"
        "assert 'NO_COLOR' not in os.environ\n"
        "import rerun as rr\n"
        "rec = rr.RecordingStream('x')\n"
        "stream = rec.binary_stream()\n"
        "rr.log('a', rr.Points3D([[0.0, 0.0, 0.0]]), recording=rec)\n"
        "del stream, rec\n"  # drops unread data: Rerun logs a warning
    )
    env = {k: v for k, v in os.environ.items() if k != "NO_COLOR"}
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env
    )
    assert proc.returncode == 0, proc.stderr
    assert "\x1b" not in proc.stderr


def test_version_and_python_dash_m_validation():
    import subprocess
    import sys
    from importlib import metadata

    proc = subprocess.run(
        [sys.executable, "-m", "validation", "--version"], capture_output=True, text=True
    )
    assert proc.returncode == 0
    assert proc.stdout.strip() == f"tumble {metadata.version('tumbling-testbed')}"
    proc = subprocess.run(
        [sys.executable, "-m", "validation", "simulate", "--rtol", "-1"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == EXIT_USAGE and proc.stdout == ""


def test_fast_bench_help_prints_help_and_runs_nothing(capsys):
    """``python -m validation.bench.fast_bench --help`` prints its usage and exits 0 before timing
    anything (no "numba available" line, which the benchmark prints first)."""
    from validation.bench import fast_bench

    with pytest.raises(SystemExit) as exc:
        fast_bench.main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: python -m validation.bench.fast_bench") and "numba available" not in out


def test_validate_counts_the_checks_as_the_report_does(tmp_path, capsys):
    """The closing verdict line counts what report.json counts: passed of the applicable checks,
    and the not-applicable ones apart (an uncontrolled scene has no control torque to compare)."""
    out = tmp_path / "v"
    rc = main(
        ["validate", "paper_example1", "--t-end", "0.2", "--plants", "analytic,mujoco",
         "--out", str(out)]
    )  # fmt: skip
    line = next(x for x in capsys.readouterr().out.splitlines() if "checks passed" in x)
    doc = json.loads((out / "report.json").read_text())
    applicable = [c for c in doc["checks"] if c["applicable"]]
    passed = sum(c["passed"] for c in applicable)
    n_na = len(doc["checks"]) - len(applicable)
    assert n_na > 0 and rc == 0
    assert line == (
        f"PASS: {passed}/{len(applicable)} checks passed ({n_na} not applicable) for paper_example1"
    )


def test_every_command_module_declares_its_command():
    """Each module of ``validation.commands`` listed in ``COMMANDS`` declares a name, its two help
    texts, whether it chooses plants, its options and its handler; the names are unique and the
    parser's sub-commands are exactly these, in this order."""
    import argparse

    from validation.cli import COMMANDS, build_parser

    for module in COMMANDS:
        declared = (("NAME", str), ("HELP", str), ("DESCRIPTION", str), ("CHOOSES_PLANTS", bool))
        for attr, kind in declared:
            assert isinstance(getattr(module, attr), kind), (module.__name__, attr)
        assert callable(module.add_arguments) and callable(module.run), module.__name__
    names = [m.NAME for m in COMMANDS]
    assert len(set(names)) == len(names)
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == names
    for module in COMMANDS:
        assert sub.choices[module.NAME].get_default("func") is module.run


@pytest.mark.parametrize("platform", ["darwin", "win32", "freebsd14"])
def test_an_unsupported_system_is_refused_in_one_line(platform, monkeypatch, capsys):
    """``tumble`` on a system other than Linux: one line naming the system, exit 2, before any
    work."""
    from validation import cli

    monkeypatch.setattr(sys, "platform", platform)
    with pytest.raises(SystemExit) as exc:
        cli.run(["--version"])
    assert exc.value.code == EXIT_USAGE
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("tumble: error: ")
    assert "Linux only" in err and repr(platform) in err


def test_linux_is_supported():
    from validation.cli import unsupported_platform

    assert unsupported_platform("linux") is None
    assert unsupported_platform() is None  # the system this suite runs on
    assert unsupported_platform("darwin") is not None
