"""The fork server's last preload (:func:`validation.runs.workers.start_served`): what every child
it forks should inherit, set once in the server after its other imports.

* Python's warning when a child runs the main module's code again although the server has
  imported it already (``runpy``: "found in sys.modules after import of package ..."), is
  silenced: the server imports the main module on purpose (:func:`workers._main_module`), and
  the warning would be printed once per plant run.
* The objects the server holds are moved out of the garbage collector's reach (:func:`gc.freeze`):
  a child's first full collection would otherwise walk, and so copy page by page, the whole
  inherited heap (the engines, numba's kernels). Measured on the 2-core machine with matplotlib
  also imported in the server: from a child's start to its task's first line, 250 ms without,
  90 ms with; without matplotlib the difference is within the noise of a loaded machine.

* BLAS is on one thread in the server, so in every child
  (:func:`validation.runs.environment.limit_blas_threads`: the server is started with the
  environment of the process that asked for it, a user's maybe).
* Every child the server forks ends when the server does
  (:func:`validation.runs.lifetime.forks_die_with_parent`), and the server ends when the process
  that started it does, also one killed with SIGKILL, from its first preload on
  (:mod:`validation.runs.server_watch`): a served plant run does not outlive a ``tumble``
  killed with SIGKILL.

Import it only on purpose: it does its work at import.
"""

from __future__ import annotations

import gc
import warnings

from validation.runs.environment import limit_blas_threads
from validation.runs.lifetime import forks_die_with_parent

RUNPY_RERUN = r".* found in sys\.modules after import of package .*"
"""The message (a regular expression) of runpy's warning silenced here."""

warnings.filterwarnings("ignore", message=RUNPY_RERUN, category=RuntimeWarning)
forks_die_with_parent()
gc.freeze()
limit_blas_threads()  # last: after the preload's imports (numpy, scipy)
