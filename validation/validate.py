"""Run a scene on both plants under one controller, compare, and write the evidence.

* :func:`run_validation`: the analytic plant (scipy, the scene's solver settings) and the MuJoCo twin
  (the scene's integrator and time step, overridable), both driven by the analytic controller;
  :func:`validation.compare.compare`; then ``report.md``, ``report.json``, the PNG figures and
  ``run.rrd`` in ``out_dir``. A run that fails (an engine error, a plant stopping early, MuJoCo's
  bridge missing) still writes what it has, marked FAILED.
* :func:`write_demo`: the teaching demo, one ``demo.rrd`` and a short ``demo.md``.
"""

from __future__ import annotations

import dataclasses
import inspect
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.effects import Effect
from analytic.scene import Scene, load_scene
from analytic.trajectory import Engine, RunStatus, Trajectory
from validation.atomic import OutputError
from validation.compare import Check, Comparison, compare, compare_plants
from validation.outputs import OutputRun, output_run
from validation.preflight import check_validation_inputs
from validation.recording import (
    atomic_stream,
    blueprint_for,
    log_run,
    write_recording,
)
from validation.referee import Verdict, referee
from validation.report import versions, write_atomic, write_report

SCENES = Path(__file__).resolve().parent / "scenes"
DEFAULT_SCENE = "paper_example1_controlled"

Progress = Callable[[str, float], None] | Callable[[float], None]
"""``progress(stage, t)`` (stage ``analytic`` or ``mujoco``) or ``progress(t)``: t is the simulated
time reached, s. A one-argument callable is told the analytic plant's progress only."""


def _stage_progress(progress: Any, stage: str) -> Callable[[float], None] | None:
    """Adapt either form of ``progress`` to the engines' ``progress(t)``."""
    if progress is None:
        return None
    try:
        params = inspect.signature(progress).parameters.values()
        two = sum(
            p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params
        ) >= 2 or any(p.kind is p.VAR_POSITIONAL for p in params)
    except (TypeError, ValueError):
        two = False
    if two:
        return lambda t: progress(stage, t)
    return progress if stage == "analytic" else None


@dataclass(frozen=True)
class ValidationResult:
    """The outcome of :func:`run_validation`.

    Attributes:
        scene: scene name.
        out_dir: where the files are.
        passed: every check passed and nothing failed.
        checks: every check (empty if no comparison could be made).
        comparison: the comparison (None if no analytic trajectory exists).
        failure: why the run failed ("" if it did not).
        files: name -> path of every file written.
        wall_times: stage -> seconds (each plant, compare, report, recording, total).
        verdicts: the referee's rulings (three plants), see :mod:`validation.referee`.
    """

    scene: str
    out_dir: Path
    passed: bool
    checks: tuple[Check, ...]
    comparison: Comparison | None
    failure: str = ""
    files: dict[str, Path] = field(default_factory=dict)
    wall_times: dict[str, float] = field(default_factory=dict)
    verdicts: tuple[Verdict, ...] = ()

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)


def _scene(scene: Scene | str | Path) -> Scene:
    if isinstance(scene, Scene):
        return scene
    p = Path(scene)
    if not p.exists() and (SCENES / f"{scene}.toml").exists():
        p = SCENES / f"{scene}.toml"
    return load_scene(p)


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


def _plant_settings(engine: Engine, sc: Scene, integrator: Any, dt: float | None) -> Any:
    """Each plant's settings: the scene's, with the MuJoCo overrides of the command line."""
    from mj_bridge.plants import MujocoRunSettings, plant

    if engine is Engine.MUJOCO:
        return MujocoRunSettings(
            sc.mujoco.integrator if integrator is None else integrator,
            sc.mujoco.timestep if dt is None else dt,
        )
    return plant(engine).default_settings(sc)


def run_validation(
    scene: Scene | str | Path,
    out_dir: str | Path,
    integrator: Any = None,
    dt: float | None = None,
    t_end: float | None = None,
    progress: Progress | None = None,
    plants: Sequence[Engine | str] | str | None = None,
) -> ValidationResult:
    """Run ``scene`` on every chosen plant under one controller, compare every pair, rule on
    disagreements, and write the report and ``run.rrd``.

    Args:
        scene: a :class:`Scene`, a scene file, or a built-in scene name.
        out_dir: output directory. It receives this run's files as one set
            (:func:`validation.outputs.output_run`): ``manifest.json`` lists them with their
            hashes and the run id; a failed run's partial set is marked failed, an interrupted one
            interrupted (and the KeyboardInterrupt re-raised after the files are in place).
        integrator: MuJoCo integrator (default the scene's ``[mujoco] integrator``).
        dt: MuJoCo time step, s (default the scene's ``[mujoco] timestep``).
        t_end: horizon, s (default the scene's ``[output] t_end``).
        progress: optional ``progress(stage, t)`` callback, stage the plant's name (a one-argument
            callable hears the analytic plant only).
        plants: which plants (engine names, or ``"analytic,mujoco"``); default every installed
            plant (:func:`mj_bridge.plants.installed_plants`). With three, the referee names the
            plant that disagrees with the two that agree (:mod:`validation.referee`).

    Returns:
        a frozen :class:`ValidationResult`; ``passed`` is False when any check fails or a plant
        could not run.

    Raises:
        ValueError: bad input (scene, plants, integrator, dt, t_end, out_dir), before any plant
            runs.
        OutputBusy: another run is writing into ``out_dir``.
        OutputError: the files could not be written; ``out_dir`` keeps its previous contents.
    """
    from mj_bridge.plants import installed_plants, parse_plants, plant

    sc = _scene(scene)
    if plants is None:
        chosen = installed_plants()
    elif isinstance(plants, str):
        chosen = parse_plants(plants)
    else:
        chosen = parse_plants(",".join(str(getattr(p, "value", p)) for p in plants))
    check_validation_inputs(  # before any plant runs
        sc, integrator=integrator, dt=dt, t_end=t_end, mujoco=Engine.MUJOCO in chosen
    )
    if t_end is not None and not (t_end > 0):
        raise ValueError(f"t_end: must be a positive time in s (got {t_end!r})")
    horizon = float(t_end) if t_end is not None else sc.output.t_end
    runs = []
    for e in chosen:
        pl = plant(e)
        pl.check_scene(sc)
        runs.append((pl, _plant_settings(e, sc, integrator, dt)))
    with output_run(out_dir, "validate") as run:
        res = _validate_into(run, sc, runs, horizon, progress)
    files = {name: run.final(name) for name in res.files}
    files["manifest.json"] = run.final("manifest.json")
    return dataclasses.replace(res, out_dir=run.target, files=files)


def _validate_into(
    run: OutputRun,
    sc: Scene,
    runs: Sequence[tuple[Any, Any]],
    horizon: float,
    progress: Progress | None,
) -> ValidationResult:
    """:func:`run_validation`'s work, writing into the staging directory ``run.path``."""
    from mj_bridge.plants import PinocchioPlant

    out = run.path
    walls: dict[str, float] = {}
    failures: list[str] = []
    t_all = time.perf_counter()

    def timed(stage: str, fn: Callable[[], Any]) -> Any:
        t0 = time.perf_counter()
        try:
            return fn()
        finally:
            walls[stage] = time.perf_counter() - t0

    trajectories: list[Trajectory] = []
    names: dict[str, str] = {}
    interrupted = False
    for pl, settings in runs:
        name = pl.engine.value
        names[name] = pl.describe(settings)
        if interrupted:  # Ctrl-C stops the run, it does not skip to the next plant
            failures.append(f"{pl.label} plant: not run (interrupted)")
            continue
        try:
            tr = timed(
                name,
                lambda pl=pl, settings=settings, name=name: pl.simulate(
                    sc, settings, t_end=horizon, progress=_stage_progress(progress, name)
                ),
            )
        except ValueError:
            raise  # the caller's input, not a failed run
        except Exception as exc:
            failures.append(f"{pl.label} plant: {_one_line(exc)}")
            continue
        trajectories.append(tr)
        interrupted = tr.status is RunStatus.INTERRUPTED
        if tr.status is not RunStatus.OK:
            failures.append(f"{name} plant stopped early: {tr.message}")

    cmp: Comparison | None = None
    verdicts: tuple[Verdict, ...] = ()
    if trajectories and trajectories[0].t.size:
        try:
            cmp = timed("compare", lambda: compare_plants(trajectories, sc, t_end=horizon))
            verdicts = referee(cmp, names)
        except Exception as exc:
            failures.append(f"comparison: {_one_line(exc)}")
            traceback.print_exc()
    failure = "; ".join(failures)
    passed = cmp is not None and cmp.passed and not failure and len(trajectories) == len(runs) >= 2
    if len(runs) < 2 and not failure:
        failure = "only one plant: nothing to compare it with"
        passed = False

    files: dict[str, Path] = {}
    try:
        rinfo = (
            timed(
                "recording",
                lambda: write_recording(
                    out / "run.rrd", sc, trajectories, cmp, recording_id=run.run_id
                ),
            )
            if trajectories
            else None
        )
        if rinfo is not None:
            files["run.rrd"] = rinfo.path
    except Exception as exc:
        why = exc.reason if isinstance(exc, OutputError) else _one_line(exc)
        failure = "; ".join([*failures, f"recording: {why}"])
        passed = False
    walls["total"] = time.perf_counter() - t_all
    by_engine = {pl.engine: (pl, st) for pl, st in runs}
    mj = by_engine.get(Engine.MUJOCO)
    referee_note = (
        ""
        if len(runs) >= 3
        else (
            "the referee (Pinocchio) is not installed: pip install 'pin>=4.1' (the [pinocchio] extra)"
            if PinocchioPlant.unavailable()
            else "the referee needs three plants"
        )
    )
    meta = {
        "run_id": run.run_id,
        "scene": {
            "name": sc.name,
            "source": sc.source,
            "description": sc.description,
            "effects": sorted(e.value for e in sc.effects),
        },
        "horizon_s": horizon,
        "output_rate_hz": sc.output.rate,
        "plants": [
            {"engine": pl.engine.value, "settings": names[pl.engine.value]} for pl, _ in runs
        ],
        "analytic_solver": {
            "method": sc.solver.method.value,
            "rtol": sc.solver.rtol,
            "atol": sc.solver.atol,
            "max_step": sc.solver.max_step,
        },
        "mujoco_settings": {
            "integrator": (mj[1].integrator.value if mj else sc.mujoco.integrator.value),
            "timestep": mj[1].dt if mj else sc.mujoco.timestep,
            "spring_model": sc.mujoco.spring_model.value,
        },
        "controller": "analytic (Udwadia–Kalaba, Eq. 89) in every plant",
        "referee": [v.to_dict() for v in verdicts],
        "referee_note": referee_note,
        "versions": versions(),
        "wall_times_s": dict(walls),
    }
    t0 = time.perf_counter()
    rep = write_report(out, cmp, trajectories, meta, failure=failure, verdicts=verdicts)
    walls["report"] = time.perf_counter() - t0
    files.update({"report.md": rep.markdown, "report.json": rep.json})
    files.update({f.name: f for f in rep.figures})
    if failure:
        run.mark_failed(failure)
    if interrupted:
        raise KeyboardInterrupt  # the partial set is committed, marked interrupted
    return ValidationResult(
        scene=sc.name,
        out_dir=out,
        passed=bool(passed),
        checks=cmp.checks if cmp is not None else (),
        comparison=cmp,
        failure=failure,
        files=files,
        wall_times=walls,
        verdicts=verdicts,
    )


# ----------------------------------------------------------------------------------------------
# The teaching demo
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DemoStep:
    """One step of the demo: an entity prefix, a title, the scene run, and its narrative."""

    prefix: str
    title: str
    scene: str
    narrative: str


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


DEMO_RTOL = 1e-12  # as `tumble validate` (the scenes' rtol): the ghost is checked against it
DEMO_T_END = 10.0  # s

_STEPS = (
    DemoStep(
        "step1_uncontrolled",
        "1. Example 1 tumbling freely",
        "paper_example1",
        """# 1. Example 1 tumbling freely

A 10 × 6 × 2 m aluminium block with a 16 m rod at a corner; two masses slide on the rod between
linear + cubic springs. No control: the motion follows Lagrange's equations in the quaternion
coordinates `q = [R, u, p]` (Eq. 44), with the norm constraint `uᵀu = 1` stabilised (Eq. 58),

    M(q) q̈ = Q(q, q̇)        (Eqs. 50–53, solved with Udwadia–Kalaba)

Watch: C follows a parabola (only gravity acts on the whole system: `Ṗ = m_T g`), the body tumbles
about its centre of mass, and the angular momentum about the system's centre of mass stays
constant (Fig. 8) — see the invariant-drift plot, at the level of the integration tolerance.""",
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

The purple arrow is the control torque τ (body axes); the rod forces are in the control plot.
Angular momentum now changes exactly by the impulse of `S(u) τ`; energy by the control's work.""",
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
plot stays at zero). Linear stiffnesses are this project's assumption (Eq. 64 is missing from the paper; docs/errata.md,
item 10).""",
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


def _demo_into(run: OutputRun, t_end: float, rtol: float, mujoco: bool) -> DemoResult:
    """:func:`write_demo`'s work, writing into the staging directory ``run.path``."""
    import numpy as np
    import rerun as rr
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
    runs = []
    ghosts = []
    for step in _STEPS:
        sc = _scene(step.scene)
        if step.prefix == "step4_no_cubic_springs":
            sc = sc.with_effects(set(sc.effects) - {Effect.SPRINGS_CUBIC})
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
        blueprint_for(s.prefix, sc, cmps[i], two, name=s.title) for i, (s, sc, _) in enumerate(runs)
    ]
    tabs[3] = _with_masses_plot(tabs[3], runs[3])
    bp = rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(state="expanded"))
    with atomic_stream(path, "tumble_demo", blueprint=bp, recording_id=run.run_id) as rec:
        for i, (step, sc, tr) in enumerate(runs):
            plants = [tr, ghosts[i]] if two else [tr]
            log_run(rec, sc, plants, cmps[i], narrative=step.narrative, prefix=step.prefix)
        # step 4: the masses' positions with and without the cubic term, in one plot
        full = runs[0][2]
        off = runs[3][2]
        for label, tr, style in (
            ("with cubic springs", full, 0),
            ("without cubic springs", off, 1),
        ):
            ent = f"/step4_no_cubic_springs/plots/mass_positions/{'with' if style == 0 else 'without'}"
            rec.log(
                ent,
                rr.SeriesLines(
                    names=[f"p_{i + 1} {label}" for i in range(tr.n)],
                    colors=[(31, 119, 180, 255) if style == 0 else (255, 127, 14, 255)] * tr.n,
                ),
                static=True,
            )
            rec.send_columns(
                ent,
                indexes=[rr.TimeColumn("sim_time", duration=tr.t)],
                columns=rr.Scalars.columns(scalars=np.ravel(tr.p)).partition(
                    [tr.n] * tr.t.shape[0]
                ),
            )
    walls["recording"] = time.perf_counter() - t0
    md = [
        "# tumble demo",
        "",
        f"Open with `rerun {path.name}`; one tab per step, {t_end:g} s each "
        f"(analytic plant, DOP853 at rtol {rtol:g}"
        + (
            "; the MuJoCo twin under the same controller as a translucent ghost, RK4 at the "
            "scene's timestep, its curves in the same plots)."
            if two
            else ")."
        ),
        "",
    ]
    for step, _, _ in runs:
        body = step.narrative.split("\n\n", 1)[1]  # the narrative without its own heading
        md += [f"## {step.title}", "", body, ""]
    mdp = write_atomic(out / "demo.md", "\n".join(md))
    return DemoResult(
        out, path, mdp, tuple(s for s, _, _ in runs), walls, tuple(cmps) if two else ()
    )


def _with_masses_plot(tab, run):
    import rerun.blueprint as rrb

    step = run[0]
    return rrb.Horizontal(
        tab,
        rrb.TimeSeriesView(
            origin=f"/{step.prefix}/plots/mass_positions", name="mass positions (m)"
        ),
        column_shares=[4, 1],
        name=step.title,
    )


__all__ = [
    "DEFAULT_SCENE",
    "DemoResult",
    "DemoStep",
    "ValidationResult",
    "run_validation",
    "write_demo",
]
