"""A run's progress callback: ``progress(t)``, or ``progress(t, q)`` with the state reached.

Contract. A plant calls ``progress(t)`` with the simulated time it has reached, s, and may add its
state there, ``progress(t, q)``: ``q`` the generalized position at ``t`` in the trajectory's
coordinates (``[R (3), u (4, w first), p (n)]``, Eq. 44, shape ``(n+7,)``; a copy the callback may
keep), so that whoever listens can watch the run while it goes (the live viewer,
:mod:`validation.recording.live`). Both sides stay free:

* a callback that takes ``t`` alone is still given ``t`` alone: :func:`with_state` wraps it into
  one that accepts and drops ``q`` (:meth:`analytic.plant.Plant.simulate` does, so a plant may
  always pass ``q``);
* a plant that passes no ``q`` (a plugin written for ``progress(t)``) is watched by its times only;
* a plant computes ``q`` only for a callback that wants it (:func:`takes_state`), so a run nobody
  watches pays nothing for it.

A callback takes ``q`` when its second positional parameter is named ``q`` (``def watch(t, q)``,
``lambda t, q=None: ...``) or it takes ``*args``: by name, so that a closure with defaults of its
own (``def inner(t, i=i)``) is never handed a state in their place.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

Progress = Callable[..., None]
"""``progress(t)`` or ``progress(t, q=None)``: t the simulated time reached, s; q the state there
(module docstring)."""


class _TimeOnly:
    """``progress(t, q=None)`` of a callback that takes ``t`` alone: ``q`` is dropped."""

    __slots__ = ("progress",)

    def __init__(self, progress: Callable[[float], Any]):
        self.progress = progress

    def __call__(self, t: float, q: Any = None) -> None:
        self.progress(t)


def takes_state(progress: Any) -> bool:
    """Whether ``progress`` wants the state: its second positional parameter is named ``q``, or
    it takes ``*args`` (a callable whose signature cannot be read is taken as ``progress(t)``)."""
    if progress is None or isinstance(progress, _TimeOnly):
        return False
    try:
        params = inspect.signature(progress).parameters.values()
    except (TypeError, ValueError):
        return False
    positional = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    names = []
    for p in params:
        if p.kind is inspect.Parameter.VAR_POSITIONAL:
            return len(names) <= 1 or names[1] == "q"
        if p.kind in positional:
            names.append(p.name)
    return len(names) >= 2 and names[1] == "q"


def with_state(progress: Any) -> Progress | None:
    """``progress`` as a callable ``progress(t, q=None)``: itself when it takes the state, else
    one that drops ``q`` (:func:`takes_state` of it is False); None stays None."""
    if progress is None or isinstance(progress, _TimeOnly) or takes_state(progress):
        return progress
    return _TimeOnly(progress)


__all__ = ["Progress", "takes_state", "with_state"]
