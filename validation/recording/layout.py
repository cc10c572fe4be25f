"""What a recording looks like when opened: its blueprint (the layout of views) and the text that
says what the views show (arrow scales, plant colours, exaggeration factors, log10 plots).

The layout of one run (:func:`blueprint_for`)::

    ┌──────────────────────────────┬──────────────────┬─────────────────────────────┐
    │ 3D "plants overlaid"         │ 3D "mujoco −     │ tabs: differences between   │
    │ (Z up; the reference solid,  │ analytic, ×1e8"  │ plants | tracking errors |  │
    │ the others wireframe; a      ├──────────────────┤ balances | control forces,  │
    │ toggle per plant)            │ 3D "pinocchio …" │ a grid of one plot per unit │
    ├──────────────────────────────┴──────────────────┤                             │
    │ "what this is": the narrative                   │                             │
    └─────────────────────────────────────────────────┴─────────────────────────────┘

:func:`legend_markdown` is the part of the narrative that describes these views; every narrative
a recording carries ends with it (the default one, and the demo's own texts).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison
from validation.compare.summary import check_sentence
from validation.recording.plots import Plot, Tab, key_path, plots_for
from validation.recording.style import (
    TIMELINE,
    entity_root,
    plant_color_name,
    power_of_ten,
    viewer_text,
)
from validation.recording.world import (
    ArrowScales,
    arrow_scales,
    difference_factors,
    largest_differences,
    plant_order,
)


def _and(names: Sequence[str]) -> str:
    names = list(names)
    if len(names) < 3:
        return " and ".join(names)
    return ", ".join(names[:-1]) + f" and {names[-1]}"


def _colour(name: str) -> str:
    return plant_color_name(name)


def overlay_title(plants: Sequence[str]) -> str:
    """The name of the 3D view with every plant."""
    if len(plants) < 2:
        return f"{plants[0]} plant" if plants else "3D"
    return f"plants overlaid: {plants[0]} solid, {_and(plants[1:])} wireframe"


def difference_title(reference: str, plant: str, factor: float | None) -> str:
    """The name of a difference view: ``mujoco − analytic, difference ×1e8``."""
    k = "exaggerated" if factor is None else f"×{power_of_ten(factor)}"
    return f"{plant} − {reference}, difference {k}"


@dataclass(frozen=True)
class Legend:
    """What a run's 3D views show, in numbers.

    Attributes:
        plants: engine names, the reference (drawn solid) first.
        arrows: arrow scales (m per rad/s, m per N·m).
        factors: per other plant, the factor its difference view multiplies its difference by.
        largest: per other plant, its largest difference from the reference, m (position of C,
            BR's size times the attitude angle, rod positions); absent when unknown.
    """

    plants: tuple[str, ...]
    arrows: ArrowScales
    factors: Mapping[str, float] = field(default_factory=dict)
    largest: Mapping[str, float] = field(default_factory=dict)


def legend_for(
    scene: Any, plants: Sequence[Trajectory], comparison: Comparison | None = None
) -> Legend:
    """The :class:`Legend` of a run (the same numbers the logged entities use)."""
    names = tuple(tr.engine for tr in plants if tr.t.shape[0])
    factors = difference_factors(scene, comparison, names, plants)
    largest = largest_differences(scene, comparison, names, plants)
    return Legend(names, arrow_scales(scene, plants), factors, largest)


def _difference_text(legend: Legend, plant: str) -> str:
    ref, k = legend.plants[0], legend.factors.get(plant)
    d = legend.largest.get(plant)
    view = f'"{difference_title(ref, plant, k)}"'
    if k is None:
        return ""
    if d == 0.0:
        return (
            f"- {view}: {plant} and {ref} are identical to the last bit here; "
            f"the two bodies coincide."
        )
    size = f" (it stays within {d:.1g} m)" if d is not None and math.isfinite(d) else ""
    if k == 1:
        return (
            f"- {view}: the {ref} body (solid) and the {plant} body (wireframe) at their true "
            f"distance{size}; the {_colour(plant)} arrow goes from the {ref} C to the {plant} C."
        )
    return (
        f"- {view}: the {ref} body (solid) and the {plant} body (wireframe) with its difference "
        f"from {ref}{size} — position of C, attitude and rod positions — multiplied by "
        f"{power_of_ten(k)}; the {_colour(plant)} arrow goes from the {ref} C to the exaggerated C."
    )


LEGEND_HEADING = "## In this recording"
INVISIBLE_FACTOR = 100.0
"""A plant whose difference view needs at least this factor differs from the reference by under
0.3 % of BR's size (DIFFERENCE_TARGET / 100): the bodies overlap in the view with every plant."""


def _agreement_text(legend: Legend) -> str:
    """How close the other plants stay to the reference, and whether that can be seen."""
    others = legend.plants[1:]
    known = [p for p in others if math.isfinite(legend.largest.get(p, math.inf))]
    if not known:
        return ""
    if len(known) == 1:
        text = f" It stays within {legend.largest[known[0]]:.1g} m of it"
    else:
        text = (
            f" They stay within {_and([f'{legend.largest[p]:.1g} m ({p})' for p in known])} of it"
        )
    if all(legend.factors.get(p, 1.0) >= INVISIBLE_FACTOR for p in others):
        return text + ", so the bodies overlap: only the coloured edges show."
    return text + "."


def legend_markdown(legend: Legend, heading: str | None = LEGEND_HEADING) -> str:
    """Markdown describing the views: what each body, arrow, line and plot is, with the arrow
    scales and the exaggeration factors; a list under ``heading`` (None: the list alone, e.g. to
    embed in a document with headings of its own)."""
    names = legend.plants
    out = [heading, ""] if heading else []
    if names:
        ref = names[0]
        view = f'"{overlay_title(names)}"'
        if len(names) > 1:
            others = [f"{p} ({_colour(p)})" for p in names[1:]]
            agree = _agreement_text(legend)
            out.append(
                f"- {view} (Z up, gravity along −Z): the {ref} body is solid {_colour(ref)}; "
                f"{_and(others)} {'are wireframes' if len(others) > 1 else 'is a wireframe'} "
                f"with translucent masses over it.{agree} Show or hide a plant with the eye icon "
                "next to `world/<plant>` in the blueprint panel."
            )
            out += [t for p in names[1:] if (t := _difference_text(legend, p))]
        else:
            out.append(f"- {view} (Z up, gravity along −Z): the {ref} body.")
    w, tau = legend.arrows.omega, legend.arrows.torque
    out += [
        "- Arrows at C, in body axes: "
        + (f"green ω ({w:.3g} m per rad/s)" if w > 0 else "no ω arrow (ω = 0 throughout)")
        + ", "
        + (
            f"purple control torque τ ({tau:.3g} m per N·m)"
            if tau > 0
            else "no control torque arrow (τ = 0 throughout)"
        )
        + "; each plant's line is the path of its C up to the time cursor.",
        "- Plots (one per unit): differences, tracking errors and balance drifts are log10 of "
        "the value in the unit of the plot's title (−9 is 1e-9); an exact zero has no log and "
        "is not plotted. The grey line is the check's threshold: a curve passes while it stays "
        "below it. Control forces are plotted as they are.",
    ]
    return "\n".join(out)


def default_narrative(
    scene: Any,
    plants: Sequence[Trajectory],
    comparison: Comparison | None,
    scales: ArrowScales | None = None,
    legend: Legend | None = None,
) -> str:
    """A short markdown text saying what the run is and what its views show."""
    legend = legend or legend_for(scene, plants, comparison)
    if scales is not None:
        legend = Legend(legend.plants, scales, legend.factors, legend.largest)
    names = list(legend.plants)
    lines = [f"# {scene.name}", "", scene.description, ""]
    lines.append(
        f"Plants: {_and(names)}, all under the same analytic controller (Udwadia–Kalaba, Eq. 89)."
        if len(names) > 1
        else f"Plant: {_and(names)}."
    )
    lines += ["", f"Effects: {', '.join(sorted(e.value for e in scene.effects))}.", ""]
    lines.append(legend_markdown(legend))
    if comparison is not None:
        verdict = "PASSED" if comparison.passed else "FAILED"
        lines += ["", f"**Verdict: {verdict}** ({len(comparison.checks)} checks)."]
        for c in comparison.failed_checks:
            lines.append(f"- {check_sentence(c, reason=False)}")
    return "\n".join(lines)


def with_legend(narrative: str, legend: Legend, heading: str | None = LEGEND_HEADING) -> str:
    """``narrative`` followed by :func:`legend_markdown` (once)."""
    text = legend_markdown(legend, heading)
    if text in narrative:
        return narrative
    return f"{narrative.rstrip()}\n\n{text}"


def narrative_for(
    scene: Any,
    plants: Sequence[Trajectory],
    comparison: Comparison | None = None,
    narrative: str = "",
    heading: str | None = LEGEND_HEADING,
) -> str:
    """The text a run's recording carries: ``narrative`` (default :func:`default_narrative`)
    followed by :func:`legend_markdown` (arrow scales, colours, exaggeration factors, how to read
    the plots). A document that shows the same run (the demo's ``demo.md``) can embed it."""
    legend = legend_for(scene, plants, comparison)
    if not narrative:
        return default_narrative(scene, plants, comparison, legend=legend)
    return with_legend(narrative, legend, heading)


# ----------------------------------------------------------------------------------------------
# Blueprint
# ----------------------------------------------------------------------------------------------


def _trail_range():
    # deferred: rerun ~0.25 s (python -X importtime), only when a recording is made
    import rerun.blueprint as rrb

    return rrb.VisibleTimeRanges(
        [
            rrb.VisibleTimeRange(
                TIMELINE,
                start=rrb.TimeRangeBoundary.infinite(),
                end=rrb.TimeRangeBoundary.cursor_relative(),
            )
        ]
    )


def views_3d(p0: str, names: Sequence[str], factors: Mapping[str, float]):
    """The 3D views of one run under entity root ``p0``: every plant overlaid (each with its
    toggle, the trail from the start to the cursor) and, beside it, one view per other plant
    with its difference from ``names[0]`` multiplied by ``factors[plant]``."""
    import rerun.blueprint as rrb

    ref = names[0] if names else "analytic"
    overrides: dict[str, Any] = {}
    for p in names:
        overrides[f"{p0}/world/{p}"] = rrb.EntityBehavior(visible=True)  # the plant's toggle
        overrides[f"{p0}/world/{p}/trail"] = _trail_range()  # the path from the start
    overlay = rrb.Spatial3DView(
        origin=f"{p0}/world",
        contents=["+ $origin/**", "- $origin/exaggerated/**"],
        name=viewer_text(overlay_title(names)),
        overrides=overrides,
        eye_controls=rrb.EyeControls3D(tracking_entity=f"{p0}/world/{ref}/body"),
    )
    reference = [f"+ $origin/{ref}/body"] + [
        f"+ $origin/{ref}/body/{part}" for part in ("shape", "rod", "masses")
    ]
    diffs = [
        rrb.Spatial3DView(
            origin=f"{p0}/world",
            contents=[*reference, f"+ $origin/exaggerated/{p}/**"],
            name=viewer_text(difference_title(ref, p, factors.get(p))),
            eye_controls=rrb.EyeControls3D(tracking_entity=f"{p0}/world/{ref}/body"),
        )
        for p in names[1:]
        if p != ref
    ]
    if not diffs:
        return overlay
    side = diffs[0] if len(diffs) == 1 else rrb.Vertical(*diffs)
    return rrb.Horizontal(overlay, side, column_shares=[2, 1])


KEY_SHARE = (1, 4)
"""Heights of a plot tab's key and of its plots: the key's few lines above a grid of plots."""


def _plot_tabs(prefix: str, plots: Sequence[Plot]):
    """One tab per :class:`Tab` that has plots: its key (what each colour and shade is,
    :func:`validation.recording.plots.plot_keys`) above its plots in a grid (one column up to
    two). The plots' legends are hidden: at the designed size a legend covers most of a plot's
    curves; the key and the viewer's tooltip name the series instead."""
    import rerun.blueprint as rrb

    tabs = []
    for tab in Tab:
        views = [
            rrb.TimeSeriesView(
                origin=p.origin,
                name=viewer_text(p.title),
                plot_legend=rrb.PlotLegend(visible=False),
            )
            for p in plots
            if p.tab is tab
        ]
        if views:
            columns = 1 if len(views) < 3 else 2
            tabs.append(
                rrb.Vertical(
                    rrb.TextDocumentView(origin=key_path(prefix, tab), name="key"),
                    rrb.Grid(*views, grid_columns=columns),
                    row_shares=list(KEY_SHARE),
                    name=viewer_text(tab.value),
                )
            )
    return rrb.Tabs(*tabs, active_tab=0)


def blueprint_for(
    prefix: str,
    scene: Any,
    comparison: Comparison | None,
    two_plants: bool,
    name: str | None = None,
    *,
    plants: Sequence[str] | None = None,
    factors: Mapping[str, float] | None = None,
):
    """The layout of one run (module docstring): the 3D views and the narrative on the left,
    the plots on the right, in tabs.

    Args:
        prefix: the run's entity prefix ("" for ``run.rrd``, the step's name in the demo).
        comparison: the run's comparison (its plots; the plants and difference factors when
            ``plants`` and ``factors`` are not given).
        two_plants: whether the run has more than one plant (used only without ``plants`` and
            without a comparison).
        name: the container's name (a tab's title in the demo).
        plants: engine names, the reference first (default: the comparison's plants).
        factors: per other plant, its difference view's factor (default:
            :func:`validation.recording.world.difference_factors` of the comparison).
    """
    import rerun.blueprint as rrb

    p0 = entity_root(prefix)
    if plants is None:
        plants = plant_order(comparison) if comparison is not None else ()
        if not plants:
            plants = ("analytic", "mujoco") if two_plants else ("analytic",)
    names = list(plants)
    if factors is None:
        factors = difference_factors(scene, comparison, names) if comparison is not None else {}
    left = rrb.Vertical(
        views_3d(p0, names, factors),
        rrb.TextDocumentView(origin=f"{p0}/narrative", name="what this is"),
        row_shares=[3, 1],
    )
    return rrb.Horizontal(
        left,
        _plot_tabs(prefix, plots_for(prefix, scene, comparison)),
        column_shares=[3, 2],
        name=viewer_text(name or scene.name),
    )


__all__ = [
    "Legend",
    "blueprint_for",
    "default_narrative",
    "difference_title",
    "legend_for",
    "legend_markdown",
    "narrative_for",
    "overlay_title",
    "with_legend",
]
