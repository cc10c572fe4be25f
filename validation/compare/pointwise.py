"""The pointwise comparison of engines: one plant's ``q̈`` at given states against MuJoCo C's and
the analytic model's, and what is found.

A plant that offers ``pointwise`` (:meth:`analytic.plant.Plant.pointwise`) gives its ``q̈`` at N
states; MuJoCo C (:meth:`mj_bridge.twin.Twin.acceleration`) and the analytic model
(:meth:`analytic.model.TumblingModel.acceleration`) give theirs at the same states, in float64.
At each state the relative difference of two ``q̈`` (shape (nq,) each, the paper's coordinates
``q = [R, u, p]``, m/s² and 1/s²) is

    ``max_j |a_j - b_j| / max(max_j |b_j|, POINTWISE_FLOOR)``  (:func:`relative_difference`)

``b`` the reference. Its bound at a state (:func:`state_bounds`) is the plant's precision's least
bound (:func:`validation.compare.thresholds.pointwise_threshold`), raised where the two float64
references' own difference shows the state's rounding is larger
(:data:`~validation.compare.thresholds.POINTWISE_MARGIN`). A difference over the bound is a
:class:`PointwiseFinding`: the engines model different bodies at that state, since no integration
has happened yet. This module computes and words; :mod:`validation.validate.pointwise` runs the
engines.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from validation.compare.thresholds import (
    POINTWISE_AGREEMENT,
    POINTWISE_FLOOR,
    POINTWISE_MARGIN,
    pointwise_threshold,
)

EPS64 = float(np.finfo(np.float64).eps)


class Case(StrEnum):
    """Which controller a pointwise evaluation applies."""

    CONTROLLED = "controlled"
    """The scene as it is: its controller (and given torque) applied."""
    UNCONTROLLED = "uncontrolled"
    """The scene with its control effects off: the engine's model alone."""


def relative_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per state, ``max_j |a - b| / max(max_j |b|, POINTWISE_FLOOR)``: ``a``, ``b`` of shape
    (N, nq), ``b`` the reference; shape (N,). A non-finite ``a`` gives ``inf``."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    diff = np.max(np.abs(a - b), axis=-1, initial=0.0)
    scale = np.maximum(np.max(np.abs(b), axis=-1, initial=0.0), POINTWISE_FLOOR)
    out = diff / scale
    return np.where(np.all(np.isfinite(a), axis=-1), out, np.inf)


def state_bounds(precision: Any, references: np.ndarray) -> np.ndarray:
    """The bound of the pointwise difference at each state, shape (N,), for a plant computing in
    ``precision``: ``ε_P · max(POINTWISE_ROUNDOFF, POINTWISE_MARGIN · d/ε64)`` with ``d`` the
    references' own relative difference there (``references``, shape (N,)), counted only where
    it is below :data:`~validation.compare.thresholds.POINTWISE_AGREEMENT` (above, the references
    disagree on the model and measure no rounding)."""
    least = pointwise_threshold(precision).value
    d = np.asarray(references, float)
    rounding = np.where(d <= POINTWISE_AGREEMENT, d, 0.0)
    eps = float(np.finfo(np.dtype(str(getattr(precision, "value", precision)))).eps)
    return np.maximum(least, POINTWISE_MARGIN * rounding / EPS64 * eps)


@dataclass(frozen=True)
class CaseDifferences:
    """One plant's ``q̈`` against both references at every state of one :class:`Case`.

    Attributes:
        case: controlled or uncontrolled.
        states: each state's name (``the initial state``, ``random state 2 (t = 3.1 s)``).
        vs_mujoco, vs_analytic: the plant's relative difference from MuJoCo C / the analytic
            model at each state (:func:`relative_difference`).
        references: MuJoCo C's relative difference from the analytic model at each state.
        bounds: the bound at each state (:func:`state_bounds`).
    """

    case: Case
    states: tuple[str, ...]
    vs_mujoco: tuple[float, ...]
    vs_analytic: tuple[float, ...]
    references: tuple[float, ...]
    bounds: tuple[float, ...]

    @classmethod
    def of(
        cls,
        case: Case,
        states: Sequence[str],
        precision: Any,
        plant: np.ndarray,
        mujoco: np.ndarray,
        analytic: np.ndarray,
    ) -> CaseDifferences:
        """The differences of ``plant``'s ``q̈`` (N, nq) from ``mujoco``'s and ``analytic``'s."""
        refs = relative_difference(mujoco, analytic)
        return cls(
            case,
            tuple(states),
            tuple(map(float, relative_difference(plant, mujoco))),
            tuple(map(float, relative_difference(plant, analytic))),
            tuple(map(float, refs)),
            tuple(map(float, state_bounds(precision, refs))),
        )

    def ratios(self) -> np.ndarray:
        """Each state's larger difference (either reference) over its bound, shape (N,)."""
        return np.maximum(self.vs_mujoco, self.vs_analytic) / np.asarray(self.bounds)

    def worst(self) -> int:
        """The state a finding names: the initial state (the first) when it is over its bound,
        else the state whose difference is the largest against its bound."""
        r = self.ratios()
        return 0 if r[0] > 1 else int(np.argmax(r))

    @property
    def over(self) -> bool:
        """Whether the plant's difference from either reference exceeds the bound at a state."""
        return bool(np.any(self.ratios() > 1))

    def to_dict(self) -> dict[str, Any]:
        return {
            "case": self.case.value,
            "states": list(self.states),
            "vs_mujoco": list(self.vs_mujoco),
            "vs_analytic": list(self.vs_analytic),
            "mujoco_vs_analytic": list(self.references),
            "bounds": list(self.bounds),
        }


@dataclass(frozen=True)
class PointwiseFinding:
    """A plant whose ``q̈`` differs from a reference beyond its bound, at the worst state of a
    case: what a user learns before any run, and a maintainer's lead.

    Attributes:
        plant: the plant's name.
        case: controlled or uncontrolled.
        state: the worst state's name.
        vs_mujoco, vs_analytic: the plant's relative differences there.
        references: MuJoCo C's relative difference from the analytic model there.
        bound: the bound there.
        precision: the plant's precision (``float32``, ``float64``).
        over_states, states: how many of the case's states are over their bound, of how many.
        cause: the effect (``springs.cubic``) whose removal makes the difference vanish, "" when
            none was found or none was looked for.
        cause_text: how the cause reads (``the difference is in springs.cubic (mjx's q̈ is
            MuJoCo C's without it)``), "" with no cause.
    """

    plant: str
    case: Case
    state: str
    vs_mujoco: float
    vs_analytic: float
    references: float
    bound: float
    precision: str
    over_states: int = 1
    states: int = 1
    cause: str = ""
    cause_text: str = ""

    @classmethod
    def of(cls, plant: str, precision: str, diffs: CaseDifferences) -> PointwiseFinding | None:
        """The finding of ``diffs`` (None when every state is within its bound)."""
        if not diffs.over:
            return None
        k = diffs.worst()
        return cls(
            plant,
            diffs.case,
            diffs.states[k],
            diffs.vs_mujoco[k],
            diffs.vs_analytic[k],
            diffs.references[k],
            diffs.bounds[k],
            precision,
            int(np.sum(diffs.ratios() > 1)),
            len(diffs.states),
        )

    @property
    def references_agree(self) -> bool:
        """Whether MuJoCo C and the analytic model agree at the worst state (within the float64
        bound of that state)."""
        return self.references <= state_bounds("float64", np.array([self.references]))[0]

    def text(self) -> str:
        """The finding in one line, as stderr and ``report.md`` give it."""
        p = self.plant
        at = f"at {self.state}, {self.case.value}, in {self.precision}"
        also = f"{self.over_states} of {self.states} states differ; " if self.states > 1 else ""
        if self.vs_mujoco > self.bound and self.references_agree:
            line = (
                f"{p}: q̈ differs from MuJoCo C by {self.vs_mujoco:.1e} relative {at} "
                f"({also}bound {self.bound:.1e}; the analytic model agrees with MuJoCo C to "
                f"{self.references:.0e} there): the models differ, not the integration"
            )
        elif self.vs_mujoco > self.bound:
            line = (
                f"{p}: q̈ differs from MuJoCo C by {self.vs_mujoco:.1e} and from the analytic "
                f"model by {self.vs_analytic:.1e} relative {at} ({also}bound {self.bound:.1e}; "
                f"MuJoCo C and the analytic model differ by {self.references:.1e} there): the "
                "models differ, not the integration"
            )
        else:
            line = (
                f"{p}: q̈ differs from the analytic model by {self.vs_analytic:.1e} relative "
                f"{at} ({also}bound {self.bound:.1e}), as MuJoCo C's does ({p} and MuJoCo C "
                f"agree to {self.vs_mujoco:.0e}): MuJoCo's model differs there, not {p}'s"
            )
        return f"{line}; {self.cause_text}" if self.cause_text else line

    def to_dict(self) -> dict[str, Any]:
        return {
            "plant": self.plant,
            "case": self.case.value,
            "state": self.state,
            "vs_mujoco": self.vs_mujoco,
            "vs_analytic": self.vs_analytic,
            "mujoco_vs_analytic": self.references,
            "bound": self.bound,
            "precision": self.precision,
            "states_over_bound": self.over_states,
            "states": self.states,
            "cause": self.cause,
            "text": self.text(),
        }


@dataclass(frozen=True)
class PlantPointwise:
    """One plant's pointwise comparison: its precision, the least bound, every case."""

    plant: str
    precision: str
    threshold: float
    cases: tuple[CaseDifferences, ...]

    def to_dict(self) -> dict[str, Any]:
        return {
            "plant": self.plant,
            "precision": self.precision,
            "threshold": self.threshold,
            "cases": [c.to_dict() for c in self.cases],
        }


@dataclass(frozen=True)
class PointwiseCheck:
    """Every plant's pointwise comparison before a run (:mod:`validation.validate.pointwise`).

    Attributes:
        plants: the plants that offered ``pointwise``, each compared.
        findings: each difference over its bound, one per plant and case.
        not_checked: one line for each plant whose ``pointwise`` could not be compared (it
            raised something other than a refusal's ``ValueError``, or returned no array of
            the states' shape), naming it and why.
        states: how many states each case evaluates (the initial state and random ones).
        seed: the random states' seed.
        wall_time_s: the check's wall time, s.
    """

    plants: tuple[PlantPointwise, ...] = ()
    findings: tuple[PointwiseFinding, ...] = ()
    not_checked: tuple[str, ...] = ()
    states: int = 0
    seed: int = 0
    wall_time_s: float = 0.0

    @property
    def empty(self) -> bool:
        """Nothing to say: no plant offered ``pointwise``."""
        return not (self.plants or self.not_checked)

    def to_dict(self) -> dict[str, Any]:
        return {
            "states": self.states,
            "seed": self.seed,
            "plants": [p.to_dict() for p in self.plants],
            "findings": [f.to_dict() for f in self.findings],
            "not_checked": list(self.not_checked),
            "wall_time_s": self.wall_time_s,
        }


__all__ = [
    "Case",
    "CaseDifferences",
    "PlantPointwise",
    "PointwiseCheck",
    "PointwiseFinding",
    "relative_difference",
    "state_bounds",
]
