"""Variants of a raw scene (the dict ``tomllib`` reads) for the tests that walk the loader's keys:
``variant(base, a__b__c=value)`` is a deep copy of ``base`` with ``[a.b] c = value`` set, or removed
when the value is None."""

from __future__ import annotations

import copy
from typing import Any


def variant(base: dict, **changes: Any) -> dict:
    """``base`` with ``a__b__c=value`` set (None: removed); ``base`` itself is left unchanged."""
    raw = copy.deepcopy(base)
    for dotted, value in changes.items():
        *head, last = dotted.split("__")
        node = raw
        for key in head:
            node = node.setdefault(key, {})
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return raw
