"""Every effect's declaration, in one tuple: :data:`DECLARATIONS` (the order of the reference and
of the warning about data of unlisted effects), and the lookups the rest of the code reads them
through. A new effect is one module beside this one and one entry here.
"""

from __future__ import annotations

from collections.abc import Mapping

from analytic.effects import Effect
from analytic.effects import damping as _damping
from analytic.effects import springs as _springs
from analytic.effects.declaration import Declaration, SpringLaw

DECLARATIONS: tuple[Declaration, ...] = (
    Declaration(Effect.GRAVITY, "Uniform gravity on BR and every mass (Eq. 46), from `[gravity]`."),
    Declaration(
        Effect.EXTERNAL_TORQUE, "The given torque `[external_torque]` on BR (Remark 2, Eq. 61)."
    ),
    Declaration(
        Effect.CONTROL_OMEGA,
        "Track the angular-velocity requirement `[control.omega]` (Eqs. 82–86).",
    ),
    Declaration(
        Effect.CONTROL_MASSES,
        "Track the mass-position requirement `[control.masses]` (Eqs. 77–81).",
        needs_masses=True,
    ),
    *_springs.DECLARATIONS,
    _damping.DECLARATION,
    Declaration(
        Effect.MASS_INERTIA,
        "The masses' own rotational inertia (Remark 1, Eq. 54), from `masses.ring_radius`, "
        "`inertia_axial` + `inertia_transverse` or `inertia_body`; without it the masses are "
        "points.",
        needs_masses=True,
    ),
)
"""Every effect, once, in the order of the reference."""

BY_EFFECT: Mapping[Effect, Declaration] = {d.effect: d for d in DECLARATIONS}
"""``effect -> its declaration``."""

SPRING_LAWS: tuple[SpringLaw, ...] = tuple(
    d.spring_law for d in DECLARATIONS if d.spring_law is not None
)
"""The spring elements' laws, in the order of the reference (the order their forces are summed)."""

if set(BY_EFFECT) != set(Effect) or len(BY_EFFECT) != len(DECLARATIONS):
    raise RuntimeError("every Effect is declared exactly once in analytic.effects.registry")


def declaration(effect: Effect | str) -> Declaration:
    """The declaration of ``effect``."""
    return BY_EFFECT[Effect(effect)]


def spring_law(effect: Effect | str) -> SpringLaw:
    """The spring law of a ``springs.*`` effect (``LookupError`` for another effect)."""
    law = declaration(effect).spring_law
    if law is None:
        raise LookupError(f"{effect}: not a spring law")
    return law


__all__ = ["BY_EFFECT", "DECLARATIONS", "SPRING_LAWS", "declaration", "spring_law"]
