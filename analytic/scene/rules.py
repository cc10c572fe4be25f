"""Rules across the tables of a scene, driven by the key declarations (:attr:`Key.effect
<analytic.scene.key.Key.effect>`, :attr:`~analytic.scene.key.Key.effect_needs`): an effect that is
listed must have the data it cannot act without, data given for an effect that is not listed is
ignored with one warning, and masses drawn beyond the pictured rod get one warning.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

from analytic.effects import Effect, ShapeKind
from analytic.scene.records import SceneRecord as Scene
from analytic.scene.schema import KEYS, Kind, effect_keys
from analytic.scene.twin import check_body_for_mujoco

EFFECT_DATA: tuple[tuple[str, Effect], ...] = tuple((k.dotted, k.effect) for k in effect_keys())
"""``(dotted table or key, the effect that reads it)``: given while the effect is off, ignored."""

_NEEDED_TABLES = tuple(k for k in KEYS if k.effect_needs and k.kind is Kind.TABLE)
_NEEDED_KEYS = tuple(k for k in KEYS if k.effect_needs and k.kind is not Kind.TABLE)


def _given(scene: Scene, dotted: str) -> bool:
    """Whether the loaded ``scene`` holds the table or key ``dotted``: a record that is not None,
    or a key its record lists as given (``Springs.given``)."""
    *parents, last = dotted.split(".")
    node: Any = scene
    for part in parents:
        node = getattr(node, part)
    given = getattr(node, "given", None)
    if given is not None:
        return last in given
    return getattr(node, last) is not None


def check_effects_consistent(scene: Scene) -> None:
    """An effect that is on must have its data (the tables, then, with masses, the per-spring keys
    it needs); control indices must fit n; BR must be representable by the MuJoCo twin."""
    e = scene.effects
    for k in _NEEDED_TABLES:
        if k.effect in e and not _given(scene, k.dotted):
            raise ValueError(
                f"{k.dotted}: effect {k.effect.value!r} is on but [{k.dotted}] is missing"
            )
    if scene.control.masses is not None and max(scene.control.masses.indices) >= scene.n:
        raise ValueError(
            f"control.masses.indices: refer to masses beyond n = {scene.n} "
            f"(got {[i + 1 for i in scene.control.masses.indices]!r})"
        )
    if scene.n:  # (with no masses there is nothing for a spring to act on)
        for k in _NEEDED_KEYS:
            if k.effect in e and not _given(scene, k.dotted):
                raise ValueError(f"{k.dotted}: required by effect {k.effect.value}")
    check_body_for_mujoco(scene)


def warn_masses_off_the_drawn_rod(scene: Scene) -> None:
    """One warning (one line) naming each ``masses.p_e`` and ``initial.p`` beyond the drawn rod.

    The rod of ``[body.shape]`` is a picture: the dynamics let the masses slide on an unbounded
    line (no end stops), so a mass beyond the drawing is allowed, but the picture would show it
    floating off the rod, which is usually a mistake in the scene (a length or a sign).
    """
    shape = scene.body.shape
    if shape.kind is ShapeKind.NONE or not scene.n:
        return
    lo, hi = shape.rod_start, shape.rod_start + shape.rod_length
    off = [
        f"{name}[{i}] = {x:g} m"
        for name, values in (("masses.p_e", scene.masses.p_e), ("initial.p", scene.initial.p))
        for i, x in enumerate(values.tolist())
        if not lo <= x <= hi
    ]
    if not off:
        return
    where = f"{lo:g} m to {hi:g} m from O'"
    warnings.warn(
        f"{', '.join(off)}: {'lies' if len(off) == 1 else 'lie'} beyond the drawn rod "
        f"(body.shape.rod_start = {lo:g} m, rod_length = {shape.rod_length:g} m: {where}); the "
        "rod's length is a picture only, the masses slide on an unbounded line",
        UserWarning,
        stacklevel=3,
    )


def warn_unused_tables(data: Mapping[str, Any], scene: Scene) -> None:
    """One warning (one line) naming the tables and keys given for effects that are not listed."""
    unused: dict[str, Effect] = {}
    for dotted, effect in EFFECT_DATA:
        node: Any = data
        for key in dotted.split("."):
            node = node.get(key) if isinstance(node, Mapping) else None
        if node is not None and effect not in scene.effects:
            unused[dotted] = effect
    if not unused:
        return
    effects = ", ".join(dict.fromkeys(repr(e.value) for e in unused.values()))
    one = len(set(unused.values())) == 1
    warnings.warn(
        f"{', '.join(unused)}: given but {'effect' if one else 'effects'} {effects} "
        f"{'is' if one else 'are'} not listed in scene.effects, so ignored",
        UserWarning,
        stacklevel=3,
    )


__all__ = [
    "EFFECT_DATA",
    "check_effects_consistent",
    "warn_masses_off_the_drawn_rod",
    "warn_unused_tables",
]
