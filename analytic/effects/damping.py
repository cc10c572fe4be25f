"""Viscous damping of the spring elements, ``springs.damping``: ``f = c ė`` on each of the n + 1
elements, along its extension rate ``ė`` (the force on the masses is ``-c ė`` against the
element's stretching), dissipating ``P = c ė² ≥ 0``.

One :class:`~analytic.effects.declaration.SpringLaw`; see that class for the elements' numbering,
extensions and sign.
"""

from __future__ import annotations

from analytic.effects import Effect
from analytic.effects.declaration import Declaration, SpringLaw
from analytic.scene.key import Key, Kind, Need


def damping_force(e, ed):
    """``φ = ė`` (``f = c ė``)."""
    return ed


def damping_dissipation(e, ed):
    """``δ = ė²`` (``P = c ė²``, W)."""
    return ed * ed


LAW = SpringLaw(
    effect=Effect.SPRINGS_DAMPING,
    key=Key(
        "springs",
        "c_damping",
        Kind.VECTOR_N1,
        "N·s/m",
        "Viscous damping coefficients `c_i` of the same springs, in parallel (force `c ẋ` at "
        "extension rate ẋ, against it).",
        Need.CONDITIONAL,
        default_text="zeros",
        when="required by the effect springs.damping (n > 0)",
        bounds="≥ 0",
        effect=Effect.SPRINGS_DAMPING,
        effect_needs=True,
    ),
    force=damping_force,
    potential=None,
    dissipation=damping_dissipation,
    random=(0.1, 1.0),
)

DECLARATION = Declaration(
    Effect.SPRINGS_DAMPING,
    "Viscous damping `c` of the spring elements, from `springs.c_damping`; the energy it "
    "dissipates is the energy balance's `D`.",
    spring_law=LAW,
    needs_masses=True,
)

__all__ = ["DECLARATION", "LAW"]
