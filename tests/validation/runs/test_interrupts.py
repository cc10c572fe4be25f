"""The interrupt mechanism's rules, in this process: what an exception stands for, and what a
run that reports to nobody does once a signal was received."""

from __future__ import annotations

import signal
import threading

import pytest

from validation.runs import interrupts


def _cut_init(exc: KeyboardInterrupt) -> ImportError:
    """What pybind11 raises when an exception interrupts a module's initialisation."""
    try:
        raise exc
    except KeyboardInterrupt as e:
        try:
            raise ImportError("initialization failed") from e
        except ImportError as imp:
            return imp


def test_an_import_error_raised_from_an_interrupt_stands_for_it():
    term = interrupts.Terminated()
    assert interrupts.interrupt_of(_cut_init(term)) is term
    assert interrupts.interrupt_of(term) is term


def test_an_exception_of_its_own_stands_for_no_interrupt_outside_a_signal():
    assert interrupts.interrupt_of(ValueError("x")) is None
    assert interrupts.interrupt_of(ImportError("no module named x")) is None
    interrupts.raise_if_interrupt(RuntimeError("x"))  # a no-op


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(), reason="handlers: main thread"
)
def test_after_a_caught_sigterm_any_exception_and_every_checkpoint_is_the_interrupt():
    with interrupts.handled():
        interrupts.checkpoint(0.0)  # nothing received: a no-op
        try:
            signal.raise_signal(signal.SIGTERM)
            for _ in range(1000):
                pass
        except interrupts.Terminated:
            pass  # caught by a layer that goes on, as a plant's loop does
        assert interrupts.received() and interrupts.received_sigterm()
        ki = interrupts.interrupt_of(ValueError("a consequence"))
        assert isinstance(ki, interrupts.Terminated)
        with pytest.raises(interrupts.Terminated):
            interrupts.checkpoint(1.0)
    assert not interrupts.received()  # the state of one command does not outlive it
