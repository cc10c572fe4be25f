"""The teaching demo: each tab gives its key plot the room, no empty control plot, a guide that teaches.

The layout tests build the Rerun blueprint only (no simulation); one short run checks what the
demo's own plots hold against the physics they show.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analytic.effects import Effect
from validation.recording.style import PLANT_COLOR
from validation.studies.demo import (
    CONTROL_PLOTS,
    PAPER,
    REQUIREMENT_HUE,
    SERIES_HUES,
    STEPS,
    WITH_HUE,
    WITHOUT_HUE,
    Plot,
    demo_markdown,
    is_controlled,
    plot_title,
    run_steps,
    step_curves,
    step_figure,
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


@pytest.fixture(scope="module")
def scenes():
    return {s.prefix: step_scene(s) for s in STEPS}


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


def test_the_guide_teaches(scenes):
    runs = [(s, scenes[s.prefix], None) for s in STEPS]
    md = demo_markdown(runs, 10.0, 1e-12, True, shown="out/demo/demo.rrd")
    assert md.startswith("# ")
    head = md.split("# The four steps")[0]
    assert "# Learning goals" in head and "    rerun out/demo/demo.rrd" in head
    for step in STEPS:
        section = md.split(f"## {step.title}")[1].split("\n## ")[0]
        assert "**What to look at:**" in section and "**Key plot:**" in section
        assert ("No control acts" in section) == (not is_controlled(scenes[step.prefix]))
    exercises = md.split("# Exercises")[1]
    assert exercises.count("**Exercise ") >= 2 and "*Prediction.*" in exercises
    assert "tumble simulate" in exercises and "γ" in exercises
    for part in ("Koganti", "Udwadia", "Journal of Guidance, Control, and Dynamics", "1.G000633"):
        assert part in PAPER
    assert md.rstrip().endswith(PAPER)
    assert md.count("## ") == len(STEPS)  # one section per step (tests/validation/recording/test_recording.py)


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


# ------------------------------------------------------------------------------------------------
# The files a teacher reads without a viewer, and the claims each step's text makes
# ------------------------------------------------------------------------------------------------

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    """The demo written once, short (0.2 s per step), with the MuJoCo ghost."""
    return write_demo(tmp_path_factory.mktemp("demo"), t_end=0.2)


@pytest.fixture(scope="module")
def step_runs():
    return run_steps(t_end=0.2)[0]


def _section(md: str, title: str) -> str:
    return md.split(f"## {title}")[1].split("\n## ")[0].split("\n# ")[0]


def test_each_step_has_a_figure_the_guide_embeds(demo_dir):
    """One PNG per step, a valid image, embedded in that step's section of demo.md; every file
    of the demo is named in the guide."""
    from PIL import Image

    out = Path(demo_dir)
    md = (out / "demo.md").read_text()
    assert [f.name for f in demo_dir.figures] == [f"{s.prefix}.png" for s in STEPS]
    for step, fig in zip(STEPS, demo_dir.figures, strict=True):
        assert fig.is_file() and fig.parent == out
        data = fig.read_bytes()
        assert data.startswith(PNG_SIGNATURE)
        with Image.open(fig) as im:
            im.verify()
        with Image.open(fig) as im:
            w, h = im.size
            assert im.format == "PNG" and w >= 800 and h >= 600
        assert f"]({fig.name})" in _section(md, step.title), step.prefix
    made = {p.name for p in out.iterdir()} - {"manifest.json", "demo.md"}
    assert all(name in md for name in made), made


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


def test_each_figure_draws_its_tab(step_runs):
    """A step's figure has its tab's plots in order, titled as the tab, and its legends name
    exactly the curves drawn."""
    for run in step_runs:
        drawing = step_figure(run)
        plots = step_plots(run.step, run.scene, run.two_plants)
        axes = drawing.figure.axes
        assert len(axes) == len(plots)
        for ax, plot in zip(axes, plots, strict=True):
            assert ax.get_title(loc="left") == plot_title(plot, run.step, run.scene)
            want = [n for c in step_curves(run, plot) if c.t.size for n in c.names]
            legend = ax.get_legend()
            got = [t.get_text() for t in legend.get_texts()] if legend else []
            assert got == want, (run.step.prefix, plot)
