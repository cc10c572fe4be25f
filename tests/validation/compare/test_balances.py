"""The balances from their terms: the same figures as the invariants' own definitions, and a
planted drift in one term shows in its balance alone."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from analytic.invariants import Balance, balance_residual, balance_scale, relative_balance
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
def test_the_figures_equal_the_invariants_own(invariants, balance):
    terms = BalanceTerms.of(invariants)
    s = spec(balance)
    np.testing.assert_array_equal(s.residual(terms), balance_residual(invariants, balance))
    assert s.scale(terms) == balance_scale(invariants, balance)
    assert relative(terms, balance, 1.0) == relative_balance(invariants, balance, 1.0)


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
