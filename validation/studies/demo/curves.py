"""What each plot of a step's tab draws (:func:`step_curves`): one list of :class:`Curves` for the
recording and the figure alike, so both show the same lines in the same colours."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from validation.compare.checks import Group, Subject
from validation.recording.style import log10_nonzero, plant_color, shade, slug, unit_text
from validation.studies.demo.plots import (
    DRIFT_QUANTITIES,
    OTHER_PLANT_LIGHTEN,
    REQUIREMENT_HUE,
    SERIES_HUES,
    WITH_HUE,
    WITHOUT_HUE,
    Plot,
)
from validation.studies.demo.runs import StepRun


@dataclass(frozen=True)
class Curves:
    """Curves of one plot on one time axis: one entity of the recording, one legend entry each.

    Attributes:
        entity: the entity path below the plot's origin (``analytic``, ``energy/mujoco``).
        t: sample times, s, shape (N,).
        values: shape (N, k): physical values, or log10 of magnitudes in a :data:`~validation.studies.demo.plots.LOG_PLOTS` plot.
        names: the k legend names.
        colors: the k colours, RGBA.
        dashed: drawn dashed in the figure (a requirement, a threshold, another plant).
    """

    entity: str
    t: np.ndarray
    values: np.ndarray
    names: tuple[str, ...]
    colors: tuple[tuple[int, int, int, int], ...]
    dashed: bool = False


def _lighter(rgba: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
    """``rgba`` :data:`OTHER_PLANT_LIGHTEN` of the way toward white."""
    f = OTHER_PLANT_LIGHTEN
    r, g, b, a = rgba
    return (round(r + (255 - r) * f), round(g + (255 - g) * f), round(b + (255 - b) * f), a)


def _omega_curves(run: StepRun) -> tuple[Curves, ...]:
    """ω of the analytic run, a hue per component; the requirement ``ω − e_ω`` in grey."""
    tr, axes = run.plants[0], "xyz"
    out = [
        Curves(
            "analytic",
            tr.t,
            tr.omega,
            tuple(f"ω_{a}" for a in axes),
            tuple(SERIES_HUES[j].rgba for j in range(3)),
        )
    ]
    tk = tr.tracking
    if tk.omega_components:
        comps = tk.omega_components
        out.append(
            Curves(
                "requirement",
                tr.t,
                tr.omega[:, list(comps)] - tk.e_omega,
                tuple(f"ω̄_{axes[c]}" for c in comps),
                (REQUIREMENT_HUE.rgba,) * len(comps),
                dashed=True,
            )
        )
    return tuple(out)


def _mass_curves(run: StepRun) -> tuple[Curves, ...]:
    """The mass positions: with an effect switched off, the runs with and without it in their
    two hues; otherwise a hue per mass and the requirements ``p − e_p`` in grey."""
    tr = run.plants[0]
    if not tr.n:
        return ()
    if run.step.switched_off:
        if run.baseline is None:
            raise ValueError(f"step {run.step.prefix}: baseline: the full scene's run is missing")
        off = ", ".join(sorted(e.value for e in run.step.switched_off))
        return tuple(
            Curves(
                label,
                r.t,
                r.p,
                tuple(f"p_{i + 1} {label} {off}" for i in range(r.n)),
                (hue.rgba,) * r.n,
            )
            for label, r, hue in (("with", run.baseline, WITH_HUE), ("without", tr, WITHOUT_HUE))
        )
    out = [
        Curves(
            "analytic",
            tr.t,
            tr.p,
            tuple(f"p_{i + 1}" for i in range(tr.n)),
            tuple(SERIES_HUES[i % len(SERIES_HUES)].rgba for i in range(tr.n)),
        )
    ]
    tk = tr.tracking
    if tk.mass_indices:
        out.append(
            Curves(
                "requirement",
                tr.t,
                tr.p[:, list(tk.mass_indices)] - tk.e_p,
                tuple(f"p̄_{i + 1}" for i in tk.mass_indices),
                (REQUIREMENT_HUE.rgba,) * len(tk.mass_indices),
                dashed=True,
            )
        )
    return tuple(out)


def _drift_curves(run: StepRun) -> tuple[Curves, ...]:
    """log10 of each plant's drift of each balance, divided by its check's scale (relative, as
    checked), and of the quaternion norm error: a hue per quantity, other plants lighter; one
    grey line per distinct threshold, naming the quantities it bounds."""
    cmp = run.comparison
    series = {s.key: s for s in cmp.series}
    checks = {c.series: c for c in cmp.checks if c.series}
    out: list[Curves] = []
    bounds: dict[float, list[tuple[str, str]]] = {}
    for (name, sym), hue in zip(DRIFT_QUANTITIES, SERIES_HUES, strict=False):
        for k, tr in enumerate(run.plants):
            plant = tr.engine
            s = series.get(f"{plant}.{name}")
            if s is None:
                continue
            c = checks.get(s.key)
            rel = s.values / c.scale if c is not None and c.scale > 0 else s.values
            t, v = log10_nonzero(s.t, rel)
            rgba = hue.rgba if k == 0 else _lighter(hue.rgba)
            out.append(
                Curves(f"{name}/{plant}", t, v[:, None], (f"{sym}, {plant}",), (rgba,), k > 0)
            )
            if c is not None and c.threshold > 0 and (name, sym) not in bounds.get(c.threshold, []):
                bounds.setdefault(c.threshold, []).append((name, sym))
    t_span = np.array([cmp.t[0], cmp.t[-1]]) if cmp.t.size else np.zeros(0)
    for bound, quantities in bounds.items():
        syms = ", ".join(sym for _, sym in quantities)
        out.append(
            Curves(
                "threshold/" + "_".join(n for n, _ in quantities),
                t_span,
                np.full((t_span.size, 1), np.log10(bound)),
                (f"threshold {bound:g} of {syms}",),
                (REQUIREMENT_HUE.rgba,),
                dashed=True,
            )
        )
    return tuple(out)


def _comparison_curves(run: StepRun, group) -> tuple[Curves, ...]:
    """The comparison's series of ``group`` (tracking errors, differences) as log10, in their
    plant's (or pair's) shades as :func:`validation.recording.plots.log_plots` draws them, each with
    its unit; one grey line per threshold."""
    cmp = run.comparison
    checks = {c.series: c for c in cmp.checks if c.series}
    names_by_unit: dict[str, list[str]] = {}
    out: list[Curves] = []
    bounds: dict[str, tuple[float, str]] = {}
    for s in cmp.series:
        if s.group is not group or not s.t.size:
            continue
        names = names_by_unit.setdefault(s.unit, [])
        if s.name not in names:
            names.append(s.name)
        who = s.subject.slug if s.subject.is_pair else s.subject.value
        t, v = log10_nonzero(s.t, s.values)
        color = shade(plant_color(s.subject.value), names.index(s.name))
        label = f"{s.subject.value}: {s.label}{unit_text(s.unit)}"
        other = s.subject not in (Subject.ANALYTIC, Subject.BOTH)  # drawn over them: dashed
        entity = f"{slug(s.unit)}/{s.name}/{who}"
        out.append(Curves(entity, t, v[:, None], (label,), (color,), dashed=other))
        c = checks.get(s.key)
        if t.size and c is not None and c.threshold * c.scale > 0 and s.name not in bounds:
            bounds[s.name] = (c.threshold * c.scale, s.unit)
    span = np.array([cmp.t[0], cmp.t[-1]]) if cmp.t.size else np.zeros(0)
    for name, (bound, unit) in bounds.items():
        out.append(
            Curves(
                f"threshold/{name}",
                span,
                np.full((span.size, 1), np.log10(bound)),
                (f"threshold of {name}{unit_text(unit)}",),
                (REQUIREMENT_HUE.rgba,),
                dashed=True,
            )
        )
    return tuple(out)


def _force_curves(run: StepRun, torque: bool) -> tuple[Curves, ...]:
    """Each plant's control torque (body axes) or rod forces, in its shades."""
    out = []
    for k, tr in enumerate(run.plants):
        name = tr.engine
        values, comps = (
            (tr.torque, ["τ_x", "τ_y", "τ_z"])
            if torque
            else (tr.rod_forces, [f"F_{i + 1}" for i in range(tr.n)])
        )
        colors = tuple(shade(plant_color(name), j) for j in range(len(comps)))
        out.append(Curves(name, tr.t, values, tuple(f"{name} {c}" for c in comps), colors, k > 0))
    return tuple(out)


def step_curves(run: StepRun, plot: Plot) -> tuple[Curves, ...]:
    """What ``plot`` of ``run``'s tab draws: the recording's curves (logged by the demo for
    :data:`~validation.studies.demo.plots.DEMO_PLOTS`) and the figure's, one list for both."""
    if plot is Plot.OMEGA:
        return _omega_curves(run)
    if plot is Plot.MASS_POSITIONS:
        return _mass_curves(run)
    if plot is Plot.INVARIANTS:
        return _drift_curves(run)
    if plot is Plot.TRACKING:
        return _comparison_curves(run, Group.TRACKING)
    if plot is Plot.ERRORS:
        return _comparison_curves(run, Group.DIFFERENCE)
    return _force_curves(run, torque=plot is Plot.TORQUE)


__all__ = ["Curves", "step_curves"]
