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

from analytic.effects import Precision
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

ACCELERATED_STAGES = STAGES["RK4"]
"""Dynamics evaluations per step of an accelerated plant (it runs RK4's stages itself)."""

PRECISION_FLOOR_GAIN = 2.0
"""A step a quarter of the last that lowers the error by less than this factor has met the
precision's floor (RK4 would lower it 4⁴ = 256x, a first-order method 4x): the last step is
the smallest that helped, and the series stops after the run that showed it."""


class Plant(enum.StrEnum):
    """The plants of the sweep, in report order: the built-ins (``mj_bridge.plants.PLANTS``), whose
    settings grids it knows (scipy rtols, MuJoCo time steps), and the project's own accelerated
    plants (MJX, MuJoCo Warp: time steps and precisions), swept when installed; any other plant
    plugin is not swept (``docs/plugins.md``)."""

    ANALYTIC = "analytic"
    MUJOCO = "mujoco"
    PINOCCHIO = "pinocchio"
    MJX = "mjx"
    MJWARP = "mjwarp"


ANALYTIC, MUJOCO, PINOCCHIO = Plant.ANALYTIC, Plant.MUJOCO, Plant.PINOCCHIO
MJX, MJWARP = Plant.MJX, Plant.MJWARP
ENGINES = tuple(Plant)
RTOL_ENGINES = frozenset({ANALYTIC, PINOCCHIO})
"""Plants integrated by scipy: their series run over ``rtols`` (MuJoCo's over ``dts``)."""
ACCELERATED = frozenset({MJX, MJWARP})
"""MuJoCo's accelerated implementations: one series per plant and precision, over time steps
(the series' ``method`` is the precision); each run is a process of its own (compilation
included, never timed)."""
FLOAT32_ONLY = frozenset({MJWARP})
"""Accelerated plants that run in float32 only."""


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
        accelerated: the accelerated series, ``(plant, precision)`` (``mjx`` float64 / float32,
            ``mjwarp`` float32), each run only when its plant is installed.
        accelerated_dts: MJX's time steps, s, large to small.
        warp_dts, warp_t_end: MuJoCo Warp's time steps, s, and its horizon, s (shorter than
            ``t_end``: ~19 ms per step on a CPU, a GPU is where it is meant to run).
        accelerated_repeats: timings per accelerated setting (each a fresh process).
        accelerated_max_run_wall_s: the budget of one accelerated run, s, from its first output
            sample (its process start and compilation are not counted).
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
    accelerated: tuple[tuple[str, str], ...] = (
        (MJX, Precision.FLOAT64),
        (MJX, Precision.FLOAT32),
        (MJWARP, Precision.FLOAT32),
    )
    # a quarter per step, as MuJoCo's: RK4 in float64 falls 256x per step to 1e-10 at 1.6e-4 s;
    # in float32 it meets its floor (~1e-7 x the growth of the error) within the first three
    # (the figures: docs/performance.md, Precision in the sweep)
    accelerated_dts: tuple[float, ...] = tuple(1e-2 / 4**k for k in range(4))  # 1e-2 … 1.6e-4 s
    # Warp on a CPU: ~19 ms per step, so 0.5 s at dt 6.25e-4 s is 800 steps, ~15 s
    warp_dts: tuple[float, ...] = tuple(1e-2 / 4**k for k in range(3))  # 1e-2 … 6.25e-4 s
    warp_t_end: float = 0.5
    accelerated_repeats: int = 1
    accelerated_max_run_wall_s: float = 120.0

    def __post_init__(self) -> None:
        for name in (
            "t_end",
            "atol_ratio",
            "repeat_budget_s",
            "max_run_wall_s",
            "diverge_error",
            "warp_t_end",
            "accelerated_max_run_wall_s",
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not (0 < v < math.inf):
                raise ValueError(f"{name}: must be a positive finite number (got {v!r})")
        for name in ("repeats", "accelerated_repeats"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name}: must be a whole number ≥ 1 (got {v!r})")
        for i, entry in enumerate(self.accelerated):
            where = f"accelerated[{i}]"
            if not (isinstance(entry, tuple | list) and len(entry) == 2):
                raise ValueError(f"{where}: must be a (plant, precision) pair (got {entry!r})")
            engine, precision = entry
            if engine not in ACCELERATED:
                allowed = ", ".join(sorted(ACCELERATED))
                raise ValueError(f"{where}: unknown accelerated plant {engine!r} ({allowed})")
            if precision not in tuple(Precision):
                raise ValueError(
                    f"{where}: precision must be float32 or float64 (got {precision!r})"
                )
            if engine in FLOAT32_ONLY and precision != Precision.FLOAT32:
                raise ValueError(f"{where}: {engine} runs in float32 only (got {precision!r})")

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
            accelerated=(),  # their processes and compilation would dominate a quick sweep
        )

    def settings(self, engine: str) -> tuple[float, ...]:
        """The settings of ``engine``'s series: rtols (scipy plants) or dts (MuJoCo, MJX, Warp)."""
        if engine in RTOL_ENGINES:
            return self.rtols
        if engine == MJWARP:
            return self.warp_dts
        return self.accelerated_dts if engine == MJX else self.dts

    def horizon(self, engine: str) -> float:
        """The horizon of ``engine``'s runs, s: ``t_end``, MuJoCo Warp's at most ``warp_t_end``."""
        return min(self.t_end, self.warp_t_end) if engine == MJWARP else self.t_end

    def budget(self, engine: str) -> float:
        """The wall-time budget of one run of ``engine``, s."""
        return self.accelerated_max_run_wall_s if engine in ACCELERATED else self.max_run_wall_s

    def repeats_for(self, engine: str) -> int:
        """The most timings of one setting of ``engine``."""
        return self.accelerated_repeats if engine in ACCELERATED else self.repeats

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


__all__ = [
    "ACCELERATED",
    "ACCELERATED_STAGES",
    "ANALYTIC",
    "DEFAULT_SCENE",
    "ENGINES",
    "FLOAT32_ONLY",
    "FLOOR_FACTOR",
    "LEVELS",
    "MJWARP",
    "MJX",
    "MJ_MAXVAL",
    "MUJOCO",
    "PAPER_HORIZON_S",
    "PINOCCHIO",
    "PRECISION_FLOOR_GAIN",
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
