"""The closed-form error dynamics each controlled plant is judged against (Eqs. 78, 84).

The controller makes the tracking errors obey exactly ``e_ω(t) = exp(-P t) e_ω(0)`` (Eq. 84 with
``docs/errata.md``, item 3) and ``ë + α ė + β e = 0`` for each controlled mass (Eq. 78), whatever
the body, the masses and the springs do. This module gives those closed forms
(:func:`omega_error_reference`, :func:`mass_error_reference`), each plant's deviation from them
(:func:`law_deviations`) and the magnitudes their bounds' relative parts scale by
(:func:`tracking_magnitudes`): a change to the control law's error dynamics costs this module only.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analytic.trajectory import Trajectory
from validation.compare.reductions import largest, maxabs, norm


def _propagate(A: np.ndarray, x0: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``x(t) = exp(A (t - t0)) x0`` at every time of ``t``, shape (N, k).

    Output times are uniform (``analytic.scene.output_times``): then ``x_{i+1} = exp(A h) x_i``
    with one matrix exponential, exact up to rounding that grows at most like ``i`` ulps for a
    stable ``A``. Other time grids take one exponential per time (scipy's batched ``expm``)."""
    from scipy.linalg import expm  # here: scipy.linalg costs 0.2 s to import, at start-up

    t = np.asarray(t, float)
    x0 = np.asarray(x0, float)
    out = np.empty((t.shape[0], x0.shape[0]))
    if t.shape[0] == 0:
        return out
    h = np.diff(t)
    if h.size and np.all(np.abs(h - h[0]) <= 1e-12 * max(abs(h[0]), abs(t[-1]))):
        step = expm(A * h[0])
        out[0] = x0
        for i in range(1, t.shape[0]):
            out[i] = step @ out[i - 1]
        return out
    return expm(A[None] * (t - t[0])[:, None, None]) @ x0


def omega_error_reference(t: np.ndarray, e0: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """``e_ω(t) = exp(-P (t - t0)) e_ω(t0)`` (Eq. 84 with ``docs/errata.md``, item 3), shape (N, k), rad/s."""
    t = np.asarray(t, float)
    gain = np.asarray(gain, float)
    if gain.size == 0:
        return np.zeros((t.shape[0], 0))
    return _propagate(-gain, e0, t)


def mass_error_reference(
    t: np.ndarray, e0: np.ndarray, edot0: np.ndarray, alpha: np.ndarray, beta: np.ndarray
) -> np.ndarray:
    """Solution of ``ë + α ė + β e = 0`` (Eq. 78) per controlled mass, shape (N, k), m."""
    t = np.asarray(t, float)
    out = np.zeros((t.shape[0], len(e0)))
    for j in range(len(e0)):
        A = np.array([[0.0, 1.0], [-beta[j], -alpha[j]]])
        out[:, j] = _propagate(A, np.array([e0[j], edot0[j]]), t)[:, 0]
    return out


def law_deviations(traj: Trajectory, scene: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Deviations of one plant's tracking errors from their closed-form dynamics, per sample:
    ``|e_ω - exp(-P t) e_ω(0)|`` (rad/s) and ``max_i |e_p,i - e_ref,i|`` (m); None for what is not
    tracked."""
    tr, t = traj.tracking, traj.t
    dev_w = dev_p = None
    if tr.omega_components and scene.control.omega is not None and t.size:
        e = tr.e_omega
        ref = omega_error_reference(t, e[0], scene.control.omega.gain)
        dev_w = norm(e - ref)
    if tr.mass_indices and scene.control.masses is not None and t.size:
        mt = scene.control.masses
        pos = [list(mt.indices).index(i) for i in tr.mass_indices]
        l, lam = np.asarray(mt.l)[pos], np.asarray(mt.lam)[pos]
        # p̄ = p_e + l cos(λ t) (Eq. 75), so ė(t0) = ṗ(t0) + l λ sin(λ t0).
        edot0 = traj.qdot[0, 7 + np.array(tr.mass_indices)] + l * lam * np.sin(lam * t[0])
        ref = mass_error_reference(
            t, tr.e_p[0], edot0, np.asarray(mt.alpha)[pos], np.asarray(mt.beta)[pos]
        )
        dev_p = maxabs(tr.e_p - ref)
    return dev_w, dev_p


def tracking_magnitudes(traj: Trajectory) -> tuple[float, float]:
    """The scales of one plant's tracking laws: its largest ``|ω|`` (rad/s) and the largest
    ``|p_i|`` of its controlled masses (m), over the run."""
    idx = list(traj.tracking.mass_indices)
    p = largest(traj.q[:, [7 + i for i in idx]], False) if idx else 0.0
    return largest(traj.omega, True), p


__all__ = [
    "law_deviations",
    "mass_error_reference",
    "omega_error_reference",
    "tracking_magnitudes",
]
