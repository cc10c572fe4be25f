"""Each spring law's place in the MJCF twin, by its effect (:data:`TENDON_TERMS`): which
polynomial of MuJoCo's fixed tendon carries it (``stiffness`` or ``damping``, MuJoCo integrating
it itself), or the spring actuator's bias with ``spring_model = "actuator"``.

Light on purpose (no MuJoCo import): the MuJoCo plant's claimed effects are read from it when the
plants are listed; :func:`model_xml.builder.build_spec` applies it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from analytic.effects import Effect


@dataclass(frozen=True)
class TendonTerm:
    """How a spring law rides on its element's fixed tendon: the tendon attribute (a polynomial
    in MuJoCo's ``stiffness`` or ``damping``) and the power of its term. ``by_actuator``: with
    ``spring_model = "actuator"`` the term is the spring actuator's bias instead."""

    attribute: str
    power: int
    by_actuator: bool


TENDON_TERMS: Mapping[Effect, TendonTerm] = {
    Effect.SPRINGS_LINEAR: TendonTerm("stiffness", 0, by_actuator=True),  # k^l x
    Effect.SPRINGS_CUBIC: TendonTerm("stiffness", 2, by_actuator=True),  # k^n x³
    Effect.SPRINGS_DAMPING: TendonTerm("damping", 0, by_actuator=False),  # c ẋ
}
"""Each spring law's place in the MJCF twin, by its effect: MuJoCo integrates every one itself."""


TWIN_EFFECTS: frozenset[Effect] = frozenset(
    {
        Effect.GRAVITY,  # the model's gravity
        Effect.MASS_INERTIA,  # the masses' bodies' inertia
        Effect.EXTERNAL_TORQUE,  # applied with the control, inside every stage
        Effect.CONTROL_OMEGA,  # the torque actuators
        Effect.CONTROL_MASSES,  # the rod-force actuators
        *TENDON_TERMS,  # each spring law the twin's tendons (or spring actuators) carry
    }
)
"""The effects the MJCF twin (:func:`model_xml.builder.build_spec`) and its control channels
carry: what every plant that runs the twin under the controller claims (MuJoCo's C engine, MJX,
MuJoCo Warp)."""


__all__ = ["TENDON_TERMS", "TWIN_EFFECTS", "TendonTerm"]
