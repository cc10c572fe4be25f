"""Run ``tumble`` with a signal that cuts an import, as it cuts a C extension's initialisation.

``python tests/support/cut_import.py MODULE SIGNAL ARGS...`` runs ``tumble ARGS...`` in this process,
and the first import of ``MODULE`` (``*``: of any module) made once the command's own handler is in
place (and, with ``CUT_AFTER_PARTIAL=DIR``, once an output set is being staged in ``DIR``) delivers
``SIGNAL`` to the process and then fails as a pybind11 module (MuJoCo) fails when an exception
interrupts its initialisation: ``ImportError: initialization failed``, raised from the interrupt.
Only the process that runs the command cuts (not its workers). The cut is said on stderr, one
line: ``cut import MODULE at T`` (``time.monotonic()``, the same clock in every process).
"""

from __future__ import annotations

import glob
import importlib.abc
import os
import signal
import sys
import time

TARGET = sys.argv[1]
SIG = getattr(signal, sys.argv[2])
PID = os.getpid()
AFTER = os.environ.get("CUT_AFTER_PARTIAL")


class Cut(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if os.getpid() != PID or (TARGET != "*" and name != TARGET):
            return None
        if signal.getsignal(SIG) in (signal.SIG_DFL, signal.default_int_handler, None):
            return None  # the command's handler is not set yet
        if AFTER and not glob.glob(os.path.join(AFTER, ".*.partial")):
            return None
        sys.meta_path.remove(self)
        print(f"cut import {name} at {time.monotonic():.3f}", file=sys.stderr, flush=True)
        try:
            os.kill(os.getpid(), SIG)
            for _ in range(10_000):  # the handler runs at the next bytecodes
                pass
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc
        raise AssertionError("the signal was not delivered")


if __name__ == "__main__":
    sys.meta_path.insert(0, Cut())
    from validation.cli import run

    run(sys.argv[3:])
