"""The engine plants behind :class:`analytic.plant.Plant`, and the registry of every plant.

* :class:`MujocoPlant`: the MJCF twin (:mod:`model_xml`) stepped by MuJoCo, the analytic controller
  inside every integrator stage (:func:`mj_bridge.simulate.simulate`);
* :class:`PinocchioPlant`: the same body in Pinocchio, ``aba`` integrated by scipy in Pinocchio's
  coordinates, the same controller (:func:`mj_bridge.pinocchio_plant.simulate`); optional
  (``pip install ".[pinocchio]"``), the referee when the other two disagree.

:func:`plant` gives a plant by name, :func:`installed_plants` the ones this installation runs by
default. The registry is open: besides these three built-ins, every entry point of the group
``tumbling_testbed.plants`` (:mod:`mj_bridge.registry`) names a plant class, loaded once, on first
use (:func:`registered`); one that fails to load or to describe itself is left out with a one-line
reason (:func:`plugin_errors`) and the others run. The Drake plant (:mod:`mj_bridge.drake_plant`) is
such a plugin, shipped with the project and declared in ``pyproject.toml``; ``docs/plugins.md`` is
the contract.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.util
import inspect
from dataclasses import dataclass
from typing import Any

from analytic.effects import Effect
from analytic.plant import TIGHTER_STEP, AnalyticPlant, AnalyticSettings, Plant, Progress
from analytic.scene import Scene
from analytic.trajectory import Engine, Trajectory
from mj_bridge.mujoco_settings import MujocoRunSettings
from mj_bridge.pinocchio_effects import EFFECTS as PINOCCHIO_EFFECTS
from mj_bridge.pinocchio_settings import (
    PINOCCHIO_MAX_MASSES,
    PinocchioSettings,
    check_pinocchio_size,
)
from mj_bridge.registry import NAME_PATTERN, RESERVED, entry_points, report_order
from mj_bridge.scipy_loop_plant import ScipyLoopPlant
from model_xml.tendon_terms import TWIN_EFFECTS


class MujocoPlant(Plant):
    """The MuJoCo twin under the analytic controller."""

    engine = Engine.MUJOCO.value
    label = "MuJoCo"
    effects = TWIN_EFFECTS
    """The effects the twin (:func:`model_xml.builder.build_spec`, its spring laws
    :data:`model_xml.tendon_terms.TENDON_TERMS`) and its callbacks (:mod:`mj_bridge.stages`)
    implement."""
    settings_type = MujocoRunSettings
    value_bound = 1e10
    """MuJoCo's ``mjMAXVAL``: ``mj_checkPos``/``mj_checkVel``/``mj_checkAcc`` reset the state and
    warn (``mjWARN_BADQPOS``/``BADQVEL``/``BADQACC``) when a coordinate, velocity or acceleration
    exceeds it, which the plant reports as a failed run."""

    def default_settings(self, scene: Scene) -> MujocoRunSettings:
        return MujocoRunSettings(scene.mujoco.integrator, scene.mujoco.timestep)

    def describe(self, settings: MujocoRunSettings) -> str:
        return f"MuJoCo {settings.integrator.value} dt {settings.dt:g} s"

    def tightened(self, scene: Scene, settings: MujocoRunSettings) -> MujocoRunSettings:
        return dataclasses.replace(settings, dt=settings.dt / TIGHTER_STEP)

    def _simulate(
        self,
        scene: Scene,
        settings: MujocoRunSettings,
        t_end: float | None,
        progress: Progress | None,
    ) -> Trajectory:
        from mj_bridge.simulate import simulate

        return simulate(
            scene,
            integrator=settings.integrator,
            dt=settings.dt,
            t_end=t_end,
            controller=settings.controller,
            progress=progress,
            native_callback=settings.native_callback,
        )


class PinocchioPlant(ScipyLoopPlant):
    """The same body in Pinocchio (optional engine: the referee). Its effects: gravity and the
    masses' inertia are Pinocchio's model (:mod:`mj_bridge.pinocchio_effects`), the springs and the
    given torque generalized forces (:mod:`mj_bridge.scipy_forces`), the control the controller's."""

    engine = Engine.PINOCCHIO.value
    label = "Pinocchio"
    model_effects = frozenset(PINOCCHIO_EFFECTS)
    settings_type = PinocchioSettings
    integration = "mj_bridge.pinocchio_plant"

    @classmethod
    def unavailable(cls) -> str:
        if importlib.util.find_spec("pinocchio") is None:
            return (
                "the Pinocchio plant needs the 'pin' package (>= 4.1): "
                "pip install 'pin>=4.1' (the [pinocchio] extra)"
            )
        return ""

    def check_scene(self, scene: Scene) -> None:
        """The effects (as every plant), and at most :data:`PINOCCHIO_MAX_MASSES` masses."""
        super().check_scene(scene)
        check_pinocchio_size(scene)


PLANTS: dict[str, type[Plant]] = {
    Engine.ANALYTIC.value: AnalyticPlant,
    Engine.MUJOCO.value: MujocoPlant,
    Engine.PINOCCHIO.value: PinocchioPlant,
}
"""The built-in plants, in report order (the analytic plant first: relative checks use its
scales). Every plant, plugins included: :func:`registered`."""

ALL = "all"
"""``--plants all``: every registered plant this installation can run, the non-default ones too."""


@dataclass(frozen=True)
class PluginError:
    """A plant plugin left out: its entry point's ``name`` and a one-line ``reason``."""

    name: str
    reason: str

    def __str__(self) -> str:
        return f"plant plugin {self.name!r} skipped: {self.reason}"


def _one_line(text: str, limit: int = 300) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 1] + "…"


def _plugin_problem(name: str, value: str, obj: Any) -> str:
    """Why the object an entry point names is not a usable plant ("" when it is)."""
    if name in PLANTS:
        return f"{value} takes the built-in plant name {name!r}"
    if name in RESERVED or not NAME_PATTERN.fullmatch(name):
        return (
            f"{name!r} is not a plant name (lower-case letters, digits and _, a letter first, "
            f"at most 32 characters; not {', '.join(sorted(RESERVED))})"
        )
    if not (isinstance(obj, type) and issubclass(obj, Plant)):
        return f"{value} is not a subclass of analytic.plant.Plant (got {type(obj).__name__})"
    if getattr(obj, "engine", None) != name:
        return f"{value}.engine is {getattr(obj, 'engine', None)!r}, not the entry point's name {name!r}"
    label = getattr(obj, "label", None)
    if not (isinstance(label, str) and label.strip()):
        return f"{value}.label must be a non-empty str (got {label!r})"
    if not isinstance(getattr(obj, "settings_type", None), type):
        return f"{value}.settings_type must be a class (the plant's settings dataclass)"
    if not isinstance(getattr(obj, "default", None), bool):
        return f"{value}.default must be True or False (got {getattr(obj, 'default', None)!r})"
    if not (isinstance(obj.effects, frozenset) and all(isinstance(e, Effect) for e in obj.effects)):
        return f"{value}.effects must be a frozenset of analytic.effects.Effect"
    if inspect.isabstract(obj):
        missing = ", ".join(sorted(getattr(obj, "__abstractmethods__", ())))
        return f"{value} does not implement {missing}"
    try:
        why = obj.unavailable()
    except Exception as exc:  # a plugin's own code: any failure is its failure
        return f"{value}.unavailable() raised {type(exc).__name__}: {exc}"
    if not isinstance(why, str):
        return f"{value}.unavailable() must return a str (got {type(why).__name__})"
    return ""


def _interrupt_behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The ``KeyboardInterrupt`` ``exc`` was raised from or while handling, if any (a C
    extension whose initialisation Ctrl-C or SIGTERM cut raises ``ImportError: initialization
    failed`` from it): the user's interrupt, not the plugin's fault."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return e
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return None


@functools.cache
def _load() -> tuple[dict[str, type[Plant]], tuple[PluginError, ...]]:
    """Every plant (built-ins, then the plugins that load, by name) and the plugins left out."""
    plants: dict[str, type[Plant]] = dict(PLANTS)
    errors: list[PluginError] = []
    for ep in entry_points():
        if ep.name in plants and ep.name not in PLANTS:
            errors.append(PluginError(ep.name, f"{ep.value}: the name is declared twice"))
            continue
        try:
            obj = ep.load()
        except BaseException as exc:  # ImportError, SyntaxError, SystemExit from a plugin ...
            if isinstance(exc, KeyboardInterrupt):
                raise
            if (ki := _interrupt_behind(exc)) is not None:  # a signal cut a C extension's init
                raise ki from exc
            errors.append(
                PluginError(
                    ep.name, _one_line(f"cannot import {ep.value}: {type(exc).__name__}: {exc}")
                )
            )
            continue
        why = _plugin_problem(ep.name, ep.value, obj)
        if why:
            errors.append(PluginError(ep.name, _one_line(why)))
            continue
        plants[ep.name] = obj
    return plants, tuple(errors)


def registered() -> dict[str, type[Plant]]:
    """Every plant by name, in report order: the built-ins, then the plugins that loaded (entry
    points of :data:`mj_bridge.registry.GROUP`), by name; installed or not (:meth:`~analytic.plant.Plant.unavailable`)."""
    return dict(_load()[0])


def plugin_errors() -> tuple[PluginError, ...]:
    """The plant plugins left out, each with its one-line reason: an import that fails, an object
    that is not a :class:`~analytic.plant.Plant` subclass or does not describe itself (``engine``
    equal to its entry point's name, ``label``, ``settings_type``, ``default``, every abstract
    method), a built-in's or a reserved name. The other plants run."""
    return _load()[1]


def plant(name: str) -> Plant:
    """The plant called ``name`` (``analytic``, ``mujoco``, ``pinocchio``, or a plugin's name)."""
    known = registered()
    cls = known.get(str(name)) if isinstance(name, str) else None
    if cls is None:
        skipped = next((e for e in plugin_errors() if e.name == name), None)
        if skipped is not None:
            raise ValueError(f"plants: {skipped}")
        raise ValueError(f"plants: unknown plant {name!r} (known: {', '.join(known)})")
    return cls()


def plants_for_scene(scene: Scene, engines: tuple[str, ...]) -> tuple[str, ...]:
    """Those of ``engines`` whose :meth:`~analytic.plant.Plant.check_scene` accepts ``scene`` (a
    default plant set without the ones that cannot run this scene, e.g. Pinocchio beyond
    :data:`PINOCCHIO_MAX_MASSES` masses), in the same order. A plant whose ``check_scene`` raises
    anything but the ``ValueError`` of a refusal (a plugin's own bug) is kept: the run fails that
    plant alone, naming what it raised."""
    out = []
    for e in engines:
        try:
            plant(e).check_scene(scene)
        except ValueError:
            continue
        except Exception:  # not a refusal: the run fails that plant alone
            pass
        out.append(str(e))
    return tuple(out)


def installed_plants() -> tuple[str, ...]:
    """The default plants this installation can run, in report order: every registered plant
    whose ``default`` is True and whose ``unavailable()`` is "" (Drake, ``default = False``, runs
    only when named)."""
    return tuple(n for n, cls in registered().items() if cls.default and not cls.unavailable())


def runnable_plants() -> tuple[str, ...]:
    """Every registered plant this installation can run, default or not (``--plants all``)."""
    return tuple(n for n, cls in registered().items() if not cls.unavailable())


def parse_plants(text: str) -> tuple[str, ...]:
    """``"analytic,mujoco"`` -> plants in report order; ``"all"`` -> :func:`runnable_plants`;
    ``ValueError`` naming ``plants``."""
    names = [s.strip() for s in str(text).split(",") if s.strip()]
    if not names:
        raise ValueError(f"plants: give at least one plant (got {text!r})")
    if ALL in names:
        if names != [ALL]:
            raise ValueError(f"plants: 'all' stands alone (got {text!r})")
        return runnable_plants()
    chosen = {plant(n).engine for n in names}
    known = registered()
    for e in chosen:
        why = known[e].unavailable()
        if why:
            raise ValueError(f"plants: {e} is not installed ({_one_line(why)})")
    return tuple(e for e in known if e in chosen)


__all__ = [
    "ALL",
    "PINOCCHIO_MAX_MASSES",
    "PLANTS",
    "AnalyticPlant",
    "AnalyticSettings",
    "MujocoPlant",
    "MujocoRunSettings",
    "PinocchioPlant",
    "PinocchioSettings",
    "PluginError",
    "check_pinocchio_size",
    "installed_plants",
    "parse_plants",
    "plant",
    "plants_for_scene",
    "plugin_errors",
    "registered",
    "report_order",
    "runnable_plants",
]
