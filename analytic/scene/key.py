"""What one key of the scene format is: :class:`Key` (type, unit, default, bounds, meaning, the
effect that reads it) and the vocabulary it is written in (:class:`Kind`, :class:`Need`).

Conventions (as in the loader): units SI; *body* vectors are in BR's principal axes at its centre
of mass C (the paper's xyz), *inertial* vectors in XYZ with Z up; quaternions are w first; mass and
axis indices in files are 1-based, as in the paper. ``n`` is the number of masses (the length of
``masses.mass``), ``k`` the number of controlled masses or axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum, StrEnum
from typing import Any

from analytic.effects import Effect


class Kind(StrEnum):
    """The kind of TOML value a key holds (as the documentation shows it)."""

    TABLE = "table"
    STRING = "string"
    BOOLEAN = "boolean"
    NUMBER = "number"
    VECTOR3 = "list of 3 numbers"
    VECTOR4 = "list of 4 numbers"
    VECTOR_N = "list of n numbers, one per mass"
    VECTOR_N1 = "list of n + 1 numbers, one per spring"
    VECTOR_K = "list of k numbers, one per controlled mass (in the order of `indices`)"
    MATRIX3 = "3×3 matrix (list of 3 rows)"
    MATRIX_K = "k×k matrix (list of k rows), k = the number of `components`"
    MATRICES_N = "list of n 3×3 matrices, one per mass"
    INDICES = "list of distinct 1-based integers"
    CHOICE = "string, one of the choices"
    CHOICES = "list of strings, each one of the choices"
    NUMBER_OR_VALUE_TABLE = "number, or table { value, rtol, reason }"
    NUMBER_OR_STRING = "number or string"


class Need(StrEnum):
    """Whether a key must be given."""

    REQUIRED = "required"
    OPTIONAL = "optional"
    CONDITIONAL = "conditional"
    """Required, or allowed, only in the case that :attr:`Key.when` states."""


class _NoDefault(Enum):
    NO_DEFAULT = "no default"


NO_DEFAULT = _NoDefault.NO_DEFAULT
"""The :attr:`Key.default` of a key without one (required, or computed when absent)."""


@dataclass(frozen=True)
class Key:
    """One key of the scene format.

    Attributes:
        table: the dotted table the key sits in (``"body.shape"``; ``""`` for the top-level tables);
            ``<name>`` stands for any name (the ``[thresholds]`` entries).
        key: the key (``"rod_length"``), or the table's own name for a table.
        kind: the kind of value.
        unit: SI unit of the value(s), ``""`` for none.
        meaning: what it is, in a sentence or two. ``meaning``, ``bounds`` and ``when`` may name
            a bound of :mod:`analytic.scene` in braces (``{MAX_MASS}``), filled in from its
            constant when the reference is rendered (so the number lives in one place); a literal
            brace is doubled.
        need: required, optional (with a default) or conditional (see ``when``).
        default: the TOML value the loader uses when the key is absent (:data:`NO_DEFAULT`: none).
        default_text: the default in words, when it is not a TOML value (``"no limit"``).
        when: for a conditional key, when it is required or allowed.
        bounds: what the loader refuses, in short (``"> 0"``).
        choices: the enum of the allowed strings, for ``CHOICE`` and ``CHOICES`` keys.
        effect: the effect that reads the key or table: given while that effect is not listed in
            ``scene.effects``, it is ignored with one warning; None for data every scene reads.
        effect_needs: the effect cannot act without it (with masses, for a per-spring key):
            listing the effect without the key is refused (``when`` says so in words).
    """

    table: str
    key: str
    kind: Kind
    unit: str
    meaning: str
    need: Need = Need.OPTIONAL
    default: Any = NO_DEFAULT
    default_text: str = ""
    when: str = ""
    bounds: str = ""
    choices: type[StrEnum] | None = None
    effect: Effect | None = None
    effect_needs: bool = False

    @property
    def dotted(self) -> str:
        """``table.key`` (``body.shape.rod_length``)."""
        return f"{self.table}.{self.key}" if self.table else self.key

    def __post_init__(self) -> None:
        if self.need is Need.REQUIRED and self.default is not NO_DEFAULT:
            raise ValueError(f"{self.dotted}: a required key has no default")
        if (self.kind in (Kind.CHOICE, Kind.CHOICES)) != (self.choices is not None):
            raise ValueError(f"{self.dotted}: choices go with the CHOICE kinds only")
        if self.need is Need.CONDITIONAL and not self.when:
            raise ValueError(f"{self.dotted}: a conditional key says when")
        if self.effect_needs and (
            self.effect is None or f"required by the effect {self.effect.value}" not in self.when
        ):
            raise ValueError(f"{self.dotted}: a key an effect needs says so in `when`")


DEFAULT_GRAVITY: tuple[float, float, float] = (0.0, 0.0, -9.81)
"""``[gravity] vector`` when the table is absent, m/s², inertial (Z up)."""


__all__ = ["DEFAULT_GRAVITY", "NO_DEFAULT", "Key", "Kind", "Need"]
