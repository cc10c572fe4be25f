"""The ``control`` figure: the reference plant's control torque (body axes) and rod forces in
engineering units, and below, for each other plant, its relative distance from the reference (log
axes): the plants agree to round-off, so their curves drawn on one linear axis would hide under
each other. Not drawn without control."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from analytic.threshold import Threshold
from analytic.trajectory import Trajectory
from validation.compare.thresholds import thresholds_for
from validation.report.figures.captions import FigureContext, join_sentences, no_control_reason
from validation.report.figures.drawing import Drawing
from validation.report.figures.layout import finish_axes, new_figure, title_panel
from validation.report.figures.panels import log_axis, side_legend
from validation.report.figures.style import SUBSCRIPT, THRESHOLD_STYLE


def _eng(maxabs: float) -> tuple[float, str]:
    """(divisor, SI prefix) that bring ``maxabs`` into [1, 1000): 9.9e9 -> (1e9, "G")."""
    from matplotlib.ticker import EngFormatter

    if not (maxabs > 0 and math.isfinite(maxabs)):
        return 1.0, ""
    exp = int(np.clip(3 * math.floor(math.log10(maxabs) / 3), -24, 24))
    return 10.0**exp, EngFormatter.ENG_PREFIXES[exp]


def _linear_axis(ax) -> None:
    """A linear y axis: the zero line, a grid, and tick labels without an offset (an offset, as
    ``+5e2`` above the axis for a nearly constant force, would stand where the title is)."""
    ax.axhline(0.0, color="0.6", linewidth=0.6)
    ax.grid(True, alpha=0.3)
    ax.ticklabel_format(axis="y", useOffset=False)


def _common_samples(a: Trajectory, b: Trajectory) -> int:
    """Leading samples at the same times (0 when the grids differ from the start)."""
    k = min(a.t.shape[0], b.t.shape[0])
    same = np.isclose(a.t[:k], b.t[:k], rtol=1e-9, atol=1e-12)
    return int(np.argmin(same)) if not same.all() else k


def figure_control(
    plants: Sequence[Trajectory],
    ctx: FigureContext | None = None,
    thresholds: Mapping[str, Threshold] | None = None,
) -> Drawing:
    """The reference plant's control torque and rod forces, and every other plant's relative
    distance from them (log axes) with the thresholds; not drawn without control."""
    plants = [p for p in plants if p.t.size]
    if not plants:
        return Drawing("control", "No plant produced a sample.")
    ctx = ctx or FigureContext(plants[0].scene)
    if not any(np.any(p.torque) or np.any(p.rod_forces) for p in plants):
        why = no_control_reason(ctx)
        return Drawing("control", f"{why[0].upper()}{why[1:]}.")
    th = dict(thresholds) if thresholds is not None else thresholds_for(None)
    ref, others = plants[0], plants[1:]
    n = ref.n
    has_tau = any(np.any(p.torque) for p in plants)
    has_f = bool(n) and any(np.any(p.rod_forces) for p in plants)
    per_other = int(has_tau) + int(has_f)  # one distance panel per force kind and other plant
    nrows = int(has_tau) + int(has_f) + per_other * len(others)
    fig, axes = new_figure(nrows, f"{ctx.scene}: control forces", side_legends=True)
    refname = ref.engine
    colors = [f"C{j}" for j in range(10)]
    row = 0
    units = []
    if has_tau:
        ax = axes[row]
        row += 1
        div, prefix = _eng(float(np.max(np.abs(ref.torque), initial=0.0)))
        for j in range(3):
            ax.plot(
                ref.t,
                ref.torque[:, j] / div,
                color=colors[j],
                linewidth=1.2,
                label=f"$\\tau_{'xyz'[j]}$",
            )
        ax.set_ylabel(f"τ ({prefix}N·m)")
        title_panel(ax, f"{refname} plant: control torque τ, body axes")
        _linear_axis(ax)
        side_legend(ax)
        units.append(f"{prefix}N·m")
    if has_f:
        ax = axes[row]
        row += 1
        div, fprefix = _eng(float(np.max(np.abs(ref.rod_forces), initial=0.0)))
        for i in range(n):
            ax.plot(
                ref.t,
                ref.rod_forces[:, i] / div,
                color=colors[(3 + i) % 10],
                linewidth=1.2,
                label=f"$F_{{{i + 1}}}$",
            )
        ax.set_ylabel(f"F ({fprefix}N)")
        title_panel(ax, f"{refname} plant: rod force on each mass")
        _linear_axis(ax)
        side_legend(ax)
        units.append(f"{fprefix}N")
    zero_rows: list[str] = []
    for other in others:
        k = _common_samples(ref, other)
        t = ref.t[:k]
        panels = []  # (what, threshold name, curves, labels)
        if has_tau:
            tau_scale = max(
                float(np.max(np.linalg.norm(ref.torque[:k], axis=1), initial=0.0)),
                th["control_torque"].floor,
            )
            dtau = np.linalg.norm(other.torque[:k] - ref.torque[:k], axis=1) / tau_scale
            panels.append(("control torque", "control_torque", [dtau], ["‖Δτ‖₂ / max‖τ‖₂"]))
        if has_f:
            f_scale = max(
                float(np.max(np.abs(ref.rod_forces[:k]), initial=0.0)), th["rod_forces"].floor
            )
            curves = [
                np.abs(other.rod_forces[:k, i] - ref.rod_forces[:k, i]) / f_scale for i in range(n)
            ]
            labels = [f"|ΔF{str(i + 1).translate(SUBSCRIPT)}| / max|F|" for i in range(n)]
            panels.append(("rod forces", "rod_forces", curves, labels))
        for what, th_name, curves, labels in panels:
            ax = axes[row]
            row += 1
            limit = th[th_name].value
            log_axis(ax, [*curves, np.asarray([limit], float)])
            for j, (v, lab) in enumerate(zip(curves, labels, strict=True)):
                if not np.any(v):
                    zero_rows.append(f"{lab} of {other.engine}")
                    continue
                color = "tab:brown" if th_name == "control_torque" else colors[(3 + j) % 10]
                ax.plot(t, np.where(v > 0, v, np.nan), color=color, linewidth=1.0, label=lab)
            ax.axhline(limit, label="threshold", **THRESHOLD_STYLE)
            ax.set_ylabel("1 (relative)")
            title_panel(
                ax,
                f"{other.engine} − {refname}: {what}, relative to the {refname} plant's largest",
            )
            ax.grid(True, which="major", alpha=0.3)
            side_legend(ax)
    axes[-1].set_xlabel("t (s)")
    finish_axes(fig, axes)
    drawn = [
        x
        for x, on in (
            ("control torque τ (body axes)", has_tau),
            ("the rod force F_i on each mass", has_f),
        )
        if on
    ]
    sentences = [
        f"Control forces. Top: the {refname} plant's {' and '.join(drawn)}, in "
        f"{' and '.join(units)}; this plant is the reference."
    ]
    if not has_tau:
        sentences.append("No control torque is drawn: neither plant applies one.")
    if others:
        sentences.append(
            "Below, for each other plant, its distance from the reference relative to the "
            "reference's largest magnitude, one panel per force so that no curve hides another: "
            + " and ".join(
                x
                for x, on in (
                    ("‖τ − τ_ref‖₂ / max‖τ_ref‖₂", has_tau),
                    ("|F_i − F_ref,i| / max_i |F_ref,i|", has_f),
                )
                if on
            )
            + " (log axes; dotted black: the threshold). Drawn on the reference's axes, the other "
            "plants' forces would hide under its curves: they agree to these relative distances."
        )
    if zero_rows:
        sentences.append(f"Not drawn, identically zero: {'; '.join(zero_rows)}.")
    sentences.append(ctx.run_sentence())
    return Drawing("control", join_sentences(*sentences), fig)


__all__ = ["figure_control"]
