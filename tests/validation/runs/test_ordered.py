"""Work taken back in index order (:mod:`validation.runs.ordered`): at most ``window`` started
ahead, every item in index order whatever order it finished in, and every item started but not
taken cancelled when the work ends (at its end, on an error)."""

from __future__ import annotations

import pytest

from validation.runs.ordered import SerialExecutor, in_index_order


def test_items_come_in_index_order_with_at_most_window_started_ahead():
    started: list[int] = []
    ahead: list[int] = []
    taken: list[int] = []

    def start(i: int) -> str:
        started.append(i)
        return f"item {i}"

    with in_index_order(start, lambda i: i < 7, 3, lambda _item: None) as items:
        for i, item in items:
            ahead.append(len(started) - len(taken))
            assert item == f"item {i}"
            taken.append(i)
    assert taken == list(range(7)) and started == list(range(7))
    assert max(ahead) == 3


def test_items_started_and_not_taken_are_cancelled_on_an_error():
    cancelled: list[str] = []
    with pytest.raises(KeyboardInterrupt):
        with in_index_order(lambda i: f"item {i}", lambda i: True, 4, cancelled.append) as items:
            for i, _item in items:
                if i == 2:
                    raise KeyboardInterrupt
    assert cancelled == ["item 3", "item 4", "item 5"]


def test_the_serial_executor_runs_at_submission_and_keeps_errors_but_not_interrupts():
    ex = SerialExecutor()
    assert ex.submit(lambda x: x * 2, 4).result() == 8
    f = ex.submit(lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        f.result()

    def interrupted():
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        ex.submit(interrupted)
