"""The pointwise check a validation makes before any plant runs: each plant that offers
``pointwise`` (:meth:`analytic.plant.Plant.pointwise`, the accelerated engines) gives its ``q̈`` at
the scene's initial state and a few seeded random states, controlled as the scene says and
uncontrolled, and :mod:`validation.compare.pointwise` compares it with MuJoCo C's
(:meth:`mj_bridge.twin.Twin.acceleration`) and the analytic model's
(:meth:`analytic.model.TumblingModel.acceleration`), both float64, here.

What it finds, a user learns in seconds instead of after a run: each difference over the bound of
the plant's precision is one :class:`PointwiseWarning` (``tumble`` prints it as one line on
stderr) and a :class:`~validation.compare.pointwise.PointwiseFinding` of the
:class:`~validation.compare.pointwise.PointwiseCheck` the report states. Where MuJoCo C and the
analytic model agree and the plant does not, the effect whose removal makes the difference vanish
is named (``the difference is in springs.cubic``): first an effect the plant drops (its ``q̈`` is
MuJoCo C's of the uncontrolled scene without it, :func:`analytic.scene.dump.modified_scene`),
else the plant is evaluated again with each effect off in turn, the likeliest first (the effect
whose MuJoCo C term best explains the difference), at most :data:`CAUSE_TRIALS` of them.

A plant's precision is its settings' ``precision`` attribute when it has one, else float64. A
``ValueError`` from ``pointwise`` is a refusal of the scene, as ``check_scene``'s
(:attr:`PointwiseOutcome.refused`; the caller refuses the run or leaves the plant out). The check
imports no engine of a plant: an accelerated plant evaluates in a process of its own
(``mj_bridge.accelerated.run_isolated``), so this process never imports jax or warp.

States (:func:`pointwise_states`): the initial state (t = 0), then ``count`` states drawn with
``seed``: t uniform over the horizon; a uniformly random unit quaternion (a tumbling body visits
every attitude); ω the initial one plus a normal spread of half its size (at least 0.1 rad/s);
each mass displaced from its initial position by a normal spread of half its distance from its
equilibrium (at least 0.1 m), its rate by half the largest initial rate (at least 0.1 m/s); C at
its initial position moved by its initial velocity. ``u̇`` is tangent (``u̇ = ½ u ⊗ (0, ω)``).
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.kinematics import udot_of
from analytic.model import TumblingModel
from analytic.plant import Plant
from analytic.scene import Scene
from analytic.scene.dump import modified_scene
from mj_bridge.mujoco_settings import ControllerSource
from mj_bridge.plants import plant
from validation.compare.pointwise import (
    Case,
    CaseDifferences,
    PlantPointwise,
    PointwiseCheck,
    PointwiseFinding,
    relative_difference,
    state_bounds,
)
from validation.compare.thresholds import pointwise_threshold

if TYPE_CHECKING:
    from mj_bridge.twin import Twin


POINTWISE_STATES = 3
"""Random states beside the initial one: four states in all, one ``pointwise`` call per case."""

POINTWISE_SEED = 0
"""The random states' seed: the same states every run, so a finding is reproducible."""

CAUSE_TRIALS = 3
"""At most this many effects are switched off in turn in the plant itself to find a cause (one
``pointwise`` call each, an accelerated engine's own process: ~10 s with MJX on 2 cores), the
likeliest first; a dropped effect is found before, at no cost to the plant."""

FITTED = 0.1
"""A difference is read as a multiple of one effect's MuJoCo C term (``applies 0.5 of it``) when
that multiple leaves less than this fraction of it unexplained."""


def one_line(exc: BaseException) -> str:
    """``TypeName: first line of the message``."""
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


class PointwiseWarning(UserWarning):
    """A pointwise finding or a plant not checked, in one line (``tumble`` prints it on stderr)."""


@dataclass(frozen=True)
class PointwiseOutcome:
    """What :func:`check_pointwise` found: the check, and the plants whose ``pointwise``
    refused the scene with a ``ValueError`` (``(engine, one-line reason)``)."""

    check: PointwiseCheck
    refused: tuple[tuple[str, str], ...] = ()


def precision_of(settings: Any) -> str:
    """A plant's precision: its settings' ``precision`` (an enum's value, a dtype's name), else
    ``"float64"``; ValueError naming ``settings.precision`` for a non-float type."""
    p = getattr(settings, "precision", None)
    if p is None:
        return "float64"
    return pointwise_threshold(p).name.removeprefix("pointwise_")


def pointwise_states(
    scene: Scene,
    count: int = POINTWISE_STATES,
    seed: int = POINTWISE_SEED,
    horizon: float | None = None,
) -> tuple[tuple[str, ...], np.ndarray, np.ndarray, np.ndarray]:
    """The check's states (module docstring): ``(names, t (N,), q (N, nq), qdot (N, nq))``,
    ``N = count + 1``, the initial state first; ``horizon`` (s) bounds t (default the scene's)."""
    ini = scene.initial
    t_end = scene.output.t_end if horizon is None else float(horizon)
    rng = np.random.default_rng(seed)
    n = scene.n
    names, ts, qs, qds = ["the initial state"], [0.0], [ini.q0()], [ini.qdot0()]
    w_spread = max(float(np.linalg.norm(ini.omega)), 0.1)
    p_spread = np.maximum(np.abs(ini.p - scene.masses.p_e), 0.1) if n else np.zeros(0)
    v_spread = max(float(np.max(np.abs(ini.pdot), initial=0.0)), 0.1)
    for k in range(count):
        t = float(rng.uniform(0.0, t_end))
        u = rng.normal(size=4)
        u /= np.linalg.norm(u)
        omega = ini.omega + 0.5 * w_spread * rng.normal(size=3)
        p = ini.p + 0.5 * p_spread * rng.normal(size=n)
        pdot = ini.pdot + 0.5 * v_spread * rng.normal(size=n)
        names.append(f"random state {k + 1} (t = {t:.3g} s)")
        ts.append(t)
        qs.append(np.concatenate([ini.R + ini.Rdot * t, u, p]))
        qds.append(np.concatenate([ini.Rdot, udot_of(u, omega), pdot]))
    return tuple(names), np.array(ts), np.array(qs), np.array(qds)


def with_effects(scene: Scene, effects: Sequence[Effect]) -> Scene | None:
    """``scene`` simulating only ``effects`` (its other tables kept, unused ones ignored
    silently); None when the scene file's rules refuse that set."""
    if set(effects) == set(scene.effects):
        return scene
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the tables of the effects switched off
        try:
            return modified_scene(scene, {"scene": {"effects": [e.value for e in effects]}})
        except ValueError:
            return None


def uncontrolled(scene: Scene) -> Scene | None:
    """``scene`` with its control effects off (itself when it has none)."""
    return with_effects(scene, [e for e in scene.effects if e not in CONTROL_EFFECTS])


class References:
    """MuJoCo C's and the analytic model's ``q̈`` at given states, float64, one model of each per
    scene (MuJoCo with the analytic controller in numpy: nothing to compile)."""

    def __init__(self) -> None:
        self._models_of: dict[int, tuple[Scene, Twin, TumblingModel]] = {}
        self._plain: dict[int, tuple[Scene, Scene | None]] = {}

    def uncontrolled(self, scene: Scene) -> Scene | None:
        """:func:`uncontrolled` of ``scene``, made once."""
        got = self._plain.get(id(scene))
        if got is None or got[0] is not scene:
            got = self._plain[id(scene)] = (scene, uncontrolled(scene))
        return got[1]

    def _models(self, scene: Scene) -> tuple[Twin, TumblingModel]:
        got = self._models_of.get(id(scene))
        if got is None or got[0] is not scene:
            from mj_bridge.twin import Twin  # here: MuJoCo and the kernels load on first use

            twin = Twin(scene, controller=ControllerSource.ANALYTIC, native_callback=False)
            got = self._models_of[id(scene)] = (scene, twin, TumblingModel(scene))
        return got[1], got[2]

    def mujoco(self, scene: Scene, t: np.ndarray, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        twin = self._models(scene)[0]
        return np.array([twin.acceleration(*s) for s in zip(t, q, qdot, strict=True)])

    def analytic(self, scene: Scene, t: np.ndarray, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        model = self._models(scene)[1]
        return np.array([model.acceleration(*s)[0] for s in zip(t, q, qdot, strict=True)])


class _NotChecked(Exception):
    """A plant's ``pointwise`` raised or returned what cannot be compared (the message says)."""


def _evaluate(pl: Plant, settings: Any, scene: Scene, t, q, qdot) -> np.ndarray | None:
    """``pl.pointwise`` at the states, checked: None (not offered), an (N, nq) float array;
    a ``ValueError`` passes (a refusal); anything else is :class:`_NotChecked`."""
    try:
        got = pl.pointwise(scene, settings, t, q, qdot)
    except ValueError:
        raise
    except Exception as exc:
        raise _NotChecked(f"pointwise raised {one_line(exc)}") from exc
    if got is None:
        return None
    try:
        arr = np.asarray(got, dtype=float)
    except (TypeError, ValueError) as exc:
        raise _NotChecked(f"pointwise returned {type(got).__name__}, not an array") from exc
    if arr.shape != q.shape:
        raise _NotChecked(f"pointwise returned shape {arr.shape}, not {q.shape}")
    return arr


def _cause(
    pl: Plant,
    settings: Any,
    precision: str,
    scene: Scene,
    states: tuple[np.ndarray, np.ndarray, np.ndarray],
    got: np.ndarray,
    mujoco: np.ndarray,
    refs: References,
) -> tuple[str, str]:
    """The effect of the uncontrolled ``scene`` whose removal makes the plant's ``q̈`` (``got``)
    agree with MuJoCo C's, and how it reads; ``("", sentence)`` when none does.

    First, at no cost to the plant: an effect ``e`` such that ``got`` is MuJoCo C's ``q̈`` of the
    scene without ``e``, within the bounds (the plant drops ``e``). Else the plant is evaluated on
    the scene without each effect in turn, at most :data:`CAUSE_TRIALS` of them, the likeliest
    first: the effect whose MuJoCo C term (``q̈`` with it less ``q̈`` without it) best explains
    the difference as a multiple of it."""
    delta = (got - mujoco).ravel()
    candidates = []
    name = pl.engine
    for e in sorted(scene.effects):
        off = with_effects(scene, [x for x in scene.effects if x != e])
        if off is None:
            continue
        c_off = refs.mujoco(off, *states)
        bounds = state_bounds(precision, relative_difference(c_off, refs.analytic(off, *states)))
        if np.all(relative_difference(got, c_off) <= bounds):
            return str(e), f"the difference is in {e} ({name}'s q̈ is MuJoCo C's without it)"
        term = (mujoco - c_off).ravel()
        tt = float(term @ term)
        if tt == 0.0:
            continue
        alpha = -float(delta @ term) / tt
        residual = float(np.linalg.norm(delta + alpha * term) / np.linalg.norm(delta))
        candidates.append((residual, e, 1.0 - alpha, off, c_off, bounds))
    candidates.sort(key=lambda c: c[0])
    for residual, e, strength, off, c_off, bounds in candidates[:CAUSE_TRIALS]:
        try:
            got_off = _evaluate(pl, settings, off, *states)
        except (ValueError, _NotChecked):
            continue
        if got_off is not None and np.all(relative_difference(got_off, c_off) <= bounds):
            how = (
                f"{name} applies {strength:.3g} of MuJoCo C's term"
                if residual < FITTED
                else f"without it {name} and MuJoCo C agree"
            )
            return str(e), f"the difference is in {e} ({how})"
    tried = f" (of the {min(len(candidates), CAUSE_TRIALS)} likeliest)" if candidates else ""
    return "", f"no single effect's removal makes the difference vanish{tried}"


def _check_plant(
    pl: Plant,
    settings: Any,
    scene: Scene,
    states: tuple[tuple[str, ...], np.ndarray, np.ndarray, np.ndarray],
    refs: References,
) -> tuple[PlantPointwise, list[PointwiseFinding]] | None:
    """One plant's comparison (None when it does not offer ``pointwise``); raises the
    ``ValueError`` of a refusal and :class:`_NotChecked`."""
    names, t, q, qdot = states
    precision = precision_of(settings)
    plain = refs.uncontrolled(scene)
    cases = [(Case.CONTROLLED, scene)] if scene.controlled else []
    if plain is not None:
        cases.insert(0, (Case.UNCONTROLLED, plain))  # first: its cause explains the other
    done: list[CaseDifferences] = []
    findings: list[PointwiseFinding] = []
    cause = ("", "")
    for case, sc in cases:
        got = _evaluate(pl, settings, sc, t, q, qdot)
        if got is None:
            return None
        mujoco = refs.mujoco(sc, t, q, qdot)
        diffs = CaseDifferences.of(
            case, names, precision, got, mujoco, refs.analytic(sc, t, q, qdot)
        )
        done.append(diffs)
        found = PointwiseFinding.of(pl.engine, precision, diffs)
        if found is None:
            continue
        if case is Case.UNCONTROLLED and found.vs_mujoco > found.bound and found.references_agree:
            cause = _cause(pl, settings, precision, sc, (t, q, qdot), got, mujoco, refs)
            found = dataclasses.replace(found, cause=cause[0], cause_text=cause[1])
        elif case is Case.CONTROLLED and cause[0]:
            found = dataclasses.replace(
                found, cause=cause[0], cause_text=f"uncontrolled, {cause[1]}"
            )
        findings.append(found)
    threshold = pointwise_threshold(precision).value
    return PlantPointwise(pl.engine, precision, threshold, tuple(done)), findings


def check_pointwise(
    scene: Scene,
    engines: Sequence[str],
    settings_of: Callable[[str], Any],
    horizon: float | None = None,
    count: int = POINTWISE_STATES,
    seed: int = POINTWISE_SEED,
) -> PointwiseOutcome:
    """Compare each of ``engines`` that offers ``pointwise`` with MuJoCo C and the analytic model
    at :func:`pointwise_states` (module docstring), before any run.

    Args:
        scene: the scene (each plant has accepted it: ``check_scene``).
        engines: the plants of the run.
        settings_of: engine -> its settings for the run (one that raises skips the plant here:
            the run fails it alone).
        horizon: the run's horizon, s (the random states' times; default the scene's).
        count, seed: the random states.

    Returns:
        the :class:`PointwiseOutcome`: each finding and each plant not checked was also warned
        once (:class:`PointwiseWarning`); the refusals are the caller's to act on.
    """
    t0 = time.perf_counter()
    states = pointwise_states(scene, count, seed, horizon)
    refs = References()
    checked: list[PlantPointwise] = []
    findings: list[PointwiseFinding] = []
    not_checked: list[str] = []
    refused: list[tuple[str, str]] = []
    for e in engines:
        pl = plant(e)
        if getattr(type(pl), "pointwise", None) is Plant.pointwise:
            continue  # the contract's default: not offered
        try:
            settings = settings_of(e)
        except Exception:  # said when the plant is prepared: it fails alone there
            continue
        try:
            got = _check_plant(pl, settings, scene, states, refs)
        except ValueError as exc:
            refused.append((pl.engine, " ".join(str(exc).split())))
            continue
        except _NotChecked as exc:
            not_checked.append(f"{pl.engine}: q̈ not checked pointwise: {exc}")
            warnings.warn(not_checked[-1], PointwiseWarning, stacklevel=2)
            continue
        if got is None:
            continue
        checked.append(got[0])
        findings += got[1]
        for f in got[1]:
            warnings.warn(f.text(), PointwiseWarning, stacklevel=2)
    check = PointwiseCheck(
        tuple(checked),
        tuple(findings),
        tuple(not_checked),
        states=len(states[0]),
        seed=seed,
        wall_time_s=time.perf_counter() - t0,
    )
    return PointwiseOutcome(check, tuple(refused))


__all__ = [
    "POINTWISE_SEED",
    "POINTWISE_STATES",
    "PointwiseOutcome",
    "PointwiseWarning",
    "References",
    "check_pointwise",
    "pointwise_states",
    "precision_of",
    "uncontrolled",
    "with_effects",
]
