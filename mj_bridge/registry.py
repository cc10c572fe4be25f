"""Plant names and their report order, from the installed metadata alone (nothing is imported).

A plant's name is an open ``str``: the three built-ins (:class:`analytic.trajectory.Engine`), the
entry points of the group :data:`GROUP` that installed distributions declare (``docs/plugins.md``),
and any other label (a trajectory read from a file under a name of the user's choosing).

Report order, everywhere a set of plants or a pair is listed (the order of ``--plants``, the
columns of a table, which plant of a pair comes first, the colours of extra plants): the built-ins
in :class:`Engine` order, then the plugins by name, then any other label by name
(:func:`order_key`). The plugins' classes are loaded by :mod:`mj_bridge.plants`; this module only
reads the entry points' names (``importlib.metadata``, once per process).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable
from importlib import metadata

from analytic.trajectory import Engine

GROUP = "tumbling_testbed.plants"
"""The entry-point group a plant plugin declares itself in (``name = "module:Class"``)."""

BUILTIN: tuple[str, ...] = tuple(e.value for e in Engine)
"""The built-in plants' names, in report order (the analytic plant first: relative checks use
its scales)."""

NAME_PATTERN = re.compile(r"[a-z][a-z0-9_]{0,31}")
"""What a plugin's name may be: lower-case ASCII letters, digits and ``_``, a letter first, at
most 32 characters. The name is a command-line word, part of keys (``diff_analytic_vs_<name>``),
file names and entity paths, so it carries nothing to escape."""

RESERVED = frozenset({"all"})
"""Words of ``--plants`` that no plant may be called."""


@functools.cache
def entry_points() -> tuple[metadata.EntryPoint, ...]:
    """The entry points of :data:`GROUP` of every installed distribution, in name order; one per
    name and value (a distribution seen twice on ``sys.path`` counts once). Read once."""
    seen: dict[tuple[str, str], metadata.EntryPoint] = {}
    for ep in metadata.entry_points(group=GROUP):
        seen.setdefault((ep.name, ep.value), ep)
    return tuple(sorted(seen.values(), key=lambda ep: (ep.name, ep.value)))


def plugin_names() -> tuple[str, ...]:
    """The names the installed plugins declare (loaded or not, valid or not), sorted."""
    return tuple(sorted({ep.name for ep in entry_points()} - set(BUILTIN)))


def order_key(name: str) -> tuple[int, int, str]:
    """Sort key of report order: built-ins (in :data:`BUILTIN` order), then plugins, then any
    other label, each group by name."""
    name = str(name)
    if name in BUILTIN:
        return (0, BUILTIN.index(name), "")
    return (1 if name in plugin_names() else 2, 0, name)


def report_order(names: Iterable[object]) -> tuple[str, ...]:
    """``names`` as plain strings, duplicates dropped, in report order (:func:`order_key`)."""
    return tuple(sorted(dict.fromkeys(str(n) for n in names), key=order_key))


def rank(name: str) -> int:
    """A plant's place in the installation's report order, for colours and line styles: 0, 1, 2
    for the built-ins, 3 + k for the k-th plugin by name, and for any other label
    ``3 + (number of plugins) + crc32(name) % 64`` (the same label, the same place, on every
    machine with the same plugins)."""
    import zlib

    name = str(name)
    if name in BUILTIN:
        return BUILTIN.index(name)
    plugins = plugin_names()
    if name in plugins:
        return len(BUILTIN) + plugins.index(name)
    return len(BUILTIN) + len(plugins) + zlib.crc32(name.encode()) % 64


__all__ = [
    "BUILTIN",
    "GROUP",
    "NAME_PATTERN",
    "RESERVED",
    "entry_points",
    "order_key",
    "plugin_names",
    "rank",
    "report_order",
]
