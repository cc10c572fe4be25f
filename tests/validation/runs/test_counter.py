"""The counted advance: plain lines at the interval with the count, the elapsed time and an ETA;
a tqdm bar on a terminal; nothing when the display is off. A fake clock, an injected stream."""

from __future__ import annotations

import io
import re

import pytest

from validation.runs.counter import Counter, duration, eta
from validation.runs.display import PLAIN_INTERVAL_S, Display, Mode

INTERVAL_S = 10.0  # the interval of these tests' display, s
DELAY_S = 2.0  # their start delay, s


class FakeClock:
    """Monotonic seconds a test advances by hand."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def plain(buf, clock) -> Display:
    return Display(Mode.PLAIN, buf, INTERVAL_S, DELAY_S, clock)


def test_plain_lines_arrive_at_the_interval_with_count_elapsed_and_eta():
    """100 items at 1 item/s, reported every second: nothing in the delay, then one line at the
    first report after it, one per interval, and one closing line; each with the count, the
    elapsed time and an ETA that is right for a linear advance."""
    buf, clock = io.StringIO(), FakeClock()
    c = Counter("sweep x", 100, unit="series", display=plain(buf, clock))
    for k in range(1, 101):
        clock.now += 1.0
        c.set(k)
    c.close()
    lines = buf.getvalue().splitlines()
    assert "\r" not in buf.getvalue()
    assert all(line.startswith("tumble: sweep x: ") for line in lines), lines
    # first report after the delay (k = 2), then every interval (k = 12, 22, ... 92), the end
    counts = [int(m.group(1)) for m in map(re.compile(r".*: (\d+)/100 series").match, lines) if m]
    assert counts == [2, 12, 22, 32, 42, 52, 62, 72, 82, 92, 100], lines
    for line, k in zip(lines[:-1], counts, strict=False):
        assert f", {duration(k)} elapsed, " in line, line  # k reports, one a second
        # 1 item/s: the rest takes as many seconds as items are left
        assert line.endswith(f", ETA {duration(100 - k)}"), line
    assert lines[-1] == "tumble: sweep x: 100/100 series, done in 1 min 40 s"


def test_eta_is_the_rate_so_far_applied_to_what_is_left():
    assert eta(30.0, 3.0, 12.0) == pytest.approx(90.0)
    assert eta(30.0, 0.0, 12.0) is None  # no advance yet: unknown
    assert eta(30.0, 3.0, None) is None  # no total: unknown


def test_a_deadline_gives_the_eta_without_a_total():
    buf, clock = io.StringIO(), FakeClock()
    c = Counter("fuzz seed 0", None, unit="scenes", display=plain(buf, clock), deadline_s=120.0)
    clock.now += 30.0
    c.set(7)
    c.close()
    first = buf.getvalue().splitlines()[0]
    assert first == "tumble: fuzz seed 0: 7 scenes, 30 s elapsed, ETA 1 min 30 s"


def test_short_work_prints_nothing():
    """Done within the delay: no line at all, not even a closing one."""
    buf, clock = io.StringIO(), FakeClock()
    c = Counter("x", 10, display=plain(buf, clock))
    clock.now += DELAY_S / 2
    c.set(10)
    c.close()
    assert buf.getvalue() == ""


def test_stopped_work_says_where_it_stopped():
    buf, clock = io.StringIO(), FakeClock()
    c = Counter("hard cases", 8, unit="cases", display=plain(buf, clock))
    clock.now += 3 * DELAY_S
    c.set(3)
    c.close()
    assert buf.getvalue().splitlines()[-1] == "tumble: hard cases: stopped at 3/8 cases after 6.0 s"


def test_ticks_write_the_line_due_between_reports():
    """A caller waiting for a long item ticks: the line is written when the interval is due,
    the count unchanged, the time passing."""
    buf, clock = io.StringIO(), FakeClock()
    c = Counter("sweep x", 4, unit="series", display=plain(buf, clock))
    clock.now += DELAY_S
    c.set(1)
    for _ in range(30):  # 30 s without an advance, a tick a second
        clock.now += 1.0
        c.tick()
    lines = buf.getvalue().splitlines()
    assert len(lines) == 4 and all("1/4 series" in line for line in lines), lines
    assert ", 32 s elapsed, " in lines[-1], lines


def test_no_thread_is_started(monkeypatch):
    """The tool forks its workers only from a single-threaded process: a count starts none."""
    import threading

    before = threading.active_count()
    c = Counter("x", 10, display=Display(Mode.PLAIN, io.StringIO(), delay_s=0.0))
    c.set(1)
    assert threading.active_count() == before
    c.close()


def test_off_prints_nothing():
    buf, clock = io.StringIO(), FakeClock()
    c = Counter("x", 10, display=Display(Mode.OFF, buf, clock=clock))
    for k in range(10):
        clock.now += 100.0
        c.set(k)
    c.close()
    assert buf.getvalue() == ""


def test_a_terminal_gets_a_tqdm_bar_with_the_count():
    buf = Tty()
    c = Counter("sweep x", 12, unit="series", display=Display(Mode.BAR, buf, delay_s=0.0))
    c.set(3)
    c.close()
    text = buf.getvalue()
    assert text.startswith("\rsweep x: ") and "3/12 series" in text and " 25%|" in text
    assert text.endswith("\n") and "tumble: " not in text


def test_a_terminal_bar_of_simulated_time():
    buf = Tty()
    c = Counter(
        "simulate x", 20.0, display=Display(Mode.BAR, buf, delay_s=0.0), simulated_time=True
    )
    c.set(5.0)
    c.close()
    assert "t = 5.000/20 s" in buf.getvalue()


def test_every_report_raises_a_pending_interrupt(monkeypatch):
    from validation.runs import counter as counter_module

    def pending():
        raise KeyboardInterrupt

    monkeypatch.setattr(counter_module, "raise_pending", pending)
    with pytest.raises(KeyboardInterrupt):
        Counter("x", 1, display=Display()).set(0.5)


@pytest.mark.parametrize("total", [0, -1, float("nan"), "3"])
def test_a_bad_total_is_refused_naming_it(total):
    with pytest.raises(ValueError, match="total"):
        Counter("x", total)


def test_the_default_interval_is_the_named_constant():
    assert Display().interval_s == PLAIN_INTERVAL_S


def test_durations_read_as_a_person_reads_them():
    assert [duration(s) for s in (4.24, 38.0, 185.0, 3725.0)] == [
        "4.2 s",
        "38 s",
        "3 min 05 s",
        "1 h 02 min",
    ]
