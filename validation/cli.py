"""The ``tumble`` command line: the parser built from the command modules, and the dispatch.

Each command is a module of :mod:`validation.commands` (its options next to its handler);
:data:`COMMANDS` lists them in ``tumble --help``'s order. Errors are one line on stderr
(``tumble: error: ...``) and a non-zero exit status, never a traceback: 2 for bad input (found
before any work), 1 for a failed run or check or a result that could not be written, 130 after
Ctrl-C and 143 after SIGTERM (the partial results are kept, marked interrupted). Every output
directory is one run, whole (:mod:`validation.runs.outputs`); default output paths are built from a
sanitised slug of the scene's name, always under ``out/``.

Only the standard library is imported before ``main`` has installed its signal handlers, so a
Ctrl-C during start-up (numpy, MuJoCo, numba loading) is one line too; an interrupt that lands
inside compiled code's Python callback is kept and raised at the next progress report, and one
that cuts an import (a C extension's initialisation then fails as ``ImportError``) or causes any
other exception ends the command as interrupted too, every command alike
(:mod:`validation.runs.interrupts`). ``--plants`` is refused when it names no plant.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import warnings
from typing import NoReturn

from validation.commands import (
    EXIT_FAILED,
    EXIT_SIGINT,
    EXIT_SIGTERM,
    EXIT_USAGE,
    Command,
    bench,
    demo,
    export_mjcf,
    fuzz,
    hard_cases,
    judge,
    reference,
    scene_reference,
    simulate,
    sweep,
    validate,
    warmup,
)
from validation.commands.options import add_quiet
from validation.runs import interrupts

COMMANDS: tuple[Command, ...] = (
    simulate,
    validate,
    judge,
    reference,
    export_mjcf,
    demo,
    hard_cases,
    sweep,
    fuzz,
    bench,
    warmup,
    scene_reference,
)
"""Every ``tumble`` command, in the order ``tumble --help`` lists them."""


class _OneLineParser(argparse.ArgumentParser):
    """An argument parser whose refusals are one line, as every other bad input's: ``tumble
    validate: error: --dt: must be a positive finite number (got '0')``, exit 2 (no usage block;
    ``--help`` is unchanged). Sub-commands' parsers are of this class too (argparse makes them of
    their parent's)."""

    def error(self, message: str) -> NoReturn:
        text = message.splitlines()[0] if message else "bad arguments"
        if text.startswith("argument "):  # "argument --dt: ..." -> "--dt: ..."
            text = text[len("argument ") :]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {text}\n")


def _version() -> str:
    """The installed distribution's version ("unknown" when run from a bare checkout)."""
    from importlib import metadata  # deferred: ~15 ms (-X importtime), after main's handlers

    try:
        return metadata.version("tumbling-testbed")
    except metadata.PackageNotFoundError:
        return "unknown"


def build_parser() -> argparse.ArgumentParser:
    """The ``tumble`` parser: one sub-command per module of :data:`COMMANDS`, its options its
    own (``add_arguments``) and its handler ``args.func`` (the module's ``run``, looked up now)."""
    parser = _OneLineParser(
        prog="tumble",
        description="Cross-validation testbed for tumbling multibody dynamics: the Koganti-Udwadia "
        "analytic model and a MuJoCo twin under one closed-form controller.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for command in COMMANDS:
        p = sub.add_parser(command.NAME, help=command.HELP, description=command.DESCRIPTION)
        command.add_arguments(p)
        add_quiet(p)
        p.set_defaults(func=command.run)
    return parser


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings as one line each (``tumble: warning: ...``), without the source line."""
    text = str(message).splitlines()[0] if str(message) else category.__name__
    if file is not None:
        print(f"tumble: warning: {text}", file=file)
        return
    from validation.runs.display import write_line  # below a progress bar, which is redrawn

    write_line(f"tumble: warning: {text}")


@contextlib.contextmanager
def user_warnings():
    """The warnings a ``tumble`` user sees: each once per place, one line each.

    ``ResourceWarning`` stays hidden, as in Python's own default: the one a user would meet is a
    Ctrl-C or SIGTERM landing inside an ``import``, which leaves that import's open ``.pyc`` file to
    the collector, a line about Python's internals before the one line that says what happened.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.simplefilter("ignore", ResourceWarning)
        warnings.showwarning = _one_line_warning
        yield


def _out_of_memory(exc: MemoryError) -> str:
    """One line for a ``MemoryError``: ``out of memory (...)`` (its own message may be empty)."""
    text = str(exc).splitlines()[0] if str(exc) else ""
    if text.startswith("out of memory"):
        return text
    return f"out of memory ({text})" if text else "out of memory"


def warn_skipped_plugins(file=None) -> None:
    """One line per plant plugin left out (``tumble: warning: plant plugin 'x' skipped: <why>``,
    :func:`mj_bridge.plants.plugin_errors`), before a command that runs plants; the others run."""
    from mj_bridge.plants import plugin_errors

    for err in plugin_errors():
        print(f"tumble: warning: {err}", file=file or sys.stderr)


_PLANT_COMMANDS = frozenset(c.NAME for c in COMMANDS if c.CHOOSES_PLANTS)
"""The commands that choose among the registered plants (their plugins are loaded, and the ones
left out named)."""


def main(argv: list[str] | None = None) -> int:
    """Run one ``tumble`` command; returns the exit status (see the module docstring).

    Every command runs under :func:`validation.runs.interrupts.handled`: a signal that arrives at
    any moment (an import of a C extension, a plant's run, a write) ends it with 130 / 143 and one
    line, whatever exception the code it landed in raised instead (:func:`_interrupted`)."""
    with interrupts.handled():
        try:
            with user_warnings():
                parser = build_parser()
                args = parser.parse_args(argv)
                from validation.recording.live import from_args  # stdlib only; after the handlers
                from validation.runs.messages import command_output  # after the handlers: numpy

                with command_output(quiet=args.quiet):  # progress, --quiet, the log's lines
                    if getattr(args, "command", None) in _PLANT_COMMANDS:
                        warn_skipped_plugins()
                    with from_args(args):  # --spawn, --connect, --serve (options.add_viewer)
                        status = args.func(args)
        except BaseException as exc:
            return _failed(exc)
        if interrupts.pending():  # swallowed by compiled code after the last progress report
            sigterm = interrupts.received_sigterm()
            print(
                f"tumble: {'terminated' if sigterm else 'interrupted'} as the run ended; "
                "its results are complete",
                file=sys.stderr,
            )
            return EXIT_SIGTERM if sigterm else EXIT_SIGINT
        if interrupts.received():  # caught and turned into a result by code that went on
            return _interrupted(interrupts.interrupt())
        return status


def _interrupted(exc: KeyboardInterrupt) -> int:
    """The one line and the status of a command a signal stopped."""
    sigterm = isinstance(exc, interrupts.Terminated) or interrupts.received_sigterm()
    print(
        f"tumble: {'terminated' if sigterm else 'interrupted'}; "
        "partial results (if any) are kept, marked interrupted",
        file=sys.stderr,
    )
    return EXIT_SIGTERM if sigterm else EXIT_SIGINT


def _failed(exc: BaseException) -> int:
    """The one line and the status of a command that raised ``exc``; an exception that is not
    one of a bad input, memory or a file is re-raised (a bug: its traceback is the report)."""
    from validation.runs.atomic import OutputError

    if isinstance(exc, OutputError):  # the run happened; its results could not be written
        print(f"tumble: error: {exc}", file=sys.stderr)
        return EXIT_FAILED
    ki = interrupts.interrupt_of(exc)  # also an ImportError of an import the signal cut
    if ki is not None:
        return _interrupted(ki)
    if isinstance(exc, ValueError):  # bad input (also OutputBusy: another run holds the directory)
        print(f"tumble: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if isinstance(exc, MemoryError):  # often without a message: one line saying what it is
        print(f"tumble: error: {_out_of_memory(exc)}", file=sys.stderr)
        return EXIT_FAILED
    if isinstance(exc, OSError):
        where = f": {exc.filename}" if exc.filename else ""
        print(f"tumble: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return EXIT_USAGE
    raise exc


def unsupported_platform(platform: str | None = None) -> str | None:
    """Why the tool cannot run on ``platform`` (default ``sys.platform``), in one line; None on
    Linux, the one system it supports: its output directories, caches and worker processes rely on
    fcntl file locks, ``/proc`` and Linux's ``renameat2`` and ``prctl``."""
    platform = sys.platform if platform is None else platform
    if platform == "linux":
        return None
    return (
        f"tumble runs on Linux only (fcntl locks, /proc, renameat2, prctl); this system is "
        f"{platform!r}"
    )


def run(argv: list[str] | None = None) -> None:
    """The ``tumble`` program: :func:`main`, then the process ends at once with its status.

    Every file is written and closed by then and the output streams are flushed here; what is
    skipped is the interpreter's teardown of the loaded compiled kernels, which does nothing the
    program needs (its cost: ``docs/performance.md``, "The command line"). Code that calls
    ``tumble`` in-process uses :func:`main`, which returns the status instead.

    The program's process is the tool's own: its numerical environment (BLAS on one thread,
    ``NO_COLOR``) is set here, before numpy is imported
    (:func:`validation.runs.environment.set_process_env`), not on ``import validation``.
    On a system other than Linux it prints one line and exits with 2, before any work
    (:func:`unsupported_platform`)."""
    refusal = unsupported_platform()
    if refusal is not None:
        print(f"tumble: error: {refusal}", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)
    from validation.runs.environment import set_process_env

    set_process_env()
    status = main(argv)
    numba_cache = sys.modules.get("analytic.runtime.cache_check")
    if numba_cache is not None:  # what Python's teardown would do: the cache's manifest kept
        numba_cache.finish()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status)


if __name__ == "__main__":
    run()
