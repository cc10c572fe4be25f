"""The record of one named bound: its value, its unit and the reason for its number.

One type for the whole project, at the lowest layer so that every layer (and the tests) can hold
its bounds in it: the comparison's scene-overridable defaults (``validation/compare/thresholds.py``) and
the tolerances only the tests use (``tests/support/tolerances.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum


class ThresholdSource(StrEnum):
    """Where a threshold's value comes from."""

    DEFAULT = "default"  # the module that defines it
    SCENE = "scene"  # a scene's ``[thresholds]`` table (or an explicit override)


@dataclass(frozen=True)
class Threshold:
    """One named bound.

    Attributes:
        name: the key used in reports and in a scene's ``[thresholds]`` table (for a test
            tolerance: its name in ``tests/support/tolerances.py``).
        value: the bound (inclusive: a check passes when ``checked value <= value``), finite and
            non-negative, in ``unit``.
        unit: unit of ``value`` ("1" for relative or dimensionless bounds).
        reason: why this number.
        relative: whether the checked value is divided by a scale (``max(scale, floor)``, see
            ``validation/compare/thresholds.py``).
        floor: for relative thresholds, the smallest scale used, in the signal's unit.
        source: :class:`ThresholdSource` (a string naming one is accepted and converted).

    Raises:
        ValueError: naming ``thresholds.<name>`` and the field for a value that is not a finite
            non-negative number, an empty name, unit or reason, a relative threshold without a
            positive floor, or an unknown source.
    """

    name: str
    value: float
    unit: str
    reason: str
    relative: bool = False
    floor: float = 0.0
    source: ThresholdSource = ThresholdSource.DEFAULT

    def __post_init__(self) -> None:
        if not (
            isinstance(self.value, int | float) and math.isfinite(self.value) and self.value >= 0
        ):
            raise ValueError(
                f"thresholds.{self.name}: must be a finite non-negative number (got {self.value!r})"
            )
        if self.relative and not self.floor > 0:
            raise ValueError(f"thresholds.{self.name}.floor: must be positive (got {self.floor!r})")
        for field in ("name", "unit", "reason"):
            text = getattr(self, field)
            if not (isinstance(text, str) and text.strip()):
                raise ValueError(
                    f"thresholds.{self.name}.{field}: must be a non-empty string (got {text!r})"
                )
        try:
            object.__setattr__(self, "source", ThresholdSource(self.source))
        except ValueError:
            known = ", ".join(s.value for s in ThresholdSource)
            raise ValueError(
                f"thresholds.{self.name}.source: unknown source {self.source!r} (known: {known})"
            ) from None


__all__ = ["Threshold", "ThresholdSource"]
