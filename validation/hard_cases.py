"""The hard-case suite: what the testbed survives, as a table (issue 6).

Each case is a scene in ``validation/scenes/hard/`` whose header states its criterion and whose
``[thresholds]`` table carries the same bounds machine-readably (keys ``hard_*``). A case runs on
both engines where that makes sense, compares them with each other and with an independent
reference (closed forms, an independent integration of Euler's equations, invariants), and ends as
one row: case, criterion, the analytic engine's figures, MuJoCo's figures, verdict and wall time.

:func:`run_hard_cases` runs the cases and writes ``hard_cases.md`` and ``hard_cases.json``
atomically (after every case, so an interrupted suite leaves the rows it finished).
"""

from __future__ import annotations

import json
import math
import time
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import mj_bridge
from analytic import simulate as _analytic_simulate
from analytic.invariants import mass_kinematics
from analytic.kinematics import omega_of
from analytic.model import TumblingModel, spring_energy
from analytic.scene import Scene, load_scene
from analytic.trajectory import RunStatus, Trajectory
from model_xml.state import mujoco_to_paper_acc
from validation.atomic import write_text
from validation.compare import attitude_angle, mass_error_reference, omega_error_reference
from validation.outputs import output_run
from validation.scenes import SCENES_DIR
from validation.summary import drift_figures

HARD_DIR = SCENES_DIR / "hard"


def simulate(*args: Any, **kwargs: Any) -> Trajectory:
    """The analytic plant; the user's Ctrl-C stops the suite, not only the current case."""
    return _analytic_simulate(*args, **kwargs).raise_if_interrupted()


def _mj_simulate(*args: Any, **kwargs: Any) -> Trajectory:
    """The MuJoCo plant; the user's Ctrl-C stops the suite, not only the current case."""
    return mj_bridge.simulate(*args, **kwargs).raise_if_interrupted()


# Verdicts.
PASS, FAIL, ERROR = "PASS", "FAIL", "ERROR"


# ----------------------------------------------------------------------------------------------
# Records
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Check:
    """One judged figure: passes when finite and ``value <= bound``."""

    label: str
    value: float
    bound: float

    @property
    def passed(self) -> bool:
        return bool(math.isfinite(self.value) and self.value <= self.bound)

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "value": self.value,
            "bound": self.bound,
            "passed": self.passed,
        }


@dataclass(frozen=True)
class HardCaseRow:
    """One hard case.

    Attributes:
        case: scene name without ``hard/``.
        criterion: the scene's stated criterion (``thresholds.hard_criterion``).
        analytic, mujoco: figures per engine (name -> number or text); ``mujoco`` holds
            ``{"not run": reason}`` where the case does not apply to MuJoCo.
        checks: every judged figure with its bound.
        verdict: ``PASS``, ``FAIL`` (a check failed) or ``ERROR`` (the case raised).
        wall_time_s: wall time of the whole case.
        notes: findings reported but not judged (e.g. crossings, solver costs).
    """

    case: str
    criterion: str
    analytic: dict[str, Any]
    mujoco: dict[str, Any]
    checks: tuple[Check, ...]
    verdict: str
    wall_time_s: float
    notes: tuple[str, ...] = ()

    @property
    def passed(self) -> bool:
        return self.verdict == PASS

    def to_dict(self) -> dict[str, Any]:
        return {
            "case": self.case,
            "criterion": self.criterion,
            "analytic": self.analytic,
            "mujoco": self.mujoco,
            "checks": [c.to_dict() for c in self.checks],
            "verdict": self.verdict,
            "wall_time_s": self.wall_time_s,
            "notes": list(self.notes),
        }


@dataclass(frozen=True)
class HardCaseTable:
    """The table of :func:`run_hard_cases`; ``passed`` when every row passed."""

    rows: tuple[HardCaseRow, ...]
    complete: bool = True
    message: str = ""

    @property
    def passed(self) -> bool:
        return self.complete and all(r.passed for r in self.rows)

    def row(self, case: str) -> HardCaseRow:
        for r in self.rows:
            if r.case == case:
                return r
        raise KeyError(case)

    def to_dict(self) -> dict[str, Any]:
        return {
            "passed": self.passed,
            "complete": self.complete,
            "message": self.message,
            "rows": [r.to_dict() for r in self.rows],
        }

    def to_markdown(self) -> str:
        head = "PASSED" if self.passed else "FAILED"
        lines = [
            f"# Hard cases: {head}",
            "",
            f"{sum(r.passed for r in self.rows)} of {len(self.rows)} cases passed"
            + ("" if self.complete else f"; INCOMPLETE: {self.message}")
            + ".",
            "",
            "| case | criterion | analytic | MuJoCo | verdict | wall s |",
            "|---|---|---|---|---|---|",
        ]
        for r in self.rows:
            lines.append(
                f"| {r.case} | {_md(r.criterion)} | {_figs(r.analytic)} | {_figs(r.mujoco)} "
                f"| **{r.verdict}** | {r.wall_time_s:.1f} |"
            )
        lines += ["", "## Checks", ""]
        for r in self.rows:
            lines.append(f"### {r.case}: {r.verdict}")
            lines.append("")
            for c in r.checks:
                mark = "ok" if c.passed else "FAIL"
                lines.append(f"- {mark}: {c.label} = {c.value:.3e} (bound {c.bound:.1e})")
            for n in r.notes:
                lines.append(f"- note: {_md(n)}")
            lines.append("")
        return "\n".join(lines)


def _md(s: str) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def _figs(d: dict[str, Any]) -> str:
    return "<br>".join(f"{_md(k)} {_md(_fmt(v))}" for k, v in d.items()) or "—"


# ----------------------------------------------------------------------------------------------
# Independent references and figures
# ----------------------------------------------------------------------------------------------


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product, w first."""
    aw, av = a[0], a[1:]
    bw, bv = b[0], b[1:]
    return np.concatenate([[aw * bw - av @ bv], aw * bv + bw * av + np.cross(av, bv)])


def euler_reference(
    J: np.ndarray, omega0: np.ndarray, u0: np.ndarray, t: np.ndarray, rtol: float = 1e-13
) -> tuple[np.ndarray, np.ndarray]:
    """Torque-free rigid body, integrated independently of the model: Euler's equations
    ``J ω̇ = (J ω) × ω`` and ``u̇ = ½ u ⊗ (0, ω)`` (body-axis ω, body → inertial u), DOP853.

    Returns ``(omega, u)`` at the times ``t``, shapes (N, 3), (N, 4).
    """
    J = np.asarray(J, float)
    Jinv = np.linalg.inv(J)

    def f(_t, y):
        w, u = y[:3], y[3:]
        return np.concatenate([Jinv @ np.cross(J @ w, w), 0.5 * quat_mul(u, np.r_[0.0, w])])

    sol = solve_ivp(
        f,
        (t[0], t[-1]),
        np.concatenate([omega0, u0]),
        method="DOP853",
        t_eval=t,
        rtol=rtol,
        atol=1e-14 * max(1.0, float(np.max(np.abs(omega0)))),
    )
    if not sol.success:
        raise RuntimeError(f"Euler reference failed: {sol.message}")
    return sol.y[:3].T, sol.y[3:].T


def _rel(x: np.ndarray, scale: float) -> float:
    return float(np.max(np.abs(x)) / scale) if scale > 0 else float(np.max(np.abs(x)))


def invariant_drift(tr: Trajectory) -> float:
    """Max of the relative energy, angular- and linear-momentum balance drifts."""
    d = drift_figures(tr)
    return max(
        d["energy_balance_rel"], d["angular_momentum_balance_rel"], d["linear_momentum_balance_rel"]
    )


def agreement(a: Trajectory, b: Trajectory, until: float | None = None) -> dict[str, float]:
    """Position of C, rod positions (m) and attitude angle (rad) differences, max over the common
    samples (up to ``until`` s)."""
    k = min(len(a.t), len(b.t))
    if until is not None:
        k = int(np.searchsorted(a.t[:k], until, side="right"))
    dR = float(np.max(np.linalg.norm(a.R[:k] - b.R[:k], axis=1)))
    dp = float(np.max(np.abs(a.p[:k] - b.p[:k]), initial=0.0))
    dth = float(np.max(attitude_angle(a.u[:k], b.u[:k])))
    return {"dR_m": dR, "dp_m": dp, "dtheta_rad": dth}


def finite(tr: Trajectory) -> bool:
    return bool(
        np.all(np.isfinite(tr.q)) and np.all(np.isfinite(tr.qdot)) and np.all(np.isfinite(tr.qddot))
    )


def tracking_law_error(tr: Trajectory, scene: Scene) -> float:
    """Max deviation of the tracking errors from their closed forms (Eqs. 78, 84, ERRATA 3),
    relative to the largest initial error."""
    t = tr.t
    errs, scales = [], []
    if tr.tracking.e_omega.size:
        e = tr.tracking.e_omega
        ref = omega_error_reference(t, e[0], scene.control.omega.gain)
        errs.append(np.max(np.abs(e - ref)))
        scales.append(np.max(np.abs(e[0])))
    if tr.tracking.e_p.size:
        e = tr.tracking.e_p
        mt = scene.control.masses
        idx = list(tr.tracking.mass_indices)
        lam, l = np.asarray(mt.lam), np.asarray(mt.l)
        pbar_dot0 = -l * lam * np.sin(lam * t[0])
        edot0 = tr.qdot[0, 7 + np.array(idx)] - pbar_dot0
        ref = mass_error_reference(t, e[0], edot0, mt.alpha, mt.beta)
        errs.append(np.max(np.abs(e - ref)))
        scales.append(np.max(np.abs(e[0])))
    if not errs:
        return 0.0
    return float(max(errs) / max(max(scales), 1e-300))


def rotation(u: np.ndarray) -> np.ndarray:
    """Rotation matrix of a quaternion (w first, normalised), body -> inertial, from scipy: a
    reference independent of the paper's S(u) and of MuJoCo's."""
    return Rotation.from_quat(np.asarray(u, float), scalar_first=True).as_matrix()


def system_com(scene: Scene, q: np.ndarray) -> np.ndarray:
    """Centre of mass of the whole system, ``(m_BR R + Σ m_i (R + S(p_i a + d))) / m_T``, (N, 3)."""
    m = np.asarray(scene.masses.mass)
    mT = scene.body.mass + m.sum()
    a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
    out = np.empty((q.shape[0], 3))
    for k in range(q.shape[0]):
        Sm = rotation(q[k, 3:7])
        out[k] = q[k, :3] + Sm @ (float(m @ q[k, 7:]) * a + m.sum() * d) / mT
    return out


def system_com_velocity0(scene: Scene) -> np.ndarray:
    """``ċ(0)`` from the initial state (ω in body axes): ``Ṙ + S(ω × r̄ + Σ m_i ṗ_i a / m_T)``."""
    ini = scene.initial
    m = np.asarray(scene.masses.mass)
    mT = scene.body.mass + m.sum()
    a, d = np.asarray(scene.rod.axis), np.asarray(scene.rod.offset)
    rbar = (float(m @ ini.p) * a + m.sum() * d) / mT
    vbar = float(m @ ini.pdot) * a / mT
    return ini.Rdot + rotation(ini.u) @ (np.cross(ini.omega, rbar) + vbar)


def status_figs(tr: Trajectory) -> dict[str, Any]:
    out: dict[str, Any] = {"status": tr.status.value}
    if tr.status is not RunStatus.OK:
        out["message"] = tr.message
    out["wall s"] = float(tr.info.get("wall_time_s", float("nan")))
    return out


def zero_crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Instants where ``x`` changes sign (linear interpolation between samples)."""
    s = np.sign(x)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


# ----------------------------------------------------------------------------------------------
# The cases. Each takes (scene, th) and returns (analytic figs, mujoco figs, checks, notes).
# ----------------------------------------------------------------------------------------------

CaseResult = tuple[dict[str, Any], dict[str, Any], list[Check], list[str]]


def _ok_checks(tr: Trajectory, who: str) -> list[Check]:
    return [
        Check(f"{who}: non-finite state (1 = yes)", 0.0 if finite(tr) else 1.0, 0.0),
        Check(f"{who}: run failed (1 = yes)", 0.0 if tr.status is RunStatus.OK else 1.0, 0.0),
    ]


def _rigid_reference_case(scene: Scene, th: dict, J: np.ndarray, p_bound: float | None):
    a = simulate(scene)
    m = _mj_simulate(scene)
    w_ref, u_ref = euler_reference(J, scene.initial.omega, scene.initial.u, a.t)
    wscale = float(np.max(np.linalg.norm(w_ref, axis=1)))
    checks = _ok_checks(a, "analytic") + _ok_checks(m, "mujoco")
    figs = {}
    for tr, key, who in (
        (a, "hard_reference_rel", "analytic"),
        (m, "hard_mujoco_reference_rel", "mujoco"),
    ):
        k = len(tr.t)
        dw = float(np.max(np.linalg.norm(tr.omega - w_ref[:k], axis=1))) / wscale
        dth = float(np.max(attitude_angle(tr.u, u_ref[:k])))
        inv = invariant_drift(tr)
        figs[who] = {"|Δω|/|ω| vs Euler": dw, "Δθ vs Euler rad": dth, "invariant drift": inv}
        checks += [
            Check(f"{who}: |ω - ω_Euler| / |ω|", dw, th[key]),
            Check(f"{who}: attitude angle to Euler reference, rad", dth, th[key]),
            Check(f"{who}: invariant balance drift", inv, th["hard_invariant_rel"]),
        ]
        if "hard_position_abs" in th:
            t = tr.t
            R_ref = (
                scene.initial.R
                + np.outer(t, scene.initial.Rdot)
                + 0.5 * np.outer(t**2, scene.gravity)
            )
            dR = float(np.max(np.linalg.norm(tr.R - R_ref, axis=1)))
            figs[who]["|R - parabola| m"] = dR
            checks.append(
                Check(f"{who}: |R - (R0 + Ṙ0 t + g t²/2)|, m", dR, th["hard_position_abs"])
            )
        if p_bound is not None:
            pmax = float(np.max(np.abs(tr.p)))
            figs[who]["max|p| m"] = pmax
            checks.append(Check(f"{who}: max |p_i|, m", pmax, p_bound))
        figs[who].update(status_figs(tr))
    return figs["analytic"], figs["mujoco"], checks, []


def case_rigid_body_alone(scene: Scene, th: dict) -> CaseResult:
    return _rigid_reference_case(scene, th, np.diag(scene.body.inertia), None)


def case_rod_through_C(scene: Scene, th: dict) -> CaseResult:
    J = np.diag(scene.body.inertia) + np.sum(scene.masses.inertia, axis=0)
    return _rigid_reference_case(scene, th, J, th["hard_p_abs"])


def _pair_case(scene: Scene, th: dict, *, tracking: bool = False, **mj_kw) -> tuple:
    a = simulate(scene)
    m = _mj_simulate(scene, **mj_kw)
    checks = _ok_checks(a, "analytic") + _ok_checks(m, "mujoco")
    fa, fm = {}, {}
    for tr, f, who in ((a, fa, "analytic"), (m, fm, "mujoco")):
        inv = invariant_drift(tr)
        f["invariant drift"] = inv
        checks.append(Check(f"{who}: invariant balance drift", inv, th["hard_invariant_rel"]))
        if tracking:
            te = tracking_law_error(tr, scene)
            f["tracking vs closed form"] = te
            checks.append(
                Check(f"{who}: tracking error vs closed form / |e(0)|", te, th["hard_tracking_rel"])
            )
        f.update(status_figs(tr))
    ag = agreement(a, m)
    fm.update({f"vs analytic {k}": v for k, v in ag.items()})
    if "hard_agreement_abs" in th:
        for k, v in ag.items():
            checks.append(Check(f"mujoco vs analytic {k}", v, th["hard_agreement_abs"]))
    return a, m, fa, fm, checks


def case_stiff_springs(scene: Scene, th: dict) -> CaseResult:
    a, m, fa, fm, checks = _pair_case(scene, th)
    fa["DOP853 nfev"] = a.info["nfev"]
    notes = [
        f"DOP853 rtol {a.info['rtol']:g}: {a.status.value}, nfev {a.info['nfev']}, "
        f"wall {a.info['wall_time_s']:.2f} s"
    ]
    for method in ("Radau", "LSODA"):
        tr = simulate(scene, method=method, rtol=1e-8, atol=1e-10)
        checks += _ok_checks(tr, method)
        ag = agreement(a, tr)
        dev = max(ag["dR_m"], ag["dp_m"])
        fa[f"{method} nfev"] = tr.info["nfev"]
        fa[f"{method} wall s"] = tr.info["wall_time_s"]
        fa[f"{method} vs DOP853 m"] = dev
        checks.append(
            Check(f"{method} (rtol 1e-8) vs DOP853, m", dev, th["hard_implicit_agreement_abs"])
        )
        notes.append(
            f"{method} rtol 1e-8: {tr.status.value}, nfev {tr.info['nfev']}, "
            f"wall {tr.info['wall_time_s']:.2f} s, max deviation from DOP853 {dev:.2e} m"
        )
    notes.append(
        f"MuJoCo RK4 dt {m.info['dt']:g}: {m.info['nsteps']} steps, wall {m.info['wall_time_s']:.2f} s"
    )
    return fa, fm, checks, notes


def case_masses_ratio(scene: Scene, th: dict) -> CaseResult:
    _, _, fa, fm, checks = _pair_case(scene, th, tracking=True)
    ratio = (
        float(np.max(scene.masses.mass) / scene.body.mass),
        float(np.min(scene.masses.mass) / scene.body.mass),
    )
    return fa, fm, checks, [f"mass ratios m_i / m_BR from {ratio[1]:.3g} to {ratio[0]:.3g}"]


def case_pair(scene: Scene, th: dict) -> CaseResult:
    _, _, fa, fm, checks = _pair_case(scene, th)
    return fa, fm, checks, []


def case_zero_gravity(scene: Scene, th: dict) -> CaseResult:
    a, m, fa, fm, checks = _pair_case(scene, th)
    for tr, f, who in ((a, fa, "analytic"), (m, fm, "mujoco")):
        c = system_com(scene, tr.q)
        vc0 = system_com_velocity0(scene)
        c_ref = c[0] + np.outer(tr.t - tr.t[0], vc0)
        dc = float(np.max(np.linalg.norm(c - c_ref, axis=1)))
        f["|c - line| m"] = dc
        checks.append(Check(f"{who}: system CoM |c - (c0 + ċ0 t)|, m", dc, th["hard_position_abs"]))
    return fa, fm, checks, []


def case_many_masses(scene: Scene, th: dict) -> CaseResult:
    a, m, fa, fm, checks = _pair_case(scene, th)
    fa["nfev"] = a.info["nfev"]
    notes = [
        f"n = {scene.n}: analytic ({a.info['backend']}) {a.info['wall_time_s']:.2f} s, "
        f"MuJoCo {m.info['wall_time_s']:.2f} s for {scene.output.t_end:g} s simulated"
    ]
    return fa, fm, checks, notes


def case_pass_through(scene: Scene, th: dict) -> CaseResult:
    a, m, fa, fm, checks = _pair_case(scene, th)
    notes = []
    first = {}
    for tr, f, who in ((a, fa, "analytic"), (m, fm, "mujoco")):
        gaps = np.diff(tr.p, axis=1)  # p_{i+1} - p_i; negative once masses have passed through
        crossings = []
        for i in range(gaps.shape[1]):
            for tc in zero_crossings(tr.t, gaps[:, i]):
                crossings.append((float(tc), i))
        crossings.sort()
        f["crossings"] = len(crossings)
        f["first crossing s"] = crossings[0][0] if crossings else float("nan")
        first[who] = crossings[0][0] if crossings else float("nan")
        checks.append(
            Check(f"{who}: no crossing reported (1 = none)", 0.0 if crossings else 1.0, 0.0)
        )
        if crossings:
            t0, i = crossings[0]
            notes.append(
                f"{who}: masses {i + 1} and {i + 2} pass through each other at t = {t0:.6f} s "
                f"(no contact in the model); {len(crossings)} crossings in {tr.t[-1]:g} s"
            )
    dtc = abs(first["analytic"] - first["mujoco"])
    checks.append(
        Check("first crossing instant, mujoco vs analytic, s", dtc, th["hard_crossing_time_abs"])
    )
    return fa, fm, checks, notes


def case_negative_w(scene: Scene, th: dict) -> CaseResult:
    ref_scene = load_scene(SCENES_DIR / "paper_example1.toml")
    if not np.allclose(ref_scene.initial.u, -scene.initial.u, rtol=0, atol=1e-15):
        raise ValueError("initial.attitude.quaternion: must be -u(0) of paper_example1")
    ref = simulate(ref_scene, t_end=scene.output.t_end)
    a = simulate(scene)
    m = _mj_simulate(scene)
    checks = _ok_checks(a, "analytic") + _ok_checks(m, "mujoco") + _ok_checks(ref, "+u reference")
    k = min(len(a.t), len(ref.t))
    sign = float(np.max(np.abs(a.u[:k] + ref.u[:k])))
    pos = max(
        float(np.max(np.abs(a.R[:k] - ref.R[:k]))), float(np.max(np.abs(a.p[:k] - ref.p[:k])))
    )
    fa = {"|u + u_ref|": sign, "|Δpos| vs +u m": pos, "min w": float(np.min(a.u[:, 0]))}
    fa.update(status_figs(a))
    ag = agreement(ref, m)
    fm = {f"vs +u analytic {k}": v for k, v in ag.items()}
    fm["min w"] = float(np.min(m.u[:, 0]))
    fm.update(status_figs(m))
    checks += [
        Check("analytic: |u(-u0) + u(+u0)|", sign, th["hard_sign_abs"]),
        Check("analytic: |R, p (-u0) - R, p (+u0)|, m", pos, th["hard_position_abs"]),
    ]
    checks += [
        Check(f"mujoco(-u0) vs analytic(+u0) {k}", v, th["hard_agreement_abs"])
        for k, v in ag.items()
    ]
    return fa, fm, checks, []


def _norm_closed_form(
    t: np.ndarray, phi0: float, phidot0: float, d1: float, d2: float
) -> np.ndarray:
    """Solution of ``φ̈ + δ1 φ̇ + δ2 φ = 0`` (Eq. 58) from φ(0), φ̇(0)."""
    r = np.roots([1.0, d1, d2]).astype(complex)
    A = np.array([[1, 1], [r[0], r[1]]], dtype=complex)
    c = np.linalg.solve(A, np.array([phi0, phidot0], dtype=complex))
    return np.real(c[0] * np.exp(r[0] * t) + c[1] * np.exp(r[1] * t))


def case_off_manifold(scene: Scene, th: dict) -> CaseResult:
    a = simulate(scene)
    checks = _ok_checks(a, "analytic")
    u0, ud0 = scene.initial.u, scene.initial.udot
    ref = _norm_closed_form(
        a.t,
        float(u0 @ u0) - 1.0,
        2.0 * float(u0 @ ud0),
        scene.stabilization.delta1,
        scene.stabilization.delta2,
    )
    dn = float(np.max(np.abs(a.invariants.quat_norm_error - ref)))
    te = tracking_law_error(a, scene)
    fa = {
        "|u(0)|": float(np.linalg.norm(u0)),
        "|φ - closed form|": dn,
        "|φ(t_end)|": float(abs(a.invariants.quat_norm_error[-1])),
        "tracking vs closed form": te,
    }
    fa.update(status_figs(a))
    checks += [
        Check("analytic: |φ - φ_closed_form| (Eq. 58)", dn, th["hard_norm_abs"]),
        Check("analytic: tracking error vs closed form / |e(0)|", te, th["hard_tracking_rel"]),
    ]
    # the loader must refuse the same start unless it is allowed explicitly
    import tomllib

    from analytic.scene import scene_from_dict

    data = tomllib.loads(Path(scene.source).read_text(encoding="utf-8"))
    del data["initial"]["attitude"]["allow_off_manifold"]
    refused = 0.0
    try:
        scene_from_dict(data)
    except ValueError as exc:
        refused = 1.0 if "initial.attitude.quaternion" in str(exc) else 0.5
    fa["refused unless allowed"] = "yes" if refused == 1.0 else "NO"
    checks.append(
        Check(
            "loader refuses |u| = 1.1 without allow_off_manifold (1 = refused)", 1.0 - refused, 0.0
        )
    )
    fm = {
        "not run": "MuJoCo renormalises quaternions every step: an off-unit start is not representable"
    }
    return fa, fm, checks, []


class DuplicatedRequirements(TumblingModel):
    """The scene's model with control rows appended again (``rows``, 0-based rows of ``A_c``) and
    their right-hand sides shifted by ``shifts``: redundant (shift 0) or conflicting requirements,
    which the scene format cannot state."""

    def __init__(self, scene: Scene, rows: Iterable[int], shifts: Iterable[float]):
        super().__init__(scene)
        self.dup_rows = np.array(list(rows), dtype=int)
        self.dup_shifts = np.array(list(shifts), dtype=float)

    def control_constraints(self, t, q, qdot, k=None):
        A, b = super().control_constraints(t, q, qdot, k)
        return (
            np.vstack([A, A[self.dup_rows]]),
            np.concatenate([b, b[self.dup_rows] + self.dup_shifts]),
        )


def _mujoco_pinv_acc(
    tw: mj_bridge.Twin, t: float, q, qd, A_rows: list, b: np.ndarray
) -> np.ndarray:
    """The Moore-Penrose Gauss law from MuJoCo's own M and forces, rows given in the paper's terms
    (``("omega", axis)`` or ``("mass", i)``); returns the paper ``q̈``."""
    tw.set_state(t, q, qd)
    m, d = tw.m, tw.d
    d.ctrl[:] = 0.0
    d.xfrc_applied[:] = 0.0
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    F = d.qfrc_passive - d.qfrc_bias + d.qfrc_actuator
    A = np.zeros((len(A_rows), m.nv))
    for j, (kind, i) in enumerate(A_rows):
        if kind == "omega":
            A[j, 3:6] = tw.R_I.T[i]
        else:
            A[j, 6 + i] = 1.0
    a0 = np.linalg.solve(M, F)
    MinvAt = np.linalg.solve(M, A.T)
    G = A @ MinvAt
    qacc = a0 + MinvAt @ (np.linalg.pinv(G, rcond=1e-10, hermitian=True) @ (b - A @ a0))
    return mujoco_to_paper_acc(d.qpos, d.qvel, qacc, tw.ipos, tw.iquat)


def case_conflicting(scene: Scene, th: dict) -> CaseResult:
    delta = float(th["hard_conflict"])
    base = TumblingModel(scene)
    k_w = len(scene.control.omega.components)
    z_row = list(scene.control.omega.components).index(2)
    m1_row = k_w + list(scene.control.masses.indices).index(0)
    red = DuplicatedRequirements(scene, [m1_row], [0.0])
    con = DuplicatedRequirements(scene, [z_row], [delta])
    # a short run of the plain scene gives realistic states
    run = simulate(scene, t_end=min(scene.output.t_end, 1.0))
    idx = np.linspace(0, len(run.t) - 1, 6).astype(int)
    tw = mj_bridge.Twin(scene)
    rows = [("omega", c) for c in scene.control.omega.components] + [
        ("mass", i) for i in scene.control.masses.indices
    ]
    red_err = res_red = con_res_err = other_err = mj_err = 0.0
    res_norm = 0.0
    for i in idx:
        t, q, qd = float(run.t[i]), run.q[i], run.qdot[i]
        qdd0, _ = base.acceleration(t, q, qd)
        qdd_r, c_r = red.acceleration(t, q, qd)
        qdd_c, c_c = con.acceleration(t, q, qd)
        red_err = max(red_err, float(np.linalg.norm(qdd_r - qdd0) / np.linalg.norm(qdd0)))
        res_red = max(res_red, float(np.max(np.abs(c_r.residual)) / max(1.0, np.max(np.abs(qdd0)))))
        expected = np.zeros(base.k + 1)
        expected[z_row], expected[-1] = delta / 2, -delta / 2
        con_res_err = max(con_res_err, float(np.max(np.abs(c_c.residual - expected)) / delta))
        res_norm = float(np.linalg.norm(c_c.residual))
        # the MuJoCo-side law on the same duplicated rows
        _, b = con.control_constraints(t, q, qd)
        qdd_mj = _mujoco_pinv_acc(tw, t, q, qd, [*rows, rows[z_row]], b)
        mj_err = max(mj_err, float(np.linalg.norm(qdd_mj - qdd_c) / np.linalg.norm(qdd_c)))
        other = [j for j in range(base.k) if j != z_row]
        other_err = max(other_err, float(np.max(np.abs(c_c.residual[other]))) / delta)
    # integrate the conflicting model: e_wz follows e0 e^{-γt} + δ/(2γ)(1 - e^{-γt})
    nq = con.nq
    t_eval = scene.output.times()

    def f(t, y):
        qdd, _ = con.acceleration(t, y[:nq], y[nq:])
        return np.concatenate([y[nq:], qdd])

    wall0 = time.perf_counter()
    sol = solve_ivp(
        f,
        (0.0, t_eval[-1]),
        np.concatenate([scene.initial.q0(), scene.initial.qdot0()]),
        method="DOP853",
        t_eval=t_eval,
        rtol=1e-11,
        atol=1e-12,
    )
    wall = time.perf_counter() - wall0
    q, qd = sol.y[:nq].T, sol.y[nq:].T
    w = omega_of(q[:, 3:7], qd[:, 3:7])
    gamma = float(scene.control.omega.gain[z_row, z_row])
    wbar = scene.control.omega.b[2] * np.cos(scene.control.omega.sigma[2] * sol.t)
    e = w[:, 2] - wbar
    ref = e[0] * np.exp(-gamma * sol.t) + delta / (2 * gamma) * (1 - np.exp(-gamma * sol.t))
    traj_err = float(np.max(np.abs(e - ref)) / max(np.max(np.abs(e)), 1e-300))
    fa = {
        "redundant: |Δq̈|/|q̈|": red_err,
        "conflicting: residual norm": res_norm,
        "residual vs ±δ/2": con_res_err,
        "e_ωz vs closed form": traj_err,
        "run": "ok" if sol.success else sol.message,
        "wall s": wall,
    }
    fm = {"pinv law from MuJoCo M: |Δq̈|/|q̈|": mj_err}
    checks = [
        Check(
            "analytic: run with conflicting rows completed (1 = failed)",
            0.0 if sol.success else 1.0,
            0.0,
        ),
        Check("redundant: |q̈ - q̈ without duplicate| / |q̈|", red_err, th["hard_redundant_rel"]),
        Check("redundant: residual / max|q̈|", res_red, th["hard_redundant_rel"]),
        Check("conflicting: |residual - (±δ/2)| / δ", con_res_err, th["hard_residual_rel"]),
        Check("conflicting: other requirements' residual / δ", other_err, th["hard_residual_rel"]),
        Check("conflicting: e_ωz(t) vs closed form / max|e|", traj_err, th["hard_tracking_rel"]),
        Check("mujoco: pinv law from MuJoCo's M vs analytic q̈", mj_err, th["hard_mujoco_rel"]),
    ]
    notes = [
        f"unattainable part of the conflicting pair: residual (+{delta / 2:g}, -{delta / 2:g}) rad/s², "
        f"norm {res_norm:.6g} (δ/√2 = {delta / math.sqrt(2):.6g}); the controller meets the mean "
        f"of the two demands"
    ]
    return fa, fm, checks, notes


def case_fast_spin_intermediate(scene: Scene, th: dict) -> CaseResult:
    a = simulate(scene)
    m = _mj_simulate(scene)
    checks = _ok_checks(a, "analytic") + _ok_checks(m, "mujoco")
    w_ref, _ = euler_reference(
        np.diag(scene.body.inertia), scene.initial.omega, scene.initial.u, a.t
    )
    flips = {
        "reference": zero_crossings(a.t, w_ref[:, 1]),
        "analytic": zero_crossings(a.t, a.omega[:, 1]),
        "mujoco": zero_crossings(m.t, m.omega[:, 1]),
    }
    fa, fm = {}, {}
    for tr, f, who in ((a, fa, "analytic"), (m, fm, "mujoco")):
        fl = flips[who]
        f["flips"] = len(fl)
        f["first flip s"] = float(fl[0]) if len(fl) else float("nan")
        inv = invariant_drift(tr)
        f["invariant drift"] = inv
        checks.append(Check(f"{who}: invariant balance drift", inv, th["hard_invariant_rel"]))
        checks.append(Check(f"{who}: no flip (1 = none)", 0.0 if len(fl) else 1.0, 0.0))
        f.update(status_figs(tr))
    nref = len(flips["reference"])

    def dt_flips(x, y):
        if len(x) != len(y) or not len(x):
            return float("inf")
        return float(np.max(np.abs(x - y)))

    da = dt_flips(flips["analytic"], flips["reference"])
    dm = dt_flips(flips["mujoco"], flips["analytic"])
    fa["flip Δt vs Euler s"] = da
    fm["flip Δt vs analytic s"] = dm
    checks += [
        Check("analytic flip instants vs Euler reference, s", da, th["hard_flip_time_abs"]),
        Check("mujoco flip instants vs analytic, s", dm, th["hard_flip_time_abs"]),
    ]
    notes = [
        f"{nref} sign changes of ω_y in {scene.output.t_end:g} s (reference), first at {flips['reference'][0]:.6f} s"
        if nref
        else "reference shows no flip"
    ]
    return fa, fm, checks, notes


def split_energy(scene: Scene, tr: Trajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Energy in the frame of the system's centre of mass, and the centre of mass itself.

    Under uniform gravity the centre of mass c moves on the parabola ``c0 + ċ0 t + g t²/2`` and
    ``E = E_int + (½ m_T |ċ|² - m_T g·c)``, each part conserved on its own. Over a long fall the
    second part's two terms grow huge and cancel (1000 s: 6.5e13 J each, against E = 3.9e8 J), so
    the total energy's relative drift measures the round-off of a 9.8 km/s velocity rather than the
    dynamics. ``E_int`` is computed directly from velocities relative to ċ (gravity does no work
    in that frame), so it carries none of that cancellation:
    ``E_int = ½ ωᵀJω + ½ m_BR |Ṙ - ċ|² + Σ ½ m_i |ṙ_i - ċ|² + U_s``.

    Returns:
        ``E_int`` (N,), J; ``c`` (N, 3) and ``ċ`` (N, 3), inertial, m and m/s.
    """
    model = TumblingModel(scene)
    r, rd, _ = mass_kinematics(model, tr.q, tr.qdot)
    m_T = model.m_T
    c = (model.m_BR * tr.q[:, :3] + np.einsum("i,nij->nj", model.m, r)) / m_T
    cd = (model.m_BR * tr.qdot[:, :3] + np.einsum("i,nij->nj", model.m, rd)) / m_T
    w = omega_of(tr.u, tr.qdot[:, 3:7])
    vR = tr.qdot[:, :3] - cd
    vi = rd - cd[:, None, :]
    E_int = (
        0.5 * np.einsum("ni,ij,nj->n", w, model.J, w)
        + 0.5 * model.m_BR * np.sum(vR * vR, axis=1)
        + 0.5 * np.einsum("i,nij,nij->n", model.m, vi, vi)
        + spring_energy(model, tr.p)
    )
    return E_int, c, cd


def case_long_horizon(scene: Scene, th: dict) -> CaseResult:
    a = simulate(scene)
    m = _mj_simulate(scene)
    checks = _ok_checks(a, "analytic") + _ok_checks(m, "mujoco")
    fa, fm = {}, {}
    g = np.array(scene.gravity)
    for tr, f, who in ((a, fa, "analytic"), (m, fm, "mujoco")):
        d = drift_figures(tr)
        E_int, c, cd = split_energy(scene, tr)
        int_drift = float(np.max(np.abs(E_int - E_int[0])) / np.max(np.abs(E_int)))
        parabola = c[0] + np.outer(tr.t, cd[0]) + 0.5 * np.outer(tr.t**2, g)
        com_dev = float(np.max(np.abs(c - parabola)) / np.max(np.abs(c)))
        f["energy drift (total, not judged)"] = d["energy_balance_rel"]
        f["internal energy drift"] = int_drift
        f["CoM off its parabola (rel.)"] = com_dev
        f["ang. mom. drift"] = d["angular_momentum_balance_rel"]
        f["lin. mom. drift"] = d["linear_momentum_balance_rel"]
        f["|u|²-1 max"] = d["quat_norm_error_max"]
        T = scene.output.t_end
        checks.append(
            Check(f"{who}: internal energy drift over {T:g} s", int_drift, th["hard_invariant_rel"])
        )
        checks.append(
            Check(
                f"{who}: centre of mass off its parabola (relative)",
                com_dev,
                th["hard_com_parabola_rel"],
            )
        )
        for k in ("angular_momentum_balance_rel", "linear_momentum_balance_rel"):
            checks.append(Check(f"{who}: {k} over {T:g} s", d[k], th["hard_invariant_rel"]))
        checks.append(
            Check(f"{who}: max |u|² - 1", d["quat_norm_error_max"], th["hard_quat_norm_abs"])
        )
        f.update(status_figs(tr))
    horizon = float(th["hard_agreement_horizon"])
    ag = agreement(a, m, until=horizon)
    for k, v in ag.items():
        fm[f"vs analytic {k} (t ≤ {horizon:g} s)"] = v
        checks.append(
            Check(f"mujoco vs analytic {k}, t ≤ {horizon:g} s", v, th["hard_agreement_abs"])
        )
    ag_all = agreement(a, m)
    fm[f"vs analytic dR_m (t ≤ {scene.output.t_end:g} s)"] = ag_all["dR_m"]
    notes = [
        f"divergence over the whole run (reported, not judged): dR {ag_all['dR_m']:.3e} m, "
        f"dp {ag_all['dp_m']:.3e} m, dθ {ag_all['dtheta_rad']:.3e} rad"
    ]
    return fa, fm, checks, notes


# name -> (function, in the fast subset)
CASES: dict[str, tuple[Callable[[Scene, dict], CaseResult], bool]] = {
    "rigid_body_alone": (case_rigid_body_alone, True),
    "rod_through_C": (case_rod_through_C, True),
    "stiff_springs": (case_stiff_springs, False),
    "heavy_masses": (case_masses_ratio, True),
    "light_masses": (case_masses_ratio, True),
    "fast_spin_intermediate": (case_fast_spin_intermediate, False),
    "fast_spin_axial": (case_pair, False),
    "long_horizon": (case_long_horizon, False),
    "many_masses": (case_many_masses, False),
    "off_manifold": (case_off_manifold, True),
    "conflicting_requirements": (case_conflicting, True),
    "negative_w": (case_negative_w, True),
    "zero_gravity": (case_zero_gravity, True),
    "pass_through": (case_pass_through, True),
}
FAST_CASES = tuple(k for k, (_, fast) in CASES.items() if fast)


def run_case(name: str) -> HardCaseRow:
    """Run one hard case; an exception becomes an ``ERROR`` row carrying its message."""
    if name not in CASES:
        raise ValueError(f"names: unknown hard case {name!r} (known: {', '.join(CASES)})")
    func, _ = CASES[name]
    wall0 = time.perf_counter()
    criterion = ""
    try:
        scene = load_scene(HARD_DIR / f"{name}.toml")
        th = dict(scene.extra.get("thresholds", {}))
        criterion = str(th.get("hard_criterion", ""))
        fa, fm, checks, notes = func(scene, th)
        verdict = PASS if all(c.passed for c in checks) else FAIL
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # a crash of a case is a finding: reported, the suite goes on
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        fa, fm, checks = {"error": f"{type(exc).__name__}: {exc}"}, {}, []
        notes = [f"raised at {Path(tb.filename).name}:{tb.lineno}"]
        verdict = ERROR
    return HardCaseRow(
        case=name,
        criterion=criterion,
        analytic=fa,
        mujoco=fm,
        checks=tuple(checks),
        verdict=verdict,
        wall_time_s=time.perf_counter() - wall0,
        notes=tuple(notes),
    )


def write_table(table: HardCaseTable, out_dir: str | Path) -> None:
    """``hard_cases.md`` and ``hard_cases.json`` in ``out_dir``, each written atomically."""
    out = Path(out_dir)
    write_text(
        out / "hard_cases.json", json.dumps(table.to_dict(), indent=2, default=_json_default)
    )
    write_text(out / "hard_cases.md", table.to_markdown() + "\n")


def _json_default(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    return str(o)


def _run_into(
    out: Path, selected: list[str], progress: Callable[[str, int, int], None] | None
) -> HardCaseTable:
    """Run the ``selected`` cases, rewriting the table in ``out`` after each one."""
    rows: list[HardCaseRow] = []
    table = HardCaseTable((), complete=True, message="no case selected")
    for i, name in enumerate(selected):
        if progress is not None:
            progress(name, i, len(selected))
        try:
            rows.append(run_case(name))
        except KeyboardInterrupt:
            table = HardCaseTable(tuple(rows), complete=False, message=f"interrupted during {name}")
            write_table(table, out)
            raise
        done = i + 1 == len(selected)
        table = HardCaseTable(
            tuple(rows),
            complete=done,
            message="" if done else f"{len(selected) - i - 1} cases still to run",
        )
        write_table(table, out)
    if not selected:
        write_table(table, out)
    return table


def run_hard_cases(
    out_dir: str | Path,
    names: Iterable[str] | None = None,
    fast_only: bool = False,
    progress: Callable[[str, int, int], None] | None = None,
) -> HardCaseTable:
    """Run the hard cases and write ``hard_cases.md`` / ``hard_cases.json`` to ``out_dir``.

    Args:
        out_dir: output directory (created).
        names: cases to run (default all, in table order); unknown names raise ValueError.
        fast_only: only the fast subset (those whose horizons are short on both engines).
        progress: called as ``progress(case, index, total)`` before each case.

    Returns:
        the :class:`HardCaseTable`; the files are rewritten after every case, so an interrupted
        suite (KeyboardInterrupt) leaves the rows it finished, marked incomplete, and re-raises.
    """
    selected = list(CASES) if names is None else list(names)
    for n in selected:
        if n not in CASES:
            raise ValueError(f"names: unknown hard case {n!r} (known: {', '.join(CASES)})")
    if fast_only:
        selected = [n for n in selected if CASES[n][1]]
    with output_run(out_dir, "hard-cases") as run:
        table = _run_into(run.path, selected, progress)
    return table


__all__ = [
    "CASES",
    "FAST_CASES",
    "Check",
    "DuplicatedRequirements",
    "HardCaseRow",
    "HardCaseTable",
    "euler_reference",
    "run_case",
    "run_hard_cases",
]
