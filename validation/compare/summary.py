"""Plain-text summaries: one trajectory (tracking errors at the end, invariant drifts, the
largest control forces) and one failed check, in the words every output uses.

The largest value of a quantity over a run is always the largest *magnitude*: for a vector the
Euclidean norm, ``max ‖τ‖₂`` (the control torque, body axes) and ``max ‖F_C‖₂``; for a signed
scalar its absolute value, ``max |F_i|`` (a rod force). :func:`max_abs` is that definition.
"""

from __future__ import annotations

import math

import numpy as np

from analytic.invariants import Balance
from analytic.threshold import BoundPart
from analytic.trajectory import Trajectory
from validation.compare.balances import BalanceTerms, relative
from validation.compare.checks import Check
from validation.compare.thresholds import DEFAULTS

COMPLETED = "completed"
"""The name of the check that a run reached its horizon (value: time reached, threshold: the
horizon; :func:`validation.compare.checks.compare`)."""


def max_abs(values: np.ndarray) -> tuple[float, int]:
    """The largest magnitude over time and its sample index: rows of a (N, k) array by their
    Euclidean norm, a (N,) array by its absolute value. ``(nan, -1)`` when empty; a non-finite
    sample is the largest (``inf``, at its index)."""
    v = np.asarray(values, float)
    if v.size == 0 or v.shape[0] == 0:
        return math.nan, -1
    mag = np.linalg.norm(v, axis=1) if v.ndim == 2 else np.abs(v)
    bad = ~np.isfinite(mag)
    if bad.any():
        return math.inf, int(np.argmax(bad))
    i = int(np.argmax(mag))
    return float(mag[i]), i


def check_sentence(check: Check, reason: bool = True) -> str:
    """One check in words: ``analytic: stopped at 9.37 s of 20 s (why)`` for a run that did not
    reach its horizon, ``position_C = 5.000e-05 m > threshold 1.000e-06 m (why)`` otherwise,
    with :func:`bound_parts` after the threshold when its relative part decided;
    ``reason=False`` leaves out a threshold's reason (a long sentence) but never why a run
    stopped; a check that does not apply says so, with why (``control_torque: not applicable
    (neither plant applies a control torque)``)."""
    if check.name == COMPLETED:
        who = check.subject.value
        if check.passed:
            return f"{who}: reached {check.threshold:g} s"
        reached = "no sample" if math.isnan(check.value) else f"{check.value:.3g} s"
        return f"{who}: stopped at {reached} of {check.threshold:g} s ({check.reason})"
    if not check.applicable:
        return f"{check.label}: not applicable ({check.reason})"
    unit = "" if check.unit in ("", "1") else f" {check.unit}"
    op = "≤" if check.passed else ">"
    why = f" ({check.reason})" if reason else ""
    return (
        f"{check.label} = {check.value:.3e}{unit} {op} threshold {check.threshold:.3e}{unit}"
        f"{bound_parts(check)}{why}"
    )


def bound_parts(check: Check) -> str:
    """What decided a check's bound, when it is the relative part (the larger of
    ``absolute_part`` and ``relative_part = rtol × magnitude``): `` (decided by the relative part
    1e-07 × scale 1.856e+03 m; absolute part 1.000e-06 m)``; "" when the absolute part decided
    (as every bound without a relative part)."""
    if check.decided_by is not BoundPart.RELATIVE:
        return ""
    unit = "" if check.unit in ("", "1") else f" {check.unit}"
    rtol = check.relative_part / check.magnitude if check.magnitude else math.nan
    return (
        f" (decided by the relative part {rtol:.3g} × scale {check.magnitude:.3e}{unit}; "
        f"absolute part {check.absolute_part:.3e}{unit})"
    )


DRIFT_KEYS = {
    Balance.ANGULAR_MOMENTUM: "angular_momentum_balance_rel",
    Balance.ENERGY: "energy_balance_rel",
    Balance.LINEAR_MOMENTUM: "linear_momentum_balance_rel",
}
"""Each balance's key in :func:`drift_figures`; the value is the one ``tumble validate`` checks
under the balance's threshold name (``analytic.angular_momentum`` ...)."""


def drift_figures(tr: Trajectory) -> dict[str, float]:
    """The norm error and the invariants' balances (max over the run), relative: exactly the
    values of ``tumble validate``'s checks of the same run, by the one definition
    :func:`validation.compare.balances.relative` (the largest residual norm divided by
    ``max(scale, floor)``, the scale that of the balanced quantity, the floor its threshold's in
    :mod:`validation.compare.thresholds`).

    Returns:
        ``quat_norm_error_max`` (max ``|uᵀu − 1|``) and, per balance, its :data:`DRIFT_KEYS` key.
    """
    iv = tr.invariants
    out = {"quat_norm_error_max": float(np.max(np.abs(iv.quat_norm_error)))}
    terms = BalanceTerms.of(iv)
    for b, key in DRIFT_KEYS.items():
        out[key] = relative(terms, b, DEFAULTS[b.value].floor)
    return out


def summary_table(tr: Trajectory) -> str:
    """A short human-readable table."""
    lines = [
        f"scene {tr.scene} on {tr.engine}: {tr.status.value.upper()}"
        + (f" ({tr.message})" if tr.message else ""),
        f"  samples {len(tr.t)}, t = {tr.t[0]:g} .. {tr.t[-1]:g} s",
    ]
    for k in ("method", "integrator", "rtol", "atol", "dt", "nfev", "nsteps", "wall_time_s"):
        if k in tr.info:
            v = tr.info[k]
            lines.append(f"  {k:<34} {v:.4g}" if isinstance(v, float) else f"  {k:<34} {v}")
    lines.append(
        "  invariants (max over the run; balances relative to the balanced quantity, "
        "as tumble validate checks them)"
    )
    for k, v in drift_figures(tr).items():
        lines.append(f"    {k:<32} {v:.3e}")
    if "max_quat_norm_error_at_steps" in tr.info:
        v = tr.info["max_quat_norm_error_at_steps"]
        lines.append(f"    {'quat_norm_error_at_steps_max':<32} {v:.3e}")
    if tr.tracking.e_omega.size:
        e = np.abs(tr.tracking.e_omega[-1])
        axes = ",".join("xyz"[c] for c in tr.tracking.omega_components)
        lines.append(f"  tracking at t = {tr.t[-1]:g} s")
        lines.append(f"    |e_omega| ({axes}) rad/s         " + " ".join(f"{x:.2e}" for x in e))
    if tr.tracking.e_p.size:
        e = np.abs(tr.tracking.e_p[-1])
        idx = ",".join(str(i + 1) for i in tr.tracking.mass_indices)
        lines.append(
            f"    |e_p| (masses {idx}) m"
            + " " * max(1, 14 - len(idx))
            + " ".join(f"{x:.2e}" for x in e)
        )
    if tr.torque.size and np.any(tr.torque):
        rod = f", max |F_i| {max_abs(np.ravel(tr.rod_forces))[0]:.3e} N" if tr.n else ""
        lines.append(
            f"  control: max ‖τ‖₂ {max_abs(tr.torque)[0]:.3e} N·m{rod}, "
            f"max ‖F_C‖₂ {max_abs(tr.force_at_C)[0]:.3e} N"
        )
    return "\n".join(lines)
