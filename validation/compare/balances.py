"""The balances of energy and momenta each plant is judged on, from its per-sample terms.

The one definition of each balance as ``tumble validate`` checks it, ``tumble simulate``'s summary
and the sweep report it (:func:`validation.compare.summary.drift_figures`) and the hard cases
measure it:

* linear momentum: ``P - (P(0) + m_T g t + ∫F_C dt)``, residual ``‖·‖₂`` (kg·m/s), scale
  ``max ‖P‖``;
* angular momentum about the system centre of mass: ``L - L(0) - ∫Sτ dt``, residual ``‖·‖₂``
  (kg·m²/s), scale ``max(max ‖L‖, max ‖∫Sτ dt‖)``;
* energy: ``E - E(0) + D - W`` (:func:`analytic.trajectory.energy_residual`), residual ``|·|``
  (J), scale ``max(max |E|, max |W|, max |D|)``; ``D`` the energy the dissipative effects took
  out of the motion (zero without one).

The inputs are the terms alone (:class:`BalanceTerms`, taken from a run's
:class:`~analytic.trajectory.Invariants` by :meth:`BalanceTerms.of`); each check is the largest
residual over the run divided by ``max(scale, floor)`` (:func:`relative`, the floor the
threshold's). A new term of a balance is a field of :class:`BalanceTerms` and a change to
:data:`BALANCES`' residual, scale and label, all in this module; the plants record the term in
their invariants. The formula is also quoted in
words by the thresholds' reasons (:mod:`validation.compare.thresholds`), the hard cases' measure
catalogue (:mod:`validation.studies.hard_cases.catalogue`), the report's figure labels and
``docs/``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from analytic.invariants import Balance
from analytic.trajectory import Invariants, energy_residual


@dataclass(frozen=True)
class BalanceTerms:
    """One run's balance terms per sample, integrals since t = 0 (shapes (N,) or (N, 3)).

    Attributes:
        energy: ``E``, kinetic + gravitational + spring energy, J.
        work: ``W``, the work of the control and the given torque, J.
        angular_momentum: ``L`` about the system centre of mass, inertial, kg·m²/s.
        angular_impulse: ``∫Sτ dt``, the external moments' impulse about it, N·m·s.
        linear_momentum: ``P``, inertial, kg·m/s.
        linear_momentum_expected: ``P(0) + m_T g t + ∫F_C dt``, kg·m/s.
        dissipated: ``D``, the energy the dissipative effects took out of the motion, J; None
            when none is on.
    """

    energy: np.ndarray
    work: np.ndarray
    angular_momentum: np.ndarray
    angular_impulse: np.ndarray
    linear_momentum: np.ndarray
    linear_momentum_expected: np.ndarray
    dissipated: np.ndarray | None = None

    @classmethod
    def of(cls, inv: Invariants) -> BalanceTerms:
        """The terms a run's invariants carry."""
        return cls(
            energy=inv.energy,
            work=inv.work,
            angular_momentum=inv.angular_momentum,
            angular_impulse=inv.angular_impulse,
            linear_momentum=inv.linear_momentum,
            linear_momentum_expected=inv.linear_momentum_expected,
            dissipated=inv.dissipated,
        )


def _max_norm(x: np.ndarray) -> float:
    """max over samples of ‖row‖₂ (of |x| for a 1-D array); 0 for no samples."""
    x = np.asarray(x, float)
    if x.size == 0:
        return 0.0
    return float(np.max(np.linalg.norm(x, axis=1) if x.ndim == 2 else np.abs(x)))


@dataclass(frozen=True)
class BalanceSpec:
    """One balance: its threshold's name, its series' words and its two formulas.

    Attributes:
        balance: which one (its value is the threshold's name and the series' name).
        label: the residual series' label, for people.
        unit: the residual's unit.
        residual: terms -> the residual's magnitude per sample, shape (N,); zero for exact dynamics.
        scale: terms -> the magnitude of what is balanced, in ``unit`` (before any floor).
    """

    balance: Balance
    label: str
    unit: str
    residual: Callable[[BalanceTerms], np.ndarray]
    scale: Callable[[BalanceTerms], float]


BALANCES: tuple[BalanceSpec, ...] = (
    BalanceSpec(
        Balance.LINEAR_MOMENTUM,
        "linear momentum balance |P − P_expected|",
        "kg·m/s",
        lambda b: np.linalg.norm(b.linear_momentum - b.linear_momentum_expected, axis=1),
        lambda b: _max_norm(b.linear_momentum),
    ),
    BalanceSpec(
        Balance.ANGULAR_MOMENTUM,
        "angular momentum balance |L − L(0) − ∫Sτ dt|",
        "kg·m²/s",
        lambda b: np.linalg.norm(
            b.angular_momentum - b.angular_momentum[0] - b.angular_impulse, axis=1
        ),
        lambda b: max(_max_norm(b.angular_momentum), _max_norm(b.angular_impulse)),
    ),
    BalanceSpec(
        Balance.ENERGY,
        "energy balance |E − E(0) + D − W|",
        "J",
        lambda b: np.abs(energy_residual(b.energy, b.work, b.dissipated)),
        lambda b: max(
            _max_norm(b.energy),
            _max_norm(b.work),
            0.0 if b.dissipated is None else _max_norm(b.dissipated),
        ),
    ),
)
"""Every balance, in report order (that of :class:`~analytic.invariants.Balance`)."""

_BY = {s.balance: s for s in BALANCES}


def spec(balance: Balance | str) -> BalanceSpec:
    """The :class:`BalanceSpec` of ``balance`` (a :class:`~analytic.invariants.Balance` or its
    name)."""
    return _BY[Balance(balance)]


def relative(terms: BalanceTerms, balance: Balance | str, floor: float) -> float:
    """``max_t residual / max(scale, floor)`` (dimensionless): the largest residual relative to
    the balanced quantity, the ``floor`` (in the quantity's unit, > 0) keeping a body nearly at rest
    from dividing by ~0. ``inf`` when a residual is not finite; NaN with no sample."""
    s = spec(balance)
    r = s.residual(terms)
    if r.size == 0:
        return math.nan
    if not np.all(np.isfinite(r)):
        return math.inf
    return float(np.max(r)) / max(s.scale(terms), float(floor))


__all__ = ["BALANCES", "BalanceSpec", "BalanceTerms", "relative", "spec"]
