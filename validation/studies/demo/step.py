"""One step of the demo (:class:`DemoStep`) and what its tab shows: the scene it runs, its plots
(key plot first; no control plot without control), their titles, the text beside the body."""

from __future__ import annotations

from dataclasses import dataclass

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.scene import Scene
from validation.scenes import resolve_scene
from validation.studies.demo.plots import (
    CONTROL_PLOTS,
    PLOT_NAMES,
    REQUIREMENT_HUE,
    WITH_HUE,
    WITHOUT_HUE,
    Plot,
)


@dataclass(frozen=True)
class DemoStep:
    """One step of the demo.

    Attributes:
        prefix: the entity prefix of the step in ``demo.rrd``.
        title: the tab's and the section's title.
        scene: the built-in scene it runs.
        narrative: markdown, with its own ``#`` heading (the recording shows it beside the body).
        look_at: what to look at, one sentence each.
        key: the step's key plot (the larger share of the tab).
        others: the other plots, in order (control plots only when the scene is controlled).
        switched_off: effects removed from the scene for this step.
    """

    prefix: str
    title: str
    scene: str
    narrative: str
    look_at: tuple[str, ...] = ()
    key: Plot = Plot.INVARIANTS
    others: tuple[Plot, ...] = ()
    switched_off: frozenset[Effect] = frozenset()


def step_scene(step: DemoStep) -> Scene:
    """The scene a step runs: its built-in scene with ``switched_off`` removed."""
    sc = resolve_scene(step.scene)
    return sc.with_effects(set(sc.effects) - step.switched_off) if step.switched_off else sc


def is_controlled(scene: Scene) -> bool:
    """Whether the scene has a control requirement (a control effect)."""
    return bool(set(scene.effects) & CONTROL_EFFECTS)


def step_plots(step: DemoStep, scene: Scene, two_plants: bool) -> tuple[Plot, ...]:
    """The plots a step's tab shows, key plot first: no control plot without control, no
    comparison plot without a second plant, no rod forces without masses."""
    out = []
    for p in (step.key, *step.others):
        if p in CONTROL_PLOTS and not is_controlled(scene):
            continue
        if p is Plot.ERRORS and not two_plants:
            continue
        if p in (Plot.ROD_FORCES, Plot.MASS_POSITIONS) and not scene.n:
            continue
        out.append(p)
    return tuple(out)


def plot_title(plot: Plot, step: DemoStep, scene: Scene) -> str:
    """A plot's title, naming the colours of what it draws and nothing it does not draw: the
    requirements only when the scene has them, the runs with and without a switched-off effect."""
    title = PLOT_NAMES[plot]
    grey = REQUIREMENT_HUE.name
    if plot is Plot.OMEGA and Effect.CONTROL_OMEGA in scene.effects:
        return f"{title}; {grey}: the requirement ω̄"
    if plot is Plot.MASS_POSITIONS and step.switched_off:
        off = ", ".join(sorted(e.value for e in step.switched_off))
        return f"{title}; {WITH_HUE.name}: with {off}, {WITHOUT_HUE.name}: without"
    if plot is Plot.MASS_POSITIONS and Effect.CONTROL_MASSES in scene.effects:
        return f"{title}; {grey}: the requirements p̄_i"
    if plot is Plot.INVARIANTS:
        return f"{title}; {grey}: thresholds"
    return title


def step_narrative(step: DemoStep) -> str:
    """The text beside the body: the story, then what to look at."""
    look = "\n".join(f"* {x}" for x in step.look_at)
    return f"{step.narrative}\n\n**What to look at**\n\n{look}" if look else step.narrative


__all__ = ["DemoStep", "is_controlled", "plot_title", "step_narrative", "step_plots", "step_scene"]
