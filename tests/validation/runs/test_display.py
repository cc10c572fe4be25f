"""The display policy: chosen from the stream and --quiet, in force for a block, off by default;
lines written whole, below a bar on a terminal."""

from __future__ import annotations

import io

import pytest

from validation.runs.counter import Counter
from validation.runs.display import Display, Mode, current, for_stream, showing, write_line


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_mode_follows_the_stream_and_quiet():
    assert for_stream(Tty()).mode is Mode.BAR
    assert for_stream(io.StringIO()).mode is Mode.PLAIN
    assert for_stream(Tty(), quiet=True).mode is Mode.OFF
    assert for_stream(io.StringIO(), quiet=True).mode is Mode.OFF


def test_off_unless_a_caller_sets_one_and_restored_after():
    assert current().mode is Mode.OFF  # a library caller that asked for nothing
    d = Display(Mode.PLAIN, io.StringIO())
    with showing(d):
        assert current() is d
        with showing(Display(Mode.OFF)):
            assert current().mode is Mode.OFF
        assert current() is d
    assert current().mode is Mode.OFF


def test_prefix_off_a_terminal_only():
    assert Display(Mode.PLAIN).prefix == "tumble: "
    assert Display(Mode.BAR).prefix == ""


@pytest.mark.parametrize(
    ("field", "value"), [("interval_s", 0.0), ("delay_s", -1.0), ("mode", "bar")]
)
def test_bad_settings_are_refused_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        Display(**{field: value})


def test_a_line_below_a_bar_leaves_the_bar_drawn_again():
    buf = Tty()
    d = Display(Mode.BAR, buf, delay_s=0.0)
    c = Counter("x", 4, unit="items", display=d)
    c.set(1)
    write_line("compiling", d)
    c.set(2)
    c.close()
    text = buf.getvalue()
    assert "compiling\n" in text
    after = text.split("compiling\n", 1)[1]
    assert "1/4 items" in after or "2/4 items" in after  # the bar again, below the line


def test_a_closed_stream_is_not_an_error():
    buf = io.StringIO()
    buf.close()
    write_line("x", Display(Mode.PLAIN, buf))
