"""The teaching demo (``tumble demo``): four narrated steps in one Rerun recording, and a guide.

:func:`write_demo` writes ``demo.rrd`` (one tab per step) and ``demo.md``: learning goals, how to
open the recording, each step's story with what to look at, exercises with the physics of their
answers, and the paper's citation. Each step runs on the analytic plant and, when the MuJoCo twin
is importable, on MuJoCo under the same controller, drawn as a translucent ghost and checked
against the analytic plant under the report's thresholds.

Each tab gives the step's *key plot* (:class:`DemoStep.key`) the larger share of the plot column;
a step without control shows no control plot (its torque and rod forces are identically zero,
though the recording keeps them under ``plots/control``).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

import numpy as np

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.scene import Scene
from analytic.simulate import simulate
from analytic.trajectory import RunStatus, Trajectory
from validation.compare.checks import Comparison, Group, Subject, compare
from validation.recording.layout import views_3d
from validation.recording.recording import AppId, atomic_stream, log_run, narrative_for
from validation.recording.style import (
    log10_nonzero,
    plant_color,
    shade,
    slug,
    unit_text,
    viewer_text,
)
from validation.recording.world import difference_factors
from validation.report.figures import Drawing, FigureFormat
from validation.runs import interrupts
from validation.runs.atomic import write_bytes, write_text
from validation.runs.outputs import OutputRun, output_run
from validation.scenes import resolve_scene

PAPER = (
    'P. B. Koganti and F. E. Udwadia, "Dynamics and Precision Control of Tumbling Multibody '
    'Systems", Journal of Guidance, Control, and Dynamics, Vol. 40, No. 3, 2017, '
    "doi:10.2514/1.G000633."
)
"""The paper the model, the controller and the equation numbers come from."""

DEMO_RTOL = 1e-12  # as `tumble validate` (the scenes' rtol): the ghost is checked against it
DEMO_T_END = 10.0  # s


class Plot(StrEnum):
    """A plot of a demo tab: the entity folder under ``/{step}/plots`` it shows."""

    OMEGA = "omega"
    MASS_POSITIONS = "mass_positions"
    TRACKING = "tracking"
    INVARIANTS = "drifts"  # the demo's own: relative drifts, one colour per quantity
    ERRORS = "errors"
    TORQUE = "control/torque"
    ROD_FORCES = "control/rod_forces"


PLOT_NAMES = {
    Plot.OMEGA: "angular velocity ω, body axes (rad/s)",
    Plot.MASS_POSITIONS: "mass positions p_i on the rod (m)",
    Plot.TRACKING: "log10 tracking errors",
    Plot.INVARIANTS: "log10 relative drift of each balance (P, L, E) and |uᵀu − 1|",
    Plot.ERRORS: "log10 |analytic − MuJoCo|",
    Plot.TORQUE: "control torque τ, body axes (N·m)",
    Plot.ROD_FORCES: "rod forces F_i (N)",
}
CONTROL_PLOTS = frozenset({Plot.TORQUE, Plot.ROD_FORCES, Plot.TRACKING})
LOG_PLOTS = frozenset({Plot.TRACKING, Plot.INVARIANTS, Plot.ERRORS})
"""The plots whose values are log10 of a magnitude (exact zeros left out)."""


@dataclass(frozen=True)
class Hue:
    """A colour of the demo's own curves, with the name its text calls it by."""

    name: str
    rgba: tuple[int, int, int, int]

    @property
    def mpl(self) -> tuple[float, float, float, float]:
        """The colour as matplotlib takes it (components in [0, 1])."""
        return tuple(c / 255 for c in self.rgba)


# The demo's colours, in one place, for the recording and the figures alike. None of them is a
# plant's (blue analytic, orange MuJoCo, green Pinocchio: validation/recording/style.py) or a pair's.
SERIES_HUES = (
    Hue("cyan", (23, 190, 207, 255)),
    Hue("olive", (188, 189, 34, 255)),
    Hue("pink", (227, 119, 194, 255)),
    Hue("violet", (120, 94, 240, 255)),
    Hue("teal", (0, 128, 128, 255)),
)
"""Component j of ω, mass i's position, quantity j of the drift plot: ``SERIES_HUES[j]``."""
REQUIREMENT_HUE = Hue("grey", (150, 150, 150, 255))
"""The requirements ω̄ and p̄_i, and the thresholds of the drift plot."""
WITH_HUE, WITHOUT_HUE = Hue("teal", (0, 128, 128, 255)), Hue("magenta", (220, 38, 127, 255))
"""The two runs of a step with an effect switched off: with the effect, and without it."""
OTHER_PLANT_LIGHTEN = 0.45
"""In the drift plot, a plant other than the analytic one is its quantity's colour this far
toward white (and dashed in the figure); the legend names the plant."""
DRIFT_QUANTITIES = (
    ("linear_momentum", "P"),
    ("angular_momentum", "L"),
    ("energy", "E"),
    ("quat_norm", "|u·u − 1|"),  # no superscript: the viewer's fonts lack ᵀ
)
"""The drift plot's quantities (the comparison's series names) and their symbols, in colour
order: quantity j is drawn in ``SERIES_HUES[j]``."""
DRIFT_KEY = ", ".join(
    f"{sym} {hue.name}" for (_, sym), hue in zip(DRIFT_QUANTITIES, SERIES_HUES, strict=False)
)
"""The drift plot's colours in words: ``P cyan, L olive, …``."""


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


@dataclass(frozen=True)
class DemoResult:
    """What :func:`write_demo` wrote: ``rrd`` and ``markdown`` paths, the steps, wall times (s).

    ``os.fspath(result)`` is the output directory, so ``Path(result) / "demo.rrd"`` works.
    """

    out_dir: Path
    rrd: Path
    markdown: Path
    steps: tuple[DemoStep, ...]
    wall_times: dict[str, float]
    comparisons: tuple[Comparison, ...] = ()
    """Per step, the analytic plant against the MuJoCo ghost (empty without MuJoCo)."""
    figures: tuple[Path, ...] = ()
    """Per step, its figure (``{prefix}.png``): the tab's plots, for reading without a viewer."""

    def __fspath__(self) -> str:
        return str(self.out_dir)


STEPS = (
    DemoStep(
        "step1_uncontrolled",
        "1. Example 1 tumbling freely",
        "paper_example1",
        """# 1. Example 1 tumbling freely

A 10 × 6 × 2 m aluminium block with a 16 m rod at a corner; two masses slide on the rod between
linear + cubic springs. No control: the motion follows Lagrange's equations in the quaternion
coordinates `q = [R, u, p]` (Eq. 44), with the norm constraint `uᵀu = 1` stabilised (Eq. 58),

    M(q) q̈ = Q(q, q̇)        (Eqs. 50–53, solved with Udwadia–Kalaba)

Only gravity acts on the system as a whole, so its centre of mass falls on a parabola
(`Ṗ = m_T g`) and its angular momentum about that centre of mass is constant (Fig. 8); C, the centre
of mass of BR alone (the trail), wobbles about the parabola as the heavy masses slide.""",
        look_at=(
            "the 3D view: the block tumbles while the masses oscillate on the rod; the trail of C "
            "bends under gravity;",
            "the drift plot (the key plot): every balance holds to the integration error, about "
            "twelve decades below the size of what it balances, all the way: nothing but the "
            f"integrator disturbs them (one colour per quantity: {DRIFT_KEY}; MuJoCo's lighter; "
            f"{REQUIREMENT_HUE.name}: the thresholds);",
            "ω: the rates change although no torque acts — the body is asymmetric (Euler's "
            "equations) and the sliding masses shift its inertia;",
            "the analytic − MuJoCo plot: the two engines agree to round-off and integration error.",
        ),
        key=Plot.INVARIANTS,
        others=(Plot.OMEGA, Plot.ERRORS),
    ),
    DemoStep(
        "step2_controlled",
        "2. Example 1 under control",
        "paper_example1_controlled",
        """# 2. The same body under control

The controller is the explicit Udwadia–Kalaba force (Eq. 89)

    Q^C = M^{1/2} (A M^{-1/2})⁺ (b − A M⁻¹ Q)

that makes the motion satisfy the requirements exactly, with the least Gauss cost (Eq. 74):

* angular velocity `ω̄ = b cos(σ t)` (Eq. 76) with `b_x = −10 rad/s, σ_x = 0`: ω_x, which starts at
  +1 rad/s, **reverses** and settles at −10 rad/s (watch the green arrow), the tracking error decaying
  as `e_ω(t) = e_ω(0) exp(−γ t)` (Eq. 84, γ = 0.6 1/s);
* masses `p̄ = p_e + l cos(λ t)` (Eq. 75): they **oscillate**, the error obeying
  `ë + α ė + β e = 0` (Eq. 78).

The purple arrow is the control torque τ (body axes); the rod forces are in their own plot.
Angular momentum now changes exactly by the impulse of `S(u) τ`; energy by the control's work.""",
        look_at=(
            "ω (the key plot): each component leaves its initial value and joins its grey "
            "requirement ω̄ — ω_x reverses from +1 to −10 rad/s, ω_y and ω_z settle on cosines;",
            "the tracking errors: straight lines on the log10 plot, the slope of |e_ω| is "
            "−γ / ln 10 = −0.26 per second (Eq. 84); the mass errors decay as e^{−αt/2} with dips "
            "where they change sign (Eq. 78);",
            "the control torque and rod forces: up to ~1e10 N·m and ~6e8 N in the first second, "
            "while the errors are large, then what the requirements keep asking for;",
            "the drift plot: the balances still hold, now counting the control's impulse and work.",
        ),
        key=Plot.OMEGA,
        others=(Plot.TRACKING, Plot.TORQUE, Plot.ROD_FORCES, Plot.INVARIANTS),
    ),
    DemoStep(
        "step3_example2_subset",
        "3. Example 2: only masses 1, 2, 4 controlled",
        "paper_example2_controlled",
        """# 3. Example 2: a hollow cylinder, five masses, three of them controlled

Remark 4: the requirements can be any subset. Here only masses 1, 2 and 4 are asked to follow
`p̄_i = p_e,i + l_i cos(λ_i t)` (Eq. 75 with the rows of A in Eq. 80 kept for i = 1, 2, 4 only), and
the angular velocity tracks `ω̄` (Eq. 76). Masses 3 and 5 are left to the springs: their motion is
whatever the dynamics give, and the control leaves them no force of their own (their rod-force
plot stays at zero). Linear stiffnesses are this project's assumption (Eq. 64 is missing from the
paper; docs/errata.md, item 10).""",
        look_at=(
            "the mass positions (the key plot): masses 1, 2 and 4 join their grey requirements "
            "p̄_i; masses 3 and 5, which have none, move as their springs push them;",
            "the rod forces: F_3 and F_5 stay at zero — the least-cost control (Eq. 74) acts only "
            "where a requirement asks it to;",
            "the tracking errors: three mass errors and the ω error decay by Eqs. 78 and 84.",
        ),
        key=Plot.MASS_POSITIONS,
        others=(Plot.ROD_FORCES, Plot.TRACKING, Plot.OMEGA),
    ),
    DemoStep(
        "step4_no_cubic_springs",
        "4. Example 1 without the cubic springs",
        "paper_example1",
        """# 4. An effect switched off: the cubic springs

The spring potential of Eq. (38) is

    U_s = Σ ½ k_l,i Δ_i² + ¼ k_n,i Δ_i⁴,   Δ_i = extension of spring i

This step runs step 1's scene with `springs.cubic` switched off (`scene.with_effects(...)`): the
masses' oscillation about `p_e` changes (plot *mass positions*: """
        + f"{WITH_HUE.name} with, {WITHOUT_HUE.name} without"
        + """ the
cubic term), and with it the body's tumble. Energy is still conserved — the switched-off term is
removed from the model and from the energy alike.""",
        look_at=(
            f"the mass positions (the key plot): with the cubic term ({WITH_HUE.name}) the "
            "springs stiffen at large extension, so the masses turn back a little sooner and "
            f"oscillate a little faster than without it ({WITHOUT_HUE.name});",
            "the drift plot: the balances hold as well as in step 1 — removing a term from the "
            "model removes it from the energy too;",
            "the analytic − MuJoCo plot: MuJoCo runs the same reduced scene and still agrees.",
        ),
        key=Plot.MASS_POSITIONS,
        others=(Plot.INVARIANTS, Plot.ERRORS),
        switched_off=frozenset({Effect.SPRINGS_CUBIC}),
    ),
)

LEARNING_GOALS = (
    "describe a tumbling body with sliding masses in the paper's coordinates `q = [R, u, p]` "
    "(Eq. 44), and say why the quaternion's norm needs stabilising (Eqs. 55–58);",
    "read the balances of a free tumble — linear momentum against gravity, angular momentum about "
    "the system's centre of mass, energy — and tell integration error from physics;",
    "explain how the Udwadia–Kalaba control (Eq. 89) makes requirements exact: the error dynamics "
    "`e_ω(t) = e_ω(0) exp(−γ t)` (Eq. 84) and `ë + α ė + β e = 0` (Eq. 78) are properties of the "
    "controlled motion, predictable without integrating anything;",
    "see that the requirements may be any subset (Remark 4), and what switching an effect off "
    "changes (the motion) and does not (the balances);",
    "judge agreement between two engines (the analytic model and MuJoCo) under one controller.",
)

EXERCISES = (
    (
        "Change γ and predict e_ω(20)",
        """Copy `analytic/scenes/paper_example1_controlled.toml` (in this repository) to
`gamma.toml`, change `name` and, under `[control.omega]`, `gamma = 0.6` to `gamma = 0.3`, then run

    tumble simulate gamma.toml        # or: python -m validation simulate gamma.toml

and read the line `|e_omega| (x,y,z) rad/s` under `tracking at t = 20 s`.

*Prediction.* The requirement enters as the first-order stabilised constraint
`ė_ω + γ e_ω = 0` (Eq. 84; docs/errata.md, item 3), and the control (Eq. 89) makes it hold exactly,
whatever the body, the masses and the springs do. So `e_ω(20) = e_ω(0) exp(−20 γ)` with
`e_ω(0) = ω(0) − ω̄(0) = (1, −1, 0.5) − (−10, 8, 15) = (11, −9, −14.5)` rad/s: for γ = 0.3,
`exp(−6) = 2.48e-3` and `|e_ω(20)| = (2.73e-2, 2.23e-2, 3.59e-2)` rad/s; for the scene's γ = 0.6,
`(6.76e-5, 5.53e-5, 8.91e-5)` rad/s. Halving γ costs three decades at 20 s. The mass errors
(`|e_p|`) do not change: they obey their own law.""",
    ),
    (
        "Soften the mass requirement: change α and predict e_p(20)",
        """In the same copy set `alpha = [1.0, 1.0]` under `[control.masses]` (β stays 12 1/s²) and
run `tumble simulate` again; read `|e_p| (masses 1,2) m`.

*Prediction.* Each mass error obeys `ë + α ė + β e = 0` (Eq. 78): a damped oscillation at
`ω_d = √(β − α²/4)` (3.43 rad/s for α = 1) under the envelope `exp(−α t / 2)`. From
`e(0) = p(0) − p̄(0) = (5 − 3, 11 − 14) = (2, −3)` m and `ė(0) = (−0.4, 0.3)` m/s the closed form
gives `|e_p(20)| = (7.28e-5, 1.07e-4)` m for α = 1, against `(4.21e-9, 6.38e-9)` m for the scene's
α = 2: half the damping rate, the envelope at 20 s is `exp(−10)` instead of `exp(−20)`. Check the
numbers with `validation.compare.tracking_laws.mass_error_reference`.""",
    ),
    (
        "Switch off the cubic springs under control and predict what changes",
        """Remove `"springs.cubic"` from `effects` in the controlled scene (the loader warns that the
now unused `k_cubic` is ignored) and run `tumble simulate`.

*Prediction.* The tracking errors at 20 s do not change at all (`|e_ω|` and `|e_p|` as in the
original), because Eqs. 78 and 84 contain neither the springs nor the body: whatever force the
springs no longer give, the control supplies. What changes is the control: the summary's
`max |F_i|` moves from 6.161e8 N to 6.172e8 N — by the order of the cubic spring force
`k_n Δ³ ~ 1e6 N` for extensions Δ of a metre or two — and the motion of everything the
requirements leave free.""",
    ),
)


def write_demo(
    out_dir: str | Path,
    *,
    t_end: float = DEMO_T_END,
    rtol: float = DEMO_RTOL,
    mujoco: bool = True,
) -> DemoResult:
    """Write the teaching demo into ``out_dir``: ``demo.rrd`` (one tab per step) and ``demo.md``.

    Each step runs on the analytic plant for ``t_end`` seconds at ``rtol`` (DOP853) and, with
    ``mujoco`` (and the MuJoCo twin importable), on the MuJoCo twin under the same controller (the
    scene's integrator and timestep), drawn as a translucent ghost over the analytic body with its
    curves in the same plots.
    """
    with output_run(out_dir, "demo") as run:
        res = _demo_into(run, t_end, rtol, mujoco)
    return dataclasses.replace(
        res,
        out_dir=run.target,
        rrd=run.final(res.rrd.name),
        markdown=run.final(res.markdown.name),
        figures=tuple(run.final(f.name) for f in res.figures),
    )


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


def step_layout(
    step: DemoStep,
    scene: Scene,
    two_plants: bool,
    comparison: Comparison | None = None,
    trajectories: Sequence[Trajectory] = (),
):
    """The tab of one step: the 3D views (the plants overlaid and, with MuJoCo, its difference
    from the analytic body exaggerated by the factor the recording logs, from ``comparison`` and
    ``trajectories``) over the narrative on the left; on the right the key plot with two thirds
    of the height (the whole column when alone), the other plots below it."""
    # deferred: rerun ~0.3 s, matplotlib ~0.25 s (python -X importtime): only to write
    import rerun.blueprint as rrb

    p0 = f"/{step.prefix}"
    plots = step_plots(step, scene, two_plants)
    views = [
        rrb.TimeSeriesView(
            origin=f"{p0}/plots/{p.value}", name=viewer_text(plot_title(p, step, scene))
        )
        for p in plots
    ]
    rest = len(views) - 1
    right = rrb.Vertical(*views, row_shares=[2 * rest] + [1] * rest) if rest else views[0]
    names = ("analytic", "mujoco") if two_plants else ("analytic",)
    factors = difference_factors(scene, comparison, names, trajectories)
    left = rrb.Vertical(
        views_3d(p0, names, factors),
        rrb.TextDocumentView(origin=f"{p0}/narrative", name="what to look at"),
        row_shares=[3, 2],
    )
    return rrb.Horizontal(left, right, column_shares=[1, 1], name=viewer_text(step.title))


def step_narrative(step: DemoStep) -> str:
    """The text beside the body: the story, then what to look at."""
    look = "\n".join(f"* {x}" for x in step.look_at)
    return f"{step.narrative}\n\n**What to look at**\n\n{look}" if look else step.narrative


@dataclass(frozen=True)
class StepRun:
    """One step's runs.

    Attributes:
        step: the step.
        scene: the scene it ran (:func:`step_scene`).
        plants: the analytic run, then the MuJoCo ghost when it ran; on the output grid.
        comparison: the analytic run against the ghost (or alone), under the report's thresholds.
        baseline: for a step with an effect switched off, the analytic run of the full scene.
    """

    step: DemoStep
    scene: Scene
    plants: tuple[Trajectory, ...]
    comparison: Comparison
    baseline: Trajectory | None = None

    @property
    def two_plants(self) -> bool:
        return len(self.plants) > 1


@dataclass(frozen=True)
class Curves:
    """Curves of one plot on one time axis: one entity of the recording, one legend entry each.

    Attributes:
        entity: the entity path below the plot's origin (``analytic``, ``energy/mujoco``).
        t: sample times, s, shape (N,).
        values: shape (N, k): physical values, or log10 of magnitudes in a :data:`LOG_PLOTS` plot.
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


DEMO_PLOTS = frozenset({Plot.OMEGA, Plot.MASS_POSITIONS, Plot.INVARIANTS})
"""The plots the demo logs itself; the others are :func:`validation.recording.recording.log_run`'s, drawn
in the figures with the same names and colours."""


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
    :data:`DEMO_PLOTS`) and the figure's, one list for both."""
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


def _log_curves(rec, origin: str, curves: Sequence[Curves]) -> None:
    """Each :class:`Curves` as scalars under ``origin/entity``, one named, coloured line per
    column (nothing for an empty one)."""
    import rerun as rr

    for c in curves:
        if not c.t.size:
            continue
        v = np.asarray(c.values, float).reshape(len(c.t), -1)
        path = f"{origin}/{c.entity}"
        names = [viewer_text(x) for x in c.names]
        rec.log(path, rr.SeriesLines(names=names, colors=list(c.colors)), static=True)
        rec.send_columns(
            path,
            indexes=[rr.TimeColumn("sim_time", duration=c.t)],
            columns=rr.Scalars.columns(scalars=np.ravel(v)).partition([v.shape[1]] * v.shape[0]),
        )


def log_step(rec, run: StepRun) -> None:
    """Log one step into the recording ``rec`` under its prefix: the run (bodies, plots, the
    narrative; :func:`validation.recording.recording.log_run`) and the demo's own plots."""
    log_run(
        rec,
        run.scene,
        list(run.plants),
        run.comparison,
        narrative=step_narrative(run.step),
        prefix=run.step.prefix,
    )
    for plot in (Plot.OMEGA, Plot.MASS_POSITIONS, Plot.INVARIANTS):
        _log_curves(rec, f"/{run.step.prefix}/plots/{plot.value}", step_curves(run, plot))


FIGURE_DPI = 150  # pixels per inch of a step's PNG
FIGURE_WIDTH_IN = 11.0  # in: the panels and, right of them, their legends
FIGURE_ROW_IN = 1.9  # in: the height of a plot (the key plot has two)
FIGURE_LEGEND_IN = 3.4  # in: room right of the panels for the legends
FIGURE_GAP_IN = 0.45  # in: between panels, for the lower one's title


def step_figure(run: StepRun):
    """The figure of one step (a :class:`validation.report.figures.Drawing`): its tab's plots in the
    tab's order, the key plot first with twice the height, each titled as in the recording, every
    curve named in a legend beside its panel."""
    from matplotlib.figure import Figure

    plots = step_plots(run.step, run.scene, run.two_plants)
    ratios = [2.0] + [1.0] * (len(plots) - 1)
    top, bottom = 0.75, 0.55
    height = FIGURE_ROW_IN * sum(ratios) + top + bottom + FIGURE_GAP_IN * (len(plots) - 1)
    fig = Figure(figsize=(FIGURE_WIDTH_IN, height), dpi=FIGURE_DPI)
    axes = fig.subplots(
        len(plots),
        1,
        sharex=True,
        squeeze=False,
        gridspec_kw={
            "height_ratios": ratios,
            "left": 0.85 / FIGURE_WIDTH_IN,
            "right": 1.0 - FIGURE_LEGEND_IN / FIGURE_WIDTH_IN,
            "top": 1.0 - top / height,
            "bottom": bottom / height,
            "hspace": FIGURE_GAP_IN / (FIGURE_ROW_IN * sum(ratios) / len(plots)),
        },
    )[:, 0]
    fig.suptitle(run.step.title, fontsize=12, x=0.85 / FIGURE_WIDTH_IN, ha="left")
    titles = []
    for ax, plot in zip(axes, plots, strict=True):
        titles.append(plot_title(plot, run.step, run.scene))
        _draw_panel(ax, plot, step_curves(run, plot), titles[-1])
    axes[-1].set_xlabel("t (s)")
    return Drawing(run.step.prefix, f"{run.step.title}: " + "; ".join(titles) + ".", fig)


def _draw_panel(ax, plot: Plot, curves: Sequence[Curves], title: str) -> None:
    """One plot of a step's figure: every column of every :class:`Curves`, with its name."""
    for c in curves:
        if not c.t.size:
            continue
        v = np.asarray(c.values, float).reshape(len(c.t), -1)
        for j, name in enumerate(c.names):
            rgba = tuple(x / 255 for x in c.colors[j])
            ax.plot(
                c.t, v[:, j], color=rgba, linestyle="--" if c.dashed else "-", lw=1.2, label=name
            )
    ax.set_title(title, fontsize=9, loc="left")
    ax.set_ylabel("log10" if plot in LOG_PLOTS else _scale_lines(ax))
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)


def _scale_lines(ax) -> str:
    """Divide a linear panel's lines by a power of ten (a multiple of three) when their values
    reach 1e4, so no offset text sits on the title; the factor, as the y label (``× 1e9``)."""
    peak = max(
        (np.nanmax(np.abs(ln.get_ydata())) for ln in ax.lines if len(ln.get_ydata())), default=0.0
    )
    if not (np.isfinite(peak) and peak >= 1e4):
        return ""
    e = 3 * int(np.floor(np.log10(peak) / 3))
    for ln in ax.lines:
        ln.set_ydata(np.asarray(ln.get_ydata(), float) / 10.0**e)
    ax.relim()
    ax.autoscale_view()
    return f"× 1e{e}"


def write_step_figures(out: Path, runs: Sequence[StepRun]) -> tuple[Path, ...]:
    """Each step's figure as ``{prefix}.png`` in ``out``, written atomically; their paths."""
    return tuple(
        write_bytes(out / f"{r.step.prefix}.png", step_figure(r).render(FigureFormat.PNG))
        for r in runs
    )


def run_steps(
    t_end: float = DEMO_T_END,
    rtol: float = DEMO_RTOL,
    mujoco: bool = True,
    steps: Sequence[DemoStep] = STEPS,
) -> tuple[tuple[StepRun, ...], dict[str, float]]:
    """Run every step on the analytic plant (DOP853 at ``rtol``) and, with ``mujoco`` (and the
    twin importable), on MuJoCo under the same controller, and compare them; for a step with an
    effect switched off, also the full scene (an earlier step's run when there is one).

    Returns the runs, in step order, and the wall time of each run, s. A run that fails raises
    RuntimeError naming the step."""
    mj_simulate = None
    if mujoco:
        try:
            from mj_bridge import simulate as mj_simulate
        except ImportError as exc:  # pragma: no cover - the twin is part of the package
            interrupts.raise_if_interrupt(exc)  # an import a signal cut is the signal
            mj_simulate = None
    walls: dict[str, float] = {}
    runs: list[StepRun] = []
    for step in steps:
        sc = step_scene(step)
        t0 = time.perf_counter()
        # checkpoint: a signal compiled code swallowed stops the run at its next report
        tr = simulate(sc, t_end=t_end, rtol=rtol, progress=interrupts.checkpoint)
        tr = tr.raise_if_interrupted()
        walls[step.prefix] = time.perf_counter() - t0
        if tr.status is not RunStatus.OK:
            raise RuntimeError(f"demo step {step.title!r} failed: {tr.message}")
        plants = [tr]
        if mj_simulate is not None:
            t0 = time.perf_counter()
            tm = mj_simulate(sc, t_end=t_end, progress=interrupts.checkpoint).raise_if_interrupted()
            walls[f"{step.prefix}_mujoco"] = time.perf_counter() - t0
            if tm.status is not RunStatus.OK:
                raise RuntimeError(f"demo step {step.title!r} failed on MuJoCo: {tm.message}")
            plants.append(tm)
        cmp = compare(tr, plants[1] if len(plants) > 1 else None, sc, t_end=t_end)
        base = _baseline(step, runs, t_end, rtol, walls) if step.switched_off else None
        runs.append(StepRun(step, sc, tuple(plants), cmp, base))
    return tuple(runs), walls


def _baseline(
    step: DemoStep, runs: Sequence[StepRun], t_end: float, rtol: float, walls: dict[str, float]
) -> Trajectory:
    """The analytic run of ``step``'s scene with every effect: an earlier step's, or run now."""
    earlier = next(
        (r for r in runs if r.step.scene == step.scene and not r.step.switched_off), None
    )
    if earlier is not None:
        return earlier.plants[0]
    t0 = time.perf_counter()
    tr = simulate(resolve_scene(step.scene), t_end=t_end, rtol=rtol, progress=interrupts.checkpoint)
    tr = tr.raise_if_interrupted()
    walls[f"{step.prefix}_baseline"] = time.perf_counter() - t0
    if tr.status is not RunStatus.OK:
        raise RuntimeError(f"demo step {step.title!r}: the full scene failed: {tr.message}")
    return tr


def _demo_into(run: OutputRun, t_end: float, rtol: float, mujoco: bool) -> DemoResult:
    """:func:`write_demo`'s work, writing into the staging directory ``run.path``."""
    import rerun.blueprint as rrb

    out = run.path
    runs, walls = run_steps(t_end, rtol, mujoco)
    two = all(r.two_plants for r in runs)

    path = out / "demo.rrd"
    t0 = time.perf_counter()
    tabs = [step_layout(r.step, r.scene, two, r.comparison, r.plants) for r in runs]
    bp = rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(state="expanded"))
    with atomic_stream(path, AppId.DEMO, blueprint=bp, recording_id=run.run_id) as rec:
        for r in runs:
            log_step(rec, r)
    walls["recording"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    figures = write_step_figures(out, runs)
    walls["figures"] = time.perf_counter() - t0
    mdp = write_text(
        out / "demo.md",
        demo_markdown(
            [(r.step, r.scene, r.plants[0]) for r in runs],
            t_end,
            rtol,
            two,
            shown=run.final(path.name),
            bodies=[
                narrative_for(r.scene, list(r.plants), r.comparison, r.step.narrative, None)
                for r in runs
            ],
            figures=[f.name for f in figures],
        ),
    )
    return DemoResult(
        out,
        path,
        mdp,
        tuple(r.step for r in runs),
        walls,
        tuple(r.comparison for r in runs) if two else (),
        figures,
    )


def demo_markdown(
    runs: list[tuple[DemoStep, Scene, Trajectory]],
    t_end: float,
    rtol: float,
    two_plants: bool,
    shown: Path | str = "demo.rrd",
    bodies: list[str] | None = None,
    figures: Sequence[str] | None = None,
) -> str:
    """The text of ``demo.md``: goals, how to open the recording, the steps with what to look
    at, exercises, and the paper. ``bodies[i]``, when given, is step i's text as its recording
    shows it (:func:`validation.recording.recording.narrative_for`: the narrative with the arrow scales,
    colours and exaggeration factors); ``figures[i]``, when given, the file name of step i's
    figure (:func:`step_figure`), embedded in its section."""
    ghost = (
        "; the MuJoCo twin under the same controller as an orange wireframe over the analytic "
        "body, and beside it with its difference exaggerated, RK4 at the scene's timestep, its "
        "curves in the same plots"
        if two_plants
        else ""
    )
    md = [
        "# tumble demo: a tumbling body with sliding masses, free and under exact control",
        "",
        f"Based on {PAPER} Equation, remark and figure numbers below are the paper's.",
        "",
        "# Learning goals",
        "",
        "After the four steps you can",
        "",
        *[f"{i}. {g}" for i, g in enumerate(LEARNING_GOALS, 1)],
        "",
        "# Opening the recording",
        "",
        f"    rerun {shown}",
        "",
        "opens it in the Rerun viewer (version 0.41, installed with this package). One tab per "
        f"step, {t_end:g} s each (analytic plant, DOP853 at rtol {rtol:g}{ghost}). Press play "
        "in the time panel at the bottom, or drag its cursor. In each tab the body is on the left "
        "(green arrow: ω; purple: the control torque τ; the line: the path of C) above the "
        "step's text; on the right the step's key plot on top, with two thirds of the height, and "
        "the others below. Errors and drifts are plotted as log10 (Rerun has no log axis; an "
        "exact zero is not plotted)."
        + (
            " Each step's plots are also drawn as a figure in its section below, for reading "
            "without the viewer."
            if figures
            else ""
        ),
        "",
        "# The four steps",
        "",
    ]
    for i, (step, sc, _) in enumerate(runs):
        # the narrative without its own heading (with the recording's legend when given)
        body = (bodies[i] if bodies else step.narrative).split("\n\n", 1)[1]
        plots = step_plots(step, sc, two_plants)
        md += [f"## {step.title}", "", body, ""]
        md += [f"**Key plot:** {plot_title(plots[0], step, sc)}.", ""] if plots else []
        if figures:
            alt = f"{step.title}: " + "; ".join(plot_title(p, step, sc) for p in plots)
            md += [f"![{alt}]({figures[i]})", ""]
        if step.look_at:
            md += ["**What to look at:**", "", *[f"- {x}" for x in step.look_at], ""]
        if not is_controlled(sc):
            md += ["No control acts in this step, so its tab has no control plot.", ""]
    md += [
        "# Exercises",
        "",
        "Each asks for a prediction first; the answer's physics follows it. The numbers are for "
        "the scene's 20 s horizon.",
        "",
    ]
    for i, (title, text) in enumerate(EXERCISES, 1):
        md += [f"**Exercise {i}. {title}.** {text}", ""]
    md += ["# Reference", "", PAPER, ""]
    return "\n".join(md)


__all__ = [
    "DEMO_RTOL",
    "DEMO_T_END",
    "PAPER",
    "REQUIREMENT_HUE",
    "SERIES_HUES",
    "STEPS",
    "WITHOUT_HUE",
    "WITH_HUE",
    "Curves",
    "DemoResult",
    "DemoStep",
    "Hue",
    "Plot",
    "StepRun",
    "demo_markdown",
    "is_controlled",
    "log_step",
    "plot_title",
    "run_steps",
    "step_curves",
    "step_figure",
    "step_layout",
    "step_plots",
    "step_scene",
    "write_demo",
    "write_step_figures",
]
