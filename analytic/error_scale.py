"""Scale-aware absolute tolerances: the ``atol`` of each group of coupled state components follows
the group's own magnitude. The one rule the adaptive plants share (the analytic plant's loops,
:mod:`analytic.stepping` and :mod:`analytic.compiled_stepping`, and through them the Pinocchio and
Drake plants).

The rule. The motion components of a state ``y`` are split into **groups** of coupled components
of one unit (:class:`ErrorGroups`): the positions ``{R, p}`` (m: a mass sits at
``R + S(u)(a + p_i d)``), the attitude quaternion, the translational velocities ``{Ṙ, ṗ}`` (m/s)
and the rotational rates (``u̇`` or ω). Component ``i`` of group ``g`` gets

    atol_i = atol · s_g,   s_g = 2^floor(log2(max(1, M_g / GROUP_UNIT))),   M_g = max_{j in g} |y_j|

(components in no group keep ``atol``), and the error norm stays scipy's ``atol_i + rtol |y_i|``.

Why. A component is computed from the terms of its whole group: ``Ṙ_z`` from the forces on every
mass, whose size follows the largest velocities and positions; ``R_z`` enters every mass position
summed with ``R_x``, ``R_y`` and ``p``. Its round-off is therefore a few ε of the *group's*
magnitude ``M_g``, not of its own value, and is amplified by the conditioning of the mass matrix
(on a runaway scene by many decades: ``docs/performance.md``, The analytic layer's tolerances
and limits). A fixed ``atol``
(1e-13 by default, ~450 ε) asks a component that stays small while its group grows to 1e5 or 1e8
for digits no evaluation carries: the error estimate is then round-off, linear in the step, and
the steps shrink until the run grinds (``docs/performance.md``, Runaway scenes). The
round-off of a group, a few ε·M_g (say 4 ε·M_g after a handful of operations), reaches the default
``atol`` (~450 ε) at M_g ≈ :data:`GROUP_UNIT` = 100 (SI units); above it the floor
``atol · M_g / 100`` is ~4.5 ε *relative to the group* at the default ``atol``: the error control
asks each component for no more than the group's round-off leaves, and a large motion costs steps
in proportion to its difficulty, not to the ratio of its size to a fixed ``atol``. It is also what
a vector's error should be: isotropic, independent of how the inertial frame's axes happen to lie.

What it leaves alone. ``s_g = 1`` while every component of the group stays below
``2 · GROUP_UNIT`` in magnitude: a scene whose state stays within a few hundred SI units (the
paper's examples over 2 s) gets exactly the fixed ``atol`` it had, and its trajectory is
bit-identical. ``s_g`` is a power of two; a loop follows it up at once and down only when it has
fallen to a quarter (:func:`follow_scales`: a swinging magnitude changes the vector once), so
``atol · s_g`` stays within twice ``atol · M_g / GROUP_UNIT``. scipy's loop rebuilds its solver
where the scales change (from where it is, with the step it had), the compiled loop recomputes the
vector at the start of each of its calls. ``atol`` scales the whole vector, so
``Plant.tightened`` (``atol / 100``) tightens the floor with it and the own-error estimate keeps
its meaning.

Beyond double precision. The scaling removes the grinding that a fixed ``atol`` causes, not the
one a motion's own conditioning causes: where the accelerations follow an ε-relative change of the
state by more than the scene's tolerance (the same runaway scene later in its run, in
``docs/performance.md``), no tolerance the scene asks for can be met, and a step's error estimate
is round-off at any step size. Every :data:`PROBE_STEPS` steps the loops therefore ask
:func:`roundoff_limited`: does a one-ulp change of the state move the last step's increment
``h · ẏ`` of some component by its whole tolerance? When :data:`PROBES_IN_A_ROW` probes in a row
find so, the error control is steering on round-off, not for a moment, and when its steps have
become :data:`SLOWDOWN` times shorter than its average (or would take more than
:data:`PROJECTED_STEPS` further steps to the horizon), the run grinds on it; it then stops
``failed`` with that reason (the component, the size of the change, the tolerance), as a plant
stops at a singular matrix. On a state whose accelerations are computed to round-off (an O(1)
scene: ``d ~ ε |ẏ|``, steps of ~1e-2 s) that change is 1e4 times smaller than the tolerance or
more, so the probe does not stop a run that the error control can judge.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

GROUP_UNIT = 100.0
"""The group magnitude (SI units) above which a group's ``atol`` grows with it (module docstring)."""

RESCALE_STEPS = 200
"""scipy's loop re-reads the groups' scales every this many steps (the compiled loop at the start of
each of its calls, at most as many steps apart, so both loops follow the state alike): a rebuild
costs an evaluation and cuts the step the solver proposed back to the last one taken, so it is
not done at every step."""

PROBE_STEPS = 2000
"""Steps between two :func:`roundoff_limited` probes (three right-hand sides each)."""

PROJECTED_STEPS = 100_000
"""A round-off limited run is stopped only when its pace would take more steps than this to its
horizon (:class:`RoundoffWatch`)."""

SLOWDOWN = 10.0
"""A round-off limited run is stopped when its last steps are this many times shorter than its
average step so far (:class:`RoundoffWatch`), unless its horizon is at most :data:`PROBE_STEPS`
steps away at that pace: finishing costs less than the run has already spent between two probes,
so a run that slows down just before its horizon finishes."""

ROUNDOFF_LIMITED = "round-off limited"
"""How the message of a run stopped by :class:`RoundoffWatch` begins (:func:`is_roundoff_stop`)."""

PROBES_IN_A_ROW = 2
"""A run stops round-off limited when this many probes in a row find it so (:class:`RoundoffWatch`):
a moment of ill-conditioning that the steps pass through does not end a run."""

QUADRATURE_ATOL = 1e300
"""``atol`` of the quadratures (work, impulses): large enough that they never take part in the
error control."""


@dataclass(frozen=True)
class ErrorGroups:
    """The groups of coupled motion components of a plant's state (module docstring).

    Attributes:
        groups: index arrays into ``y``, one per group (disjoint, all below ``n_motion``).
        n_motion: components under error control; those after them are quadratures.
    """

    groups: tuple[np.ndarray, ...]
    n_motion: int

    def __post_init__(self) -> None:
        for g in self.groups:
            if g.size and not (0 <= g.min() and g.max() < self.n_motion):
                raise ValueError(
                    f"groups: indices must lie in [0, {self.n_motion}) (got {g.min()}..{g.max()})"
                )

    @classmethod
    def of(cls, n_motion: int, *groups: Sequence[int] | np.ndarray) -> ErrorGroups:
        """Groups from index sequences."""
        return cls(tuple(np.asarray(g, dtype=np.intp) for g in groups), int(n_motion))


def group_scales(y: np.ndarray, groups: ErrorGroups) -> np.ndarray:
    """``s_g`` of each group at the state ``y``: the largest power of two not above
    ``max(1, max |y_j| / GROUP_UNIT)`` (1 for an empty group or a non-finite magnitude)."""
    out = np.ones(len(groups.groups))
    for k, g in enumerate(groups.groups):
        if g.size:
            m = float(np.max(np.abs(y[g]))) / GROUP_UNIT
            if np.isfinite(m) and m >= 2.0:
                out[k] = 2.0 ** (np.frexp(m)[1] - 1)
    return out


def follow_scales(scales: np.ndarray, y: np.ndarray, groups: ErrorGroups) -> np.ndarray:
    """The scales a loop carries on with at ``y``, having used ``scales`` so far: a group's scale
    follows its magnitude up at once (growth is what grinds), and down only when
    :func:`group_scales` has fallen to a quarter of it, so a magnitude that swings across a power
    of two changes the vector once, not at every swing (the scale stays within ``2 M_g``). The
    same array when nothing changes."""
    now = group_scales(y, groups)
    if np.all((now <= scales) & (now * 4.0 > scales)):
        return scales
    return np.where((now > scales) | (now * 4.0 <= scales), now, scales)


def atol_vector(
    atol: float, ny: int, n_motion: int, groups: ErrorGroups | None = None, scales=None
) -> np.ndarray:
    """The per-component ``atol`` (``ny``): ``atol · s_g`` on each group's components, ``atol``
    on the other motion components, :data:`QUADRATURE_ATOL` on the quadratures. Without
    ``groups`` (or ``scales``) every motion component gets ``atol``."""
    vec = np.concatenate([np.full(n_motion, float(atol)), np.full(ny - n_motion, QUADRATURE_ATOL)])
    if groups is not None and scales is not None:
        for g, s in zip(groups.groups, scales, strict=True):
            vec[g] = float(atol) * s
    return vec


def roundoff_limited(
    f: Callable[[float, np.ndarray], np.ndarray],
    t: float,
    y: np.ndarray,
    h: float,
    atol: np.ndarray,
    rtol: float,
    n_motion: int,
) -> str:
    """Why the error control at ``(t, y)`` steers on round-off ("" when it does not).

    ``f`` is evaluated at ``y`` and at ``y`` with each motion component moved by one ε relative,
    in alternating directions, and the other way; the largest change ``d_i`` of ``ẏ_i`` is the
    right-hand side's round-off floor there. When ``h · d_i`` reaches the component's tolerance
    ``atol_i + rtol |y_i|`` for some ``i``, a one-ulp change of the state moves the step's
    increment by the whole tolerance: the step size ``h`` is set by round-off, not by the motion,
    and smaller steps cannot help. A right-hand side that raises on the moved state answers "".
    """
    eps = np.finfo(float).eps
    y = np.array(y, dtype=float)
    sign = np.zeros(y.size)
    sign[:n_motion] = np.where(np.arange(n_motion) % 2 == 0, eps, -eps)
    try:
        base = np.asarray(f(t, y))[:n_motion]
        d = np.zeros(n_motion)
        for s in (sign, -sign):
            d = np.maximum(d, np.abs(np.asarray(f(t, y * (1.0 + s)))[:n_motion] - base))
    except (ArithmeticError, ValueError, np.linalg.LinAlgError):
        return ""
    tol = atol[:n_motion] + rtol * np.abs(y[:n_motion])
    ratio = abs(h) * d / tol
    i = int(np.argmax(ratio))
    if not (np.isfinite(ratio[i]) and ratio[i] >= 1.0):
        return ""
    scale = float(np.max(np.abs(base))) or 1.0
    return (
        f"{ROUNDOFF_LIMITED} at t = {t:.6g} s: a one-ulp change of the state moves ẏ[{i}] by "
        f"{d[i]:.3g} (~{d[i] / scale:.1g} of the largest rate {scale:.3g}), so a step of "
        f"{abs(h):.3g} s moves component {i} by {ratio[i]:.2g} × its tolerance "
        f"{tol[i]:.3g}: the motion is beyond what double precision resolves at rtol {rtol:g}"
    )


def is_roundoff_stop(message: str) -> bool:
    """Whether a run's ``message`` says :class:`RoundoffWatch` stopped it: the motion beyond what
    double precision resolves at the run's tolerance (a statement about the scene and the
    tolerance, never about a plant's model)."""
    return str(message).startswith(ROUNDOFF_LIMITED)


class RoundoffWatch:
    """The probe as the loops ask it. :meth:`check`, every :data:`PROBE_STEPS` steps, answers the
    reason to stop once :data:`PROBES_IN_A_ROW` probes in a row found the run round-off limited
    *and* it grinds: the steps since the probe before are :data:`SLOWDOWN` times shorter than the
    run's average, or at their pace the horizon is more than :data:`PROJECTED_STEPS` steps away
    ("" otherwise). A run whose steps are set by round-off but keep their pace (a body 6.6e5 m from the origin,
    where Pinocchio's world-frame products round ω̇ at 1e-10) finishes and is judged as usual."""

    def __init__(
        self,
        f: Callable[[float, np.ndarray], np.ndarray],
        rtol: float,
        n_motion: int,
        t0: float,
        t_end: float,
    ):
        self.f, self.rtol, self.n_motion = f, float(rtol), int(n_motion)
        self.t0, self.t_end = float(t0), float(t_end)
        self.in_a_row = 0
        self.last: tuple[float, int] | None = None

    def check(self, t: float, y: np.ndarray, h: float, atol: np.ndarray, nsteps: int) -> str:
        """Probe at ``(t, y)`` after a step of ``h`` under ``atol``, ``nsteps`` steps into the run;
        the reason to stop, or ""."""
        last, self.last = self.last, (float(t), int(nsteps))
        why = roundoff_limited(self.f, t, y, h, atol, self.rtol, self.n_motion)
        self.in_a_row = self.in_a_row + 1 if why else 0
        if self.in_a_row < PROBES_IN_A_ROW or last is None or nsteps <= last[1]:
            return ""
        pace = (t - last[0]) / (nsteps - last[1])  # s per step since the probe before
        average = (t - self.t0) / nsteps  # s per step over the run so far
        projected = (self.t_end - t) / pace if pace > 0 else math.inf
        if projected <= PROBE_STEPS or (projected <= PROJECTED_STEPS and pace * SLOWDOWN >= average):
            return ""
        return (
            f"{why} (at {PROBES_IN_A_ROW} probes in a row, {PROBE_STEPS} steps apart; the last "
            f"steps average {pace:.2g} s against {average:.2g} s over the run, the horizon is "
            f"{projected:.2g} steps away at that pace)"
        )


__all__ = [
    "GROUP_UNIT",
    "PROBES_IN_A_ROW",
    "PROBE_STEPS",
    "PROJECTED_STEPS",
    "QUADRATURE_ATOL",
    "RESCALE_STEPS",
    "ROUNDOFF_LIMITED",
    "SLOWDOWN",
    "ErrorGroups",
    "RoundoffWatch",
    "atol_vector",
    "follow_scales",
    "group_scales",
    "is_roundoff_stop",
    "roundoff_limited",
]
