"""Plain-text summary of one trajectory: tracking errors at the end and invariant drifts."""

from __future__ import annotations

import numpy as np

from analytic.trajectory import Trajectory


def _rel(x: np.ndarray, scale: float) -> float:
    return float(np.max(np.abs(x)) / scale) if scale > 0 else float(np.max(np.abs(x)))


def drift_figures(tr: Trajectory) -> dict[str, float]:
    """Relative drifts of the invariants' balances (max over the run) and the norm error.

    Scales: angular momentum by max(|L|, |∫Sτ dt|); energy by max(|E|, |W|, kinetic scale);
    linear momentum by max|P|.
    """
    iv = tr.invariants
    L_scale = max(
        float(np.max(np.linalg.norm(iv.angular_momentum, axis=1))),
        float(np.max(np.linalg.norm(iv.angular_impulse, axis=1))),
    )
    E_scale = max(float(np.max(np.abs(iv.energy))), float(np.max(np.abs(iv.work))))
    P_scale = float(np.max(np.linalg.norm(iv.linear_momentum, axis=1)))
    return {
        "quat_norm_error_max": float(np.max(np.abs(iv.quat_norm_error))),
        "angular_momentum_balance_rel": _rel(iv.angular_momentum_balance(), L_scale),
        "energy_balance_rel": _rel(iv.energy_balance(), E_scale),
        "linear_momentum_balance_rel": _rel(iv.linear_momentum_balance(), P_scale),
    }


def summary_table(tr: Trajectory) -> str:
    """A short human-readable table."""
    lines = [
        f"scene {tr.scene} on {tr.engine.value}: {tr.status.value.upper()}"
        + (f" ({tr.message})" if tr.message else ""),
        f"  samples {len(tr.t)}, t = {tr.t[0]:g} .. {tr.t[-1]:g} s",
    ]
    for k in ("method", "integrator", "rtol", "atol", "dt", "nfev", "nsteps", "wall_time_s"):
        if k in tr.info:
            v = tr.info[k]
            lines.append(f"  {k:<34} {v:.4g}" if isinstance(v, float) else f"  {k:<34} {v}")
    lines.append("  invariants (max over the run)")
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
        lines.append(
            f"  control: max |tau| {np.max(np.abs(tr.torque)):.3e} N m, "
            f"max |F_rod| {np.max(np.abs(tr.rod_forces)) if tr.rod_forces.size else 0:.3e} N, "
            f"max |F_C| {np.max(np.abs(tr.force_at_C)):.3e} N"
        )
    return "\n".join(lines)
