"""One row per setting of the grid: its columns, their types, and a blank row.

Every row has every key of :data:`COLUMNS` (None where it does not apply) and, beyond them,
``wall_time_samples_s``: every timing of the setting (``sweep.json`` only; the CSV has the
median, min and max).
"""

from __future__ import annotations

from typing import Any

from analytic.effects import Precision
from validation.studies.sweep.config import ACCELERATED, RTOL_ENGINES, SweepConfig

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
    "wall_time_min_s",
    "wall_time_max_s",
    "wall_time_repeats",
    "wall_time_predicted_s",
    "nfev",
    "nsteps",
    "precision",
    "horizon_s",
    "at_precision_floor",
)
"""Columns of ``sweep.csv``, in order. ``wall_time_s`` is the median of the setting's timings,
``wall_time_min_s`` / ``wall_time_max_s`` their spread, ``wall_time_repeats`` how many;
``wall_time_predicted_s`` the predicted wall of a run not started for its budget. ``precision``
is the run's floating-point precision (float64 but for an accelerated plant's float32 series),
``horizon_s`` its horizon (the sweep's, MuJoCo Warp's shorter), ``at_precision_floor`` true on
the smallest step of a series beyond which a smaller step stopped lowering the error
(:data:`~validation.studies.sweep.config.PRECISION_FLOOR_GAIN`)."""

SAMPLES_KEY = "wall_time_samples_s"
"""Key of the list of every timing of a row (seconds, in the order taken)."""

NON_FLOAT_COLUMNS = frozenset(
    {
        "run_id",
        "engine",
        "method",
        "setting_name",
        "status",
        "note",
        "at_reference_floor",
        "at_precision_floor",
        "precision",
        "nfev",
        "nsteps",
        "wall_time_repeats",
    }
)
FLOAT_COLUMNS = frozenset(COLUMNS) - NON_FLOAT_COLUMNS
INT_COLUMNS = frozenset({"run_id", "wall_time_repeats", "nfev", "nsteps"})
BOOL_COLUMNS = frozenset({"at_reference_floor", "at_precision_floor"})


def blank_row(engine: str, method: str, setting: float, cfg: SweepConfig) -> dict[str, Any]:
    """A row of ``engine`` / ``method`` at ``setting`` (rtol or dt), nothing measured yet."""
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(engine=str(engine), method=method, setting=setting, note="")
    row[SAMPLES_KEY] = []
    accelerated = engine in ACCELERATED
    row.update(
        precision=str(Precision(method) if accelerated else Precision.FLOAT64),
        horizon_s=cfg.horizon(engine),
        at_precision_floor=False,
    )
    if engine in RTOL_ENGINES:
        row.update(setting_name="rtol", rtol=setting, atol=setting * cfg.atol_ratio)
    else:
        row.update(setting_name="dt", dt=setting)
    return row


__all__ = [
    "BOOL_COLUMNS",
    "COLUMNS",
    "FLOAT_COLUMNS",
    "INT_COLUMNS",
    "NON_FLOAT_COLUMNS",
    "SAMPLES_KEY",
    "blank_row",
]
