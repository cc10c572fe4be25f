"""Every key of the scene format, with its type, unit, default, bounds, meaning and the effect that
reads it: :data:`KEYS`, the one place they live, and the lookups the loader reads them through.

The loader (:mod:`analytic.scene.loading`) reads a key only through this table: a key it reads that
is not declared here is a programming error (``LookupError``), a default it applies is the one
declared here, and the kind of value it reads (a number, a list of n numbers, ...) must be the
declared kind. The cross-field rules (:mod:`analytic.scene.rules`) take from it which data each
effect reads and which it cannot act without (:func:`effect_keys`). The reference
``docs/scene-format.md`` is rendered from this table (``python -m validation scene-reference``), so
the documentation and the loader cannot drift apart; ``tests/validation/report/test_scene_reference.py``
checks both directions. The declarations themselves are in :mod:`analytic.scene.keys_body`,
:mod:`~analytic.scene.keys_motion` and :mod:`~analytic.scene.keys_run`, the vocabulary in
:mod:`analytic.scene.key`.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum

from analytic.effects import (
    Effect,
    MjIntegrator,
    ShapeKind,
    SolverMethod,
    SpringModel,
    Weighting,
)
from analytic.effects.registry import DECLARATIONS
from analytic.scene.key import DEFAULT_GRAVITY, NO_DEFAULT, Key, Kind, Need
from analytic.scene.keys_body import BODY_KEYS
from analytic.scene.keys_motion import MOTION_KEYS
from analytic.scene.keys_run import RUN_KEYS

KEYS: tuple[Key, ...] = BODY_KEYS + MOTION_KEYS + RUN_KEYS
"""Every key, in the order of the reference."""

KEY_INDEX: Mapping[tuple[str, str], Key] = {(k.table, k.key): k for k in KEYS}
"""``(table, key) -> Key``."""

TABLES: tuple[str, ...] = tuple(k.dotted for k in KEYS if k.kind is Kind.TABLE)
"""Every table, in the order of the reference (``scene``, ``body``, ``body.shape``, ...)."""

_WILDCARDS: Mapping[str, tuple[tuple[str, str], ...]] = {
    "thresholds": (("hard_", "hard_<criterion>"), ("", "<name>")),
}


def key_spec(table: str, key: str) -> Key:
    """The declaration of ``key`` in ``table`` (generic table names: ``thresholds.<name>``).

    Raises:
        LookupError: the key is not declared (a loader reading it is a programming error).
    """
    spec = KEY_INDEX.get((table, key))
    if spec is not None:
        return spec
    for prefix, generic in _WILDCARDS.get(table, ()):
        if key.startswith(prefix):
            return KEY_INDEX[table, generic]
    raise LookupError(f"scene key {table + '.' if table else ''}{key} is not declared in KEYS")


VERBATIM_TABLES: frozenset[str] = frozenset({"hard_case", "mjx"})
"""Tables kept verbatim for a later layer: their keys are not declared here (the hard-case suite
declares and checks ``[hard_case]``, the MJX plant ``[mjx]``)."""


def declared_keys(table: str) -> tuple[str, ...] | None:
    """The keys and sub-tables declared in ``table`` (generic name, ``""`` for the document), in
    the order of the reference; None for a table whose keys are not declared here (a verbatim
    table, or one of any names such as ``[thresholds]``)."""
    if table in VERBATIM_TABLES or table in _WILDCARDS:
        return None
    return tuple(k.key for k in KEYS if k.table == table)


def generic_table(table: str, key: str) -> str:
    """The generic name of the sub-table ``key`` of ``table`` (``thresholds.<name>``)."""
    spec = key_spec(table, key)
    return spec.dotted


EFFECT_WARNING_ORDER: tuple[Effect, ...] = tuple(d.effect for d in DECLARATIONS)
"""The order in which the warning about data of unlisted effects names them (the order of
:func:`effect_keys`): the order of the declarations."""


def effect_keys() -> tuple[Key, ...]:
    """The keys and tables that only an effect reads (:attr:`Key.effect`), grouped by effect in
    :data:`EFFECT_WARNING_ORDER`, in the order of the reference within an effect."""
    keyed = [k for k in KEYS if k.effect is not None]
    return tuple(sorted(keyed, key=lambda k: EFFECT_WARNING_ORDER.index(k.effect)))


CHOICE_MEANINGS: Mapping[StrEnum, str] = {
    **{d.effect: d.meaning for d in DECLARATIONS},
    ShapeKind.NONE: "No picture.",
    ShapeKind.BOX_AND_ROD: "A box (`box_*`) and the rod: Example 1's block with a corner rod.",
    ShapeKind.HOLLOW_CYLINDER_AND_ROD: "A closed hollow cylinder (`cylinder_*`) centred on C "
    "and the rod: Example 2.",
    Weighting.M_INV: "`N = M⁻¹`: Gauss's principle, the paper's choice (Eqs. 74, B12).",
    Weighting.M_INV2: "`N = M⁻²` (Eq. B13).",
    Weighting.IDENTITY: "`N = I`: the plain Euclidean norm of the generalized control force.",
    SolverMethod.DOP853: "Explicit Runge-Kutta of order 8 (the paper used MATLAB's ode113).",
    SolverMethod.RK45: "Explicit Runge-Kutta of order 5(4).",
    SolverMethod.RK23: "Explicit Runge-Kutta of order 3(2).",
    SolverMethod.RADAU: "Implicit Runge-Kutta (Radau IIA) of order 5.",
    SolverMethod.BDF: "Implicit multistep (backward differentiation).",
    SolverMethod.LSODA: "Adams/BDF with automatic stiffness detection.",
    MjIntegrator.EULER: "Semi-implicit Euler.",
    MjIntegrator.RK4: "Fourth-order Runge-Kutta, the controller evaluated in every stage.",
    MjIntegrator.IMPLICIT: "Implicit in velocity.",
    MjIntegrator.IMPLICITFAST: "Implicit in velocity, without the Coriolis derivatives.",
    SpringModel.TENDON: "Fixed tendons with MuJoCo's polynomial stiffness (energy counted by "
    "MuJoCo).",
    SpringModel.ACTUATOR: "One general actuator per spring (affine bias plus a cubic term).",
}
"""What each allowed string of a ``CHOICE`` key means."""


__all__ = [
    "CHOICE_MEANINGS",
    "DEFAULT_GRAVITY",
    "EFFECT_WARNING_ORDER",
    "KEYS",
    "KEY_INDEX",
    "NO_DEFAULT",
    "TABLES",
    "VERBATIM_TABLES",
    "Key",
    "Kind",
    "Need",
    "declared_keys",
    "effect_keys",
    "generic_table",
    "key_spec",
]
