"""What accuracy costs in time: a work-precision study of the plants on one scene.

``run_sweep(scene, out_dir)`` (CLI: ``tumble sweep [SCENE] [--out DIR] [--t-end S]``, also
``python -m validation.studies.sweep``, the same command line), over the paper's 20 s horizon by default:

1. **Reference** (:mod:`~validation.studies.sweep.reference`): the analytic engine at scipy's tightest
   tolerance, its error estimated by self-convergence; computed once per scene, horizon and code
   version and cached.
2. **Grid** (:mod:`~validation.studies.sweep.series`): the analytic engine over scipy solvers x rtol,
   MuJoCo over integrators x timestep, and, when Pinocchio (``pin``) is installed, the Pinocchio
   plant over the same solvers x rtol, and, when installed, MuJoCo's accelerated plants (MJX in
   float64 and float32, MuJoCo Warp in float32) over time steps, one series per precision
   (:mod:`~validation.studies.sweep.accelerated`: each series' precision floor); one series per
   plant and solver / integrator / precision, cheap to expensive, each a task of the executor. A series is cut when a run is too slow (measured or
   predicted against the per-run budget), fails or diverges after an earlier setting worked, or
   reaches the reference's floor, or (an accelerated series) shows its precision's floor.
3. **Per run**: the errors (:mod:`~validation.studies.sweep.metrics`), invariant drifts, final tracking
   errors, and the cost (:mod:`~validation.studies.sweep.timing`): the median and spread of a few timings
   of the integration, right-hand-side evaluations and steps.
4. **Stabilisation** (:mod:`~validation.studies.sweep.stabilization`) and **effects**
   (:mod:`validation.studies.effects_cost`).
5. **Files**: ``sweep.csv`` (:mod:`~validation.studies.sweep.csv_rows`), ``sweep.json``
   (:mod:`~validation.studies.sweep.json_doc`), ``sweep.md`` (:mod:`~validation.studies.sweep.markdown`),
   ``work_precision.png`` (:mod:`~validation.studies.sweep.figure`), ``sweep.rrd``
   (:mod:`~validation.studies.sweep.rrd`).

:mod:`~validation.studies.sweep.config` holds the configuration record and the default scene,
:mod:`~validation.studies.sweep.running` one run within its budget and the executor,
:mod:`~validation.studies.sweep.study` the order of work.
"""

from __future__ import annotations

from validation.studies.sweep.config import (
    ANALYTIC,
    DEFAULT_SCENE,
    ENGINES,
    FLOOR_FACTOR,
    LEVELS,
    MUJOCO,
    PINOCCHIO,
    REFERENCE_ATOL,
    REFERENCE_RTOL,
    Outcome,
    Plant,
    SweepConfig,
)
from validation.studies.sweep.csv_rows import read_csv, to_csv
from validation.studies.sweep.metrics import RefSamples, errors_against, ref_samples
from validation.studies.sweep.reference import reference_run
from validation.studies.sweep.result import SweepResult
from validation.studies.sweep.rows import COLUMNS
from validation.studies.sweep.selection import cheapest_settings
from validation.studies.sweep.series import run_series
from validation.studies.sweep.study import run_sweep

__all__ = [
    "ANALYTIC",
    "COLUMNS",
    "DEFAULT_SCENE",
    "ENGINES",
    "FLOOR_FACTOR",
    "LEVELS",
    "MUJOCO",
    "PINOCCHIO",
    "REFERENCE_ATOL",
    "REFERENCE_RTOL",
    "Outcome",
    "Plant",
    "RefSamples",
    "SweepConfig",
    "SweepResult",
    "cheapest_settings",
    "errors_against",
    "read_csv",
    "ref_samples",
    "reference_run",
    "run_series",
    "run_sweep",
    "to_csv",
]
