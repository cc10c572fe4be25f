"""Plants behind one protocol: an engine that runs a scene and returns a :class:`Trajectory`.

Modelled on scipy's ``OdeSolver``: the small base class :class:`Plant` keeps the bookkeeping that
every engine shares (which effects it can simulate, refusing a scene it cannot run *before* it
runs, checking the horizon, default settings from the scene, a one-line description of the
settings for reports); each engine fills in :meth:`Plant._simulate` in its own module:

* :class:`AnalyticPlant` (here): the paper's model, Eqs. (50)-(58) with the controller of Eq. (89),
  integrated by scipy (:func:`analytic.simulate.simulate`);
* ``mj_bridge.plants.MujocoPlant``: the MJCF twin in MuJoCo, the same controller inside every
  integrator stage;
* ``mj_bridge.plants.PinocchioPlant``: the same body in Pinocchio (``aba``), the same controller,
  integrated by scipy in Pinocchio's coordinates.

Every plant returns its trajectory in the paper's coordinates ``q = [R (3), u (4, w first), p (n)]``
(Eq. 44) on the scene's output grid, so every comparison is engine-agnostic. ``mj_bridge.plants``
holds the registry: the three built-ins and the plants installed as plugins (entry-point group
``tumbling_testbed.plants``, ``docs/plugins.md``); this layer does not import the engines.

Two optional entries (``docs/plugins.md``, Batched runs and the pointwise check):
:meth:`Plant.simulate_batch` runs many scenes of one structure in one call (native where
:attr:`Plant.batched`, else the loop of ``_simulate``), and :meth:`Plant.pointwise` gives the
engine's ``q̈`` at given states (None where the engine does not offer it).
"""

from __future__ import annotations

import abc
import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar

from analytic.effects import Backend, Effect, SolverMethod, Stepper
from analytic.model import MODEL_EFFECTS
from analytic.progress import with_state
from analytic.scene import Scene
from analytic.trajectory import Engine, Trajectory

if TYPE_CHECKING:
    import numpy as np

Progress = Callable[..., None]
"""``progress(t)`` or ``progress(t, q)``: the simulated time reached, s, and optionally the state
there (:mod:`analytic.progress`). :meth:`Plant.simulate` hands ``_simulate`` a callback that takes
both, whichever the caller gave."""

TIGHTER_RTOL = 100.0
""":meth:`Plant.tightened` of a tolerance-driven plant divides its tolerances by this: an adaptive
method's global error follows its tolerance about proportionally, so its error at the tighter
settings is about a hundredth of the one at the given settings, and the difference between the
two runs estimates the given settings' error to about 1 %. A factor of 10 leaves the tighter
run's own error large enough to spoil the estimate by tens of percent on a fast spin; 100 leaves a
decade more (the figure: ``docs/performance.md``, The analytic layer's tolerances and limits)."""

RTOL_FLOOR = 100 * 2.220446049250313e-16
"""The smallest relative tolerance scipy's ``solve_ivp`` accepts (it raises smaller ones to
``100 ε`` with a warning): :meth:`Plant.tightened` never asks for less."""

TIGHTER_STEP = 4
""":meth:`Plant.tightened` of a fixed-step plant divides its step by this: RK4's global error
falls by 4⁴ = 256 (the semi-implicit Euler's by 4), and a step that divides the output interval
still does."""


def tighter_rtol(rtol: float, atol: float) -> tuple[float, float] | None:
    """``(rtol, atol)`` divided by :data:`TIGHTER_RTOL`, rtol no lower than :data:`RTOL_FLOOR`;
    None when rtol is at the floor already (nothing tighter to ask of scipy)."""
    if rtol <= RTOL_FLOOR * 1.0000001:
        return None
    return max(rtol / TIGHTER_RTOL, RTOL_FLOOR), atol / TIGHTER_RTOL


def check_horizon(t_end: Any, field: str = "t_end") -> float | None:
    """``t_end`` as a float (None stays None), or ``ValueError`` naming ``field``."""
    if t_end is None:
        return None
    try:
        t = float(t_end)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{field}: must be a positive time in s (got {t_end!r})") from None
    if not (t > 0 and math.isfinite(t)):
        raise ValueError(f"{field}: must be a positive finite time in s (got {t_end!r})")
    return t


def coerce_enum(record: Any, name: str, enum: type[Enum]) -> None:
    """Set the field ``name`` of a frozen settings ``record`` to its ``enum`` member, or raise
    ``ValueError`` naming the field and listing the choices."""
    value = getattr(record, name)
    try:
        object.__setattr__(record, name, enum(value))
    except ValueError:
        raise ValueError(
            f"{name}: must be one of {[m.value for m in enum]} (got {value!r})"
        ) from None


def check_positive(
    record: Any, name: str, *, allow_none: bool = False, allow_inf: bool = False, what: str = ""
) -> None:
    """``ValueError`` naming the field unless ``record.name`` is a positive number (finite unless
    ``allow_inf``; None passes when ``allow_none``). ``what`` replaces "number" in the message."""
    v = getattr(record, name)
    if v is None and allow_none:
        return
    ok = isinstance(v, int | float) and not isinstance(v, bool) and v > 0
    if not (ok and (allow_inf or math.isfinite(v))):
        kind = what or ("positive number" if allow_inf else "positive finite number")
        tail = " or None" if allow_none else ""
        raise ValueError(f"{name}: must be a {kind}{tail} (got {v!r})")


class Plant(abc.ABC):
    """One engine behind the protocol (see the module docstring).

    Class attributes a subclass sets:
        engine: its name, a ``str`` (the name used on the command line, in reports, keys and
            entity paths; a built-in's is an :class:`Engine` value, a plugin's its entry point's).
        label: how reports name it (``"MuJoCo"``).
        effects: the :class:`Effect` members it can simulate, listed by each plant: none by
            default, so a plant claims no effect it does not name (a scene with any effect on is
            refused by :meth:`check_scene`), and an effect added to :class:`Effect` is claimed by
            no plant until its code lists it.
        settings_type: its frozen settings dataclass.
        default: whether it is among the plants a run uses when none are named
            (``mj_bridge.plants.installed_plants``); False keeps an optional engine out of
            default runs, to be asked for by name (``--plants analytic,drake``).
        value_bound: the largest magnitude of a coordinate, velocity or acceleration (SI units)
            the engine carries on with; past it the engine stops its run by design (MuJoCo's
            instability guard at ``mjMAXVAL`` = 1e10). Infinite (the default) for an engine with
            no such bound. The fuzzer reads it to tell a motion that left an engine's range
            from a failure (``docs/fuzzing.md``).
        batched: True when :meth:`_simulate_batch` runs many scenes in one native call (many
            worlds at once); False (the default) when it is the loop of :meth:`_simulate`. A
            caller with many scenes of one structure submits them as one batch to a plant that
            says True, and scene by scene to the others.
    """

    engine: ClassVar[str]
    label: ClassVar[str]
    effects: ClassVar[frozenset[Effect]] = frozenset()
    settings_type: ClassVar[type]
    default: ClassVar[bool] = True
    value_bound: ClassVar[float] = math.inf
    batched: ClassVar[bool] = False

    @classmethod
    def unavailable(cls) -> str:
        """Why this plant cannot run on this installation ("" when it can)."""
        return ""

    @abc.abstractmethod
    def default_settings(self, scene: Scene) -> Any:
        """The settings the scene asks for (its ``[solver]`` or ``[mujoco]`` table)."""

    @abc.abstractmethod
    def describe(self, settings: Any) -> str:
        """One line naming the engine and its settings, e.g. ``MuJoCo RK4 dt 0.00025 s``."""

    def tightened(self, scene: Scene, settings: Any) -> Any | None:
        """Settings of the same method whose error on ``scene`` is far smaller than that of
        ``settings`` (tolerances divided by :data:`TIGHTER_RTOL`, a step by :data:`TIGHTER_STEP`),
        or None when this plant cannot tighten them (the default: a plugin that does not say).
        The difference between a run at ``settings`` and one at the tightened settings is this
        plant's own error estimate at ``settings``: what a verdict may blame on the settings
        rather than on the model (``docs/fuzzing.md``)."""
        return None

    @abc.abstractmethod
    def _simulate(
        self, scene: Scene, settings: Any, t_end: float | None, progress: Progress | None
    ) -> Trajectory:
        """Run the scene (already checked); ``t_end`` None means the scene's horizon."""

    def check_scene(self, scene: Scene) -> None:
        """``ValueError`` naming ``scene.effects`` and the effects this plant cannot simulate."""
        missing = sorted(e.value for e in scene.effects - self.effects)
        if missing:
            none = "" if self.effects else " (it declares no effects: Plant.effects)"
            raise ValueError(
                f"scene.effects: the {self.engine} plant cannot simulate {', '.join(missing)}{none}"
            )

    def simulate(
        self,
        scene: Scene,
        settings: Any = None,
        t_end: float | None = None,
        progress: Progress | None = None,
    ) -> Trajectory:
        """Run ``scene`` on this plant; samples at the scene's output rate, paper coordinates.

        Args:
            scene: a validated scene.
            settings: an instance of :attr:`settings_type` (default :meth:`default_settings`).
            t_end: horizon, s (default the scene's ``[output] t_end``).
            progress: called with the simulated time reached, s, and, where the plant gives
                it and the callback takes it, the state there (``progress(t, q)``:
                :mod:`analytic.progress`).

        Raises:
            ValueError: the scene needs an effect this plant lacks, bad settings or ``t_end``,
                before anything runs.
            ImportError: the engine is not installed (:meth:`unavailable` says why).
        """
        why = self.unavailable()
        if why:
            raise ImportError(why)
        self.check_scene(scene)
        t = check_horizon(t_end)
        settings = self._checked_settings(settings, scene)
        try:
            return self._simulate(scene, settings, t, with_state(progress))
        except MemoryError as exc:  # numpy's and C++'s (bad_alloc) often carry no message
            detail = f": {exc}" if str(exc) else ""
            raise MemoryError(
                f"out of memory ({self.label} with {scene.n:,} masses{detail})"
            ) from None

    def _checked_settings(self, settings: Any, scene: Scene) -> Any:
        """``settings`` (None: the scene's defaults), or ``ValueError`` naming ``settings``."""
        if settings is None:
            return self.default_settings(scene)
        if not isinstance(settings, self.settings_type):
            raise ValueError(
                f"settings: the {self.engine} plant takes {self.settings_type.__name__} "
                f"(got {type(settings).__name__})"
            )
        return settings

    def simulate_batch(
        self,
        scenes: Sequence[Scene],
        settings: Any = None,
        t_end: float | None = None,
        progress: Progress | None = None,
    ) -> list[Trajectory]:
        """Run many scenes of one structure on this plant: one trajectory per scene, in order.

        Never overridden: it checks what :meth:`simulate` checks, for every scene, and that the
        scenes share one structure (the same number of masses ``n`` and the same effects; their
        parameters and initial states may differ), then calls :meth:`_simulate_batch`, native
        when :attr:`batched`, else the loop of :meth:`_simulate`.

        Args:
            scenes: validated scenes of one structure (an empty sequence returns ``[]``).
            settings: one instance of :attr:`settings_type` for every scene (default
                :meth:`default_settings` of ``scenes[0]``).
            t_end: horizon, s, of every scene (default each scene's ``[output] t_end``).
            progress: called with the simulated time reached by the batch, s.

        Raises:
            ValueError: ``"scenes[i]: ..."`` for a scene this plant refuses or one whose
                structure differs from ``scenes[0]``'s; bad settings or ``t_end``; before
                anything runs.
            ImportError: the engine is not installed (:meth:`unavailable` says why).
        """
        why = self.unavailable()
        if why:
            raise ImportError(why)
        scenes = list(scenes)
        t = check_horizon(t_end)
        if not scenes:
            return []
        first = scenes[0]
        for i, scene in enumerate(scenes):
            try:
                self.check_scene(scene)
            except ValueError as exc:
                raise ValueError(f"scenes[{i}]: {exc}") from None
            if scene.n != first.n:
                raise ValueError(
                    f"scenes[{i}]: a batch holds scenes of one structure: n = {scene.n} masses, "
                    f"scenes[0] has {first.n}"
                )
            if scene.effects != first.effects:
                extra = sorted(e.value for e in scene.effects - first.effects)
                lacking = sorted(e.value for e in first.effects - scene.effects)
                parts = [f"has {', '.join(extra)}"] if extra else []
                parts += [f"lacks {', '.join(lacking)}"] if lacking else []
                raise ValueError(
                    f"scenes[{i}]: a batch holds scenes of one structure: its effects differ "
                    f"from scenes[0]'s (it {' and '.join(parts)})"
                )
        settings = self._checked_settings(settings, first)
        try:
            return list(self._simulate_batch(scenes, settings, t, with_state(progress)))
        except MemoryError as exc:
            detail = f": {exc}" if str(exc) else ""
            raise MemoryError(
                f"out of memory ({self.label}, a batch of {len(scenes):,} scenes with "
                f"{first.n:,} masses{detail})"
            ) from None

    def _simulate_batch(
        self,
        scenes: list[Scene],
        settings: Any,
        t_end: float | None,
        progress: Progress | None,
    ) -> list[Trajectory]:
        """Run the scenes (already checked, one structure); one trajectory per scene, in order.

        The default is the loop of :meth:`_simulate`. ``progress`` then gets the batch's share of
        work done as a time on the longest horizon ``T``: ``T (i + t_i / T_i) / N`` while scene
        ``i`` of ``N`` is at ``t_i`` of its horizon ``T_i`` (monotonic, ``T`` at the end). A
        native batch (:attr:`batched`) steps every world together and reports their common time.
        """
        horizons = [t_end if t_end is not None else s.output.t_end for s in scenes]
        longest, count = max(horizons), len(scenes)
        out = []
        for i, (scene, horizon) in enumerate(zip(scenes, horizons, strict=True)):
            inner: Progress | None = None
            if progress is not None:

                def inner(t: float, i: int = i, horizon: float = horizon) -> None:
                    progress(longest * (i + min(t / horizon, 1.0)) / count)

            # one scene's state is not the batch's: with_state drops it
            out.append(self._simulate(scene, settings, t_end, with_state(inner)))
        return out

    def pointwise(
        self, scene: Scene, settings: Any, t: np.ndarray, q: np.ndarray, qdot: np.ndarray
    ) -> np.ndarray | None:
        """This engine's ``q̈`` at ``N`` given states, or None when it does not offer it (default).

        Args:
            scene: a validated scene this plant accepts (:meth:`check_scene`).
            settings: an instance of :attr:`settings_type`.
            t: shape (N,), s.
            q, qdot: shape (N, n+7), the paper's coordinates (Eq. 44; ``u`` w first).

        Returns:
            shape (N, n+7): ``q̈`` in the paper's coordinates, with the scene's controller (and its
            given torque) applied when on, evaluated by the engine's own forward dynamics, so a
            caller compares engines before any run; or None (not offered).

        Raises:
            ValueError: naming a field, when the engine refuses the scene (as :meth:`check_scene`).
        """
        return None


@dataclass(frozen=True)
class AnalyticSettings:
    """How the analytic plant integrates (scipy ``solve_ivp`` methods).

    Attributes:
        method: the scipy method.
        rtol, atol: tolerances on the motion (dimensionless; atol in the state's SI units, raised
            for a group of coupled components whose magnitude exceeds a few hundred by the
            loop's rule, :mod:`analytic.error_scale`; the setting itself is kept as given).
        backend: the right-hand side, compiled or the numpy reference (:class:`Backend`).
        stepper: the loop that steps the method: ``auto`` (CyRK's compiled loop for DOP853, RK45
            and RK23 on the compiled right-hand side, else scipy's), ``compiled`` (an error where
            it cannot apply) or ``scipy``, the reference (:class:`Stepper`,
            :mod:`analytic.compiled_stepping`).
    """

    method: SolverMethod = SolverMethod.DOP853
    rtol: float = 1e-12
    atol: float = 1e-13
    backend: Backend = Backend.AUTO
    stepper: Stepper = Stepper.AUTO

    def __post_init__(self) -> None:
        coerce_enum(self, "method", SolverMethod)
        coerce_enum(self, "backend", Backend)
        coerce_enum(self, "stepper", Stepper)
        check_positive(self, "rtol")
        check_positive(self, "atol")


class AnalyticPlant(Plant):
    """The paper's model (:func:`analytic.simulate.simulate`)."""

    engine = Engine.ANALYTIC.value
    label = "analytic"
    effects = MODEL_EFFECTS
    """Every effect the paper's model assembles (:data:`analytic.model.MODEL_EFFECTS`)."""
    settings_type = AnalyticSettings

    def default_settings(self, scene: Scene) -> AnalyticSettings:
        return AnalyticSettings(scene.solver.method, scene.solver.rtol, scene.solver.atol)

    def describe(self, settings: AnalyticSettings) -> str:
        # the label, not a fixed word: a plugin built on this plant is named as itself
        return f"{self.label} {settings.method.value} rtol {settings.rtol:g}"

    def tightened(self, scene: Scene, settings: AnalyticSettings) -> AnalyticSettings | None:
        tight = tighter_rtol(settings.rtol, settings.atol)
        if tight is None:
            return None
        return dataclasses.replace(settings, rtol=tight[0], atol=tight[1])

    def _simulate(
        self,
        scene: Scene,
        settings: AnalyticSettings,
        t_end: float | None,
        progress: Progress | None,
    ) -> Trajectory:
        from analytic.simulate import simulate

        return simulate(
            scene,
            method=settings.method,
            rtol=settings.rtol,
            atol=settings.atol,
            t_end=t_end,
            progress=progress,
            backend=settings.backend,
            stepper=settings.stepper,
        )


__all__ = [
    "RTOL_FLOOR",
    "TIGHTER_RTOL",
    "TIGHTER_STEP",
    "AnalyticPlant",
    "AnalyticSettings",
    "Plant",
    "Progress",
    "check_horizon",
    "check_positive",
    "coerce_enum",
    "tighter_rtol",
]
