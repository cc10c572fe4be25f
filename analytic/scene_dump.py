"""A resolved :class:`~analytic.scene.Scene` as plain data: every field of the record, every
default filled in, for the provenance block of the JSON outputs (:mod:`validation.provenance`).

The dump follows the *record* (``Scene`` and its frozen dataclasses), not the TOML file format: a
scene file may give the attitude as a rotation matrix or leave the solver table out, the dump has
the quaternion ``initial.u`` (w first) and ``solver.method``, ``rtol``, ``atol``, ``max_step`` as the
loader resolved them. Units are those of the record's docstrings (SI: m, kg, s, rad, N).

Conversions: numpy arrays -> nested lists of floats; string enums stay (they are ``str``), other
enums -> their value; frozensets -> sorted
lists; tuples -> lists; mappings -> dicts with string keys. Floats are kept as they are (``inf``
included, e.g. ``solver.max_step``): turning them into JSON is the encoder's job
(:func:`validation.provenance.to_json_value`).
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from typing import Any

import numpy as np

from analytic.scene import Scene


def plain(x: Any) -> Any:
    """``x`` with dataclasses, arrays, enums and sets turned into dicts, lists and scalars."""
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return {f.name: plain(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, enum.Enum):  # a string enum stays itself (a str): the encoder knows that
        return x if isinstance(x, str) else x.value  # "none" is a declared value, not a gap
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, Mapping):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, frozenset | set):
        return sorted(plain(v) for v in x)
    if isinstance(x, list | tuple):
        return [plain(v) for v in x]
    return x


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """Every field of ``scene`` (defaults included) as plain data; see the module docstring.

    ``source`` is the path the scene was read from ("" for a scene built in memory); ``extra`` keeps
    the scene's verbatim extra tables (``[thresholds]``).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an analytic.scene.Scene (got {type(scene).__name__})")
    return plain(scene)


__all__ = ["plain", "scene_to_dict"]
