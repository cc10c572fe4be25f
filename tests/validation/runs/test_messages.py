"""The command line's messages: log records as the tool's one-line messages, --quiet, and
nothing left behind after a command."""

from __future__ import annotations

import io
import logging
from pathlib import Path

import pytest

from analytic.runtime.log import ROOT, get_logger
from validation.cli import main
from validation.runs import display, messages
from validation.runs.display import Display, Mode, showing
from validation.runs.messages import OneLineHandler, command_output

log = get_logger("tests.messages")
PAPER1 = Path(__file__).resolve().parents[3] / "analytic" / "scenes" / "paper_example1.toml"


def _record(level: int, text: str) -> logging.LogRecord:
    return logging.LogRecord(ROOT, level, __file__, 1, text, None, None)


@pytest.mark.parametrize(
    ("mode", "level", "text", "line"),
    [
        (
            Mode.PLAIN,
            logging.WARNING,
            "cache entry not used\nsecond",
            "tumble: warning: cache entry not used",
        ),
        (Mode.BAR, logging.WARNING, "x", "tumble: warning: x"),
        (Mode.PLAIN, logging.ERROR, "x", "tumble: error: x"),
        (Mode.PLAIN, logging.INFO, "grid: 12 series", "tumble: grid: 12 series"),
        (Mode.BAR, logging.INFO, "grid: 12 series", "grid: 12 series"),
    ],
)
def test_records_read_as_todays_lines(mode, level, text, line):
    buf = io.StringIO()
    OneLineHandler(Display(mode, buf)).handle(_record(level, text))
    assert buf.getvalue() == f"{line}\n"


def test_a_command_shows_notices_and_warnings_once_quiet_only_warnings(capsys):
    root = logging.getLogger()
    seen: list[logging.LogRecord] = []
    catcher = logging.Handler()
    catcher.emit = seen.append  # a program embedding the command line that configured logging
    root.addHandler(catcher)
    try:
        with command_output(quiet=False):
            log.info("notice")
            log.warning("careful")
        with command_output(quiet=True):
            log.info("notice")
            log.warning("careful")
    finally:
        root.removeHandler(catcher)
    assert capsys.readouterr().err.splitlines() == [
        "tumble: notice",
        "tumble: warning: careful",
        "tumble: warning: careful",
    ]
    assert seen == []  # not propagated: nothing twice
    root_logger = logging.getLogger(ROOT)
    assert [h for h in root_logger.handlers if isinstance(h, OneLineHandler)] == []
    assert root_logger.propagate


def test_a_library_user_who_configured_nothing_sees_nothing(capsys):
    log.warning("careful")
    log.info("notice")
    assert capsys.readouterr().err == ""


def _fast_display(monkeypatch):
    """The command's display without its start delay, so a short run shows its progress."""
    monkeypatch.setattr(
        messages,
        "for_stream",
        lambda s, quiet: display.for_stream(s, quiet=quiet, delay_s=0.0),
    )


def test_quiet_silences_the_progress_of_a_command(tmp_path, monkeypatch, capsys):
    _fast_display(monkeypatch)
    argv = ["simulate", "paper_example1", "--t-end", "2", "--out", str(tmp_path / "a")]
    assert main(argv) == 0
    err = capsys.readouterr().err.splitlines()
    assert err and all(line.startswith("tumble: simulate paper_example1: t = ") for line in err)
    assert main([*argv[:-1], str(tmp_path / "b"), "--quiet"]) == 0
    got = capsys.readouterr()
    assert got.err == "" and "wrote " in got.out  # the results still on stdout


def test_quiet_keeps_the_warnings(tmp_path, monkeypatch, capsys):
    _fast_display(monkeypatch)
    scene = tmp_path / "s.toml"
    scene.write_text(PAPER1.read_text() + "\n[external_torque]\nconstant = [1.0, 0.0, 0.0]\n")
    rc = main(["simulate", str(scene), "--t-end", "0.05", "--out", str(tmp_path / "o"), "-q"])
    assert rc == 0
    assert capsys.readouterr().err.splitlines() == [
        "tumble: warning: external_torque: given but effect 'external_torque' is not listed in "
        "scene.effects, so ignored"
    ]


def test_the_display_is_off_again_after_a_command(tmp_path, capsys):
    main(["simulate", "paper_example1", "--t-end", "0.01", "--out", str(tmp_path)])
    assert display.current().mode is Mode.OFF
    with showing(Display(Mode.PLAIN, io.StringIO())):
        pass
    assert display.current().mode is Mode.OFF
