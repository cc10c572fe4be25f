"""Runs the report's figures are tested on: the analytic run and a copy labelled MuJoCo with
planted differences (C moved by :data:`C_OFFSET`, the control torque scaled by 1 +
:data:`TORQUE_SCALE`), so what each figure draws is known exactly."""

from __future__ import annotations

import dataclasses

from analytic.effects import Effect
from analytic.simulate import simulate
from analytic.trajectory import Engine
from validation.compare.checks import compare
from validation.report.figures import (
    FigureContext,
    figure_control,
    figure_errors,
    figure_invariants,
    figure_tracking,
)
from validation.scenes import resolve_scene

T_END = 0.3
C_OFFSET = 5e-9  # m, planted in the copy's position of C
TORQUE_SCALE = 1e-9  # planted relative error of the copy's control torque
PNG = b"\x89PNG\r\n\x1a\n"
SCENES = ("paper_example1_controlled", "paper_example1")
"""A controlled and an uncontrolled scene."""


def planted_copy(tr):
    q = tr.q.copy()
    q[:, 0] += C_OFFSET
    return dataclasses.replace(
        tr, engine=Engine.MUJOCO, q=q, torque=tr.torque * (1.0 + TORQUE_SCALE)
    )


def controlled(sc) -> bool:
    return any(e.value.startswith("control.") for e in sc.effects)


def planted_run(name: str):
    """(scene, plants, comparison, meta) of built-in scene ``name``."""
    sc = resolve_scene(name)
    tr = simulate(sc, t_end=T_END, rtol=1e-10)
    plants = [tr, planted_copy(tr)]
    meta = {
        "scene": {"name": sc.name, "effects": sorted(e.value for e in sc.effects)},
        "horizon_s": T_END,
        "output_rate_hz": sc.output.rate,
        "plants": [
            {"engine": "analytic", "settings": "analytic DOP853 rtol 1e-10"},
            {"engine": "mujoco", "settings": "a planted copy"},
        ],
    }
    return sc, plants, compare(plants[0], plants[1], sc, t_end=T_END), meta


def masses_only_run():
    """(scene, plants, comparison) of Example 1 with the masses controlled and ω not: no control
    torque in either plant, rod forces in both (the copy's forces scaled by 1 + 1e-9)."""
    sc = resolve_scene("paper_example1_controlled")
    sc = sc.with_effects(sc.effects - {Effect.CONTROL_OMEGA})
    tr = simulate(sc, t_end=T_END, rtol=1e-10)
    copy = dataclasses.replace(planted_copy(tr), rod_forces=tr.rod_forces * (1.0 + TORQUE_SCALE))
    return sc, [tr, copy], compare(tr, copy, sc, t_end=T_END)


def drawn_figures(run):
    """Every figure drawn for the run (as its PNG is: Agg at the figure's dpi), with the renderer
    that drew it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    _, plants, cmp, meta = run
    ctx = FigureContext.from_meta(meta)
    drawings = (
        figure_errors(cmp, ctx),
        figure_tracking(cmp, ctx),
        figure_invariants(cmp, ctx),
        figure_control(plants, ctx, cmp.thresholds),
    )
    out = []
    for d in drawings:
        if d.drawn:
            canvas = FigureCanvasAgg(d.figure)
            canvas.draw()
            out.append((d, canvas.get_renderer()))
    return out
