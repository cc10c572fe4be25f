"""The balances from their terms: the same figures as the invariants' own definitions, and a
planted drift in one term shows in its balance alone."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from analytic.invariants import Balance
from analytic.scene import load_scene
from analytic.simulate import simulate
from analytic.trajectory import RunStatus
from validation.compare.balances import BALANCES, BalanceTerms, relative, spec

SCENES = Path(__file__).resolve().parents[3] / "analytic" / "scenes"


@pytest.fixture(scope="module")
def invariants():
    tr = simulate(load_scene(SCENES / "paper_example1_controlled.toml"), t_end=0.5, rtol=1e-10)
    assert tr.status is RunStatus.OK
    return tr.invariants


def test_every_balance_once_in_report_order():
    assert [s.balance for s in BALANCES] == list(Balance)


@pytest.mark.parametrize("balance", list(Balance))
def test_the_residuals_equal_the_invariants_own(invariants, balance):
    terms = BalanceTerms.of(invariants)
    own = {
        Balance.LINEAR_MOMENTUM: np.linalg.norm(invariants.linear_momentum_balance(), axis=1),
        Balance.ANGULAR_MOMENTUM: np.linalg.norm(invariants.angular_momentum_balance(), axis=1),
        Balance.ENERGY: np.abs(invariants.energy_balance()),
    }[balance]
    np.testing.assert_array_equal(spec(balance).residual(terms), own)


def test_the_dissipated_energy_closes_the_energy_balance(invariants):
    """``E - E(0) + D = W``: energy taken out by a damper, counted as D, leaves it closed; the
    same energy lost without D opens it."""
    terms = BalanceTerms.of(invariants)
    loss = 1e-3 * max(np.max(np.abs(terms.energy)), 1.0) * np.linspace(0, 1, terms.energy.size)
    damped = dataclasses.replace(terms, energy=terms.energy - loss, dissipated=loss)
    assert relative(damped, Balance.ENERGY, 1.0) < 1e-12 + relative(terms, Balance.ENERGY, 1.0)
    leaking = dataclasses.replace(terms, energy=terms.energy - loss)
    assert relative(leaking, Balance.ENERGY, 1.0) > 1e-4


def test_a_planted_work_drift_shows_in_the_energy_balance_alone(invariants):
    terms = BalanceTerms.of(invariants)
    leak = 1e-6 * max(np.max(np.abs(terms.energy)), 1.0)
    drifted = dataclasses.replace(
        terms, work=terms.work + leak * np.linspace(0, 1, terms.work.size)
    )
    assert relative(drifted, Balance.ENERGY, 1.0) > 1e-7
    for b in (Balance.LINEAR_MOMENTUM, Balance.ANGULAR_MOMENTUM):
        assert relative(drifted, b, 1.0) == relative(terms, b, 1.0)


def test_a_non_finite_residual_is_infinite_and_no_sample_is_nan(invariants):
    terms = BalanceTerms.of(invariants)
    energy = terms.energy.copy()
    energy[-1] = math.nan
    assert relative(dataclasses.replace(terms, energy=energy), Balance.ENERGY, 1.0) == math.inf
    fields = (getattr(terms, f.name) for f in dataclasses.fields(terms))
    empty = BalanceTerms(*(np.zeros((0, *np.shape(x)[1:])) for x in fields))
    assert math.isnan(relative(empty, Balance.LINEAR_MOMENTUM, 1.0))
