"""What each measure of :data:`validation.studies.hard_cases.catalogue.MEASURES` computes, on the runs of
one case.

A :class:`CaseRuns` holds one case's scene, its plants and every run and reference it has made
(each made once, when a measure first needs it); :func:`measure` returns the value(s) of one
``(what, against)`` pair for one plant. The agreement with the analytic plant is the comparison's
own difference series (:func:`validation.compare.checks.difference_series`); the balances are
:func:`validation.compare.summary.drift_figures`; the tracking laws' closed forms are
:func:`validation.compare.tracking_laws.omega_error_reference` and ``mass_error_reference``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from analytic.effects import SolverMethod
from analytic.scene import Scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from mj_bridge import plants as _plants
from validation.compare.checks import Check, Subject, difference_series
from validation.compare.differences import attitude_angle
from validation.compare.summary import drift_figures
from validation.compare.tracking_laws import mass_error_reference, omega_error_reference
from validation.runs.interrupts import checkpoint
from validation.studies.hard_cases.catalogue import Measure, Reference
from validation.studies.hard_cases.criterion import CheckSpec, Criterion
from validation.studies.hard_cases.references import (
    centre_of_mass,
    crossings,
    double_cover,
    euler,
    off_manifold,
    pinv_law,
    solvers,
)

ANALYTIC = Engine.ANALYTIC.value
"""The plant every other plant is compared with (``against = "analytic"``)."""


def label(engine: str) -> str:
    """How reports name a plant (``MuJoCo``; a plant in no registry by its name)."""
    cls = _plants.registered().get(str(engine))
    return cls.label if cls is not None else str(engine)


def run_plant(
    engine: str, scene: Scene, settings: Any = None, t_end: float | None = None
) -> Trajectory:
    """``scene`` on the plant ``engine`` through the plant protocol (its settings default to the
    scene's); the user's Ctrl-C stops the suite, not only the current case."""
    pl = _plants.plant(engine)
    # checkpoint: a signal compiled code swallowed stops the run at its next report
    return pl.simulate(scene, settings, t_end=t_end, progress=checkpoint).raise_if_interrupted()


@dataclass(frozen=True)
class Run:
    """One run a case made: ``plant``'s run of the case (``what`` ""), or of a reference
    (``what`` says which, e.g. ``Radau``, ``mirror``), and the horizon it was asked for (s)."""

    plant: str
    what: str
    trajectory: Trajectory
    t_end: float


@dataclass
class CaseRuns:
    """The runs and references of one case, each made once when first needed.

    Attributes:
        name, path: the case and its scene file.
        scene, criterion: the scene and its validated criterion.
        plants: the plants the case runs on (report order; the analytic plant first).
        runs: every run made, in order (their ``completed`` and ``finite`` checks are implicit).
        figures: plant -> extra figures found on the way (counts, costs).
        notes: findings reported with the row.
        checks: implicit checks of what is not a plant's run (an integration of a reference).
    """

    name: str
    path: Path
    scene: Scene
    criterion: Criterion
    plants: tuple[str, ...]
    runs: list[Run] = field(default_factory=list)
    figures: dict[str, dict[str, Any]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    checks: list[Check] = field(default_factory=list)
    _cache: dict[Any, Any] = field(default_factory=dict)

    def _once(self, key: Any, make: Callable[[], Any]) -> Any:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    def _record(self, plant: str, what: str, tr: Trajectory, t_end: float) -> Trajectory:
        self.runs.append(Run(plant, what, tr, t_end))
        return tr

    def run(self, plant: str) -> Trajectory:
        """``plant``'s run of the case's scene (its default settings)."""
        return self._once(
            ("run", plant),
            lambda: self._record(plant, "", run_plant(plant, self.scene), self.scene.output.t_end),
        )

    def mirror(self) -> Scene:
        assert self.criterion.mirror is not None  # (the criterion requires it)
        return self._once(
            "mirror", lambda: double_cover.mirror_scene(self.scene, self.criterion.mirror.scene)
        )

    def mirror_run(self, plant: str) -> Trajectory:
        """``plant``'s run of the mirrored scene over this scene's horizon."""
        t_end = self.scene.output.t_end

        def make() -> Trajectory:
            tr = run_plant(plant, self.mirror(), t_end=t_end)
            return self._record(plant, "mirror", tr, t_end)

        return self._once(("mirror", plant), make)

    def solver_run(self, plant: str, method: SolverMethod) -> Trajectory:
        p = self.criterion.solvers
        assert p is not None  # (the criterion requires it)

        def make() -> Trajectory:
            tr = run_plant(plant, self.scene, solvers.settings(plant, method, p.rtol, p.atol))
            return self._record(plant, method.value, tr, self.scene.output.t_end)

        return self._once(("solver", plant, method), make)

    def euler(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(t, ω, u, J)`` of the torque-free reference on the analytic run's samples."""

        def make():
            J = euler.rigid_inertia(self.scene)
            t = self.run(ANALYTIC).t
            w, u = euler.torque_free(J, self.scene.initial.omega, self.scene.initial.u, t)
            return t, w, u, J

        return self._once("euler", make)

    def flips(self, plant: str) -> np.ndarray:
        """Instants (s) where ``plant``'s ω about the intermediate axis changes sign."""
        axis = euler.intermediate_axis(euler.rigid_inertia(self.scene))
        tr = self.run(plant)
        return self._once(
            ("flips", plant), lambda: crossings.zero_crossings(tr.t, tr.omega[:, axis])
        )

    def euler_flips(self) -> np.ndarray:
        t, w, _, J = self.euler()
        axis = euler.intermediate_axis(J)

        def make():
            fl = crossings.zero_crossings(t, w[:, axis])
            self.notes.append(
                f"{len(fl)} sign changes of ω_{'xyz'[axis]} in {self.scene.output.t_end:g} s "
                f"(Euler reference)" + (f", first at {fl[0]:.6f} s" if len(fl) else "")
            )
            return fl

        return self._once("euler_flips", make)

    def first_crossing(self, plant: str) -> float:
        """The first instant (s) two neighbouring masses pass through each other on ``plant``
        (NaN when none do); the crossings are reported in the notes."""

        def make() -> float:
            tr = self.run(plant)
            found = crossings.mass_crossings(tr.t, tr.p)
            f = self.figures.setdefault(plant, {})
            f["crossings"] = len(found)
            f["first crossing s"] = found[0][0] if found else None
            if found:
                t0, i = found[0]
                self.notes.append(
                    f"{plant}: masses {i + 1} and {i + 2} pass through each other at "
                    f"t = {t0:.6f} s (no contact in the model); {len(found)} crossings in "
                    f"{tr.t[-1]:g} s"
                )
            return found[0][0] if found else math.nan

        return self._once(("crossing", plant), make)

    def states(self) -> Trajectory:
        """A short analytic run of the scene: the states the pointwise properties are
        evaluated at."""
        t_end = min(self.scene.output.t_end, pinv_law.STATE_RUN_S)
        return self._once(
            "states",
            lambda: self._record(
                ANALYTIC, "states", run_plant(ANALYTIC, self.scene, t_end=t_end), t_end
            ),
        )

    def pinv(self) -> pinv_law.PinvFindings:
        p = self.criterion.pinv_law
        assert p is not None  # (the criterion requires it)

        def make() -> pinv_law.PinvFindings:
            found = pinv_law.evaluate(
                self.scene,
                self.states(),
                self.plants,
                p.duplicate_mass,
                p.conflict_axis,
                p.conflict,
            )
            run = found.run
            reached = float(run.t[-1]) if run is not None and run.t.size else math.nan
            ok = run is not None and run.status is RunStatus.OK and reached >= found.t_end
            self.checks.append(
                Check(
                    "completed (conflicting rows)",
                    Subject.plant(ANALYTIC),
                    reached,
                    found.t_end,
                    "s",
                    bool(ok),
                    "the run with the conflicting rows reached its horizon"
                    if ok
                    else f"the run with the conflicting rows did not finish: {run and run.message}",
                )
            )
            d = p.conflict
            self.notes.append(
                f"unattainable part of the conflicting pair: residual (+{d / 2:g}, -{d / 2:g}) "
                f"rad/s², norm {found.residual_norm:.6g} (δ/√2 = {d / math.sqrt(2):.6g}); the "
                f"controller meets the mean of the two demands"
            )
            return found

        return self._once("pinv", make)


# ----------------------------------------------------------------------------------------------
# Measures
# ----------------------------------------------------------------------------------------------

Values = list[tuple[str, float]]
"""A measure's value(s): ``(qualifier, value)``; the qualifier ("" or e.g. ``Radau``) tells apart
the values of one measure that has several (one per method)."""


def _drift(key: str) -> Callable[[CaseRuns, CheckSpec, str], float]:
    return lambda c, s, p: drift_figures(c.run(p))[key]


def _invariants(c: CaseRuns, s: CheckSpec, p: str) -> float:
    d = drift_figures(c.run(p))
    return max(
        d["energy_balance_rel"], d["angular_momentum_balance_rel"], d["linear_momentum_balance_rel"]
    )


def _norm_decay(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr = c.run(p)
    ref = off_manifold.norm_error_reference(c.scene, tr.t)
    return float(np.max(np.abs(tr.invariants.quat_norm_error - ref)))


def _internal_energy(c: CaseRuns, s: CheckSpec, p: str) -> float:
    E_int, _, _ = centre_of_mass.split_energy(c.scene, c.run(p))
    return float(np.max(np.abs(E_int - E_int[0])) / np.max(np.abs(E_int)))


def _com_path(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr = c.run(p)
    dc = centre_of_mass.system_com(c.scene, tr.q) - centre_of_mass.com_path(c.scene, tr.t)
    return float(np.max(np.linalg.norm(dc, axis=1)))


def _com_path_rel(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr = c.run(p)
    _, com, cd = centre_of_mass.split_energy(c.scene, tr)
    g = centre_of_mass.gravity(c.scene)
    parabola = com[0] + np.outer(tr.t, cd[0]) + 0.5 * np.outer(tr.t**2, g)
    return float(np.max(np.abs(com - parabola)) / np.max(np.abs(com)))


def _vs_euler(c: CaseRuns, p: str) -> tuple[Trajectory, np.ndarray, np.ndarray, int]:
    _, w, u, _ = c.euler()
    tr = c.run(p)
    return tr, w, u, min(len(tr.t), len(w))


def _euler_omega(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr, w, _, k = _vs_euler(c, p)
    scale = float(np.max(np.linalg.norm(w, axis=1)))
    return float(np.max(np.linalg.norm(tr.omega[:k] - w[:k], axis=1))) / scale


def _euler_attitude(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr, _, u, k = _vs_euler(c, p)
    return float(np.max(attitude_angle(tr.u[:k], u[:k])))


def _at_c(c: CaseRuns, s: CheckSpec, p: str) -> float:
    c.euler()  # (refuses a scene whose masses do not rest at C)
    return float(np.max(np.abs(c.run(p).p), initial=0.0))


def _flips_seen(c: CaseRuns, s: CheckSpec, p: str) -> float:
    fl = c.flips(p)
    f = c.figures.setdefault(p, {})
    f["flips"] = len(fl)
    f["first flip s"] = float(fl[0]) if len(fl) else None
    return 0.0 if len(fl) else 1.0


def _flip_times_euler(c: CaseRuns, s: CheckSpec, p: str) -> float:
    return crossings.max_instant_difference(c.flips(p), c.euler_flips())


def _flip_times_analytic(c: CaseRuns, s: CheckSpec, p: str) -> float:
    return crossings.max_instant_difference(c.flips(p), c.flips(ANALYTIC))


def _crossings_seen(c: CaseRuns, s: CheckSpec, p: str) -> float:
    return 1.0 if math.isnan(c.first_crossing(p)) else 0.0


def _first_crossing(c: CaseRuns, s: CheckSpec, p: str) -> float:
    return abs(c.first_crossing(ANALYTIC) - c.first_crossing(p))


def _difference(ref: Trajectory, tr: Trajectory, name: str, until: float | None) -> float:
    """max over the common samples (up to ``until`` s) of the comparison's difference series."""
    series = next(x for x in difference_series(ref, tr) if x.name == name)
    v = series.values
    if until is not None:
        v = v[: int(np.searchsorted(series.t, until, side="right"))]
    return float(np.max(v))


def _vs_analytic(name: str) -> Callable[[CaseRuns, CheckSpec, str], float]:
    return lambda c, s, p: _difference(c.run(ANALYTIC), c.run(p), name, s.until)


def _vs_analytic_mirror(name: str) -> Callable[[CaseRuns, CheckSpec, str], float]:
    return lambda c, s, p: _difference(c.mirror_run(ANALYTIC), c.run(p), name, s.until)


def tracking_law_error(tr: Trajectory, scene: Scene) -> float:
    """Max deviation of the tracking errors from their closed forms (Eqs. 78, 84;
    ``docs/errata.md``, item 3), relative to the largest initial error."""
    t = tr.t
    errs, scales = [], []
    if tr.tracking.e_omega.size:
        e = tr.tracking.e_omega
        ref = omega_error_reference(t, e[0], scene.control.omega.gain)
        errs.append(np.max(np.abs(e - ref)))
        scales.append(np.max(np.abs(e[0])))
    if tr.tracking.e_p.size:
        e = tr.tracking.e_p
        mt = scene.control.masses
        idx = list(tr.tracking.mass_indices)
        lam, l = np.asarray(mt.lam), np.asarray(mt.l)
        pbar_dot0 = -l * lam * np.sin(lam * t[0])
        edot0 = tr.qdot[0, 7 + np.array(idx)] - pbar_dot0
        ref = mass_error_reference(t, e[0], edot0, mt.alpha, mt.beta)
        errs.append(np.max(np.abs(e - ref)))
        scales.append(np.max(np.abs(e[0])))
    if not errs:
        return 0.0
    return float(max(errs) / max(max(scales), 1e-300))


def _refused(c: CaseRuns, s: CheckSpec, p: str) -> float:
    return 0.0 if off_manifold.refused_unless_allowed(c.path) else 1.0


def _mirror_quaternion(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr, ref = c.run(p), c.mirror_run(p)
    k = min(len(tr.t), len(ref.t))
    return float(np.max(np.abs(tr.u[:k] + ref.u[:k])))


def _mirror_positions(c: CaseRuns, s: CheckSpec, p: str) -> float:
    tr, ref = c.run(p), c.mirror_run(p)
    k = min(len(tr.t), len(ref.t))
    return max(
        float(np.max(np.abs(tr.R[:k] - ref.R[:k]))),
        float(np.max(np.abs(tr.p[:k] - ref.p[:k]), initial=0.0)),
    )


def _solvers(c: CaseRuns, s: CheckSpec, p: str) -> Values:
    params = c.criterion.solvers
    assert params is not None
    tr0 = c.run(p)
    f = c.figures.setdefault(p, {})
    f[f"{tr0.info.get('method', 'DOP853')} nfev"] = tr0.info.get("nfev")
    c.notes.append(
        f"{p}: {tr0.info.get('method')} rtol {tr0.info.get('rtol'):g}: {tr0.status.value}, "
        f"nfev {tr0.info.get('nfev')}, wall {tr0.info.get('wall_time_s', math.nan):.2f} s"
    )
    out = []
    for method in params.methods:
        tr = c.solver_run(p, method)
        dev = max(
            _difference(tr0, tr, "position_C", None), _difference(tr0, tr, "rod_positions", None)
        )
        f[f"{method.value} nfev"] = tr.info.get("nfev")
        f[f"{method.value} wall s"] = tr.info.get("wall_time_s")
        c.notes.append(
            f"{p}: {method.value} rtol {params.rtol:g}: {tr.status.value}, nfev "
            f"{tr.info.get('nfev')}, wall {tr.info.get('wall_time_s', math.nan):.2f} s, max "
            f"deviation from its {tr0.info.get('method')} {dev:.2e} m"
        )
        out.append((method.value, dev))
    return out


def _pinv(name: str) -> Callable[[CaseRuns, CheckSpec, str], float]:
    return lambda c, s, p: getattr(c.pinv(), name)


def _engine_law(c: CaseRuns, s: CheckSpec, p: str) -> float:
    return c.pinv().engine_law[p]


_M, _R = Measure, Reference
_IMPL: dict[tuple[Measure, Reference], Callable[[CaseRuns, CheckSpec, str], Any]] = {
    (_M.FLIPS, _R.RUN): _flips_seen,
    (_M.CROSSINGS, _R.RUN): _crossings_seen,
    (_M.INVARIANTS, _R.BALANCES): _invariants,
    (_M.ENERGY, _R.BALANCES): _drift("energy_balance_rel"),
    (_M.ANGULAR_MOMENTUM, _R.BALANCES): _drift("angular_momentum_balance_rel"),
    (_M.LINEAR_MOMENTUM, _R.BALANCES): _drift("linear_momentum_balance_rel"),
    (_M.QUAT_NORM, _R.BALANCES): _drift("quat_norm_error_max"),
    (_M.QUAT_NORM, _R.NORM_DECAY): _norm_decay,
    (_M.INTERNAL_ENERGY, _R.CENTRE_OF_MASS): _internal_energy,
    (_M.COM_PATH, _R.CENTRE_OF_MASS): _com_path,
    (_M.COM_PATH_REL, _R.CENTRE_OF_MASS): _com_path_rel,
    (_M.ANGULAR_VELOCITY, _R.EULER): _euler_omega,
    (_M.ATTITUDE, _R.EULER): _euler_attitude,
    (_M.ROD_POSITIONS, _R.EULER): _at_c,
    (_M.FLIP_TIMES, _R.EULER): _flip_times_euler,
    (_M.POSITION_C, _R.ANALYTIC): _vs_analytic("position_C"),
    (_M.ROD_POSITIONS, _R.ANALYTIC): _vs_analytic("rod_positions"),
    (_M.ATTITUDE, _R.ANALYTIC): _vs_analytic("attitude"),
    (_M.FLIP_TIMES, _R.ANALYTIC): _flip_times_analytic,
    (_M.FIRST_CROSSING_TIME, _R.ANALYTIC): _first_crossing,
    (_M.TRACKING, _R.TRACKING_LAWS): lambda c, s, p: tracking_law_error(c.run(p), c.scene),
    (_M.REFUSED, _R.LOADER): _refused,
    (_M.QUATERNION, _R.MIRROR): _mirror_quaternion,
    (_M.POSITIONS, _R.MIRROR): _mirror_positions,
    (_M.POSITION_C, _R.ANALYTIC_MIRROR): _vs_analytic_mirror("position_C"),
    (_M.ROD_POSITIONS, _R.ANALYTIC_MIRROR): _vs_analytic_mirror("rod_positions"),
    (_M.ATTITUDE, _R.ANALYTIC_MIRROR): _vs_analytic_mirror("attitude"),
    (_M.POSITIONS, _R.SOLVERS): _solvers,
    (_M.REDUNDANT_ACCELERATION, _R.PINV_LAW): _pinv("redundant_acceleration"),
    (_M.REDUNDANT_RESIDUAL, _R.PINV_LAW): _pinv("redundant_residual"),
    (_M.CONFLICT_RESIDUAL, _R.PINV_LAW): _pinv("conflict_residual"),
    (_M.OTHER_RESIDUALS, _R.PINV_LAW): _pinv("other_residuals"),
    (_M.CONFLICT_TRACKING, _R.PINV_LAW): _pinv("conflict_tracking"),
    (_M.ENGINE_LAW, _R.PINV_LAW): _engine_law,
}


def measure(c: CaseRuns, spec: CheckSpec, plant: str) -> Values:
    """The value(s) of ``spec`` on ``plant`` (see :data:`Values`)."""
    v = _IMPL[(spec.what, spec.against)](c, spec, plant)
    return v if isinstance(v, list) else [("", float(v))]


def finite(tr: Trajectory) -> bool:
    """Whether a run's q, q̇ and q̈ are finite throughout."""
    return bool(
        np.all(np.isfinite(tr.q)) and np.all(np.isfinite(tr.qdot)) and np.all(np.isfinite(tr.qddot))
    )


__all__ = [
    "ANALYTIC",
    "CaseRuns",
    "Run",
    "Values",
    "finite",
    "label",
    "measure",
    "run_plant",
    "tracking_law_error",
]
