"""The run-shaped reporters: a run's simulated time, a job's stages side by side, runs one after
the other, free-text events; each under the display in force or for its own stream."""

from __future__ import annotations

import io

from validation.runs.counter import duration
from validation.runs.display import Display, Mode, showing
from validation.runs.progress import Progress, RunsProgress, StageProgress, Status

INTERVAL_S = 10.0  # these tests' interval between plain lines, s


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _plain(buf, clock) -> Display:
    return Display(Mode.PLAIN, buf, INTERVAL_S, 0.0, clock)


def test_stages_side_by_side_count_together_with_an_eta():
    """Two plants of 20 s each, both at 1 simulated s per wall s: a line at the interval with
    the share of the stages' time done, each stage's time, and the ETA of a linear advance."""
    buf, clock = io.StringIO(), FakeClock()
    with showing(_plain(buf, clock)):
        p = StageProgress("validate x", 20.0, stages=2)
        for k in range(21):
            clock.now = float(k)
            p("analytic", float(k))
            p("mujoco", float(k))
        p.close()
    lines = buf.getvalue().splitlines()
    assert [line for line in lines if " plant, 0 -> " in line] == [
        "tumble: validate x: analytic plant, 0 -> 20 s",
        "tumble: validate x: mujoco plant, 0 -> 20 s",
    ]
    assert all(line.startswith("tumble: validate x") for line in lines), lines
    # at 10 s the analytic plant reports first: 19 of the 40 plant-seconds are done
    at_10 = next(line for line in lines if ", 10 s elapsed" in line)
    assert "19 of 40 plant-seconds (48 %; analytic 10 s, mujoco 9 s)" in at_10, at_10
    assert at_10.endswith(f", ETA {duration(10.0 * (40 - 19) / 19)}"), at_10  # linear advance
    assert lines[-1].startswith("tumble: validate x: stages done (analytic 20 s, mujoco 20 s")


def test_runs_one_after_the_other_are_counted_together():
    """Two runs of 10 s: the count names the run; the ETA's rate is measured from the first
    report (1 simulated s per wall s after a 1 s start-up), so it is the linear advance's."""
    buf, clock = io.StringIO(), FakeClock()
    with showing(_plain(buf, clock)), RunsProgress("reference x", 10.0, 2) as shown:
        first, second = shown.next(), shown.next()
        clock.now = 1.0  # kernels loaded: the first report
        first(0.0)
        clock.now = 11.0
        first(10.0)
        clock.now = 16.0
        second(5.0)
    lines = buf.getvalue().splitlines()
    assert lines == [
        "tumble: reference x: run 1/2, t = 0.000 / 10 s (0 %), 1.0 s elapsed, ETA unknown",
        "tumble: reference x: run 2/2, t = 0.000 / 10 s (50 %), 11 s elapsed, ETA 10 s",
        "tumble: reference x: stopped at run 2/2, t = 5.000 / 10 s after 16 s",
    ]


def test_a_simulation_with_no_display_set_prints_nothing(capsys):
    """A library caller that asked for nothing: the display in force is off."""
    p = Progress("simulate x", 1.0, delay=0.0)
    p(0.5)
    p.close()
    assert capsys.readouterr().err == ""


def test_status_is_silent_when_quiet_and_one_line_otherwise():
    buf = io.StringIO()
    with showing(Display(Mode.OFF, buf)):
        Status()("compiling")
    with showing(Display(Mode.PLAIN, buf)):
        Status()("compiling")
    assert buf.getvalue() == "tumble: compiling\n"
