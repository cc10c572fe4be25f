"""What each plot of a step draws: requirements exactly where the scene has them, the demo's own
colours (never a plant's), the drift plot's lines under their thresholds; the recording agrees."""

from __future__ import annotations

import numpy as np

from analytic.effects import Effect
from validation.recording.style import PLANT_COLOR
from validation.studies.demo import (
    REQUIREMENT_HUE,
    SERIES_HUES,
    WITH_HUE,
    WITHOUT_HUE,
    Plot,
    is_controlled,
    plot_title,
    step_curves,
)


def test_an_uncontrolled_step_draws_no_requirement(step_runs, demo_dir):
    """A requirement curve (ω̄, p̄_i) exists exactly when the scene has that control effect, and a
    title or a step's text speaks of requirements only then; the recording agrees."""
    from rerun.chunk import RrdReader

    entities = [str(e) for e in RrdReader(demo_dir.rrd).store().schema().entity_paths()]
    for run in step_runs:
        effects = set(run.scene.effects)
        for plot, effect in (
            (Plot.OMEGA, Effect.CONTROL_OMEGA),
            (Plot.MASS_POSITIONS, Effect.CONTROL_MASSES),
        ):
            has = any(c.entity == "requirement" for c in step_curves(run, plot))
            assert has == (effect in effects and not run.step.switched_off), (run.step.prefix, plot)
            title = plot_title(plot, run.step, run.scene)
            assert ("requirement" in title) == has, title
            logged = f"/{run.step.prefix}/plots/{plot.value}/requirement" in entities
            assert logged == has, (run.step.prefix, plot)
        if not is_controlled(run.scene):
            text = run.step.narrative + " ".join(run.step.look_at)
            assert "requirement" not in text and "p̄" not in text, run.step.prefix
    assert not is_controlled(step_runs[3].scene)  # the step the guide once got wrong


def test_the_demo_colours_are_not_the_plants_and_the_text_names_them(step_runs):
    """Blue, orange and green mean analytic, MuJoCo and Pinocchio everywhere: the demo's own
    curves use none of the plant or pair colours; step 4's with/without runs are drawn in two
    hues that its title and text name."""
    reserved = set(PLANT_COLOR.values())
    hues = [*SERIES_HUES, REQUIREMENT_HUE, WITH_HUE, WITHOUT_HUE]
    assert not {h.rgba for h in hues} & reserved
    assert len({h.rgba for h in SERIES_HUES}) == len(SERIES_HUES)
    assert WITH_HUE.rgba != WITHOUT_HUE.rgba
    for run in step_runs:
        for plot in (Plot.OMEGA, Plot.MASS_POSITIONS, Plot.INVARIANTS):
            for c in step_curves(run, plot):
                assert not set(c.colors) & reserved, (run.step.prefix, c.entity)
    step4 = step_runs[3]
    curves = {c.entity: c for c in step_curves(step4, Plot.MASS_POSITIONS)}
    assert set(curves) == {"with", "without"}
    assert set(curves["with"].colors) == {WITH_HUE.rgba}
    assert set(curves["without"].colors) == {WITHOUT_HUE.rgba}
    text = " ".join(
        (
            step4.step.narrative,
            *step4.step.look_at,
            plot_title(Plot.MASS_POSITIONS, step4.step, step4.scene),
        )
    )
    assert WITH_HUE.name in text and WITHOUT_HUE.name in text
    assert "blue" not in text and "orange" not in text
    # the with-run is the full scene: its masses move differently from the run without the term
    assert np.max(np.abs(curves["with"].values - curves["without"].values)) > 0


def test_the_drift_plot_names_every_line_and_holds_under_its_thresholds(step_runs):
    """Step 1's key plot: a hue per quantity (P, L, E, |uᵀu − 1|), each plant's line named, each
    threshold a named line at the value of validation.compare.thresholds; the balances hold below it."""
    from validation.compare.thresholds import DEFAULTS

    run = step_runs[0]
    assert run.step.key is Plot.INVARIANTS and run.two_plants
    curves = step_curves(run, Plot.INVARIANTS)
    names = [n for c in curves for n in c.names]
    assert len(names) == len(set(names))
    drifts = [c for c in curves if not c.entity.startswith("threshold")]
    assert len(drifts) == 4 * len(run.plants)
    analytic = [c for c in drifts if c.entity.endswith("/analytic")]
    assert len({c.colors[0] for c in analytic}) == 4
    assert all(c.names[0].endswith(", analytic") for c in analytic)
    lines = [c for c in curves if c.entity.startswith("threshold")]
    assert lines and all(c.names[0].startswith("threshold") for c in lines)
    for name in ("linear_momentum", "angular_momentum", "energy", "quat_norm"):
        bound = DEFAULTS[name].value
        line = next(c for c in lines if name in c.entity)
        assert np.allclose(line.values, np.log10(bound))
        for c in drifts:
            if c.entity.startswith(f"{name}/") and c.t.size:
                assert np.max(c.values) <= np.log10(bound), c.entity
