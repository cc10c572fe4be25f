"""A table of a scene being read, key by key, through the key declarations
(:data:`analytic.scene.schema.KEYS`): declared defaults, declared kinds, and a refusal of every key
that is unknown at its level or not used in its case.
"""

from __future__ import annotations

import difflib
from collections import deque
from collections.abc import Mapping
from typing import Any

import numpy as np

from analytic.scene.schema import (
    NO_DEFAULT,
    Key,
    Kind,
    Need,
    declared_keys,
    generic_table,
    key_spec,
)
from analytic.scene.values import SceneText, as_enum, as_number, as_vector, show

_VECTOR_KINDS = (Kind.VECTOR3, Kind.VECTOR4, Kind.VECTOR_N, Kind.VECTOR_N1, Kind.VECTOR_K)


class Table:
    """A TOML table being read: tracks its dotted path and which keys were consumed.

    Every key is read through its declaration in :data:`analytic.scene.schema.KEYS` (``schema`` is
    the table's generic name there, e.g. ``thresholds.<name>``): reading an undeclared key, or a
    key as another kind than declared, is a programming error (``LookupError``, ``TypeError``),
    and a key's default is the declared one. A caller passes a default of its own only for a key
    declared without one (a default that depends on n, such as zeros of length n + 1).
    """

    def __init__(self, data: Any, path: str, schema: str | None = None):
        if not isinstance(data, Mapping):
            raise ValueError(f"{path or 'scene'}: must be a table (got {show(data)})")
        self.data = data
        self.path = path
        self.schema = path if schema is None else schema
        self.used: set[str] = set()

    def name(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def spec(self, key: str, *kinds: Kind) -> Key:
        """The declaration of ``key``; ``kinds``: those the caller reads it as."""
        spec = key_spec(self.schema, key)
        if kinds and spec.kind not in kinds:
            raise TypeError(
                f"the loader reads {spec.dotted} as {' or '.join(kinds)}, declared {spec.kind}"
            )
        return spec

    def has(self, key: str) -> bool:
        self.spec(key)
        return key in self.data

    def raw(self, key: str, default: Any = ..., *, kinds: tuple[Kind, ...] = ()) -> Any:
        spec = self.spec(key, *kinds)
        if default is not ... and spec.default is not NO_DEFAULT:
            raise LookupError(
                f"{spec.dotted}: has a declared default; the loader must not pass one"
            )
        if default is ... and spec.default is not NO_DEFAULT:
            default = spec.default
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                raise ValueError(f"{self.name(key)}: missing required key")
            return default
        return self.data[key]

    def table(self, key: str) -> Table | None:
        """The sub-table ``key``; None when it is absent and optional, refused when required."""
        spec = self.spec(key, Kind.TABLE)
        if key not in self.data:
            if spec.need is Need.REQUIRED:
                raise ValueError(f"{self.name(key)}: missing required table")
            self.used.add(key)
            return None
        return Table(self.raw(key), self.name(key), generic_table(self.schema, key))

    def required_table(self, key: str) -> Table:
        """The sub-table ``key`` that the format requires: refused when it is absent."""
        t = self.table(key)
        if t is None:
            raise ValueError(f"{self.name(key)}: missing required table")
        return t

    def table_or_empty(self, key: str) -> Table:
        """The sub-table ``key``, or an empty one (every key at its default) when it is absent."""
        t = self.table(key)
        return t if t is not None else Table({}, self.name(key), generic_table(self.schema, key))

    def number(self, key: str, default: Any = ..., *, positive=False, nonneg=False) -> float:
        v = self.raw(key, default, kinds=(Kind.NUMBER,))
        return as_number(v, self.name(key), positive=positive, nonneg=nonneg)

    def vector(self, key: str, length: int | None = None, default: Any = ..., **kw) -> np.ndarray:
        v = self.raw(key, default, kinds=_VECTOR_KINDS)
        return as_vector(v, self.name(key), length, **kw)

    def string(self, key: str, default: Any = ...) -> str:
        v = self.raw(key, default, kinds=(Kind.STRING,))
        if not isinstance(v, str):
            raise ValueError(f"{self.name(key)}: must be a string (got {show(v)})")
        return SceneText(v)

    def boolean(self, key: str, default: Any = ...) -> bool:
        v = self.raw(key, default, kinds=(Kind.BOOLEAN,))
        if not isinstance(v, bool):
            raise ValueError(f"{self.name(key)}: must be true or false (got {show(v)})")
        return v

    def enum(self, key: str, kind: type, default: Any = ...):
        return as_enum(kind, self.raw(key, default, kinds=(Kind.CHOICE,)), self.name(key))

    def finish(self) -> None:
        """Refuse a key given here that the loader did not read: one not allowed in this case
        (the declaration's ``when``: ``box_center`` without a box), else an unknown one."""
        extra = sorted(set(self.data) - self.used)
        if not extra:
            return
        key = extra[0]
        got = show(self.data[key])
        try:
            spec = key_spec(self.schema, key)
        except LookupError:
            message = unknown_key_message(self.name(key), key, self.data[key], self.schema)
            raise ValueError(message) from None
        raise ValueError(
            f"{self.name(key)}: not used here: {spec.when or 'not allowed'} (got {got})"
        )


def unknown_key_message(dotted: str, key: Any, value: Any, schema: str) -> str:
    """``dotted: unknown key (did you mean 'lambda'?; ...) (got ...)``: the closest declared name
    at that level (:func:`difflib.get_close_matches`), and every declared name there."""
    names = declared_keys(schema) or ()
    close = difflib.get_close_matches(str(key), names, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    where = f" in [{schema}]" if schema else ""
    known = f"known{where}: {', '.join(names)}"
    if isinstance(value, Mapping):  # its content is not the point: its name is
        return f"{dotted}: unknown table ({hint}{known}) (got a table of {len(value)} keys)"
    return f"{dotted}: unknown key ({hint}{known}) (got {show(value)})"


def refuse_unknown_keys(data: Mapping[str, Any]) -> None:
    """Refuse, before anything is read, a table or key that is not declared at its level
    (:data:`analytic.scene.schema.KEYS`), naming it and the closest declared name: a misspelt
    ``[mass]`` or ``lamda`` is named as such, never reported as the missing or mis-sized key it
    leaves behind. Tables are walked level by level in the document's order; a verbatim table
    (``[hard_case]``) and the names of ``[thresholds]`` are checked by the layers that own them;
    a value of the wrong type is left to the reader that names it."""
    queue: deque[tuple[Mapping[str, Any], str, str]] = deque([(data, "", "")])
    while queue:
        node, path, schema = queue.popleft()
        names = declared_keys(schema)
        for key, value in node.items():
            dotted = f"{path}.{key}" if path else str(key)
            if names is not None and key not in names:
                raise ValueError(unknown_key_message(dotted, key, value, schema))
            if not isinstance(value, Mapping):
                continue
            try:
                sub = generic_table(schema, key)
            except LookupError:  # a verbatim table's own content
                continue
            if key_spec(schema, key).kind in (Kind.TABLE, Kind.NUMBER_OR_VALUE_TABLE):
                queue.append((value, dotted, sub))


__all__ = ["Table", "refuse_unknown_keys", "unknown_key_message"]
