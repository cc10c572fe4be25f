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

from analytic.effects import CONTROL_EFFECTS, Effect
from analytic.scene import Scene
from analytic.trajectory import RunStatus, Trajectory
from validation.atomic import write_text
from validation.compare import Comparison, compare
from validation.outputs import OutputRun, output_run
from validation.recording import atomic_stream, log_run, narrative_for
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
    INVARIANTS = "invariants"
    ERRORS = "errors"
    TORQUE = "control/torque"
    ROD_FORCES = "control/rod_forces"


PLOT_NAMES = {
    Plot.OMEGA: "angular velocity ω, body axes (rad/s); grey: the requirement ω̄",
    Plot.MASS_POSITIONS: "mass positions p_i on the rod (m); grey: the requirements p̄_i",
    Plot.TRACKING: "log10 tracking errors",
    Plot.INVARIANTS: "log10 drift of each balance (P, L, E) and of |uᵀu − 1|",
    Plot.ERRORS: "log10 |analytic − MuJoCo|",
    Plot.TORQUE: "control torque τ, body axes (N·m)",
    Plot.ROD_FORCES: "rod forces F_i (N)",
}
CONTROL_PLOTS = frozenset({Plot.TORQUE, Plot.ROD_FORCES, Plot.TRACKING})
REQUIREMENT_RGBA = (150, 150, 150, 255)
ANALYTIC_RGBA = ((31, 119, 180, 255), (44, 160, 44, 255), (214, 39, 40, 255))
WITH_RGBA, WITHOUT_RGBA = (31, 119, 180, 255), (255, 127, 14, 255)


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
            "integrator disturbs them;",
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
masses' oscillation about `p_e` changes (plot *mass positions*: blue with, orange without the
cubic term), and with it the body's tumble. Energy is still conserved — the switched-off term is
removed from the model and from the energy alike.""",
        look_at=(
            "the mass positions (the key plot): with the cubic term (blue) the springs stiffen at "
            "large extension, so the masses turn back a little sooner and oscillate a little "
            "faster than without it (orange);",
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
numbers with `validation.compare.mass_error_reference`.""",
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
        res, out_dir=run.target, rrd=run.final(res.rrd.name), markdown=run.final(res.markdown.name)
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
    import rerun.blueprint as rrb

    from validation.rrd_layout import views_3d
    from validation.rrd_world import difference_factors

    p0 = f"/{step.prefix}"
    plots = step_plots(step, scene, two_plants)
    views = [rrb.TimeSeriesView(origin=f"{p0}/plots/{p.value}", name=PLOT_NAMES[p]) for p in plots]
    rest = len(views) - 1
    right = rrb.Vertical(*views, row_shares=[2 * rest] + [1] * rest) if rest else views[0]
    names = ("analytic", "mujoco") if two_plants else ("analytic",)
    factors = difference_factors(scene, comparison, names, trajectories)
    left = rrb.Vertical(
        views_3d(p0, names, factors),
        rrb.TextDocumentView(origin=f"{p0}/narrative", name="what to look at"),
        row_shares=[3, 2],
    )
    return rrb.Horizontal(left, right, column_shares=[1, 1], name=step.title)


def _narrative(step: DemoStep) -> str:
    """The text beside the body: the story, then what to look at."""
    look = "\n".join(f"* {x}" for x in step.look_at)
    return f"{step.narrative}\n\n**What to look at**\n\n{look}" if look else step.narrative


def _log_series(rec, path: str, t, values, names, colors) -> None:
    """Scalars ``values`` (N, k) under ``path``, one named, coloured line per column."""
    import numpy as np
    import rerun as rr

    v = np.asarray(values, float).reshape(len(t), -1)
    rec.log(path, rr.SeriesLines(names=list(names), colors=list(colors)), static=True)
    rec.send_columns(
        path,
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Scalars.columns(scalars=np.ravel(v)).partition([v.shape[1]] * v.shape[0]),
    )


def _log_step_plots(rec, step: DemoStep, tr: Trajectory, baseline: Trajectory | None) -> None:
    """The demo's own plots of one step: ω with ω̄, the mass positions with p̄ (or, with an
    effect switched off, with and without it). The requirements are ``ω − e_ω`` and ``p − e_p``."""
    p0 = f"/{step.prefix}/plots"
    axes = "xyz"
    _log_series(
        rec, f"{p0}/omega/analytic", tr.t, tr.omega, [f"ω_{a}" for a in axes], ANALYTIC_RGBA
    )
    tk = tr.tracking
    if tk.omega_components:
        _log_series(
            rec,
            f"{p0}/omega/requirement",
            tr.t,
            tr.omega[:, list(tk.omega_components)] - tk.e_omega,
            [f"ω̄_{axes[c]}" for c in tk.omega_components],
            [REQUIREMENT_RGBA] * len(tk.omega_components),
        )
    if not tr.n:
        return
    if step.switched_off and baseline is not None:  # with and without the effect, one plot
        for label, run, rgba in (("with", baseline, WITH_RGBA), ("without", tr, WITHOUT_RGBA)):
            off = ", ".join(sorted(e.value for e in step.switched_off))
            _log_series(
                rec,
                f"{p0}/mass_positions/{label}",
                run.t,
                run.p,
                [f"p_{i + 1} {label} {off}" for i in range(run.n)],
                [rgba] * run.n,
            )
        return
    _log_series(
        rec,
        f"{p0}/mass_positions/analytic",
        tr.t,
        tr.p,
        [f"p_{i + 1}" for i in range(tr.n)],
        [ANALYTIC_RGBA[i % 3] for i in range(tr.n)],
    )
    if tk.mass_indices:
        _log_series(
            rec,
            f"{p0}/mass_positions/requirement",
            tr.t,
            tr.p[:, list(tk.mass_indices)] - tk.e_p,
            [f"p̄_{i + 1}" for i in tk.mass_indices],
            [REQUIREMENT_RGBA] * len(tk.mass_indices),
        )


def _demo_into(run: OutputRun, t_end: float, rtol: float, mujoco: bool) -> DemoResult:
    """:func:`write_demo`'s work, writing into the staging directory ``run.path``."""
    import rerun.blueprint as rrb

    from analytic.simulate import simulate

    out = run.path
    mj_simulate = None
    if mujoco:
        try:
            from mj_bridge import simulate as mj_simulate
        except ImportError:  # pragma: no cover - the twin is part of the package
            mj_simulate = None
    walls: dict[str, float] = {}
    runs: list[tuple[DemoStep, Scene, Trajectory]] = []
    ghosts: list[Trajectory] = []
    for step in STEPS:
        sc = step_scene(step)
        t0 = time.perf_counter()
        tr = simulate(sc, t_end=t_end, rtol=rtol).raise_if_interrupted()
        walls[step.prefix] = time.perf_counter() - t0
        if tr.status is not RunStatus.OK:
            raise RuntimeError(f"demo step {step.title!r} failed: {tr.message}")
        runs.append((step, sc, tr))
        if mj_simulate is not None:
            t0 = time.perf_counter()
            tm = mj_simulate(sc, t_end=t_end).raise_if_interrupted()
            walls[f"{step.prefix}_mujoco"] = time.perf_counter() - t0
            if tm.status is not RunStatus.OK:
                raise RuntimeError(f"demo step {step.title!r} failed on MuJoCo: {tm.message}")
            ghosts.append(tm)
    two = len(ghosts) == len(runs)
    cmps = [
        compare(tr, ghosts[i] if two else None, sc, t_end=t_end)
        for i, (_, sc, tr) in enumerate(runs)
    ]

    path = out / "demo.rrd"
    t0 = time.perf_counter()
    tabs = [
        step_layout(s, sc, two, cmps[i], [tr, ghosts[i]] if two else [tr])
        for i, (s, sc, tr) in enumerate(runs)
    ]
    bp = rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(state="expanded"))
    with atomic_stream(path, "tumble_demo", blueprint=bp, recording_id=run.run_id) as rec:
        for i, (step, sc, tr) in enumerate(runs):
            plants = [tr, ghosts[i]] if two else [tr]
            log_run(rec, sc, plants, cmps[i], narrative=_narrative(step), prefix=step.prefix)
            _log_step_plots(rec, step, tr, _baseline(step, runs))
    walls["recording"] = time.perf_counter() - t0
    mdp = write_text(
        out / "demo.md",
        demo_markdown(
            runs,
            t_end,
            rtol,
            two,
            shown=run.final(path.name),
            bodies=[
                narrative_for(sc, [tr, ghosts[i]] if two else [tr], cmps[i], step.narrative, None)
                for i, (step, sc, tr) in enumerate(runs)
            ],
        ),
    )
    return DemoResult(
        out, path, mdp, tuple(s for s, _, _ in runs), walls, tuple(cmps) if two else ()
    )


def _baseline(step: DemoStep, runs: list[tuple[DemoStep, Scene, Trajectory]]) -> Trajectory | None:
    """For a step with an effect switched off, the run of the same scene with every effect."""
    if not step.switched_off:
        return None
    return next((tr for s, _, tr in runs if s.scene == step.scene and not s.switched_off), None)


def demo_markdown(
    runs: list[tuple[DemoStep, Scene, Trajectory]],
    t_end: float,
    rtol: float,
    two_plants: bool,
    shown: Path | str = "demo.rrd",
    bodies: list[str] | None = None,
) -> str:
    """The text of ``demo.md``: goals, how to open the recording, the steps with what to look
    at, exercises, and the paper. ``bodies[i]``, when given, is step i's text as its recording
    shows it (:func:`validation.recording.narrative_for`: the narrative with the arrow scales,
    colours and exaggeration factors)."""
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
        "exact zero is not plotted).",
        "",
        "# The four steps",
        "",
    ]
    for i, (step, sc, _) in enumerate(runs):
        # the narrative without its own heading (with the recording's legend when given)
        body = (bodies[i] if bodies else step.narrative).split("\n\n", 1)[1]
        plots = step_plots(step, sc, two_plants)
        md += [f"## {step.title}", "", body, ""]
        md += [f"**Key plot:** {PLOT_NAMES[plots[0]]}.", ""] if plots else []
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
    "STEPS",
    "DemoResult",
    "DemoStep",
    "Plot",
    "demo_markdown",
    "is_controlled",
    "step_layout",
    "step_plots",
    "step_scene",
    "write_demo",
]
