"""The spring elements' conservative laws, ``springs.linear`` and ``springs.cubic`` (Eq. 38):
``f = k^l e`` and ``f = k^n e³``, potentials ``½ k^l e²`` and ``¼ k^n e⁴``.

Each is one :class:`~analytic.effects.declaration.SpringLaw`; see that class for the elements'
numbering, extensions and sign.
"""

from __future__ import annotations

from analytic.effects import Effect
from analytic.effects.declaration import Declaration, SpringLaw
from analytic.scene.key import Key, Kind, Need


def linear_force(e, ed):
    """``φ = e`` (``f = k^l e``, Eq. 38)."""
    return e


def linear_potential(e):
    """``ψ = ½ e²`` (``U = ½ k^l e²``, Eq. 38)."""
    return 0.5 * e**2


def cubic_force(e, ed):
    """``φ = e³`` (``f = k^n e³``, Eq. 38)."""
    return e * e * e


def cubic_potential(e):
    """``ψ = ¼ e⁴`` (``U = ¼ k^n e⁴``, Eq. 38)."""
    return 0.25 * e**4


LINEAR = SpringLaw(
    effect=Effect.SPRINGS_LINEAR,
    key=Key(
        "springs",
        "k_linear",
        Kind.VECTOR_N1,
        "N/m",
        "Linear stiffnesses `k_i^l`; spring 1 joins the near wall and m_1, spring i joins m_(i-1) "
        "and m_i, spring n + 1 joins m_n and the far wall.",
        Need.CONDITIONAL,
        default_text="zeros",
        when="required by the effect springs.linear (n > 0)",
        bounds="≥ 0",
        effect=Effect.SPRINGS_LINEAR,
        effect_needs=True,
    ),
    force=linear_force,
    potential=linear_potential,
    dissipation=None,
    random=(1.0, 10.0),
    seeded=True,
)

CUBIC = SpringLaw(
    effect=Effect.SPRINGS_CUBIC,
    key=Key(
        "springs",
        "k_cubic",
        Kind.VECTOR_N1,
        "N/m³",
        "Cubic stiffnesses `k_i^n`, the same springs in parallel (force `k^n x³` at extension x).",
        Need.CONDITIONAL,
        default_text="zeros",
        when="required by the effect springs.cubic (n > 0)",
        bounds="≥ 0",
        effect=Effect.SPRINGS_CUBIC,
        effect_needs=True,
    ),
    force=cubic_force,
    potential=cubic_potential,
    dissipation=None,
    random=(0.0, 1.0),
    seeded=True,
)

DECLARATIONS = (
    Declaration(
        Effect.SPRINGS_LINEAR,
        "The linear spring elements `k^l` (Eq. 38), from `springs.k_linear`.",
        spring_law=LINEAR,
        needs_masses=True,
    ),
    Declaration(
        Effect.SPRINGS_CUBIC,
        "The cubic spring elements `k^n` (Eq. 38), from `springs.k_cubic`.",
        spring_law=CUBIC,
        needs_masses=True,
    ),
)
"""The two conservative spring effects."""

__all__ = ["CUBIC", "DECLARATIONS", "LINEAR"]
