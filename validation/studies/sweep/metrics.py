"""The sweep's error measures: a run against the reference on their common output samples.

Three measures, each as a maximum over the trajectory and at the final sample:

* **position of C**, ``|R - R_ref|`` relative to the largest displacement of C in the reference;
* **attitude**, the angle of the relative rotation, rad (:func:`validation.compare.differences.attitude_angle`);
* **rod positions**, ``max_i |p_i - p_ref,i|`` relative to the largest ``|p|`` in the reference.

``error`` is the largest of the three maxima: the accuracy the sweep's levels refer to. Also here:
the invariant drifts and final tracking errors a row reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from validation.compare.differences import attitude_angle
from validation.compare.summary import drift_figures

ERROR_MEASURE = (
    "max over the trajectory of: position of C relative to its largest displacement, attitude "
    "angle (rad), rod positions relative to the largest |p| (all against the reference)"
)
"""One sentence naming the error measure, for the figure and the captions."""

SAMPLE_TIME_ATOL = 1e-9
"""Sample times of a run and the reference match to this, s (both are the scene's output grid)."""


@dataclass(frozen=True)
class RefSamples:
    """What a worker needs of the reference: the sampled motion and the error scales.

    Attributes:
        t: sample times, s, shape (N,).
        R: position of C, inertial, m, shape (N, 3).
        u: attitude quaternion, w first, shape (N, 4).
        p: rod positions, m, shape (N, n).
        R_scale: largest ``|R - R(0)|``, m (1 when C does not move).
        p_scale: largest ``|p|``, m (1 without masses).
    """

    t: np.ndarray
    R: np.ndarray
    u: np.ndarray
    p: np.ndarray
    R_scale: float
    p_scale: float


def ref_samples(tr) -> RefSamples:
    """The samples and scales of a reference trajectory (anything with ``t, R, u, p``)."""
    R_scale = float(np.max(np.linalg.norm(tr.R - tr.R[0], axis=1)))
    p_scale = float(np.max(np.abs(tr.p))) if tr.p.size else 0.0
    return RefSamples(
        np.array(tr.t, dtype=float),
        np.array(tr.R, dtype=float),
        np.array(tr.u, dtype=float),
        np.array(tr.p, dtype=float),
        R_scale if R_scale > 0 else 1.0,
        p_scale if p_scale > 0 else 1.0,
    )


def ref_until(ref: RefSamples, t_end: float) -> RefSamples:
    """The reference up to ``t_end`` s, its scales those of that part: the error measure of a
    series with a shorter horizon (MuJoCo Warp's) is the same definition over its own horizon."""
    if t_end >= ref.t[-1] - SAMPLE_TIME_ATOL:
        return ref
    k = int(np.searchsorted(ref.t, t_end + SAMPLE_TIME_ATOL, side="right"))
    part = RefSamples(ref.t[:k], ref.R[:k], ref.u[:k], ref.p[:k], 1.0, 1.0)
    return ref_samples(part)


def errors_against(tr, ref: RefSamples) -> dict[str, float]:
    """Final and max-over-trajectory errors of ``tr`` against the reference (same sample times).

    Keys ``err_{pos,att,rod}_{max,final}``, ``error`` (the largest maximum) and ``error_final``.
    NaN everywhere when the run has no finite samples in common with the reference; inf for a
    measure that is not finite somewhere.
    """
    n = min(len(tr.t), len(ref.t))
    keys = ("pos", "att", "rod")
    if n < 2 or not np.allclose(tr.t[:n], ref.t[:n], rtol=0, atol=SAMPLE_TIME_ATOL):
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


def drifts(tr) -> dict[str, float]:
    """The invariant drifts of :func:`validation.compare.summary.drift_figures` ({} when not computable)."""
    try:
        return {k: float(v) for k, v in drift_figures(tr).items()}
    except (ValueError, FloatingPointError):
        return {}


def tracking(tr) -> dict[str, float | None]:
    """The largest component of the final tracking errors e_ω (rad/s) and e_p (m)."""
    tk = tr.tracking
    w = float(np.max(np.abs(tk.e_omega[-1]))) if tk.e_omega.size else None
    p = float(np.max(np.abs(tk.e_p[-1]))) if tk.e_p.size else None
    return {"tracking_omega_final": w, "tracking_p_final": p}


__all__ = [
    "ERROR_MEASURE",
    "RefSamples",
    "drifts",
    "errors_against",
    "ref_samples",
    "ref_until",
    "tracking",
]
