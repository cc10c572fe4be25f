"""The record of one named bound: its value, its unit and the reason for its number.

One type for the whole project, at the lowest layer so that every layer (and the tests) can hold
its bounds in it: the comparison's scene-overridable defaults (``validation/compare/thresholds.py``) and
the tolerances only the tests use (``tests/support/tolerances.py``).

An absolute threshold may carry a relative part as well, as scipy's ``atol + rtol·|y|``: the bound
is then ``value + rtol · scale`` (:meth:`Threshold.bound`), ``scale`` the quantity's own magnitude
over the run; :class:`Bound` holds the two parts and names the larger (:class:`BoundPart`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum


class BoundPart(StrEnum):
    """Which part of a bound ``atol + rtol · scale`` is the larger, hence decided the check."""

    ABSOLUTE = "absolute"  # the threshold's value (atol)
    RELATIVE = "relative"  # rtol × the quantity's scale


@dataclass(frozen=True)
class Bound:
    """An effective bound and its two parts, in the threshold's unit.

    Attributes:
        absolute: the absolute part, the threshold's ``value`` (atol).
        relative: the relative part, ``rtol · scale`` (0 without a relative part).
        scale: the magnitude the relative part multiplies (max over time and the compared
            plants of the quantity's own size, e.g. ``max |p_i|`` in m), in the threshold's unit;
            0 when the threshold has no relative part.
    """

    absolute: float
    relative: float = 0.0
    scale: float = 0.0

    @property
    def value(self) -> float:
        """The effective bound ``absolute + relative`` (a check passes when its value is at most this)."""
        return self.absolute + self.relative

    @property
    def decided_by(self) -> BoundPart:
        """RELATIVE when the relative part is the larger, else ABSOLUTE (ties: ABSOLUTE, the
        part that was there before)."""
        return BoundPart.RELATIVE if self.relative > self.absolute else BoundPart.ABSOLUTE


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
        rtol: the relative part of an absolute threshold, dimensionless: the bound is
            ``value + rtol · scale`` (:meth:`bound`), as scipy's ``atol + rtol·|y|``. 0 (the
            default) for a purely absolute bound; must be 0 for a relative threshold, whose value
            is already a fraction of a scale.

    Raises:
        ValueError: naming ``thresholds.<name>`` and the field for a value or rtol that is not a
            finite non-negative number, an empty name, unit or reason, a relative threshold
            without a positive floor or with a non-zero rtol, or an unknown source.
    """

    name: str
    value: float
    unit: str
    reason: str
    relative: bool = False
    floor: float = 0.0
    source: ThresholdSource = ThresholdSource.DEFAULT
    rtol: float = 0.0

    def __post_init__(self) -> None:
        if not (
            isinstance(self.value, int | float) and math.isfinite(self.value) and self.value >= 0
        ):
            raise ValueError(
                f"thresholds.{self.name}: must be a finite non-negative number (got {self.value!r})"
            )
        if not (
            isinstance(self.rtol, int | float)
            and not isinstance(self.rtol, bool)
            and math.isfinite(self.rtol)
            and self.rtol >= 0
        ):
            raise ValueError(
                f"thresholds.{self.name}.rtol: must be a finite non-negative number (got {self.rtol!r})"
            )
        if self.relative and self.rtol != 0:
            raise ValueError(
                f"thresholds.{self.name}.rtol: must be 0 for a relative threshold, whose value is "
                f"already a fraction of its scale (got {self.rtol!r})"
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

    def bound(self, scale: float = 0.0) -> Bound:
        """The effective bound for a quantity of magnitude ``scale`` (in ``unit``): the absolute
        part ``value`` and the relative part ``rtol · scale``.

        Args:
            scale: the quantity's own magnitude over the run (finite, non-negative; e.g. the
                largest ``|p_i|`` in m over time and the compared plants). Ignored (relative part
                0) when ``rtol`` is 0.

        Raises:
            ValueError: naming ``thresholds.<name>.scale`` for a scale that is not a finite
                non-negative number while ``rtol`` is positive.
        """
        if self.rtol == 0:
            return Bound(float(self.value), 0.0, 0.0)
        scale = float(scale)
        if not (math.isfinite(scale) and scale >= 0):
            raise ValueError(
                f"thresholds.{self.name}.scale: must be a finite non-negative number (got {scale!r})"
            )
        return Bound(float(self.value), self.rtol * scale, scale)


__all__ = ["Bound", "BoundPart", "Threshold", "ThresholdSource"]
