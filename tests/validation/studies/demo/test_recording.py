"""A step's tab in ``demo.rrd``: the key plot given the room, no empty control plot (the blueprint
only, no simulation); one short run checks what the demo's own plots hold against the physics
they show."""

from __future__ import annotations

import numpy as np
import pytest

from validation.studies.demo import (
    CONTROL_PLOTS,
    STEPS,
    Plot,
    is_controlled,
    step_layout,
    step_plots,
    step_scene,
    write_demo,
)


def _views(container) -> list:
    """Every view of a blueprint container, depth first."""
    out = []
    for c in getattr(container, "contents", None) or ():
        out += _views(c) if hasattr(c, "column_shares") else [c]
    return out


def test_uncontrolled_steps_show_no_control_plot(scenes):
    kinds = {s.prefix: is_controlled(scenes[s.prefix]) for s in STEPS}
    assert kinds == {
        "step1_uncontrolled": False,
        "step2_controlled": True,
        "step3_example2_subset": True,
        "step4_no_cubic_springs": False,
    }
    for step in STEPS:
        sc = scenes[step.prefix]
        origins = [str(v.origin) for v in _views(step_layout(step, sc, True))]
        control = [o for o in origins if "/plots/control" in o or "/plots/tracking" in o]
        if is_controlled(sc):
            assert control, step.prefix
        else:
            assert not control and not set(step_plots(step, sc, True)) & CONTROL_PLOTS, origins


def test_each_step_gives_its_key_plot_the_room(scenes):
    """The key plot is the first plot of the right half and has two thirds of its height (all of
    it when alone); step 4's mass positions take half the width, not a fifth."""
    for step in STEPS:
        tab = step_layout(step, scenes[step.prefix], True)
        left, right = tab.contents
        assert list(tab.column_shares) == [1, 1]
        key = f"/{step.prefix}/plots/{step.key.value}"
        if hasattr(right, "row_shares"):
            shares = list(right.row_shares)
            assert str(right.contents[0].origin) == key
            assert shares[0] / sum(shares) == pytest.approx(2 / 3)
        else:
            assert str(right.origin) == key
        view3d = left.contents[0]  # the overlay, or the overlay beside the difference view
        view3d = view3d.contents[0] if hasattr(view3d, "contents") else view3d
        assert str(view3d.origin) == f"/{step.prefix}/world"
    assert STEPS[3].key is Plot.MASS_POSITIONS


def test_the_demo_plots_show_the_requirements_they_name(tmp_path):
    """ω̄ logged beside ω is the requirement b cos(σ t) (Eq. 76); in step 3 the masses without a
    requirement get no control force (F_3 = F_5 = 0)."""
    from rerun.chunk import RrdReader

    res = write_demo(tmp_path, t_end=0.2, mujoco=False)
    store = RrdReader(res.rrd).store()

    def scalars(entity: str) -> np.ndarray:
        rows = []
        for ch in store.stream().filter(content=entity, is_static=False).to_chunks():
            rb = ch.to_record_batch()
            name = next(n for n in rb.schema.names if "scalars" in n.lower())
            rows += rb.column(name).to_pylist()
        return np.array(rows, float)

    sc = step_scene(STEPS[1])
    w = sc.control.omega
    t = np.linspace(0.0, 0.2, scalars("/step2_controlled/plots/omega/requirement").shape[0])
    expected = np.asarray(w.b)[None, :] * np.cos(np.asarray(w.sigma)[None, :] * t[:, None])
    got = scalars("/step2_controlled/plots/omega/requirement")
    assert np.max(np.abs(got - expected)) <= 1e-8 * np.max(np.abs(expected))
    F = scalars("/step3_example2_subset/plots/control/rod_forces/analytic")
    assert np.all(F[:, [2, 4]] == 0.0) and np.all(np.max(np.abs(F[:, [0, 1, 3]]), axis=0) > 0)
