"""The sweep's configuration record, its grid and limits, and the names the other modules share.

:class:`SweepConfig` is the one description of a sweep: ``tumble sweep`` and ``python -m
validation.studies.sweep`` (the same parser, :mod:`validation.cli`) and :func:`validation.studies.sweep.run_sweep`
all start from its defaults; :data:`DEFAULT_SCENE` is the scene every entry uses when none is
given.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass
from typing import Any

from validation.scenes import DEFAULT_SCENE  # the one default scene of every command

PAPER_HORIZON_S = 20.0
"""The horizon of the paper's figures (Sec. V and VII: "a time duration of 20 s"), s."""

LEVELS = tuple(10.0**-k for k in range(3, 11))
"""Accuracy levels of the cheapest-setting table (error ≤ level)."""

REFERENCE_METHOD = "DOP853"
REFERENCE_RTOL = 2.5e-14
"""Just above scipy's floor (100 eps): tighter than every rtol of the sweep."""
REFERENCE_ATOL = 1e-15
REFERENCE_STEP_FRACTION = 0.5
"""The capped reference run's largest step, as a fraction of the uncapped run's mean step."""

FLOOR_FACTOR = 3.0
"""A run's error within this factor of the reference's estimated error is not resolved."""

MJ_MAXVAL = 1e10
"""MuJoCo's ``mjMAXVAL``: a larger |ctrl| is "Nan, Inf or huge value in CTRL"."""

STAGES = {"RK4": 4, "Euler": 1, "implicitfast": 1, "implicit": 1}
"""Dynamics evaluations per MuJoCo step, by integrator."""


class Plant(enum.StrEnum):
    """The plants of the sweep, in report order: the built-ins (``mj_bridge.plants.PLANTS``), whose
    settings grids it knows (scipy rtols, MuJoCo time steps); a plant plugin is not swept
    (``docs/plugins.md``)."""

    ANALYTIC = "analytic"
    MUJOCO = "mujoco"
    PINOCCHIO = "pinocchio"


ANALYTIC, MUJOCO, PINOCCHIO = Plant.ANALYTIC, Plant.MUJOCO, Plant.PINOCCHIO
ENGINES = tuple(Plant)
RTOL_ENGINES = frozenset({ANALYTIC, PINOCCHIO})
"""Plants integrated by scipy: their series run over ``rtols`` (MuJoCo's over ``dts``)."""


class Outcome(enum.StrEnum):
    """How one setting of a series ended (``status`` of a row)."""

    OK = "ok"
    DIVERGED = "diverged"  # non-finite, or error above ``diverge_error``
    FAILED = "failed"  # the engine refused the setting or failed part way
    TOO_SLOW = "too_slow"  # over its wall-time budget (measured) or predicted to be
    SKIPPED = "skipped"  # not run: the series had stopped (the note says why)
    # ran to the end, but not as asked: MuJoCo dropped a control for a step (a sampled control
    # reached MJ_MAXVAL); its error and time are measured and shown, never picked as cheapest
    DEGRADED = "degraded"


@dataclass(frozen=True)
class SweepConfig:
    """The grid, its limits and how runs are timed.

    Attributes:
        t_end: horizon, s (default the paper's 20 s, long enough for a tumbling body's error to
            grow).
        solvers: scipy solvers of the analytic and Pinocchio plants.
        rtols: their relative tolerances, loose to tight; atol = rtol x ``atol_ratio``.
        integrators, dts: MuJoCo integrators and timesteps (s), large to small.
        repeats: most timings per setting (its accuracy run is the first).
        repeat_budget_s: no further timing of a setting once its timings add up to this, s: cheap
            runs (noisy, relatively) get ``repeats`` timings, expensive ones fewer.
        max_run_wall_s: wall-time budget of one run, s: a scipy run is stopped when it passes
            it, and a run predicted to pass it is not started (the series is cut).
        diverge_error: a run whose error exceeds this has diverged.
        deltas, delta_rtols, delta_norm_offset: the stabilisation study (Eq. 58).
        effects_repeats: rounds of the per-evaluation cost of each effect.
        levels: accuracy levels of the cheapest-setting table.
    """

    t_end: float = PAPER_HORIZON_S
    solvers: tuple[str, ...] = ("DOP853", "RK45", "Radau", "LSODA")
    # two decades apart, from a loose rtol to one whose error over 20 s is just above the
    # reference's floor, so every level of LEVELS is reached by some rtol (the errors per rtol:
    # docs/performance.md, The accuracy sweep's grid)
    rtols: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    atol_ratio: float = 0.1
    integrators: tuple[str, ...] = ("RK4", "Euler", "implicitfast", "implicit")
    # a quarter per step: RK4's error falls 4⁴ = 256x, the first-order integrators' 4x; RK4
    # reaches the reference's floor within the grid (where each integrator gets to:
    # docs/performance.md, The accuracy sweep's grid)
    dts: tuple[float, ...] = tuple(1e-2 / 4**k for k in range(5))  # 1e-2 … 3.9e-5 s
    repeats: int = 3
    repeat_budget_s: float = 1.0
    max_run_wall_s: float = 8.0
    diverge_error: float = 1.0
    deltas: tuple[tuple[float, float], ...] = (
        (0.0, 0.0),
        (0.5, 8.0),
        (2.0, 8.0),
        (0.5, 50.0),
        (10.0, 25.0),
    )
    delta_rtols: tuple[float, ...] = (1e-6, 1e-10)
    delta_norm_offset: float = 1e-4
    effects_repeats: int = 15
    levels: tuple[float, ...] = LEVELS

    def __post_init__(self) -> None:
        for name in ("t_end", "atol_ratio", "repeat_budget_s", "max_run_wall_s", "diverge_error"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not (0 < v < math.inf):
                raise ValueError(f"{name}: must be a positive finite number (got {v!r})")
        if isinstance(self.repeats, bool) or not isinstance(self.repeats, int) or self.repeats < 1:
            raise ValueError(f"repeats: must be a whole number ≥ 1 (got {self.repeats!r})")

    @classmethod
    def quick(cls) -> SweepConfig:
        """A small grid (40 runs over 0.5 s, 60 with Pinocchio) for tests and CI.

        Its budget is a safety net only (every run takes a few seconds at most on an idle
        machine): what the quick grid reports must not depend on how loaded the machine is; the
        tests of the budget use made-up clocks.
        """
        return cls(
            t_end=0.5,
            rtols=(1e-3, 1e-5, 1e-7, 1e-9, 1e-11),
            dts=tuple(1e-2 / 2**k for k in range(5)),
            # three timings of every run under 0.1 s in all: the cheapest setting is picked from
            # timings with their spread, and a quick sweep stays short (its duration:
            # docs/performance.md, The accuracy sweep's grid)
            repeats=3,
            repeat_budget_s=0.1,
            max_run_wall_s=60.0,
            deltas=((0.0, 0.0), (0.5, 8.0), (10.0, 25.0)),
            delta_rtols=(1e-10,),
            effects_repeats=5,
        )

    def settings(self, engine: str) -> tuple[float, ...]:
        """The settings of ``engine``'s series: rtols (scipy plants) or dts (MuJoCo)."""
        return self.rtols if engine in RTOL_ENGINES else self.dts

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


__all__ = [
    "ANALYTIC",
    "DEFAULT_SCENE",
    "ENGINES",
    "FLOOR_FACTOR",
    "LEVELS",
    "MJ_MAXVAL",
    "MUJOCO",
    "PAPER_HORIZON_S",
    "PINOCCHIO",
    "REFERENCE_ATOL",
    "REFERENCE_METHOD",
    "REFERENCE_RTOL",
    "REFERENCE_STEP_FRACTION",
    "RTOL_ENGINES",
    "STAGES",
    "Outcome",
    "Plant",
    "SweepConfig",
]
