"""The ``tumble`` commands, one module each: its options declared next to its handler.

A command module is a :class:`Command`: ``NAME`` (the sub-command), ``HELP`` (its line in
``tumble --help``), ``DESCRIPTION`` (its own ``--help``), ``CHOOSES_PLANTS`` (whether it chooses
among the registered plants: :func:`validation.cli.main` loads the plant plugins first and names
the ones left out), ``add_arguments(parser)`` (its options, on the sub-command's parser) and
``run(args)`` (the handler: the exit status, or an exception :func:`validation.cli.main` turns
into one line). :mod:`validation.cli` lists the modules in ``tumble --help``'s order, builds the
parser from them and dispatches; the options several commands share are defined once in
:mod:`validation.commands.options`.

Every module imports only the standard library at its top: :mod:`validation.cli` imports them all
before its signal handlers are installed, and what a handler needs (numpy, the engines) is imported
inside it (:mod:`validation.cli`'s docstring).
"""

from __future__ import annotations

import argparse
from typing import Protocol

EXIT_FAILED = 1  # a run or a check failed, or its results could not be written
EXIT_USAGE = 2  # bad input (scene, arguments), found before any work
EXIT_SIGINT = 130  # 128 + SIGINT, the shell's convention
EXIT_SIGTERM = 143  # 128 + SIGTERM


class Command(Protocol):
    """What a command module declares (a module satisfies it by its names)."""

    NAME: str
    HELP: str
    DESCRIPTION: str
    CHOOSES_PLANTS: bool

    def add_arguments(self, parser: argparse.ArgumentParser) -> None: ...

    def run(self, args: argparse.Namespace) -> int: ...
