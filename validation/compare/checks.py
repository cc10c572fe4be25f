"""Diff of two :class:`~analytic.trajectory.Trajectory` records over time, summaries and checks.

What is compared (every quantity a scalar per output sample, so it can be summarised as max, RMS,
final value and time of the max, plotted on a log axis and logged to Rerun):

* analytic vs MuJoCo (key ``diff.<name>``): position of C ``|R_a - R_m|`` (m, inertial); attitude,
  the angle of the relative quaternion ``conj(u_a) ⊗ u_m``, ``2·atan2(|vec|, |w|)`` (rad, so q and -q
  are the same attitude); rod positions ``max_i |p_a,i - p_m,i|`` (m); velocity of C (m/s); rod
  velocities (m/s); body angular velocity ``|ω_a - ω_m|`` (rad/s, body axes); control torque
  ``|τ_a - τ_m|`` (N·m, body axes); rod forces ``max_i |F_a,i - F_m,i|`` (N);
* each plant (key ``<plant>.<name>``): tracking errors against the requirement ``|e_ω|`` (rad/s) and
  ``max_i |e_p,i|`` (m); their deviations from the closed-form error dynamics (``docs/errata.md``, item 3:
  ``e_ω(t) = exp(-P t) e_ω(0)``, and ``ë + α ė + β e = 0`` for each controlled mass, Eq. 78);
  the quaternion norm error ``|uᵀu - 1|``; the balances of linear momentum (against gravity),
  angular momentum about the system centre of mass (against the impulse of the control torque) and
  energy (against the work of the control); the control torque ``|τ|`` and each rod force.

Each check compares one summarised value with a named threshold from :mod:`validation.compare.thresholds`
(the scene's ``[thresholds]`` override the defaults). For the states' differences and the tracking
laws the bound is ``value + rtol · scale`` (:meth:`analytic.threshold.Threshold.bound`), ``scale``
the quantity's own magnitude: the largest over time and over the compared plants of C's departure
from its uniformly accelerated motion (position and velocity of C), ``|p_i|`` (rod positions),
``|ṗ_i|``, ``|ω|`` (:data:`MAGNITUDES`); for
a tracking law the plant's own ``|ω|`` or controlled ``|p_i|``. Non-finite samples are left out
of a scale (a diverged run's difference is infinite and fails anyway). Quaternions are w first.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, ClassVar

import numpy as np

from analytic.effects import Effect
from analytic.invariants import Balance, balance_residual, balance_scale
from analytic.threshold import Bound, BoundPart
from analytic.trajectory import Engine, RunStatus, Trajectory
from validation.compare.thresholds import Threshold, thresholds_for

# Two sample times are the same sample when they agree to this (s).
TIME_MATCH_TOL = 1e-9


class Group(StrEnum):
    """What a series shows (one figure / one Rerun plot per group)."""

    DIFFERENCE = "difference"
    TRACKING = "tracking"
    INVARIANT = "invariant"
    CONTROL = "control"


class Difference(StrEnum):
    """The quantities compared between two plants, in report order (the names of their
    thresholds in :mod:`validation.compare.thresholds`); the last two are relative to the reference
    plant's largest control force, ``rod_forces`` only with masses."""

    POSITION_C = "position_C"
    ATTITUDE = "attitude"
    ROD_POSITIONS = "rod_positions"
    VELOCITY_C = "velocity_C"
    ROD_VELOCITIES = "rod_velocities"
    ANGULAR_VELOCITY = "angular_velocity"
    CONTROL_TORQUE = "control_torque"
    ROD_FORCES = "rod_forces"


PAIR_SEPARATOR = " vs "


class Subject(str):
    """Whose quantity a series or check is: one plant (its name, ``"mujoco"``) or the difference of
    two (``"analytic vs mujoco"``, the two in report order: :func:`mj_bridge.registry.order_key`).

    Open: any plant name, a built-in's, a plugin's or another label (ordered last). A ``str``, so
    it equals, hashes and serialises as its text; compare subjects with ``==``, not ``is``. The
    built-in plants and their pairs are the class constants :attr:`ANALYTIC`, :attr:`MUJOCO`,
    :attr:`PINOCCHIO`, :attr:`BOTH` (the reference pair, analytic vs MuJoCo),
    :attr:`ANALYTIC_PINOCCHIO` and :attr:`MUJOCO_PINOCCHIO`.
    """

    __slots__ = ()

    ANALYTIC: ClassVar[Subject]
    MUJOCO: ClassVar[Subject]
    PINOCCHIO: ClassVar[Subject]
    BOTH: ClassVar[Subject]
    ANALYTIC_PINOCCHIO: ClassVar[Subject]
    MUJOCO_PINOCCHIO: ClassVar[Subject]

    def __new__(cls, text: str) -> Subject:
        text = str(text)
        parts = text.split(PAIR_SEPARATOR)
        if len(parts) > 2 or not all(p and p == p.strip() for p in parts):
            raise ValueError(
                f"subject: a plant name or 'a vs b', each a non-empty name (got {text!r})"
            )
        return super().__new__(cls, text)

    @classmethod
    def plant(cls, name: str) -> Subject:
        """The subject of plant ``name`` alone (``ValueError`` for a name holding ``" vs "``)."""
        s = cls(name)
        if s.is_pair:
            raise ValueError(f"subject: a plant name cannot hold {PAIR_SEPARATOR!r} (got {name!r})")
        return s

    @classmethod
    def pair(cls, a: str, b: str) -> Subject:
        """The subject of the difference of plants ``a`` and ``b`` (names, either order), the
        two in report order."""
        # deferred: mj_bridge.registry reads installed metadata (importlib.metadata, ~20 ms by python -X importtime), paid only when plants are ordered
        from mj_bridge.registry import order_key

        first, second = sorted((str(cls.plant(a)), str(cls.plant(b))), key=order_key)
        if first == second:
            raise ValueError(f"subject: a pair of two different plants (got {a!r} twice)")
        return cls(f"{first}{PAIR_SEPARATOR}{second}")

    @property
    def value(self) -> str:
        """The text, a plain ``str`` (as an enum member's ``value``)."""
        return str.__str__(self)

    @property
    def is_pair(self) -> bool:
        return PAIR_SEPARATOR in self

    @property
    def plants(self) -> tuple[str, ...]:
        """The plant names this subject is about (two for a pair)."""
        return tuple(self.value.split(PAIR_SEPARATOR))

    @property
    def slug(self) -> str:
        """``analytic_vs_mujoco``: the subject in keys, labels and entity paths."""
        return self.value.replace(PAIR_SEPARATOR, "_vs_")

    def __repr__(self) -> str:
        return f"Subject({self.value!r})"


Subject.ANALYTIC = Subject(Engine.ANALYTIC.value)
Subject.MUJOCO = Subject(Engine.MUJOCO.value)
Subject.PINOCCHIO = Subject(Engine.PINOCCHIO.value)
Subject.BOTH = Subject("analytic vs mujoco")
Subject.ANALYTIC_PINOCCHIO = Subject("analytic vs pinocchio")
Subject.MUJOCO_PINOCCHIO = Subject("mujoco vs pinocchio")


def subject_order_key(subject: str) -> tuple:
    """Sort key of subjects in report order: the plants first (in report order), then the pairs
    (by their first plant, then their second)."""
    from mj_bridge.registry import order_key

    s = Subject(subject)
    return (len(s.plants), *(order_key(p) for p in s.plants))


def _frozen(a: Any) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Summary:
    """Summary of a series over time: ``max`` (of the values), ``rms``, ``final`` value and
    ``t_max`` (s), the time of the max. NaN when the series is empty or has no finite sample."""

    max: float
    rms: float
    final: float
    t_max: float

    @classmethod
    def of(cls, t: np.ndarray, values: np.ndarray) -> Summary:
        t = np.asarray(t, float)
        v = np.asarray(values, float)
        if v.size == 0:
            return cls(math.nan, math.nan, math.nan, math.nan)
        finite = np.isfinite(v)
        if not finite.all():
            # A non-finite sample is the worst value: report it as the max, at its time.
            i = int(np.argmin(finite))
            return cls(math.inf, math.inf, float(v[-1]), float(t[i]))
        i = int(np.argmax(v))
        return cls(float(v[i]), float(np.sqrt(np.mean(v * v))), float(v[-1]), float(t[i]))

    def to_dict(self) -> dict[str, float]:
        return {"max": self.max, "rms": self.rms, "final": self.final, "t_max": self.t_max}


@dataclass(frozen=True)
class Series:
    """One scalar quantity per sample.

    Attributes:
        key: unique name, ``diff.<name>`` or ``<plant>.<name>``.
        label: what it is, for people.
        unit: SI unit ("1" for dimensionless).
        group: see :class:`Group`.
        subject: see :class:`Subject`.
        t: sample times, s, shape (N,).
        values: shape (N,).
    """

    key: str
    label: str
    unit: str
    group: Group
    subject: Subject
    t: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.subject, Subject):
            object.__setattr__(self, "subject", Subject(self.subject))
        object.__setattr__(self, "t", _frozen(self.t))
        object.__setattr__(self, "values", _frozen(self.values))
        if self.t.shape != self.values.shape or self.t.ndim != 1:
            raise ValueError(
                f"{self.key}.values: shape must equal t's (N,) = {self.t.shape} (got {self.values.shape})"
            )

    @property
    def summary(self) -> Summary:
        return Summary.of(self.t, self.values)

    @property
    def name(self) -> str:
        return self.key.split(".", 1)[1]


class CheckState(StrEnum):
    """A check's outcome, as every output states it (``report.md``'s verdict column, the
    ``verdict`` of report.json's check records)."""

    PASS = "pass"
    FAIL = "FAIL"
    NOT_APPLICABLE = "not applicable"  # nothing to check (no control torque in either plant)


@dataclass(frozen=True)
class Check:
    """One verdict.

    Attributes:
        name: the threshold's name (``position_C``) or ``completed``.
        subject: whose value it is.
        value: the checked value (max over time, divided by ``scale`` for relative checks).
        threshold: the effective bound; passes when ``value <= threshold`` (``completed``: the
            run reached its horizon, value = time reached, threshold = horizon). For a bound with
            a relative part, ``absolute_part + relative_part``.
        unit: unit of value and threshold.
        passed: the verdict.
        reason: why the threshold has its value (or why the check failed).
        series: key of the series the value summarises ("" when none).
        scale: the divisor of a relative check, in the signal's unit (1.0 for absolute checks).
        t_max: time of the worst value, s.
        bound: the name of the threshold when ``name`` is not it ("" when it is): a hard case's
            ``hard_*`` bound (:mod:`validation.studies.hard_cases`), which several checks share.
        applicable: False when there is nothing to check (neither plant has the quantity, e.g. no
            control torque in a scene that controls no angular velocity): the check is neither
            passed nor failed but NOT_APPLICABLE (``passed`` is True so it fails nothing;
            ``value`` and ``t_max`` are NaN; ``reason`` says why).
        absolute_part: the threshold's absolute part (its ``value``, atol), in ``unit``; NaN
            given means ``threshold`` (a bound without a relative part).
        relative_part: ``rtol × magnitude``, in ``unit`` (0 without a relative part).
        magnitude: the quantity's own scale the relative part multiplies (the largest departure
            of C from its uniformly accelerated motion, ``|p_i|``, ``|ṗ_i|`` or ``|ω|`` over time
            and the compared plants), in
            ``unit``; 0 without a relative part.
        decided_by: :class:`~analytic.threshold.BoundPart`, the larger part (ABSOLUTE on a tie
            or without a relative part).
    """

    name: str
    subject: Subject
    value: float
    threshold: float
    unit: str
    passed: bool
    reason: str
    series: str = ""
    scale: float = 1.0
    t_max: float = math.nan
    bound: str = ""
    applicable: bool = True
    absolute_part: float = math.nan
    relative_part: float = 0.0
    magnitude: float = 0.0
    decided_by: BoundPart = BoundPart.ABSOLUTE

    def __post_init__(self) -> None:
        if not isinstance(self.subject, Subject):
            object.__setattr__(self, "subject", Subject(self.subject))
        if math.isnan(self.absolute_part):
            object.__setattr__(self, "absolute_part", float(self.threshold))
        object.__setattr__(self, "decided_by", BoundPart(self.decided_by))

    @property
    def state(self) -> CheckState:
        """PASS, FAIL or NOT_APPLICABLE."""
        if not self.applicable:
            return CheckState.NOT_APPLICABLE
        return CheckState.PASS if self.passed else CheckState.FAIL

    @property
    def label(self) -> str:
        """``position_C`` (analytic vs MuJoCo), ``analytic_vs_pinocchio.position_C``,
        ``mujoco.energy``: unique within a comparison."""
        if self.subject == Subject.BOTH:
            return self.name
        return f"{self.subject.slug}.{self.name}"

    def to_dict(self) -> dict[str, Any]:
        out = {
            "name": self.name,
            "subject": self.subject.value,
            "value": self.value,
            "threshold": self.threshold,
            "unit": self.unit,
            "passed": self.passed,
            "verdict": self.state.value,
            "applicable": self.applicable,
            "reason": self.reason,
            "series": self.series,
            "scale": self.scale,
            "t_max": self.t_max,
            "absolute_part": self.absolute_part,
            "relative_part": self.relative_part,
            "magnitude": self.magnitude,
            "decided_by": self.decided_by.value,
        }
        if self.bound:
            out["bound"] = self.bound
        return out


@dataclass(frozen=True)
class Comparison:
    """The result of :func:`compare`: every series, every check, and notes.

    Attributes:
        scene: scene name.
        t: common sample times, s, shape (N,).
        series: all series (differences first, then each plant's).
        checks: all checks.
        notes: what was not compared and why (e.g. MuJoCo missing, a run failed part way).
        thresholds: the thresholds in force.
    """

    scene: str
    t: np.ndarray
    series: tuple[Series, ...]
    checks: tuple[Check, ...]
    notes: tuple[str, ...] = ()
    thresholds: Mapping[str, Threshold] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return bool(self.checks) and all(c.passed for c in self.checks)

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)

    @property
    def applicable_checks(self) -> tuple[Check, ...]:
        """The checks that check something (not NOT_APPLICABLE)."""
        return tuple(c for c in self.checks if c.applicable)

    def get(self, key: str) -> Series:
        for s in self.series:
            if s.key == key:
                return s
        raise KeyError(f"no series {key!r} (have: {', '.join(s.key for s in self.series)})")

    def check(self, label: str) -> Check:
        for c in self.checks:
            if c.label == label:
                return c
        raise KeyError(f"no check {label!r} (have: {', '.join(c.label for c in self.checks)})")

    def to_dict(self) -> dict[str, Any]:
        return {
            "scene": self.scene,
            "passed": self.passed,
            "samples": int(self.t.shape[0]),
            "t_end": float(self.t[-1]) if self.t.size else None,
            "checks": [c.to_dict() for c in self.checks],
            "summaries": {
                s.key: {"label": s.label, "unit": s.unit, **s.summary.to_dict()}
                for s in self.series
            },
            "notes": list(self.notes),
        }


# ----------------------------------------------------------------------------------------------
# Elementary measures
# ----------------------------------------------------------------------------------------------


def attitude_angle(u_a: np.ndarray, u_b: np.ndarray) -> np.ndarray:
    """Angle of the relative rotation between two attitudes, rad, in [0, π].

    ``conj(u_a) ⊗ u_b = (w, vec)`` with ``w = u_a·u_b`` and ``vec = a0 b⃗ - b0 a⃗ - a⃗ × b⃗``; the
    angle is ``2·atan2(|vec|, |w|)``, so q and -q give 0. Quaternions need not be unit (the ratio is
    scale-free). Shapes (N, 4), (N, 4) -> (N,), or (4,), (4,) -> ().
    """
    a = np.asarray(u_a, float)
    b = np.asarray(u_b, float)
    if a.shape != b.shape or a.shape[-1] != 4:
        raise ValueError(f"u_b: shape must equal u_a's (..., 4) = {a.shape} (got {b.shape})")
    w = np.sum(a * b, axis=-1)
    vec = a[..., :1] * b[..., 1:] - b[..., :1] * a[..., 1:] - np.cross(a[..., 1:], b[..., 1:])
    return 2.0 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(w))


def _norm(x: np.ndarray) -> np.ndarray:
    return np.linalg.norm(x, axis=1) if x.ndim == 2 else np.abs(x)


def _maxabs(x: np.ndarray) -> np.ndarray:
    """Max over columns of |x|, shape (N, k) -> (N,); zeros when k = 0."""
    if x.shape[1] == 0:
        return np.zeros(x.shape[0])
    return np.max(np.abs(x), axis=1)


def _common(a: Trajectory, b: Trajectory) -> int:
    """Number of leading samples the two trajectories share (same times)."""
    n = min(a.t.shape[0], b.t.shape[0])
    if n == 0:
        return 0
    same = np.abs(a.t[:n] - b.t[:n]) <= TIME_MATCH_TOL * np.maximum(1.0, np.abs(a.t[:n]))
    if not same[0]:
        raise ValueError(
            f"t: the two trajectories start at different times ({a.t[0]} vs {b.t[0]} s)"
        )
    return int(np.argmin(same)) if not same.all() else n


# ----------------------------------------------------------------------------------------------
# Series
# ----------------------------------------------------------------------------------------------


def pair_subject(a: Trajectory, b: Trajectory) -> Subject:
    """The subject of ``a`` vs ``b``; two runs of one engine are compared as the reference pair."""
    if a.engine == b.engine:
        return Subject.BOTH
    return Subject.pair(a.engine, b.engine)


def diff_key(subject: Subject, name: str) -> str:
    """Key of a difference series: ``diff.<name>`` for analytic vs MuJoCo (the two-plant report's
    keys), ``diff_<pair slug>.<name>`` for any other pair."""
    return f"diff.{name}" if subject == Subject.BOTH else f"diff_{subject.slug}.{name}"


def difference_series(a: Trajectory, b: Trajectory) -> tuple[Series, ...]:
    """Differences of two plants on their common samples (see the module docstring)."""
    if a.n != b.n:
        raise ValueError(f"q: the trajectories have different numbers of masses ({a.n} vs {b.n})")
    k = _common(a, b)
    t = a.t[:k]
    qa, qb, va, vb = a.q[:k], b.q[:k], a.qdot[:k], b.qdot[:k]
    D, S = Group.DIFFERENCE, pair_subject(a, b)
    rows = [
        ("position_C", "position of C |R_a − R_m|", "m", _norm(qa[:, :3] - qb[:, :3])),
        (
            "attitude",
            "attitude angle of conj(u_a)⊗u_m",
            "rad",
            attitude_angle(qa[:, 3:7], qb[:, 3:7]),
        ),
        ("rod_positions", "rod positions max_i |p_a − p_m|", "m", _maxabs(qa[:, 7:] - qb[:, 7:])),
        ("velocity_C", "velocity of C |Ṙ_a − Ṙ_m|", "m/s", _norm(va[:, :3] - vb[:, :3])),
        (
            "rod_velocities",
            "rod velocities max_i |ṗ_a − ṗ_m|",
            "m/s",
            _maxabs(va[:, 7:] - vb[:, 7:]),
        ),
        (
            "angular_velocity",
            "body angular velocity |ω_a − ω_m|",
            "rad/s",
            _norm(a.omega[:k] - b.omega[:k]),
        ),
        ("control_torque", "control torque |τ_a − τ_m|", "N·m", _norm(a.torque[:k] - b.torque[:k])),
        (
            "rod_forces",
            "rod forces max_i |F_a − F_m|",
            "N",
            _maxabs(a.rod_forces[:k] - b.rod_forces[:k]),
        ),
    ]
    return tuple(Series(diff_key(S, n), lab, u, D, S, t, v) for n, lab, u, v in rows)


def _propagate(A: np.ndarray, x0: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``x(t) = exp(A (t - t0)) x0`` at every time of ``t``, shape (N, k).

    Output times are uniform (``analytic.scene.output_times``): then ``x_{i+1} = exp(A h) x_i``
    with one matrix exponential, exact up to rounding that grows at most like ``i`` ulps for a
    stable ``A`` (below 1e-12 relative over 10⁴ samples, far under the tracking thresholds).
    Other time grids take one exponential per time (scipy's batched ``expm``)."""
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


def _tracking_law(traj: Trajectory, scene: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Deviations of the tracking errors from their closed-form dynamics, or None when untracked."""
    tr, t = traj.tracking, traj.t
    dev_w = dev_p = None
    if tr.omega_components and scene.control.omega is not None and t.size:
        e = tr.e_omega
        ref = omega_error_reference(t, e[0], scene.control.omega.gain)
        dev_w = _norm(e - ref)
    if tr.mass_indices and scene.control.masses is not None and t.size:
        mt = scene.control.masses
        pos = [list(mt.indices).index(i) for i in tr.mass_indices]
        l, lam = np.asarray(mt.l)[pos], np.asarray(mt.lam)[pos]
        # p̄ = p_e + l cos(λ t) (Eq. 75), so ė(t0) = ṗ(t0) + l λ sin(λ t0).
        edot0 = traj.qdot[0, 7 + np.array(tr.mass_indices)] + l * lam * np.sin(lam * t[0])
        ref = mass_error_reference(
            t, tr.e_p[0], edot0, np.asarray(mt.alpha)[pos], np.asarray(mt.beta)[pos]
        )
        dev_p = _maxabs(tr.e_p - ref)
    return dev_w, dev_p


def plant_series(traj: Trajectory, scene: Any = None) -> tuple[Series, ...]:
    """One plant's tracking errors, invariants' balances and control forces (module docstring)."""
    subj = Subject.plant(traj.engine)
    t = traj.t
    inv = traj.invariants
    out: list[Series] = []

    def add(name, label, unit, group, values):
        out.append(Series(f"{subj.value}.{name}", label, unit, group, subj, t, values))

    T, I, C = Group.TRACKING, Group.INVARIANT, Group.CONTROL
    if traj.tracking.omega_components:
        add("e_omega", "tracking error |ω − ω̄|", "rad/s", T, _norm(traj.tracking.e_omega))
    if traj.tracking.mass_indices:
        add("e_p", "tracking error max_i |p_i − p̄_i|", "m", T, _maxabs(traj.tracking.e_p))
    if scene is not None:
        dev_w, dev_p = _tracking_law(traj, scene)
        if dev_w is not None:
            add("e_omega_law", "|e_ω − exp(−P t) e_ω(0)|", "rad/s", T, dev_w)
        if dev_p is not None:
            add("e_p_law", "max_i |e_p − e_ref| (ë + αė + βe = 0)", "m", T, dev_p)
    add("quat_norm", "quaternion norm error |uᵀu − 1|", "1", I, np.abs(inv.quat_norm_error))
    add(
        "linear_momentum",
        "linear momentum balance |P − P_expected|",
        "kg·m/s",
        I,
        balance_residual(inv, Balance.LINEAR_MOMENTUM),
    )
    add(
        "angular_momentum",
        "angular momentum balance |L − L(0) − ∫Sτ dt|",
        "kg·m²/s",
        I,
        balance_residual(inv, Balance.ANGULAR_MOMENTUM),
    )
    add("energy", "energy balance |E − E(0) − W|", "J", I, balance_residual(inv, Balance.ENERGY))
    add("torque", "control torque |τ| (body axes)", "N·m", C, _norm(traj.torque))
    for i in range(traj.n):
        add(f"rod_force_{i + 1}", f"rod force on mass {i + 1}", "N", C, traj.rod_forces[:, i])
    return tuple(out)


# ----------------------------------------------------------------------------------------------
# Checks
# ----------------------------------------------------------------------------------------------


def _not_applicable(th: Threshold, subject: Subject, why: str) -> Check:
    """A check of ``th`` with nothing to check (:attr:`Check.applicable` False), saying why."""
    return Check(th.name, subject, math.nan, th.value, th.unit, True, why, applicable=False)


def _bound_check(
    th: Threshold, subject: Subject, series: Series, scale: float = 1.0, magnitude: float = 0.0
) -> Check:
    """The check of ``series``' max against ``th``: divided by ``max(scale, floor)`` for a
    relative threshold; against ``th.value + th.rtol · magnitude`` (``magnitude``: the quantity's
    own scale over the run, in its unit) for an absolute one."""
    s = series.summary
    if th.relative:
        scale = max(float(scale), th.floor)
        value = s.max / scale
        bound = Bound(th.value)
    else:
        scale = 1.0
        value = s.max
        bound = th.bound(magnitude)
    passed = bool(np.isfinite(value) and value <= bound.value)
    return Check(
        th.name,
        subject,
        float(value),
        bound.value,
        th.unit,
        passed,
        th.reason,
        series.key,
        scale,
        s.t_max,
        absolute_part=bound.absolute,
        relative_part=bound.relative,
        magnitude=bound.scale,
        decided_by=bound.decided_by,
    )


def judge(
    name: str,
    subject: Subject,
    value: float,
    threshold: float,
    unit: str,
    reason: str,
    *,
    bound: str = "",
    t_max: float = math.nan,
) -> Check:
    """A check of one value already summarised: passes when ``value`` is finite and at most
    ``threshold`` (a NaN or an infinity fails); ``bound`` names the threshold when ``name`` is not
    it. For values that are not a series' summary (a closed form met at sampled states, a count)."""
    value = float(value)
    passed = bool(math.isfinite(value) and value <= threshold)
    return Check(
        name, subject, value, float(threshold), unit, passed, reason, t_max=t_max, bound=bound
    )


def completed_check(traj: Trajectory, t_end: float | None = None) -> Check:
    """The ``completed`` check of one run: status ``ok`` and its last sample at ``t_end`` (s;
    default the run's own last sample)."""
    return _completed_check(traj, t_end)


def _completed_check(traj: Trajectory, t_end: float | None) -> Check:
    reached = float(traj.t[-1]) if traj.t.size else math.nan
    horizon = float(t_end) if t_end is not None else reached
    ok = traj.status is RunStatus.OK and traj.t.size > 0 and reached >= horizon - TIME_MATCH_TOL
    reason = (
        "the run reached its horizon"
        if ok
        else f"the run did not finish: {traj.message or traj.status.value}"
    )
    return Check("completed", Subject.plant(traj.engine), reached, horizon, "s", bool(ok), reason)


def _largest(x: np.ndarray, rows: bool) -> float:
    """The largest finite magnitude of ``x`` (shape (N, k)): of each row's Euclidean norm when
    ``rows`` (a vector per sample), else of every entry; 0 when there is none."""
    a = np.asarray(x, float)
    if a.size == 0:
        return 0.0
    m = np.linalg.norm(a, axis=1) if rows else np.abs(a)
    m = m[np.isfinite(m)]
    return float(m.max()) if m.size else 0.0


def _departure(tr: Trajectory, k: int, g: np.ndarray, velocity: bool) -> float:
    """The largest departure of C's motion over the first ``k`` samples from the uniformly
    accelerated one its first sample and gravity ``g`` (inertial, m/s², zeros without the effect)
    give: ``|R - (R(0) + Ṙ(0) t + ½ g t²)|`` (m), or ``|Ṙ - (Ṙ(0) + g t)|`` (m/s) for
    ``velocity``. The uniformly accelerated part is a polynomial of degree two that both kinds of
    integrator (Runge-Kutta methods of order 4 and 8) reproduce to round-off, so it is not a scale
    of their error, however far it carries C (1.6 km of free fall in the paper scenes)."""
    k = min(k, tr.t.shape[0])
    if k == 0:
        return 0.0
    t = (tr.t[:k] - tr.t[0])[:, None]
    R, V = tr.q[:k, :3], tr.qdot[:k, :3]
    if velocity:
        return _largest(V - (V[0] + g * t), True)
    return _largest(R - (R[0] + V[0] * t + 0.5 * g * t * t), True)


MAGNITUDES: Mapping[str, Any] = {
    "position_C": lambda tr, k, g: _departure(tr, k, g, False),  # m
    "rod_positions": lambda tr, k, g: _largest(tr.q[:k, 7:], False),  # |p_i|, m
    "velocity_C": lambda tr, k, g: _departure(tr, k, g, True),  # m/s
    "rod_velocities": lambda tr, k, g: _largest(tr.qdot[:k, 7:], False),  # |ṗ_i|, m/s
    "angular_velocity": lambda tr, k, g: _largest(tr.omega[:k], True),  # |ω|, rad/s (body axes)
}
"""Difference quantity -> ``(trajectory, k, g) -> its largest magnitude over the first k
samples``, in the quantity's unit: the scale of its bound's relative part (the pair's is the
larger of the two plants'). For C, its departure from the uniformly accelerated motion
(:func:`_departure`); for the others, their own magnitude. The attitude has none
(:data:`validation.compare.thresholds.SCALED`)."""


def scene_gravity(scene: Any) -> np.ndarray:
    """The scene's gravity vector (inertial, m/s², shape (3,)); zeros without the effect or
    without a scene."""
    if scene is None or not scene.has(Effect.GRAVITY):
        return np.zeros(3)
    return np.asarray(scene.gravity, float)


def pair_magnitude(
    name: str, a: Trajectory, b: Trajectory, k: int | None = None, scene: Any = None
) -> float:
    """The scale of difference ``name``'s relative part for plants ``a`` and ``b``: the largest
    magnitude over their first ``k`` samples (default all) and over the two, in the quantity's
    unit (:data:`MAGNITUDES`; ``scene`` gives C's gravity); 0 for a quantity without one."""
    of = MAGNITUDES.get(name)
    if of is None:
        return 0.0
    if k is None:
        k = min(a.t.shape[0], b.t.shape[0])
    g = scene_gravity(scene)
    return max(of(a, k, g), of(b, k, g))


def _tracking_magnitudes(traj: Trajectory) -> tuple[float, float]:
    """The scales of one plant's tracking laws: its largest ``|ω|`` (rad/s) and the largest
    ``|p_i|`` of its controlled masses (m), over the run."""
    idx = list(traj.tracking.mass_indices)
    p = _largest(traj.q[:, [7 + i for i in idx]], False) if idx else 0.0
    return _largest(traj.omega, True), p


def _scale_max(x: np.ndarray) -> float:
    if x.size == 0:
        return 0.0
    v = (
        _norm(x)
        if x.ndim == 2 and x.shape[1] > 1
        else np.abs(x).reshape(x.shape[0], -1).max(axis=1)
    )
    return float(np.max(v)) if v.size else 0.0


def compare(
    analytic: Trajectory,
    mujoco: Trajectory | None,
    scene: Any = None,
    thresholds: Mapping[str, Threshold] | None = None,
    t_end: float | None = None,
) -> Comparison:
    """Compare two plants (or check one, when ``mujoco`` is None).

    Args:
        analytic: the reference trajectory (relative checks divide by its scales).
        mujoco: the other plant's trajectory (any engine), or None.
        scene: the scene (for the tracking gains and its ``[thresholds]``); without it the
            closed-form tracking checks are skipped.
        thresholds: thresholds in force (default ``thresholds_for(scene)``).
        t_end: the horizon both runs were asked for, s (default the scene's); a run that stops
            earlier fails its ``completed`` check.

    Returns:
        a frozen :class:`Comparison`.
    """
    th = dict(thresholds) if thresholds is not None else thresholds_for(scene)
    if t_end is None and scene is not None:
        t_end = scene.output.t_end
    notes: list[str] = []
    series: list[Series] = []
    checks: list[Check] = []
    plants = [p for p in (analytic, mujoco) if p is not None]

    for p in plants:
        checks.append(_completed_check(p, t_end))
        if p.status is not RunStatus.OK:
            notes.append(
                f"{p.engine} run failed: {p.message} (compared up to t = {p.t[-1]:.6g} s)"
                if p.t.size
                else f"{p.engine} run failed before its first sample: {p.message}"
            )

    if mujoco is not None:
        pair = pair_subject(analytic, mujoco)
        diffs = difference_series(analytic, mujoco)
        series.extend(diffs)
        by = {s.name: s for s in diffs}
        k = by["position_C"].t.shape[0]
        for name in list(Difference)[:6]:  # the absolute ones; the forces are relative, below
            size = pair_magnitude(name, analytic, mujoco, k, scene)
            checks.append(_bound_check(th[name], pair, by[name], magnitude=size))
        if np.any(analytic.torque[:k]) or np.any(mujoco.torque[:k]):
            checks.append(
                _bound_check(
                    th["control_torque"],
                    pair,
                    by["control_torque"],
                    _scale_max(analytic.torque[:k]),
                )
            )
        else:
            checks.append(
                _not_applicable(
                    th["control_torque"], pair, "neither plant applies a control torque"
                )
            )
        if analytic.n and (np.any(analytic.rod_forces[:k]) or np.any(mujoco.rod_forces[:k])):
            checks.append(
                _bound_check(
                    th["rod_forces"],
                    pair,
                    by["rod_forces"],
                    float(np.max(np.abs(analytic.rod_forces[:k]), initial=0.0)),
                )
            )
        elif analytic.n:
            checks.append(
                _not_applicable(th["rod_forces"], pair, "neither plant applies a rod force")
            )
    else:
        notes.append("no MuJoCo trajectory: only the analytic plant's own checks were made")

    if scene is None:
        notes.append("no scene given: the closed-form tracking checks were skipped")
    for p in plants:
        ps = plant_series(p, scene)
        series.extend(ps)
        by = {s.name: s for s in ps}
        subj = Subject.plant(p.engine)
        w_size, p_size = _tracking_magnitudes(p)
        if "e_omega_law" in by:
            checks.append(
                _bound_check(th["tracking_omega"], subj, by["e_omega_law"], magnitude=w_size)
            )
        if "e_p_law" in by:
            checks.append(_bound_check(th["tracking_p"], subj, by["e_p_law"], magnitude=p_size))
        inv = p.invariants
        checks.append(_bound_check(th["quat_norm"], subj, by["quat_norm"]))
        for b in Balance:  # relative to the balanced quantity: analytic.invariants.relative_balance
            checks.append(_bound_check(th[b.value], subj, by[b.value], balance_scale(inv, b)))

    t = series[0].t if series else analytic.t
    return Comparison(
        scene=analytic.scene,
        t=_frozen(t),
        series=tuple(series),
        checks=tuple(checks),
        notes=tuple(notes),
        thresholds=th,
    )


def compare_plants(
    plants: Sequence[Trajectory],
    scene: Any = None,
    thresholds: Mapping[str, Threshold] | None = None,
    t_end: float | None = None,
) -> Comparison:
    """Compare every pair of plants, and check each plant once.

    The first plant is the reference of the first pair (the two-plant comparison of
    :func:`compare`, keys ``diff.<name>``); every other pair adds its difference series
    (``diff_<pair>.<name>``) and checks (labels ``<pair>.<name>``) under the same thresholds, and
    every plant after the second adds its own checks (tracking, invariants).

    Args:
        plants: one trajectory per plant, in report order (the analytic plant first).
        scene, thresholds, t_end: as for :func:`compare`.
    """
    if not plants:
        raise ValueError("plants: no trajectory to compare")
    first = compare(plants[0], plants[1] if len(plants) > 1 else None, scene, thresholds, t_end)
    series, checks, notes = list(first.series), list(first.checks), list(first.notes)
    for i, j in itertools.combinations(range(len(plants)), 2):
        if (i, j) == (0, 1):
            continue
        c = compare(plants[i], plants[j], scene, first.thresholds, t_end)
        pair = pair_subject(plants[i], plants[j])
        series += [x for x in c.series if x.subject == pair]
        checks += [x for x in c.checks if x.subject == pair]
        if i == 0:  # plant j's own series and checks, once
            own = Subject.plant(plants[j].engine)
            series += [x for x in c.series if x.subject == own]
            checks += [x for x in c.checks if x.subject == own]
            notes += [n for n in c.notes if n not in notes]
    return dataclasses.replace(
        first, series=tuple(series), checks=tuple(checks), notes=tuple(notes)
    )


__all__ = [
    "MAGNITUDES",
    "PAIR_SEPARATOR",
    "Check",
    "Comparison",
    "Difference",
    "Group",
    "Series",
    "Subject",
    "Summary",
    "attitude_angle",
    "compare",
    "compare_plants",
    "completed_check",
    "diff_key",
    "difference_series",
    "judge",
    "mass_error_reference",
    "omega_error_reference",
    "pair_magnitude",
    "pair_subject",
    "plant_series",
    "subject_order_key",
]
