"""What accuracy costs in time: a work-precision study of the plants on one scene.

``run_sweep(scene, out_dir)`` (CLI: ``tumble sweep [SCENE] [--out DIR]``):

1. **Reference.** The analytic engine (DOP853) at scipy's tightest tolerance (rtol 2.5e-14, below
   every rtol of the sweep), with its steps capped at half the mean step of the same run uncapped.
   Its error is estimated by self-convergence: the difference between the capped and the uncapped
   run, in the error measure below. DOP853 is of order 8, so halving the steps shrinks truncation
   error ~256x: the difference bounds the coarser run's error and hence the reference's (what is
   left is round-off). Runs whose error is within :data:`FLOOR_FACTOR` of that estimate are marked
   ``at_reference_floor`` (their error is not resolved by the reference).
2. **Grid.** The analytic engine over solvers x rtol (atol = rtol x ``atol_ratio``), MuJoCo over
   integrators x timestep, and, when Pinocchio (``pin``) is installed, the Pinocchio plant over the
   same solvers x rtol as the analytic engine (through the plant protocol,
   ``plant("pinocchio").simulate(scene, PinocchioSettings(method, rtol, atol))``); one series per
   plant and solver / integrator, from cheap to expensive. Without ``pin`` the Pinocchio series are
   skipped and ``sweep.md`` / ``sweep.json`` say so. A series stops when a run is too slow
   (measured for the scipy plants: interrupted at ``max_run_wall_s``; predicted for MuJoCo: cost
   ∝ 1/dt from the previous run) or fails/diverges after an earlier setting worked; the settings
   not run are listed as ``skipped`` with the reason.
3. **Per run**: error against the reference on the common output samples, final and maximum over
   the trajectory, of the position of C (relative to the largest displacement of C in the
   reference), the attitude (angle of the relative rotation, rad) and the rod positions (relative to
   the largest |p| in the reference); ``error`` is the largest of the three maxima (the accuracy
   that the levels refer to). Invariant drifts (:func:`validation.summary.drift_figures`), final
   tracking errors, and cost: median wall time of ``repeats`` runs timed serially in this process
   (one run at a time, repeats round-robin over the grid; the integration only, as measured by
   the engines), right-hand-side
   evaluations (analytic and Pinocchio ``nfev``; MuJoCo steps x stages, 4 for RK4) and steps.
   A MuJoCo run is ``diverged`` when it is non-finite or its error exceeds ``diverge_error`` (MuJoCo
   resets an unstable simulation to its initial state, so a diverged run can look finite).
4. **Stabilisation**: the quaternion norm error under several (δ1, δ2), from the exact initial
   attitude and from one off the unit sphere by ``delta_norm_offset``.
5. **Effects**: the cost of one dynamics evaluation with each effect switched off, the analytic
   engine and MuJoCo (:mod:`validation.effects_cost`).

Accuracy runs go through a ``concurrent.futures`` executor (a local process pool unless one is
passed, e.g. a Dask ``Client.get_executor()``); timings are taken afterwards one run at a time,
after a warm-up run of every plant and method (JIT compilation and cache loading stay outside).

Outputs in ``out_dir`` (each written atomically): ``sweep.csv`` and ``sweep.json`` (every run),
``sweep.md`` (tables; for each plant the cheapest setting reaching each accuracy level
1e-3 … 1e-10 marked), ``work_precision.png`` and ``sweep.rrd`` (one series per plant and method).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # small matrices: one BLAS thread (also in pool workers)

import csv  # noqa: E402
import dataclasses  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import multiprocessing  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable, Mapping, Sequence  # noqa: E402
from concurrent.futures import Executor, ProcessPoolExecutor  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from analytic.scene import Scene, SolverSettings, Stabilization  # noqa: E402
from validation.atomic import write_bytes, write_text  # noqa: E402
from validation.outputs import output_run  # noqa: E402

DEFAULT_SCENE = "paper_example1_controlled"
LEVELS = tuple(10.0**-k for k in range(3, 11))
"""Accuracy levels of the cheapest-setting table (error ≤ level)."""
REFERENCE_RTOL = 2.5e-14
"""Just above scipy's floor (100 eps): tighter than every rtol of the sweep."""
REFERENCE_ATOL = 1e-15
FLOOR_FACTOR = 3.0
"""A run's error within this factor of the reference's estimated error is not resolved."""
ANALYTIC = "analytic"
MUJOCO = "mujoco"
PINOCCHIO = "pinocchio"
ENGINES = (ANALYTIC, MUJOCO, PINOCCHIO)
"""The plants of the sweep, in report order (as ``mj_bridge.plants.PLANTS``)."""
RTOL_ENGINES = frozenset({ANALYTIC, PINOCCHIO})
"""Plants integrated by scipy: their series run over ``rtols`` (MuJoCo's over ``dts``)."""
MJ_MAXVAL = 1e10  # MuJoCo's mjMAXVAL: a larger |ctrl| is "Nan, Inf or huge value in CTRL"
STAGES = {"RK4": 4, "Euler": 1, "implicitfast": 1, "implicit": 1}

# Columns of sweep.csv, in order (every row has every key; None when not applicable).
COLUMNS = (
    "run_id",
    "engine",
    "method",
    "setting_name",
    "setting",
    "rtol",
    "atol",
    "dt",
    "status",
    "note",
    "error",
    "error_final",
    "err_pos_max",
    "err_pos_final",
    "err_att_max",
    "err_att_final",
    "err_rod_max",
    "err_rod_final",
    "at_reference_floor",
    "quat_norm_error_max",
    "angular_momentum_balance_rel",
    "energy_balance_rel",
    "linear_momentum_balance_rel",
    "tracking_omega_final",
    "tracking_p_final",
    "wall_time_s",
    "wall_time_repeats",
    "wall_time_pool_s",
    "nfev",
    "nsteps",
)
# Columns that are not floats; every other column is (csv round trip).
NON_FLOAT_COLUMNS = frozenset(
    {
        "run_id",
        "engine",
        "method",
        "setting_name",
        "status",
        "note",
        "at_reference_floor",
        "nfev",
        "nsteps",
        "wall_time_repeats",
    }
)
FLOAT_COLUMNS = frozenset(COLUMNS) - NON_FLOAT_COLUMNS
INT_COLUMNS = frozenset({"wall_time_repeats", "nfev", "nsteps"})
BOOL_COLUMNS = frozenset({"at_reference_floor"})


@dataclass(frozen=True)
class SweepConfig:
    """The grid and its limits. ``SweepConfig.quick()`` is the small grid of tests and CI."""

    t_end: float = 2.0
    solvers: tuple[str, ...] = ("DOP853", "RK45", "Radau", "LSODA")
    rtols: tuple[float, ...] = tuple(10.0**-k for k in range(3, 14))
    atol_ratio: float = 0.1
    integrators: tuple[str, ...] = ("RK4", "Euler", "implicitfast", "implicit")
    dts: tuple[float, ...] = tuple(1e-2 / 2**k for k in range(11))  # 1e-2 … 9.8e-6 s, halving
    repeats: int = 3
    max_run_wall_s: float = 30.0
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

    @classmethod
    def quick(cls) -> SweepConfig:
        """A small grid (40 runs over 0.5 s, 60 with Pinocchio) for tests and CI."""
        return cls(
            t_end=0.5,
            rtols=(1e-3, 1e-5, 1e-7, 1e-9, 1e-11),
            dts=tuple(1e-2 / 2**k for k in range(5)),
            repeats=1,
            max_run_wall_s=5.0,
            deltas=((0.0, 0.0), (0.5, 8.0), (10.0, 25.0)),
            delta_rtols=(1e-10,),
            effects_repeats=5,
        )

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class SweepResult:
    """The outcome of :func:`run_sweep`.

    Attributes:
        scene: the scene's name.
        out_dir: where the files are.
        config: the grid and limits used (:class:`SweepConfig` as a dict).
        reference: how the reference was computed, its cost and estimated error.
        runs: one row per setting (keys :data:`COLUMNS`), in grid order.
        cheapest: ``{engine: {level: run_id or None}}``, the cheapest run (median wall time) whose
            error is at most the level, for every plant that ran.
        stabilization: rows of the (δ1, δ2) study.
        effects: rows of the per-evaluation cost with each effect off.
        skipped_series: ``{engine: reason}`` for the plants whose series were not run (Pinocchio
            when ``pin`` is not installed).
        files: name -> path of every file written.
        wall_time_s: the whole sweep.
    """

    scene: str
    out_dir: Path
    config: Mapping[str, Any]
    reference: Mapping[str, Any]
    runs: tuple[Mapping[str, Any], ...]
    cheapest: Mapping[str, Mapping[float, int | None]]
    stabilization: tuple[Mapping[str, Any], ...]
    effects: tuple[Mapping[str, Any], ...]
    skipped_series: Mapping[str, str] = field(default_factory=dict)
    files: Mapping[str, Path] = field(default_factory=dict)
    wall_time_s: float = 0.0

    def run(self, run_id: int) -> Mapping[str, Any]:
        return self.runs[run_id]


# ----------------------------------------------------------------------------------------------
# Errors against the reference
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RefSamples:
    """What a worker needs of the reference: the sampled motion and the error scales."""

    t: np.ndarray
    R: np.ndarray
    u: np.ndarray
    p: np.ndarray
    R_scale: float
    p_scale: float


def ref_samples(tr) -> RefSamples:
    R_scale = float(np.max(np.linalg.norm(tr.R - tr.R[0], axis=1)))
    p_scale = float(np.max(np.abs(tr.p))) if tr.p.size else 0.0
    return RefSamples(
        tr.t.copy(),
        tr.R.copy(),
        tr.u.copy(),
        tr.p.copy(),
        R_scale if R_scale > 0 else 1.0,
        p_scale if p_scale > 0 else 1.0,
    )


def errors_against(tr, ref: RefSamples) -> dict[str, float]:
    """Final and max-over-trajectory errors of ``tr`` against the reference (same sample times).

    Position of C relative to ``ref.R_scale``, attitude as the angle of the relative rotation
    (rad), rod positions relative to ``ref.p_scale``; ``error`` = the largest maximum.
    NaN everywhere when the run has no finite samples in common with the reference.
    """
    from validation.compare import attitude_angle

    n = min(len(tr.t), len(ref.t))
    keys = ("pos", "att", "rod")
    if n < 2 or not np.allclose(tr.t[:n], ref.t[:n], rtol=0, atol=1e-9):
        out = {f"err_{k}_{s}": math.nan for k in keys for s in ("max", "final")}
        out.update(error=math.nan, error_final=math.nan)
        return out
    e = {
        "pos": np.linalg.norm(tr.R[:n] - ref.R[:n], axis=1) / ref.R_scale,
        "att": attitude_angle(tr.u[:n], ref.u[:n]),
        "rod": (
            np.max(np.abs(tr.p[:n] - ref.p[:n]), axis=1) / ref.p_scale
            if ref.p.shape[1]
            else np.zeros(n)
        ),
    }
    out = {}
    for k, v in e.items():
        bad = not np.all(np.isfinite(v))
        out[f"err_{k}_max"] = math.inf if bad else float(np.max(v))
        out[f"err_{k}_final"] = float(v[-1]) if np.isfinite(v[-1]) else math.inf
    out["error"] = max(out[f"err_{k}_max"] for k in keys)
    out["error_final"] = max(out[f"err_{k}_final"] for k in keys)
    return out


def _drifts(tr) -> dict[str, float]:
    from validation.summary import drift_figures

    try:
        return {k: float(v) for k, v in drift_figures(tr).items()}
    except (ValueError, FloatingPointError):
        return {}


def _tracking(tr) -> dict[str, float | None]:
    tk = tr.tracking
    w = float(np.max(np.abs(tk.e_omega[-1]))) if tk.e_omega.size else None
    p = float(np.max(np.abs(tk.e_p[-1]))) if tk.e_p.size else None
    return {"tracking_omega_final": w, "tracking_p_final": p}


# ----------------------------------------------------------------------------------------------
# Runs (module-level functions: they travel to pool workers and Dask)
# ----------------------------------------------------------------------------------------------


class _TooSlow(KeyboardInterrupt):
    """Raised from a scipy plant's progress callback; the plant ends the run interrupted."""


TOO_SLOW_INFO = "stopped_over_budget"
"""``Trajectory.info`` key set (True) on a run that :func:`_analytic_run` or
:func:`_pinocchio_run` stopped for its budget."""


def _within_budget(run: Callable[[Callable[[float], None] | None], Any], budget: float | None):
    """``run(progress)`` (a scipy plant's run), stopped when it takes more than ``budget`` s.

    A run stopped for its budget comes back INTERRUPTED with ``info[TOO_SLOW_INFO]``; a run
    interrupted by the user (Ctrl-C, SIGTERM) raises KeyboardInterrupt, so the sweep stops.
    """
    from analytic.trajectory import RunStatus

    progress = None
    over = []
    if budget is not None:
        start = time.perf_counter()

        def progress(_t: float) -> None:
            if time.perf_counter() - start > budget:
                over.append(True)
                raise _TooSlow

    with warnings.catch_warnings():
        # the plants' quadrature states carry atol 1e300 (outside error control); scipy's
        # first-step heuristic then overflows harmlessly
        warnings.filterwarnings("ignore", "overflow encountered", RuntimeWarning)
        tr = run(progress)
    if tr.status is RunStatus.INTERRUPTED:
        if not over:
            tr.raise_if_interrupted()
        tr = dataclasses.replace(tr, info={**tr.info, TOO_SLOW_INFO: True})
    return tr


def _analytic_run(scene: Scene, method: str, rtol: float, atol: float, t_end: float, budget=None):
    """One analytic run; with ``budget`` (s of wall time), stopped when it exceeds it
    (:func:`_within_budget`)."""
    import analytic

    return _within_budget(
        lambda progress: analytic.simulate(
            scene, method=method, rtol=rtol, atol=atol, t_end=t_end, progress=progress
        ),
        budget,
    )


def _pinocchio_run(scene: Scene, method: str, rtol: float, atol: float, t_end: float, budget=None):
    """One Pinocchio run through the plant protocol; ``budget`` as for :func:`_analytic_run`."""
    from mj_bridge.plants import PinocchioSettings, plant

    settings = PinocchioSettings(method, rtol, atol)
    return _within_budget(
        lambda progress: plant(PINOCCHIO).simulate(scene, settings, t_end=t_end, progress=progress),
        budget,
    )


def _scipy_run(engine: str, *args, **kw):
    """:func:`_analytic_run` or :func:`_pinocchio_run`, by ``engine``."""
    if engine == PINOCCHIO:
        return _pinocchio_run(*args, **kw)
    return _analytic_run(*args, **kw)


def _mujoco_run(scene: Scene, integrator: str, dt: float, t_end: float):
    import mj_bridge

    return mj_bridge.simulate(
        scene, integrator=integrator, dt=dt, t_end=t_end
    ).raise_if_interrupted()


def pinocchio_unavailable() -> str:
    """Why the Pinocchio series cannot run here ("" when ``pin`` is installed)."""
    from mj_bridge.plants import PinocchioPlant

    return PinocchioPlant.unavailable()


def _blank_row(engine: str, method: str, setting: float, cfg: SweepConfig) -> dict[str, Any]:
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(engine=engine, method=method, setting=setting, note="")
    if engine in RTOL_ENGINES:
        row.update(setting_name="rtol", rtol=setting, atol=setting * cfg.atol_ratio)
    else:
        row.update(setting_name="dt", dt=setting)
    return row


def _fill_row(row: dict[str, Any], tr, ref: RefSamples) -> None:
    row.update(errors_against(tr, ref))
    row.update(_drifts(tr))
    row.update(_tracking(tr))
    row["wall_time_pool_s"] = float(tr.info["wall_time_s"])
    row["nsteps"] = int(tr.info.get("nsteps", 0))
    if row["engine"] in RTOL_ENGINES:
        row["nfev"] = int(tr.info["nfev"])
    else:
        row["nfev"] = row["nsteps"] * STAGES.get(row["method"], 1)
        big = max(
            float(np.max(np.abs(tr.torque), initial=0.0)),
            float(np.max(np.abs(tr.rod_forces), initial=0.0)),
        )
        if big >= MJ_MAXVAL:
            row["note"] = (
                f"a sampled control reached {big:.3g} ≥ {MJ_MAXVAL:g}: MuJoCo treats such a ctrl "
                "as unstable and drops it for that step"
            )


def run_series(
    scene: Scene, engine: str, method: str, cfg: SweepConfig, ref: RefSamples
) -> list[dict[str, Any]]:
    """One solver of a scipy plant (``analytic`` or ``pinocchio``: rtols loose → tight) or one
    MuJoCo integrator (dts large → small); rows for every setting.

    Stops on a run that is too slow, or that fails or diverges after an earlier setting worked;
    the rest of the series is reported as ``skipped`` with the reason.
    """
    settings = cfg.rtols if engine in RTOL_ENGINES else cfg.dts
    rows: list[dict[str, Any]] = []
    stop_reason = ""
    any_ok = False
    last_ok: tuple[float, float] | None = None  # (setting, wall) of the last finished run
    for s in settings:
        row = _blank_row(engine, method, s, cfg)
        rows.append(row)
        if stop_reason:
            row.update(status="skipped", note=stop_reason)
            continue
        if engine == MUJOCO and last_ok is not None:
            predicted = last_ok[1] * last_ok[0] / s
            if predicted > cfg.max_run_wall_s:
                stop_reason = (
                    f"too slow: predicted {predicted:.3g} s > {cfg.max_run_wall_s:g} s "
                    f"(cost ∝ 1/dt from dt = {last_ok[0]:.3g} s)"
                )
                row.update(status="too_slow", note=stop_reason)
                stop_reason = f"series stopped at dt = {s:.3g} s: {stop_reason}"
                continue
        try:
            if engine in RTOL_ENGINES:
                tr = _scipy_run(
                    engine,
                    scene,
                    method,
                    s,
                    s * cfg.atol_ratio,
                    cfg.t_end,
                    budget=cfg.max_run_wall_s,
                )
            else:
                tr = _mujoco_run(scene, method, s, cfg.t_end)
        except Exception as exc:  # a setting the engine refuses is a result, not a crash
            row.update(status="failed", note=f"{type(exc).__name__}: {exc}")
            if any_ok:
                stop_reason = f"series stopped: failed at {s:.3g}"
            continue
        _fill_row(row, tr, ref)
        if engine in RTOL_ENGINES and tr.info.get(TOO_SLOW_INFO):
            row.update(
                status="too_slow",
                note=f"interrupted after {cfg.max_run_wall_s:g} s ({tr.message})",
            )
            stop_reason = f"series stopped: rtol {s:.3g} took longer than {cfg.max_run_wall_s:g} s"
            continue
        if tr.status.value != "ok":
            row.update(status="failed", note=tr.message)
        elif not (math.isfinite(row["error"]) and row["error"] <= cfg.diverge_error):
            row.update(
                status="diverged",
                note=f"error {row['error']:.3g} > {cfg.diverge_error:g} (or not finite)",
            )
        else:
            row["status"] = "ok"
            any_ok = True
            last_ok = (s, row["wall_time_pool_s"])
            continue
        if any_ok:
            stop_reason = f"series stopped: {row['status']} at {row['setting_name']} = {s:.3g}"
    return rows


def reference_run(scene: Scene, t_end: float, max_step: float = math.inf):
    """The analytic engine at the reference tolerance (DOP853), steps capped at ``max_step``."""
    import analytic

    sc = scene.replace(
        solver=SolverSettings(
            method="DOP853", rtol=REFERENCE_RTOL, atol=REFERENCE_ATOL, max_step=max_step
        )
    )
    return analytic.simulate(sc, t_end=t_end)


def _reference_task(scene: Scene, t_end: float, max_step: float) -> dict[str, Any]:
    tr = reference_run(scene, t_end, max_step)
    return {
        "samples": ref_samples(tr),
        "status": tr.status.value,
        "message": tr.message,
        "nfev": int(tr.info["nfev"]),
        "nsteps": int(tr.info["nsteps"]),
        "wall_time_s": float(tr.info["wall_time_s"]),
        "drift": _drifts(tr),
    }


def stabilization_row(
    scene: Scene, delta1: float, delta2: float, rtol: float, offset: float, t_end: float
) -> dict[str, Any]:
    """Quaternion norm error of one analytic run with (δ1, δ2), initial |u| = 1 + ``offset``."""
    u0 = scene.initial.u * (1.0 + offset)
    sc = scene.replace(
        stabilization=Stabilization(delta1=delta1, delta2=delta2),
        initial=dataclasses.replace(scene.initial, u=u0),
    )
    tr = _analytic_run(sc, "DOP853", rtol, rtol * 0.1, t_end)
    e = tr.invariants.quat_norm_error
    return {
        "delta1": delta1,
        "delta2": delta2,
        "rtol": rtol,
        "initial_norm_error": float(u0 @ u0 - 1.0),
        "status": tr.status.value,
        "quat_norm_error_final": float(e[-1]),
        "quat_norm_error_max": float(np.max(np.abs(e))),
        "quat_norm_error_at_steps_max": float(tr.info["max_quat_norm_error_at_steps"]),
        "nfev": int(tr.info["nfev"]),
        "t_end": float(tr.t[-1]),
    }


# ----------------------------------------------------------------------------------------------
# Timing, selection, output
# ----------------------------------------------------------------------------------------------


def _time_once(scene: Scene, row: Mapping[str, Any], cfg: SweepConfig) -> float:
    """Wall time (s) of one run of a setting, as the engine measures it (integration only)."""
    if row["engine"] in RTOL_ENGINES:
        tr = _scipy_run(row["engine"], scene, row["method"], row["rtol"], row["atol"], cfg.t_end)
    else:
        tr = _mujoco_run(scene, row["method"], row["dt"], cfg.t_end)
    return float(tr.info["wall_time_s"])


def warm_compiled(scene: Scene, skipped: Mapping[str, str]) -> None:
    """One output interval on every plant that runs (the compiled kernels built and cached)."""
    interval = 1.0 / scene.output.rate
    for engine in RTOL_ENGINES:
        if engine not in skipped:
            _scipy_run(engine, scene, "DOP853", 1e-6, 1e-8, interval)
    _mujoco_run(scene, "RK4", scene.mujoco.timestep, interval)


def warm_up(scene: Scene, runs: Sequence[Mapping[str, Any]]) -> None:
    """One short run (one output interval, at the first setting that ran ``ok``) of every plant and
    method among the ``ok`` runs, so that compilation, cache loads and first-call imports stay out
    of the timings."""
    interval = 1.0 / scene.output.rate
    done = set()
    for r in runs:
        key = (r["engine"], r["method"])
        if r["status"] != "ok" or key in done:
            continue
        done.add(key)
        if r["engine"] in RTOL_ENGINES:
            _scipy_run(r["engine"], scene, r["method"], r["rtol"], r["atol"], interval)
        else:
            _mujoco_run(scene, r["method"], r["dt"], interval)


def time_runs(scene: Scene, runs: Sequence[dict[str, Any]], cfg: SweepConfig) -> None:
    """Fill ``wall_time_s`` (median) and ``wall_time_repeats`` of the ``ok`` runs, serially.

    Repeats go round-robin over the runs (every run once, then again …), so that a slow spell of a
    shared machine is spread over many settings instead of biasing one. A run whose first timing
    exceeds ``max_run_wall_s / repeats`` is not repeated. Runs that are not ``ok`` keep the wall
    time of their accuracy run with ``wall_time_repeats = 0``.
    """
    todo = [r for r in runs if r["status"] == "ok"]
    walls: dict[int, list[float]] = {id(r): [] for r in todo}
    for k in range(max(1, cfg.repeats)):
        for r in todo:
            if k > 0 and walls[id(r)][0] * cfg.repeats > cfg.max_run_wall_s:
                continue
            walls[id(r)].append(_time_once(scene, r, cfg))
    for r in runs:
        if r["status"] == "ok":
            r["wall_time_s"] = statistics.median(walls[id(r)])
            r["wall_time_repeats"] = len(walls[id(r)])
        elif r["wall_time_pool_s"] is not None:
            r["wall_time_s"], r["wall_time_repeats"] = r["wall_time_pool_s"], 0


def cheapest_settings(
    runs: Sequence[Mapping[str, Any]],
    levels: Sequence[float] = LEVELS,
    floor: float = 0.0,
    engines: Sequence[str] | None = None,
) -> dict[str, dict[float, int | None]]:
    """For each engine and level, the ``ok`` run of least median wall time with error ≤ level.

    Levels at or below ``floor`` (what the reference can resolve) get None. ``engines``: the plants
    to report, in order (default: those of :data:`ENGINES` that have runs).
    """
    if engines is None:
        engines = [e for e in ENGINES if any(r["engine"] == e for r in runs)]
    out: dict[str, dict[float, int | None]] = {}
    for engine in engines:
        ok = [
            r
            for r in runs
            if r["engine"] == engine
            and r["status"] == "ok"
            and r["error"] is not None
            and r["wall_time_s"] is not None
        ]
        out[engine] = {}
        for lv in levels:
            cand = [r for r in ok if r["error"] <= lv] if lv > floor else []
            best = min(cand, key=lambda r: (r["wall_time_s"], r["run_id"]), default=None)
            out[engine][lv] = None if best is None else int(best["run_id"])
    return out


def _fmt(v: Any, spec: str = ".3g") -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else ""
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return format(v, spec)
    return str(v)


def _csv_cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)  # shortest repr that round-trips exactly
    return str(v)


def to_csv(runs: Sequence[Mapping[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in runs:
        w.writerow([_csv_cell(r[c]) for c in COLUMNS])
    return buf.getvalue()


def read_csv(path: str | Path) -> list[dict[str, Any]]:
    """Rows of ``sweep.csv`` with their types restored (empty cells -> None)."""
    rows = []
    with open(path, newline="", encoding="utf-8") as f:
        for raw in csv.DictReader(f):
            row: dict[str, Any] = {}
            for k, v in raw.items():
                if v == "" and k != "note":
                    row[k] = None
                elif k in FLOAT_COLUMNS:
                    row[k] = float(v)
                elif k in INT_COLUMNS or k == "run_id":
                    row[k] = int(v)
                elif k in BOOL_COLUMNS:
                    row[k] = v == "true"
                else:
                    row[k] = v
            rows.append(row)
    return rows


def _json_safe(x: Any) -> Any:
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, Mapping):
        return {str(k): _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    if isinstance(x, Path):
        return str(x)
    if isinstance(x, np.generic):
        return x.item()
    return x


def skipped_note(engine: str, reason: str) -> str:
    """The sentence ``sweep.md`` gives for a plant whose series were skipped."""
    if engine == PINOCCHIO:
        return f"Pinocchio series skipped: pin is not installed ({reason})"
    return f"{engine} series skipped: {reason}"


def _plants_markdown(
    cfg: SweepConfig, runs: Sequence[Mapping[str, Any]], skipped: Mapping[str, str]
) -> list[str]:
    """One bullet per plant: its series, or why they were skipped."""
    rtols = ", ".join(f"{r:.0e}" for r in cfg.rtols)
    dts = f"{max(cfg.dts):.3g} … {min(cfg.dts):.3g} s" if cfg.dts else "none"
    what = {
        ANALYTIC: f"the paper's model, scipy {', '.join(cfg.solvers)} over rtol {rtols} "
        f"(atol = {cfg.atol_ratio:g} rtol)",
        MUJOCO: f"the MJCF twin, {', '.join(cfg.integrators)} over dt {dts}",
        PINOCCHIO: "the same body in Pinocchio (`pin.aba`), the same scipy solvers and rtol grid "
        "as the analytic engine, through the plant protocol",
    }
    out = []
    for e in ENGINES:
        if e in skipped:
            out.append(f"- **{e}**: {skipped_note(e, skipped[e])}.")
            continue
        mine = [r for r in runs if r["engine"] == e]
        if not mine:
            continue
        ok = sum(r["status"] == "ok" for r in mine)
        out.append(f"- **{e}**: {what[e]}; {ok}/{len(mine)} runs ok.")
    out += [
        "",
        "Every plant is measured against the same reference (the analytic engine's), with the same "
        "error measure and the same timing rules (warm-up run first, median of serial repeats, "
        "the same budget per run).",
    ]
    return out


def _pinocchio_vs_analytic_markdown(runs: Sequence[Mapping[str, Any]]) -> list[str]:
    """The two scipy plants side by side at each solver and rtol they both ran."""
    a = {(r["method"], r["rtol"]): r for r in runs if r["engine"] == ANALYTIC}
    pairs = [
        (a[(r["method"], r["rtol"])], r)
        for r in runs
        if r["engine"] == PINOCCHIO and (r["method"], r["rtol"]) in a
    ]
    if not pairs:
        return []
    L = [
        "",
        "## Pinocchio and the analytic engine at the same setting",
        "",
        "Same solver, rtol and atol; errors against the same reference.",
        "",
        "| method | rtol | analytic error | Pinocchio error | analytic ms | Pinocchio ms | "
        "wall ratio | analytic nfev | Pinocchio nfev |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for ra, rp in pairs:
        wa, wp = ra["wall_time_s"], rp["wall_time_s"]
        ratio = wp / wa if wa and wp and ra["status"] == rp["status"] == "ok" else None
        L.append(
            f"| {rp['method']} | {rp['rtol']:.0e} | "
            f"{_fmt(ra['error'], '.2e') if ra['status'] == 'ok' else ra['status']} | "
            f"{_fmt(rp['error'], '.2e') if rp['status'] == 'ok' else rp['status']} | "
            f"{_fmt(None if wa is None else wa * 1e3, '.3g')} | "
            f"{_fmt(None if wp is None else wp * 1e3, '.3g')} | {_fmt(ratio, '.2f')} | "
            f"{_fmt(ra['nfev'])} | {_fmt(rp['nfev'])} |"
        )
    return L


def _markdown(res_parts: dict[str, Any]) -> str:
    cfg: SweepConfig = res_parts["cfg"]
    ref = res_parts["reference"]
    runs = res_parts["runs"]
    cheapest = res_parts["cheapest"]
    skipped = res_parts.get("skipped_series", {})
    columns = list(cheapest) + [e for e in skipped if e not in cheapest]
    marked = {rid: [] for rid in range(len(runs))}
    for by_level in cheapest.values():
        for lv, rid in by_level.items():
            if rid is not None:
                marked[rid].append(lv)
    L = [
        f"# What accuracy costs in time: {res_parts['scene']}",
        "",
        f"Horizon {cfg.t_end:g} s. Error = the largest over the trajectory of: position of C "
        f"relative to its largest displacement ({ref['R_scale']:.4g} m), attitude angle (rad), rod "
        f"positions relative to the largest |p| ({ref['p_scale']:.4g} m), against the reference. "
        f"Wall time: median of up to {cfg.repeats} serial runs (integration only).",
        "",
        "## Reference",
        "",
        f"Analytic engine, DOP853, rtol {REFERENCE_RTOL:g}, atol {REFERENCE_ATOL:g}, steps capped "
        f"at {ref['max_step']:.3g} s (half the mean step uncapped): {ref['nfev']} evaluations, "
        f"{ref['wall_time_s']:.3g} s. **Estimated error {ref['error_estimate']:.2e}** "
        f"(self-convergence: difference to the uncapped run; position "
        f"{ref['error_components']['pos']:.2e}, attitude {ref['error_components']['att']:.2e} "
        f"rad, rod {ref['error_components']['rod']:.2e}). Runs within {FLOOR_FACTOR:g}x of it are "
        f"marked 'floor': their error is not resolved.",
        "",
        "## Plants",
        "",
    ]
    L += _plants_markdown(cfg, runs, skipped)
    L += [
        "",
        "## Cheapest setting per accuracy level",
        "",
        "| level | " + " | ".join(columns) + " |",
        "|---|" + "---|" * len(columns),
    ]
    for lv in cfg.levels:
        cells = []
        for engine in columns:
            rid = cheapest.get(engine, {}).get(lv)
            if engine in skipped:
                cells.append("series skipped")
            elif lv <= FLOOR_FACTOR * ref["error_estimate"]:
                cells.append("below the reference's resolution")
            elif rid is None:
                cells.append("not reached")
            else:
                r = runs[rid]
                cells.append(
                    f"#{rid} {r['method']} {r['setting_name']} {r['setting']:.3g}: "
                    f"{r['wall_time_s'] * 1e3:.3g} ms (error {r['error']:.2g})"
                )
        L.append(f"| {lv:.0e} | " + " | ".join(cells) + " |")
    L += _pinocchio_vs_analytic_markdown(runs)
    L += [
        "",
        "## Every run",
        "",
        "★ marks the cheapest run for the levels listed. Drift columns: max abs(uᵀu−1) (e_u), "
        "relative angular-momentum and energy balances (`validation.summary.drift_figures`).",
        "",
        "| # | engine | method | setting | status | error (max) | error (final) | "
        "max e_u | L bal. | E bal. | track ω (final) | wall ms | nfev | steps | ★ / note |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        star = ""
        if marked[r["run_id"]]:
            star = "★ " + ", ".join(f"{lv:.0e}" for lv in marked[r["run_id"]])
        note = " ".join(
            x for x in (star, "floor" if r["at_reference_floor"] else "", r["note"]) if x
        )
        wall = r["wall_time_s"]
        L.append(
            f"| {r['run_id']} | {r['engine']} | {r['method']} | {r['setting_name']} "
            f"{r['setting']:.3g} | {r['status']} | {_fmt(r['error'], '.2e')} | "
            f"{_fmt(r['error_final'], '.2e')} | {_fmt(r['quat_norm_error_max'], '.1e')} | "
            f"{_fmt(r['angular_momentum_balance_rel'], '.1e')} | "
            f"{_fmt(r['energy_balance_rel'], '.1e')} | {_fmt(r['tracking_omega_final'], '.3g')} | "
            f"{_fmt(None if wall is None else wall * 1e3, '.3g')} | {_fmt(r['nfev'])} | "
            f"{_fmt(r['nsteps'])} | {note.replace('|', '/')} |"
        )
    L += [
        "",
        "## Stabilisation (δ1, δ2) and the quaternion norm",
        "",
        "Analytic engine, DOP853. `φ = uᵀu − 1` obeys φ̈ + δ1 φ̇ + δ2 φ = 0 (Eq. 58); started off the "
        "unit sphere it decays only when δ1, δ2 > 0.",
        "",
        "| δ1 | δ2 | rtol | φ(0) | φ(T) | max abs φ | max abs φ at steps |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in res_parts["stabilization"]:
        L.append(
            f"| {s['delta1']:g} | {s['delta2']:g} | {s['rtol']:.0e} | "
            f"{s['initial_norm_error']:.2e} | {s['quat_norm_error_final']:.2e} | "
            f"{s['quat_norm_error_max']:.2e} | {s['quat_norm_error_at_steps_max']:.2e} |"
        )
    L += ["", "## Cost of one dynamics evaluation with each effect off", ""]
    from validation.effects_cost import effects_markdown

    L += effects_markdown(res_parts["effects"])
    L += ["", "![work-precision](work_precision.png)", ""]
    return "\n".join(L)


def _series_points(runs: Sequence[Mapping[str, Any]]) -> dict[tuple[str, str], np.ndarray]:
    out: dict[tuple[str, str], list] = {}
    for r in runs:
        if r["status"] == "ok" and r["wall_time_s"] and r["error"] and r["error"] > 0:
            out.setdefault((r["engine"], r["method"]), []).append((r["wall_time_s"], r["error"]))
    return {k: np.array(v) for k, v in out.items()}


def _figure_png(runs, ref_error: float, title: str) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    series = _series_points(runs)
    # one colour per method (a scipy solver has the same colour on both scipy plants), one line
    # style and marker per plant
    methods = list(dict.fromkeys(m for _, m in series))
    colours = plt.get_cmap("tab10").colors
    styles = {ANALYTIC: ("-", "o"), MUJOCO: ("--", "s"), PINOCCHIO: (":", "^")}
    for (engine, method), pts in series.items():
        ls, marker = styles.get(engine, ("-.", "x"))
        ax.loglog(
            pts[:, 0],
            pts[:, 1],
            ls=ls,
            marker=marker,
            ms=4,
            color=colours[methods.index(method) % len(colours)],
            label=f"{engine} {method}",
        )
    if ref_error > 0:
        ax.axhline(ref_error, color="gray", ls=":", label="reference estimated error")
    ax.set_xlabel("wall time per run (s, median)")
    ax.set_ylabel("error (max over trajectory)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def _write_rrd(path: Path, runs, png: bytes, md: str) -> None:
    """Work-precision lines in log10 coordinates (x: wall time, y: error), the PNG and the text."""

    import rerun as rr

    from validation.recording import atomic_stream

    with atomic_stream(path, "tumble_sweep") as rec:
        for (engine, method), pts in _series_points(runs).items():
            xy = np.log10(pts)
            ent = f"work_precision/{engine}/{method}"
            rec.log(ent, rr.LineStrips2D([xy]), rr.Points2D(xy, radii=0.02), static=True)
            walls = pts[:, 0]
            rec.send_columns(
                f"plots/log10_error/{engine}/{method}",
                indexes=[rr.TimeColumn("wall_time", duration=walls)],
                columns=rr.Scalars.columns(scalars=np.log10(pts[:, 1])),
            )
        rec.log("figure", rr.EncodedImage(contents=png, media_type="image/png"), static=True)
        rec.log("report", rr.TextDocument(md, media_type=rr.MediaType.MARKDOWN), static=True)


# ----------------------------------------------------------------------------------------------
# The study
# ----------------------------------------------------------------------------------------------


def _resolve(scene: Scene | str | None) -> Scene:
    if isinstance(scene, Scene):
        return scene
    from validation.scenes import resolve_scene

    return resolve_scene(scene, default=DEFAULT_SCENE)


def run_sweep(
    scene: Scene | str | None,
    out_dir: str | Path,
    *,
    quick: bool = False,
    executor: Executor | None = None,
    progress: Callable[[str], None] | None = None,
    config: SweepConfig | None = None,
) -> SweepResult:
    """Run the study on ``scene`` (a Scene, a built-in name or a path; None: the default) and write
    ``sweep.csv``, ``sweep.json``, ``sweep.md``, ``work_precision.png``, ``sweep.rrd`` to ``out_dir``
    as one set (:func:`validation.outputs.output_run`, with ``manifest.json``).

    Args:
        quick: the small grid of :meth:`SweepConfig.quick` (ignored when ``config`` is given).
        executor: where the accuracy runs go (any ``concurrent.futures.Executor``); default a local
            process pool, shut down at the end. Timing runs are always serial, in this process.
        progress: called with one line of text per stage.
        config: the grid and limits (default :class:`SweepConfig`).
    """
    sc = _resolve(scene)
    cfg = config or (SweepConfig.quick() if quick else SweepConfig())
    with output_run(out_dir, "sweep") as run:
        res = _sweep_into(sc, cfg, run.path, executor=executor, progress=progress)
    if progress is not None:
        progress(f"wrote {', '.join(sorted(res.files))} to {run.target}")
    return dataclasses.replace(
        res, out_dir=run.target, files={k: run.final(p.name) for k, p in res.files.items()}
    )


def _sweep_into(
    sc: Scene,
    cfg: SweepConfig,
    out: Path,
    *,
    executor: Executor | None,
    progress: Callable[[str], None] | None,
) -> SweepResult:
    """:func:`run_sweep`'s work, writing into the staging directory ``out``."""
    t_start = time.perf_counter()
    say = progress or (lambda _msg: None)
    skipped_series: dict[str, str] = {}
    why = pinocchio_unavailable()
    if why:
        skipped_series[PINOCCHIO] = why
        say(f"  {skipped_note(PINOCCHIO, why)}")
    # 0. Compile once, here, before any run that is timed or has a wall-time budget: numba writes
    # the kernels to its disk cache, and every worker then loads them (~1 s) instead of compiling
    # them (~20 s on a fresh machine), which would count against a run's budget.
    say("compiling the kernels (once per machine; later runs load them from numba's cache)")
    warm_compiled(sc, skipped_series)
    own = executor is None
    # spawn, not fork: the parent may hold threads (BLAS, numba, a Dask client) that fork would copy
    # mid-state; workers import the engines afresh
    ex = executor or ProcessPoolExecutor(
        max_workers=max(1, min(4, os.cpu_count() or 1)),
        mp_context=multiprocessing.get_context("spawn"),
    )
    try:
        # 1. Reference: uncapped, then steps capped at half its mean step.
        say(f"reference: DOP853 rtol {REFERENCE_RTOL:g}, {cfg.t_end:g} s")
        coarse = ex.submit(_reference_task, sc, cfg.t_end, math.inf).result()
        if coarse["status"] != "ok":
            raise RuntimeError(f"reference run failed: {coarse['message']}")
        max_step = 0.5 * cfg.t_end / max(coarse["nsteps"], 1)
        fine_f = ex.submit(_reference_task, sc, cfg.t_end, max_step)
        # 2. The grid and the stabilisation study, in the executor.
        say("grid: accuracy runs in the executor")
        fine = fine_f.result()
        if fine["status"] != "ok":
            raise RuntimeError(f"reference run failed: {fine['message']}")
        ref: RefSamples = fine["samples"]

        est = errors_against(coarse["samples"], ref)  # anything with t, R, u, p
        reference = {
            "method": "DOP853",
            "rtol": REFERENCE_RTOL,
            "atol": REFERENCE_ATOL,
            "max_step": max_step,
            "nfev": fine["nfev"],
            "nsteps": fine["nsteps"],
            "wall_time_s": fine["wall_time_s"],
            "uncapped_nsteps": coarse["nsteps"],
            "error_estimate": est["error"],
            "error_components": {
                "pos": est["err_pos_max"],
                "att": est["err_att_max"],
                "rod": est["err_rod_max"],
            },
            "R_scale": ref.R_scale,
            "p_scale": ref.p_scale,
            "drift": fine["drift"],
        }
        series = [(ANALYTIC, m) for m in cfg.solvers] + [(MUJOCO, i) for i in cfg.integrators]
        if PINOCCHIO not in skipped_series:
            series += [(PINOCCHIO, m) for m in cfg.solvers]
        futs = [ex.submit(run_series, sc, e, m, cfg, ref) for e, m in series]
        stab_futs = [
            ex.submit(stabilization_row, sc, d1, d2, rt, off, cfg.t_end)
            for rt in cfg.delta_rtols
            for off in (0.0, cfg.delta_norm_offset)
            for d1, d2 in cfg.deltas
        ]
        runs: list[dict[str, Any]] = []
        for (e, m), f in zip(series, futs, strict=True):
            rows = f.result()
            say(f"  {e} {m}: {sum(r['status'] == 'ok' for r in rows)}/{len(rows)} ok")
            runs.extend(rows)
        stabilization = [f.result() for f in stab_futs]
    finally:
        if own:
            ex.shutdown(wait=True, cancel_futures=True)
    for i, r in enumerate(runs):
        r["run_id"] = i
        err = r["error"]
        r["at_reference_floor"] = bool(
            err is not None
            and math.isfinite(err)
            and err <= FLOOR_FACTOR * reference["error_estimate"]
        )
    # 3. Timings, one run at a time in this process, after a warm-up run of every plant and method
    # timed (JIT compilation, cache loads and first-call imports outside the timings).
    say("timing: serial runs")
    warm_up(sc, runs)
    time_runs(sc, runs, cfg)
    engines = list(dict.fromkeys(e for e, _ in series))
    cheapest = cheapest_settings(
        runs, cfg.levels, FLOOR_FACTOR * reference["error_estimate"], engines=engines
    )
    # 4. Effects.
    say("effects: cost of one evaluation with each effect off")
    from validation.effects_cost import effects_cost

    effects = effects_cost(sc, repeats=cfg.effects_repeats)
    # 5. Files.
    parts = {
        "scene": sc.name,
        "cfg": cfg,
        "reference": reference,
        "runs": runs,
        "cheapest": cheapest,
        "stabilization": stabilization,
        "effects": effects,
        "skipped_series": skipped_series,
    }
    md = _markdown(parts)
    png = _figure_png(runs, reference["error_estimate"], f"work-precision: {sc.name}")
    files = {
        "csv": out / "sweep.csv",
        "json": out / "sweep.json",
        "md": out / "sweep.md",
        "png": out / "work_precision.png",
        "rrd": out / "sweep.rrd",
    }
    write_text(files["csv"], to_csv(runs))
    doc = {
        "scene": sc.name,
        "config": cfg.to_dict(),
        "reference": reference,
        "levels": list(cfg.levels),
        "cheapest": {e: {repr(lv): rid for lv, rid in d.items()} for e, d in cheapest.items()},
        "series": [{"engine": e, "method": m} for e, m in series],
        "skipped_series": [
            {"engine": e, "reason": why, "note": skipped_note(e, why)}
            for e, why in skipped_series.items()
        ],
        "runs": runs,
        "stabilization": stabilization,
        "effects": effects,
    }
    write_text(files["json"], json.dumps(_json_safe(doc), indent=1))
    write_text(files["md"], md)
    write_bytes(files["png"], png)
    _write_rrd(files["rrd"], runs, png, md)
    return SweepResult(
        scene=sc.name,
        out_dir=out,
        config=cfg.to_dict(),
        reference=reference,
        runs=tuple(runs),
        cheapest=cheapest,
        stabilization=tuple(stabilization),
        effects=tuple(effects),
        skipped_series=skipped_series,
        files=files,
        wall_time_s=time.perf_counter() - t_start,
    )


def main(argv: list[str] | None = None) -> int:
    """``python -m validation.sweep [SCENE] [--out DIR] [--quick] [--t-end S] ...``"""
    import argparse

    ap = argparse.ArgumentParser(
        prog="python -m validation.sweep", description=__doc__.split("\n")[0]
    )
    ap.add_argument("scene", nargs="?", default=None, help=f"scene name or path ({DEFAULT_SCENE})")
    ap.add_argument("--out", default=None, help="output directory (default: out/sweep_<scene>)")
    ap.add_argument("--quick", action="store_true", help="the small grid of tests and CI")
    ap.add_argument("--t-end", type=float, default=None, help="horizon, s")
    ap.add_argument("--max-run-wall", type=float, default=None, help="per-run wall cap, s")
    ap.add_argument("--repeats", type=int, default=None, help="timing repeats (median)")
    args = ap.parse_args(argv)
    cfg = SweepConfig.quick() if args.quick else SweepConfig()
    changes = {}
    if args.t_end is not None:
        changes["t_end"] = args.t_end
    if args.max_run_wall is not None:
        changes["max_run_wall_s"] = args.max_run_wall
    if args.repeats is not None:
        changes["repeats"] = args.repeats
    cfg = dataclasses.replace(cfg, **changes)
    from validation.outputs import default_out_dir

    sc = _resolve(args.scene)
    res = run_sweep(sc, args.out or default_out_dir("sweep_", sc.name), config=cfg, progress=print)
    print(f"reference estimated error {res.reference['error_estimate']:.2e}")
    for engine, why in res.skipped_series.items():
        print(f"  {skipped_note(engine, why)}")
    for engine, by_level in res.cheapest.items():
        for lv, rid in by_level.items():
            if rid is None:
                print(f"  {engine:8s} {lv:.0e}: not reached")
            else:
                r = res.runs[rid]
                print(
                    f"  {engine:8s} {lv:.0e}: {r['method']} {r['setting_name']} "
                    f"{r['setting']:.3g} ({r['wall_time_s'] * 1e3:.3g} ms, error {r['error']:.2e})"
                )
    print(f"sweep took {res.wall_time_s:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
