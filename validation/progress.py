"""Progress on stderr for runs that take more than a few seconds; silent when not a terminal."""

from __future__ import annotations

import sys
import time


class Progress:
    """Callable ``progress(t)`` printing ``label: t / t_end s`` at most a few times per second.

    Prints nothing when stderr is not a terminal, or before ``delay`` seconds have passed.
    """

    def __init__(self, label: str, t_end: float, delay: float = 2.0, stream=None):
        self.label = label
        self.t_end = t_end
        self.delay = delay
        self.stream = stream or sys.stderr
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = time.monotonic()
        self.last = 0.0
        self.shown = False

    def __call__(self, t: float) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self.start < self.delay or now - self.last < 0.25:
            return
        self.last = now
        self.shown = True
        frac = min(max(t / self.t_end, 0.0), 1.0) if self.t_end > 0 else 1.0
        self.stream.write(f"\r{self.label}: t = {t:8.3f} / {self.t_end:g} s ({100 * frac:5.1f} %)")
        self.stream.flush()

    def close(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
