"""The numerical environment of the tool's own processes: BLAS on one thread, no colour codes.

Nothing here runs at import: ``import validation`` (a library user, the pytest plugin loaded in
every pytest session of an environment that has the package) changes no environment variable and
no thread pool. What changes, and where:

* the ``tumble`` program (:func:`validation.cli.run`, ``python -m validation``) calls
  :func:`set_process_env` first thing, before numpy is imported: its whole process, and every
  child it starts, is the tool's; so do the ``python -m`` measurement programs
  (:func:`as_program`);
* a scene run of the pytest plugin (:mod:`validation.testing.pytest_plugin`) runs inside
  :func:`one_blas_thread`: the process's BLAS pools are limited for the run (``threadpoolctl``)
  and given back as they were; the worker processes forked meanwhile keep the limit;
* the tool's worker processes that are not forked from such a block (the fork server, the local
  process pools' workers) call :func:`limit_blas_threads` for their whole life.

Why one BLAS thread: the model works on small dense matrices (n + 7 up to a few hundred), where
multithreaded BLAS only adds synchronisation, and on a loaded 2-core machine its spinning threads
slowed one evaluation by up to 100x (measured: n = 50, 1.3 ms with one thread against 120 ms with
two while another process ran). A user's explicit setting of the variables wins in
:func:`set_process_env`.

Why ``NO_COLOR``: Rerun's logger otherwise writes ANSI colour codes into files and pipes. It reads
the variable once, when ``rerun`` is first imported: :func:`import_rerun` sets it for that import
only (when stderr is not a terminal and the user has not set it), in the process that records.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator

BLAS_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The variables that size the BLAS and OpenMP thread pools, read when the library is loaded."""

NO_COLOR = "NO_COLOR"


def _wants_no_color() -> bool:
    return NO_COLOR not in os.environ and not os.isatty(2)


TRACKER_QUIET = "ignore:resource_tracker:UserWarning"
"""A ``PYTHONWARNINGS`` entry for the program's children: a command interrupted while a process
pool runs stops without waiting for the pool's running tasks (its workers end with it) and ends
with ``os._exit``, so multiprocessing's resource tracker, a child of its own, unlinks the pool's
semaphores itself and would add a two-line "leaked semaphore objects" warning after the one line
that says the command was interrupted."""


def set_process_env() -> None:
    """For the ``tumble`` program's process only, before numpy is imported: each of
    :data:`BLAS_VARS` to ``1`` unless set, ``NO_COLOR=1`` when stderr is not a terminal (unless
    set), and :data:`TRACKER_QUIET` added to ``PYTHONWARNINGS`` (for the children it starts)."""
    for var in BLAS_VARS:
        os.environ.setdefault(var, "1")
    if _wants_no_color():
        os.environ[NO_COLOR] = "1"
    given = os.environ.get("PYTHONWARNINGS", "")
    if TRACKER_QUIET not in given.split(","):
        os.environ["PYTHONWARNINGS"] = f"{given},{TRACKER_QUIET}" if given else TRACKER_QUIET


def as_program() -> None:
    """For a ``python -m validation....`` measurement program, first thing in its ``__main__``
    block: its process is the tool's, so :func:`set_process_env`; when numpy was imported already
    (by the module's own imports) without the variables, the program is started again in the
    same process (``os.execv``, the same command line) with them set, so its BLAS starts with one
    thread (and no BLAS thread keeps :func:`validation.runs.workers.can_fork` from forking)."""
    missing = [var for var in BLAS_VARS if var not in os.environ]
    set_process_env()
    if missing and "numpy" in sys.modules:
        sys.stdout.flush()
        sys.stderr.flush()
        os.execv(sys.executable, [sys.executable, *sys.orig_argv[1:]])


def _load_blas() -> None:
    """numpy's and scipy's BLAS loaded now: ``threadpoolctl`` limits only the libraries loaded
    when the limit is set, and scipy carries its own OpenBLAS."""
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """This process's BLAS and OpenMP pools on one thread inside the block, as they were after."""
    _load_blas()
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        yield


def limit_blas_threads() -> None:
    """This process's BLAS and OpenMP pools on one thread from now on: for the tool's own worker
    processes only (the fork server, a pool's worker). Nothing to do in a process started with
    each of :data:`BLAS_VARS` at ``1`` (by ``tumble``): its BLAS started with one thread."""
    if all(os.environ.get(var) == "1" for var in BLAS_VARS):
        return
    _load_blas()
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)


def import_rerun() -> None:
    """Import ``rerun`` (first import: with ``NO_COLOR=1`` set for the import only, when stderr is
    not a terminal and the user has not set it; module docstring)."""
    if "rerun" in sys.modules:
        return
    scoped = _wants_no_color()
    if scoped:
        os.environ[NO_COLOR] = "1"
    try:
        import rerun  # noqa: F401
    finally:
        if scoped:
            os.environ.pop(NO_COLOR, None)


__all__ = [
    "BLAS_VARS",
    "as_program",
    "import_rerun",
    "limit_blas_threads",
    "one_blas_thread",
    "set_process_env",
]
