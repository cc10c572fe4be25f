"""What an effect declares, once: :class:`Declaration` (its meaning, the scene keys only it reads,
how it acts on the masses and the body) and :class:`SpringLaw` (one term of the spring elements'
force, the shape every effect of the ``springs.*`` family takes).

Everything else follows from the declarations (:mod:`analytic.effects.registry`): the scene
format's keys and their reference (``docs/scene-format.md``), parsing, dumping, random scenes and
overflow limits of a spring law's coefficients, the numpy model's generalized force and its energy,
the power it dissipates (the energy balance's ``D``), the fuzzer's space and shrinker. What an
*engine* must do itself (MuJoCo, Pinocchio, Drake each carry the effect their own way, which is the
point of a testbed) is one function per effect in that engine's module, found by the effect's name.

A spring law is linear in its coefficient: ``f = c φ(e, ė)``. Its shape ``φ`` is plain arithmetic
on its arguments, so one function serves numpy arrays (the reference model, the balances) and
scalars in compiled code (:mod:`analytic.kernel.forces` wraps each with numba); its multiplications
are written out (``e * e * e``, not ``e ** 3``) so that the two evaluate it to the same bits.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from analytic.effects import Effect
from analytic.scene.key import Key

Shape = Callable[..., Any]
"""``φ(e, ed)``: one spring element's tension per unit coefficient, from its extension ``e`` (m)
and extension rate ``ed`` (m/s); arrays or scalars alike."""


@dataclass(frozen=True)
class SpringLaw:
    """One term of the n + 1 spring elements' force (Eq. 38's elements, in parallel).

    Spring ``j`` (0-based) joins mass ``j - 1`` and mass ``j`` (the walls at both ends); its
    extension is ``e_j = x_j - x_{j-1}`` with ``x = p - p_e`` and ``x_{-1} = x_n = 0``, and its
    tension ``f_j = Σ c_j φ(e_j, ė_j)`` over the laws that are on. The generalized force on
    mass ``i`` is ``Q_i = f_{i+1} - f_i`` (``F^S = -∂U_s/∂p`` for a conservative law; the paper's
    Eq. 53 with the sign of docs/errata.md item 2).

    Attributes:
        effect: the effect that switches the law on.
        key: its coefficients' declaration in ``[springs]`` (a ``VECTOR_N1``, ≥ 0).
        force: ``φ``, the tension per unit coefficient: ``f = c φ(e, ė)``, N (:data:`Shape`).
        potential: ``ψ(e)``, the energy per unit coefficient, ``U = c ψ(e)`` J with
            ``dψ/de = φ`` (a conservative law); else None.
        dissipation: ``δ(e, ė) = φ ė ≥ 0``, the power per unit coefficient the law takes out of
            the motion, ``P = c δ`` W (a dissipative law); else None.
        random: ``(lo, hi)``: random scenes draw ``c ~ m̄ U(lo, hi)`` (``m̄`` the mean mass), in the
            law's unit.
        fuzz: ``(lo, hi)``: the fuzzer draws ``c = m_min 10^U(lo, hi)`` (``m_min`` the lightest
            mass), for a law that is not ``seeded`` (the seeded ones have their own rules in
            :mod:`validation.studies.fuzz.space`).
        seeded: its coefficients are part of the random scenes' seeded stream (drawn in the order
            of the laws, whatever the effects listed); a law added later is drawn after every
            other draw, and only when its effect is listed, so the seeded scenes of the others do
            not change.
    """

    effect: Effect
    key: Key
    force: Shape
    potential: Shape | None
    dissipation: Shape | None
    random: tuple[float, float]
    fuzz: tuple[float, float] = (-2.0, 1.0)
    seeded: bool = False

    def __post_init__(self) -> None:
        if (self.potential is None) == (self.dissipation is None):
            raise ValueError(f"{self.effect}: a spring law is conservative or dissipative")
        if self.key.table != "springs" or self.key.effect is not self.effect:
            raise ValueError(f"{self.key.dotted}: a spring law's key is in [springs], its own")


@dataclass(frozen=True)
class Declaration:
    """One effect's declaration.

    Attributes:
        effect: the effect.
        meaning: one sentence for the reference (``docs/scene-format.md``'s list of effects).
        keys: the scene keys only this effect reads, beyond its spring law's (their
            :attr:`Key.effect` is this effect), in the order of the reference.
        spring_law: the effect's term of the spring elements' force, for a ``springs.*`` effect.
        needs_masses: the effect acts only on a scene with masses (a rigid body alone drops it).
    """

    effect: Effect
    meaning: str
    keys: tuple[Key, ...] = ()
    spring_law: SpringLaw | None = None
    needs_masses: bool = False


__all__ = ["Declaration", "Shape", "SpringLaw"]
