"""The options several ``tumble`` commands share, each defined once: the value types (a positive
number, a whole number, plant names), the scene argument, ``--plants``, ``--out``, ``--t-end``,
``--time-limit``, ``--figure-format`` and the Dask workers (``--scheduler`` / ``--dask-workers``).

Each function adds one option to a command's parser with the type, name and metavar every command
gives it; the help text, which says what the option means for that command, is the command's own
argument. A refused value is an ``argparse.ArgumentTypeError`` quoting it, which the parser turns
into one line (``tumble validate: error: --dt: must be a positive finite number (got '0')``).
"""

from __future__ import annotations

import argparse


def positive_float(s: str) -> float:
    """A positive finite number given on the command line; ``ArgumentTypeError`` quoting it."""
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number (got {s!r})") from None
    if not v > 0 or v != v or v == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number (got {s!r})")
    return v


def positive_int(s: str) -> int:
    """A whole number ≥ 1 given on the command line; ``ArgumentTypeError`` quoting it."""
    try:
        v = int(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number (got {s!r})") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be ≥ 1 (got {s!r})")
    return v


def plant_names(s: str) -> str:
    """A ``--plants`` value: comma-separated names, at least one (``''`` or ``','`` would
    otherwise read as "not given" and run the default plants); ``ArgumentTypeError`` quoting it.
    The names themselves are checked by the command (:func:`mj_bridge.plants.parse_plants`)."""
    if not any(x.strip() for x in s.split(",")):
        raise argparse.ArgumentTypeError(f"give at least one plant name (got {s!r})")
    return s


def add_scene(p: argparse.ArgumentParser, *, every_builtin: bool = False) -> None:
    """The optional positional ``scene``: a scene file or a built-in name; without it the default
    scene (:data:`validation.scenes.DEFAULT_SCENE`), or with ``every_builtin`` every built-in one."""
    from validation.scenes import DEFAULT_SCENE, builtin_names

    names = ", ".join(builtin_names())
    if every_builtin:
        text = f"scene file (TOML) or built-in scene name (default: all: {names})"
    else:
        text = f"scene file (TOML) or built-in scene name (default: {DEFAULT_SCENE}); "
        text += f"built-in: {names}"
    p.add_argument("scene", nargs="?", default=None, help=text)


def add_out(p: argparse.ArgumentParser, help: str) -> None:
    """``--out``: where the command writes (``help`` states its default)."""
    p.add_argument("--out", help=help)


def add_plants(p: argparse.ArgumentParser, help: str) -> None:
    """``--plants``: comma-separated plant names (at least one; :func:`plant_names`)."""
    p.add_argument("--plants", type=plant_names, help=help)


def add_t_end(p: argparse.ArgumentParser, help: str, metavar: str | None = None) -> None:
    """``--t-end``: a horizon in seconds, positive and finite."""
    p.add_argument("--t-end", type=positive_float, metavar=metavar, help=help)


def add_time_limit(p: argparse.ArgumentParser, help: str) -> None:
    """``--time-limit SECONDS``: the wall-time limit of a plant's run, positive and finite."""
    p.add_argument("--time-limit", type=positive_float, metavar="SECONDS", help=help)


def add_figure_format(p: argparse.ArgumentParser, help: str) -> None:
    """``--figure-format``: comma-separated figure formats, ``png`` unless given."""
    p.add_argument("--figure-format", default="png", help=help)


def add_workers(p: argparse.ArgumentParser) -> None:
    """Where the work runs: ``--scheduler`` (a Dask scheduler's address) or ``--dask-workers N``
    (a local Dask cluster), at most one of them; neither: the command's own processes."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--scheduler", help="a Dask scheduler's address (tcp://host:8786)")
    g.add_argument(
        "--dask-workers",
        type=positive_int,
        help="run on a local Dask cluster of N single-threaded worker processes",
    )


def add_quiet(p: argparse.ArgumentParser) -> None:
    """``--quiet`` / ``-q``: no progress and no notices; warnings and errors still show
    (:func:`validation.runs.messages.command_output`). Every command has it."""
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="show no progress and no notices (warnings and errors still show)",
    )


def add_dashboard(p: argparse.ArgumentParser) -> None:
    """``--dashboard``: the local Dask cluster a command starts (``--dask-workers``) serves its
    dashboard on 127.0.0.1, its link logged once (:mod:`validation.studies.dask_options`)."""
    p.add_argument(
        "--dashboard",
        action="store_true",
        help="with --dask-workers: serve the local Dask cluster's dashboard on 127.0.0.1 and "
        "print its link",
    )


def viewer_port(s: str) -> int:
    """A TCP port (1 to 65535) given on the command line; ``ArgumentTypeError`` quoting it."""
    try:
        v = int(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a port number (got {s!r})") from None
    if not 0 < v < 65536:
        raise argparse.ArgumentTypeError(f"must be a port 1 to 65535 (got {s!r})")
    return v


def add_viewer(p: argparse.ArgumentParser) -> None:
    """A live Rerun viewer, Rerun's options (:mod:`validation.recording.live`), at most one:
    ``--spawn``, ``--connect [URL]``, ``--serve [PORT]``; none: nothing connects anywhere."""
    from validation.recording.live import DEFAULT_PORT

    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--spawn",
        action="store_true",
        help="spawn a Rerun viewer and stream the run to it live (the files are written as ever)",
    )
    g.add_argument(
        "--connect",
        nargs="?",
        const="",
        metavar="URL",
        help="stream the run live to a running Rerun viewer or server at URL or port (default: "
        f"rerun+http://127.0.0.1:{DEFAULT_PORT}/proxy)",
    )
    g.add_argument(
        "--serve",
        nargs="?",
        const=DEFAULT_PORT,
        type=viewer_port,
        metavar="PORT",
        help=f"host Rerun's gRPC server and web viewer on 127.0.0.1:PORT (default {DEFAULT_PORT}) "
        "and stream the run to it; it keeps serving after the run until Ctrl-C",
    )
