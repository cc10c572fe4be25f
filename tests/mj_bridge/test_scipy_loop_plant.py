"""The plant class of the engines on scipy's loop: the effects each claims are derived from the
functions that implement them, and a plant claiming an effect no function implements is refused
when its class is made."""

from __future__ import annotations

import pytest

from analytic.effects import CONTROL_EFFECTS, Effect
from mj_bridge import drake_effects, pinocchio_effects
from mj_bridge.drake_plugin import DrakePlant
from mj_bridge.pinocchio_settings import PinocchioSettings
from mj_bridge.plants import PinocchioPlant
from mj_bridge.scipy_forces import FORCE_EFFECTS, FORCES
from mj_bridge.scipy_loop_plant import ScipyLoopPlant, scipy_loop_effects


@pytest.mark.parametrize(
    "cls, table",
    [(PinocchioPlant, pinocchio_effects.EFFECTS), (DrakePlant, drake_effects.EFFECTS)],
    ids=["pinocchio", "drake"],
)
def test_effects_are_the_keys_of_the_tables(cls, table):
    """The engine's model effects, the shared forces and the control: nothing else."""
    assert cls.effects == frozenset(table) | frozenset(FORCES) | CONTROL_EFFECTS
    assert cls.effects == scipy_loop_effects(table)
    assert all(callable(fn) for fn in table.values())
    assert frozenset(table).isdisjoint(FORCE_EFFECTS)  # one implementation per effect


def test_a_plant_claiming_an_effect_it_has_no_function_for_is_refused():
    with pytest.raises(TypeError, match=r"claims mass_inertia, which no function"):

        class Claims(ScipyLoopPlant):  # refused at its creation
            engine = "claims"
            label = "Claims"
            settings_type = PinocchioSettings
            integration = "mj_bridge.pinocchio_plant"
            model_effects = frozenset({Effect.GRAVITY})
            effects = scipy_loop_effects({Effect.GRAVITY}) | {Effect.MASS_INERTIA}


def test_a_plant_without_an_effects_function_does_not_claim_it():
    class NoInertia(ScipyLoopPlant):
        engine = "noinertia"
        label = "No inertia"
        settings_type = PinocchioSettings
        integration = "mj_bridge.pinocchio_plant"
        model_effects = frozenset({Effect.GRAVITY})

    assert Effect.MASS_INERTIA not in NoInertia.effects
    assert Effect.GRAVITY in NoInertia.effects
    assert NoInertia().describe(PinocchioSettings(rtol=1e-9)) == "No inertia DOP853 rtol 1e-09"
