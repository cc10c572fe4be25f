"""The command line's messages: the project's log records as one-line messages, and the display
policy of one command (progress bars or plain lines or nothing), set together.

Contract:

* :class:`OneLineHandler` formats a record of the project's loggers
  (:mod:`analytic.runtime.log`) as the tool's other lines: ``tumble: warning: <message>`` for a
  warning, ``tumble: error: <message>`` for an error, and an ``INFO`` notice as a progress
  event: ``tumble: <message>`` off a terminal, ``<message>`` on one; only the first line of a
  message, and through :func:`validation.runs.display.write_line`, so a progress bar on the
  same terminal is drawn again below it.
* :func:`command_output` ``(quiet)``, for the duration of one command: the display policy for
  stderr (:func:`validation.runs.display.for_stream`) in force, and one :class:`OneLineHandler`
  on the project's root logger at ``INFO`` (``WARNING`` with ``quiet``: warnings and errors
  still show, progress and notices do not), the root set not to propagate to Python's root
  logger (a program embedding the command line that configured logging does not get each line
  twice). Both are undone at the end, so commands run in one process (the tests) do not pile up
  handlers.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator

from analytic.runtime.log import ROOT_LOGGER
from validation.runs.display import PREFIX, Display, current, for_stream, showing, write_line


class OneLineHandler(logging.Handler):
    """A record as one line on the display's stream (module docstring).

    Args:
        display: the policy whose stream and prefix it writes with (default: the one in force
            when a record is written).
    """

    def __init__(self, display: Display | None = None, level: int = logging.INFO):
        super().__init__(level)
        self.display = display

    def format(self, record: logging.LogRecord) -> str:
        text = record.getMessage()
        text = text.splitlines()[0].rstrip() if text.strip() else record.levelname.lower()
        d = self.display if self.display is not None else current()
        if record.levelno >= logging.ERROR:
            return f"{PREFIX}error: {text}"
        if record.levelno >= logging.WARNING:
            return f"{PREFIX}warning: {text}"
        return f"{d.prefix}{text}"

    def emit(self, record: logging.LogRecord) -> None:
        try:
            write_line(self.format(record), self.display)
        except Exception:  # a handler never raises into the code that logged
            self.handleError(record)


@contextlib.contextmanager
def command_output(quiet: bool = False) -> Iterator[Display]:
    """One command's display policy and log handler (module docstring); yields the policy."""
    display = for_stream(None, quiet=quiet)
    handler = OneLineHandler(None, logging.WARNING if quiet else logging.INFO)
    root = ROOT_LOGGER
    saved = (root.level, root.propagate)
    root.addHandler(handler)
    root.setLevel(handler.level)
    root.propagate = False
    try:
        with showing(display):
            yield display
    finally:
        root.removeHandler(handler)
        root.setLevel(saved[0])
        root.propagate = saved[1]


__all__ = ["OneLineHandler", "command_output"]
