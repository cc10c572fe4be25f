"""Comparison of two trajectories: independent references for every measure and planted offsets."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from analytic.effects import Effect
from analytic.scene import load_scene
from analytic.simulate import simulate
from analytic.threshold import BoundPart
from analytic.trajectory import Engine, RunStatus, Trajectory
from validation.compare.checks import Check, Subject, compare
from validation.compare.differences import Difference
from validation.compare.thresholds import DEFAULTS, thresholds_for

SCENES = Path(__file__).resolve().parents[3] / "analytic" / "scenes"
T_END = 0.5


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENES / "paper_example1_controlled.toml")


@pytest.fixture(scope="module")
def traj(scene) -> Trajectory:
    tr = simulate(scene, t_end=T_END, rtol=1e-10)
    assert tr.status is RunStatus.OK
    return tr


def as_mujoco(tr: Trajectory, **changes) -> Trajectory:
    """The same record relabelled as the other plant, with some fields replaced."""
    return dataclasses.replace(tr, engine=Engine.MUJOCO, **changes)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product, w first, batched over leading axes."""
    a0, av = a[..., :1], a[..., 1:]
    b0, bv = b[..., :1], b[..., 1:]
    w = a0 * b0 - np.sum(av * bv, axis=-1, keepdims=True)
    v = a0 * bv + b0 * av + np.cross(av, bv)
    return np.concatenate([w, v], axis=-1)


# ----------------------------------------------------------------------------------------------
# compare
# ----------------------------------------------------------------------------------------------


def test_self_comparison_gives_zero_differences(scene, traj):
    c = compare(traj, as_mujoco(traj), scene, t_end=T_END)
    diffs = [s for s in c.series if s.subject == Subject.BOTH]
    assert {s.name for s in diffs} == {d.value for d in Difference}  # every compared quantity
    for s in diffs:
        assert s.t.shape == traj.t.shape
        assert np.all(s.values == 0.0), s.key
    for ch in c.checks:
        if ch.subject == Subject.BOTH:
            assert ch.value == 0.0 and ch.passed, ch.label
    assert c.passed


def test_the_analytic_plant_obeys_its_error_dynamics_and_balances(scene, traj):
    """The physics, not the comparison: with the engine at rtol 1e-10 every per-plant check passes."""
    c = compare(traj, None, scene, t_end=T_END)
    labels = {ch.label for ch in c.checks}
    assert {
        "analytic.completed",
        "analytic.tracking_omega",
        "analytic.tracking_p",
        "analytic.quat_norm",
        "analytic.linear_momentum",
        "analytic.angular_momentum",
        "analytic.energy",
    } <= labels
    assert c.passed, [ch.label for ch in c.failed_checks]
    assert any("no MuJoCo" in n for n in c.notes)


def _g(scene) -> np.ndarray:
    return np.asarray(scene.gravity, float) if scene.has(Effect.GRAVITY) else np.zeros(3)


def _departure(tr: Trajectory, scene, velocity: bool) -> float:
    """The largest |R - (R(0) + Ṙ(0) t + ½ g t²)| (or |Ṙ - (Ṙ(0) + g t)| for ``velocity``) of
    ``tr``, by numpy: the scale of C's relative part."""
    t, g = (tr.t - tr.t[0])[:, None], _g(scene)
    R, V = tr.q[:, :3], tr.qdot[:, :3]
    if velocity:
        return float(np.linalg.norm(V - (V[0] + g * t), axis=1).max())
    return float(np.linalg.norm(R - (R[0] + V[0] * t + 0.5 * g * t * t), axis=1).max())


def test_planted_offset_of_C_appears_with_its_exact_magnitude(scene, traj):
    k = 20  # a spike of 5e-5 m at sample k, then half of it to the end
    off = np.array([3e-5, 0.0, -4e-5])  # |off| = 5e-5 m exactly
    q = traj.q.copy()
    q[k, :3] += off
    q[k + 1 :, :3] += 0.5 * off
    c = compare(traj, as_mujoco(traj, q=q), scene, t_end=T_END)
    s = c.get("diff.position_C")
    assert s.summary.max == pytest.approx(5e-5, rel=1e-9)
    assert s.summary.final == pytest.approx(2.5e-5, rel=1e-9)
    assert s.summary.t_max == pytest.approx(traj.t[k])
    n = traj.t.shape[0]
    rms = math.sqrt((5e-5**2 + (n - k - 1) * 2.5e-5**2) / n)
    assert s.summary.rms == pytest.approx(rms, rel=1e-9)
    ch = c.check("position_C")
    assert ch.value == pytest.approx(5e-5, rel=1e-9)
    # the bound: the absolute value plus rtol × C's largest departure from its uniformly
    # accelerated motion over both runs (below 10 m here, so the absolute part decides)
    th = DEFAULTS["position_C"]
    size = max(_departure(traj, scene, False), _departure(as_mujoco(traj, q=q), scene, False))
    assert ch.threshold == pytest.approx(th.value + th.rtol * size, rel=1e-12)
    assert ch.absolute_part == th.value and ch.decided_by == "absolute"
    assert not ch.passed and not c.passed
    assert c.failed_checks == (ch,)


def test_planted_rotation_appears_as_its_angle_and_sign_flip_does_not(scene, traj):
    theta = 2e-3
    dq = np.array([math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0])
    q = traj.q.copy()
    q[:, 3:7] = quat_mul(q[:, 3:7], dq)
    c = compare(traj, as_mujoco(traj, q=q), scene, t_end=T_END)
    assert c.check("attitude").value == pytest.approx(theta, rel=1e-9)
    assert not c.check("attitude").passed

    q = traj.q.copy()
    q[:, 3:7] *= -1.0
    c = compare(traj, as_mujoco(traj, q=q), scene, t_end=T_END)
    assert c.check("attitude").value == 0.0 and c.check("attitude").passed


def test_relative_torque_check_divides_by_the_analytic_peak(scene, traj):
    c = compare(traj, as_mujoco(traj, torque=traj.torque * (1 + 1e-3)), scene, t_end=T_END)
    ch = c.check("control_torque")
    assert ch.scale == pytest.approx(np.max(np.linalg.norm(traj.torque, axis=1)))
    assert ch.value == pytest.approx(1e-3, rel=1e-9)
    assert not ch.passed


def test_planted_energy_leak_fails_the_energy_balance(scene, traj):
    inv = traj.invariants
    leak = 1e-6 * np.max(np.abs(inv.energy)) * np.linspace(0.0, 1.0, traj.t.shape[0])
    bad = as_mujoco(traj, invariants=dataclasses.replace(inv, energy=inv.energy + leak))
    c = compare(traj, bad, scene, t_end=T_END)
    ch = c.check("mujoco.energy")
    assert not ch.passed
    assert ch.value >= 0.9e-6  # the leak, less the (≤1e-8 relative) integration error
    assert c.check("analytic.energy").passed


def test_failed_run_is_compared_on_its_samples_and_fails_completed(scene, traj):
    k = 17
    fields = (
        "t",
        "q",
        "qdot",
        "qddot",
        "QC",
        "torque",
        "rod_forces",
        "force_at_C",
        "residual_norm",
    )
    cut = {f: getattr(traj, f)[:k] for f in fields}
    inv = traj.invariants
    cut["invariants"] = dataclasses.replace(
        inv, **{f.name: getattr(inv, f.name)[:k] for f in dataclasses.fields(inv)}
    )
    tk = traj.tracking
    cut["tracking"] = dataclasses.replace(tk, e_omega=tk.e_omega[:k], e_p=tk.e_p[:k])
    failed = as_mujoco(traj, status=RunStatus.FAILED, message="planted failure", **cut)
    c = compare(traj, failed, scene, t_end=T_END)
    assert c.get("diff.position_C").t.shape == (k,)
    done = c.check("mujoco.completed")
    assert not done.passed and "planted failure" in done.reason
    assert done.value == pytest.approx(traj.t[k - 1])
    assert c.check("analytic.completed").passed
    assert not c.passed
    assert any("planted failure" in n for n in c.notes)


def test_comparison_is_frozen(scene, traj):
    c = compare(traj, as_mujoco(traj), scene, t_end=T_END)
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.checks = ()  # type: ignore[misc]
    with pytest.raises(ValueError):
        c.series[0].values[0] = 1.0


# ----------------------------------------------------------------------------------------------
# thresholds
# ----------------------------------------------------------------------------------------------


def test_every_default_threshold_has_a_reason_and_a_unit():
    for name, th in DEFAULTS.items():
        assert th.name == name and th.reason and th.unit and th.value > 0


def test_scene_thresholds_override_the_defaults(scene, traj):
    q = traj.q.copy()
    q[:, :3] += np.array([5e-5, 0.0, 0.0])
    looser = scene.replace(
        extra={"thresholds": {"position_C": {"value": 1e-4, "rtol": 0.0, "reason": "planted"}}}
    )
    th = thresholds_for(looser)
    assert th["position_C"].value == 1e-4 and th["position_C"].source == "scene"
    assert th["position_C"].rtol == 0.0  # the table's rtol replaces the default's
    assert "planted" in th["position_C"].reason
    assert th["attitude"] == DEFAULTS["attitude"]
    c = compare(traj, as_mujoco(traj, q=q), looser, t_end=T_END)
    assert c.check("position_C").passed and c.check("position_C").threshold == 1e-4
    tighter = scene.replace(extra={"thresholds": {"position_C": 1e-5}})
    c = compare(traj, as_mujoco(traj, q=q), tighter, t_end=T_END)
    assert not c.check("position_C").passed


@pytest.mark.parametrize(
    ("table", "field"),
    [
        ({"positon_C": 1e-6}, "thresholds.positon_C"),
        ({"position_C": -1.0}, "thresholds.position_C"),
        ({"position_C": "small"}, "thresholds.position_C"),
        ({"position_C": {"reason": "x"}}, "thresholds.position_C.value"),
        ({"position_C": {"value": 1.0, "why": "x"}}, "thresholds.position_C.why"),
    ],
)
def test_bad_threshold_tables_name_the_field(scene, table, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        thresholds_for(scene.replace(extra={"thresholds": table}))


# ----------------------------------------------------------------------------------------------
# scale-aware bounds: atol + rtol · scale
# ----------------------------------------------------------------------------------------------


def _fast(traj: Trajectory, speed: float, rel: float) -> tuple[Trajectory, Trajectory]:
    """Two runs whose C and masses all move at ``speed`` m/s (C along (0.6, 0.8, 0), each mass
    along its rod), the second faster by the fraction ``rel``: a difference of ``rel`` relative
    on a ``speed`` scale, in velocity_C and rod_velocities alone."""
    qd = traj.qdot.copy()
    qd[:, :3] = speed * np.array([0.6, 0.8, 0.0])
    qd[:, 7:] = speed
    other = qd.copy()
    other[:, :3] *= 1 + rel
    other[:, 7:] *= 1 + rel
    return dataclasses.replace(traj, qdot=qd), as_mujoco(traj, qdot=other)


def test_a_difference_of_1e7_relative_at_1000_m_per_s_passes_by_the_relative_part(scene, traj):
    """1e-4 m/s at 1000 m/s: ten times the absolute 1e-5 m/s (the old verdict, FAIL, blind to
    the scale), inside 1e-5 + 1e-7 × 1000(1 + 1e-7) m/s for the masses' rod velocities; the
    record names the relative part. C moving uniformly at 1000 m/s is another matter: its scale
    is its departure from the uniformly accelerated motion (here g t ≤ 4.9 m/s, the velocities
    being constant), which integrators reproduce exactly, so the absolute part decides and the
    same difference fails."""
    a, b = _fast(traj, 1000.0, 1e-7)
    c = compare(a, b, scene, t_end=T_END)
    ch = c.check("rod_velocities")
    assert ch.value == pytest.approx(1e-4, rel=1e-6)
    assert ch.value > DEFAULTS["rod_velocities"].value  # the absolute part alone fails it
    scale = 1000.0 * (1 + 1e-7)  # the faster of the two plants
    assert ch.magnitude == pytest.approx(scale, rel=1e-12)
    assert ch.relative_part == pytest.approx(1e-7 * scale, rel=1e-12)
    assert ch.absolute_part == 1e-5
    assert ch.threshold == pytest.approx(1e-5 + 1e-7 * scale, rel=1e-12)
    assert ch.passed and ch.decided_by is BoundPart.RELATIVE
    d = ch.to_dict()
    assert d["decided_by"] == "relative" and d["threshold"] == ch.threshold
    vc = c.check("velocity_C")
    assert vc.value == pytest.approx(1e-4, rel=1e-6)
    size = max(_departure(a, scene, True), _departure(b, scene, True))
    assert vc.magnitude == pytest.approx(size, rel=1e-12) and size < 5.0
    assert not vc.passed and vc.decided_by is BoundPart.ABSOLUTE
    # three times that relative difference fails: the relative part is a bound, not a waiver
    a, b = _fast(traj, 1000.0, 3e-7)
    assert not compare(a, b, scene, t_end=T_END).check("rod_velocities").passed


def test_a_small_scale_difference_is_decided_by_the_absolute_part_as_before(scene, traj):
    """5e-5 m/s at 1 m/s: the relative part (1e-7 m/s) is a hundredth of the absolute 1e-5 m/s,
    which decides; the verdict is the one the absolute bound alone gives."""
    a, b = _fast(traj, 1.0, 5e-5)
    ch = compare(a, b, scene, t_end=T_END).check("velocity_C")
    assert ch.value == pytest.approx(5e-5, rel=1e-6)
    assert ch.decided_by is BoundPart.ABSOLUTE and ch.absolute_part == 1e-5
    size = max(_departure(a, scene, True), _departure(b, scene, True))
    assert ch.threshold == pytest.approx(1e-5 + 1e-7 * size, rel=1e-12)
    assert not ch.passed and (ch.value <= DEFAULTS["velocity_C"].value) == ch.passed
    a, b = _fast(traj, 1.0, 5e-6)  # 5e-6 m/s: passes, as under the absolute bound alone
    ch = compare(a, b, scene, t_end=T_END).check("velocity_C")
    assert ch.passed and ch.decided_by is BoundPart.ABSOLUTE


def test_every_bound_is_recomputed_from_the_trajectories_own_arrays(scene, traj):
    """The scale of each relative part, from the arrays by numpy alone: the largest over time
    and over both plants of C's departure from its uniformly accelerated motion (position and
    velocity), |p_i|, |ṗ_i|, |ω|; for the tracking laws the plant's own |ω| and controlled |p_i|."""
    q = traj.q.copy()
    q[:, :3] *= 1.5
    q[:, 7:] += 2.0
    qd = traj.qdot * 3.0  # ω follows (the body rates from u and u̇)
    b = as_mujoco(traj, q=q, qdot=qd)
    c = compare(traj, b, scene, t_end=T_END)
    w = b.omega

    def vec(x):
        return np.sqrt(np.sum(x * x, axis=1)).max()

    expected = {
        "position_C": max(_departure(traj, scene, False), _departure(b, scene, False)),
        "rod_positions": max(np.abs(traj.q[:, 7:]).max(), np.abs(q[:, 7:]).max()),
        "velocity_C": max(_departure(traj, scene, True), _departure(b, scene, True)),
        "rod_velocities": max(np.abs(traj.qdot[:, 7:]).max(), np.abs(qd[:, 7:]).max()),
        "angular_velocity": max(vec(traj.omega), vec(w)),
    }
    for name, size in expected.items():
        ch, th = c.check(name), DEFAULTS[name]
        assert ch.magnitude == pytest.approx(size, rel=1e-12), name
        assert ch.threshold == pytest.approx(th.value + th.rtol * size, rel=1e-12), name
        want = BoundPart.RELATIVE if th.rtol * size > th.value else BoundPart.ABSOLUTE
        assert ch.decided_by is want, name
    att = c.check("attitude")
    assert att.threshold == DEFAULTS["attitude"].value and att.relative_part == 0.0
    # the tracking laws: one plant each, its own magnitudes
    idx = [7 + i for i in traj.tracking.mass_indices]
    for plant, tr in (("analytic", traj), ("mujoco", b)):
        tw, tp = c.check(f"{plant}.tracking_omega"), c.check(f"{plant}.tracking_p")
        assert tw.magnitude == pytest.approx(vec(tr.omega), rel=1e-12)
        assert tp.magnitude == pytest.approx(np.abs(tr.q[:, idx]).max(), rel=1e-12)
        assert tp.threshold == pytest.approx(1e-6 + 1e-7 * tp.magnitude, rel=1e-12)
    # the relative checks keep their single part
    for ch in c.checks:
        if ch.name in ("control_torque", "rod_forces", "linear_momentum", "energy"):
            assert ch.relative_part == 0.0 and ch.threshold == ch.absolute_part


def test_a_diverged_sample_leaves_the_scale_finite_and_fails_the_check(scene, traj):
    """A non-finite state is left out of the scale (it would make the bound infinite); the
    difference is infinite there, so the check fails."""
    qd = traj.qdot.copy()
    qd[5, :3] = np.inf
    c = compare(traj, as_mujoco(traj, qdot=qd), scene, t_end=T_END)
    ch = c.check("velocity_C")
    assert math.isfinite(ch.magnitude) and math.isfinite(ch.threshold)
    assert not ch.passed


def test_a_scene_rtol_changes_the_verdict_through_the_relative_part(scene, traj):
    a, b = _fast(traj, 1000.0, 1e-7)
    off = scene.replace(extra={"thresholds": {"rod_velocities": {"value": 1e-5, "rtol": 0.0}}})
    ch = compare(a, b, off, t_end=T_END).check("rod_velocities")
    assert not ch.passed and ch.threshold == 1e-5 and ch.decided_by is BoundPart.ABSOLUTE
    wide = scene.replace(extra={"thresholds": {"rod_velocities": {"value": 1e-5, "rtol": 1e-6}}})
    ch = compare(a, b, wide, t_end=T_END).check("rod_velocities")
    assert ch.passed and ch.relative_part == pytest.approx(1e-6 * 1000 * (1 + 1e-7), rel=1e-12)


def test_a_check_built_without_parts_reads_as_absolute():
    """Checks other code builds (a hard case's, a count) have one part: the threshold."""
    ch = Check("x", Subject.ANALYTIC, 1.0, 2.0, "m", True, "why")
    assert ch.absolute_part == 2.0 and ch.relative_part == 0.0
    assert ch.decided_by is BoundPart.ABSOLUTE and ch.to_dict()["decided_by"] == "absolute"
