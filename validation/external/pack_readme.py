"""The ``README.md`` of a reference pack (:mod:`validation.external.reference_pack`): the problem, the
controller's equations for a controlled scene (the paper's equation numbers, Koganti & Udwadia,
JGCD 40(3), 2017, with ``docs/errata.md``), the error definitions and the acceptance thresholds,
and the reference's own accuracy. Text only: every number comes from the scene, the thresholds in
force and the pack's record."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from analytic.scene import Scene
from analytic.threshold import Threshold

_ERRORS = {
    "position_C": "max over samples of |R − R_ref| (position of C, inertial)",
    "attitude": "max over samples of 2·atan2(|vec|, |w|) of conj(u_ref) ⊗ u (u and −u agree)",
    "rod_positions": "max over samples and masses of |p_i − p_ref,i|",
    "velocity_C": "max over samples of |v − v_ref|",
    "rod_velocities": "max over samples and masses of |ṗ_i − ṗ_ref,i|",
    "angular_velocity": "max over samples of |ω − ω_ref| (body axes)",
    "control_torque": "max |τ − τ_ref| / max(max |τ_ref|, 1 N·m)",
    "rod_forces": "max over masses |F_i − F_ref,i| / max(max |F_ref|, 1 N)",
    "tracking_omega": "max |e_ω(t) − exp(−P t) e_ω(0)|, e_ω = ω − ω̄ on the controlled axes "
    "(Eq. 84, errata 3)",
    "tracking_p": "max over controlled masses |e_p(t) − e_ref(t)|, e_ref solving ë + α ė + β e = 0 "
    "(Eq. 78) from e_p(0), ė_p(0)",
    "quat_norm": "max |uᵀu − 1| (your own quaternion, unnormalised as your integrator carries it)",
    "linear_momentum": "max |P − P(0) − m_T g t − I_P| / max(max |P|, 1 kg·m/s)",
    "angular_momentum": "max |L − L(0) − I_L| / max(max |L|, max |I_L|, 1 kg·m²/s), about the "
    "system centre of mass, inertial",
    "energy": "max |E − E(0) + D − W| / max(max |E|, max |W|, max |D|, 1 J)",
}
"""How each check's value is computed from a trajectory file (``validation/compare/checks.py``)."""


def _vec(x: Any) -> str:
    return "[" + ", ".join(f"{float(v):.17g}" for v in x) + "]"


def _controller(scene: Scene) -> list[str]:
    """The controller an engine must implement for ``scene`` (empty when uncontrolled)."""
    if not scene.controlled:
        return [
            "## Controller",
            "",
            "None: the scene is uncontrolled. Your engine integrates the free motion "
            "(`tau = 0`, `F = 0`), with the scene's springs, gravity and given torque if any.",
            "",
        ]
    c = scene.control
    lines = [
        "## Controller (implement this)",
        "",
        "The paper's closed-form controller (Koganti & Udwadia, J. Guidance, Control, and "
        "Dynamics 40(3), 2017). Coordinates `q = [R, u, p]` (Eq. 44), `ω = H(u) u̇` in body axes "
        "(Eq. 12). The requirements become constraints on the accelerations, `A_c q̈ = b_c`, "
        "and the control is the Udwadia–Kalaba force that enforces them at least cost:",
        "",
        "    q̈ = a + M^(-1/2) (A M^(-1/2))⁺ (b − A a),  a = M⁻¹ Q,  Q^C = M q̈ − Q      (Eq. 89)",
        "",
        "with `A`, `b` the quaternion-norm row (Eqs. 56–59: `uᵀü = −δ1 uᵀu̇ − ½ δ2 (uᵀu − 1) − "
        f"u̇ᵀu̇`, δ1 = {scene.stabilization.delta1:g} 1/s, δ2 = {scene.stabilization.delta2:g} 1/s²) "
        "stacked over the control rows below, and the cost weighting "
        f"`N = {c.weighting.value}` (Appendix B, Eq. B10; `M^-1` is Gauss's principle, Eq. 74). "
        "The outputs are the body-axis torque `τ = ¼ H(u) Q^C_u` and the rod forces "
        "`F_i = Q^C_p,i` (the `tau_*` and `F_*` columns of reference.csv: the controller's outputs "
        "along the reference); the force at C, `Q^C_R`, is zero.",
        "",
    ]
    if c.omega is not None and len(c.omega.components):
        axes = ", ".join("xyz"[k] for k in c.omega.components)
        lines += [
            f"**Angular velocity (Eqs. 76, 83–86), axes {axes}.** Requirement "
            "`ω̄_k(t) = b_k cos(σ_k t)` (Eq. 76) with "
            f"b = {_vec(c.omega.b)} rad/s, σ = {_vec(c.omega.sigma)} rad/s; control rows "
            "`H_k(u) ü = ω̄̇_k − [P (ω − ω̄)]_k` (rows k of `[0, H, 0] q̈`, Eqs. 84–86; first order, "
            "errata 3), with the gain P (Eq. B6; γI in the paper) on the controlled axes = "
            f"{[list(map(float, r)) for r in c.omega.gain]} 1/s. Then "
            "`e_ω(t) = exp(−P t) e_ω(0)` exactly.",
            "",
        ]
    if c.masses is not None and len(c.masses.indices):
        idx = ", ".join(str(i + 1) for i in c.masses.indices)
        lines += [
            f"**Mass positions (Eqs. 75, 77–81), masses {idx}.** Requirement "
            "`p̄_i(t) = p_e,i + l_i cos(λ_i t)` (Eq. 75; `p_e` the scene's equilibrium positions) "
            f"with l = {_vec(c.masses.l)} m, λ = {_vec(c.masses.lam)} rad/s; control rows "
            "`p̈_i = p̄̈_i − α_i (ṗ_i − p̄̇_i) − β_i (p_i − p̄_i)` (Eq. 81, rows `[0, 0, e_i] q̈` of "
            f"Eq. 80), α = {_vec(c.masses.alpha)} 1/s, β = {_vec(c.masses.beta)} 1/s². Then "
            "`ë + α ė + β e = 0` (Eq. 78).",
            "",
        ]
    return lines


def _fmt(x: float | None) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2e}"


def render_readme(
    scene: Scene,
    thresholds: Mapping[str, Threshold],
    accuracy: Sequence[Any],
    record: Mapping[str, Any],
) -> str:
    """The pack's README (module docstring)."""
    ref = record["reference_settings"]
    chk = record["check_settings"]
    lines = [
        f"# Reference pack: {scene.name}",
        "",
        scene.description or "",
        "",
        "## The problem",
        "",
        f"Integrate the scene in `scene.toml` (n = {scene.n} sliding masses; effects: "
        f"{', '.join(sorted(e.value for e in scene.effects))}) from its initial state to "
        f"t_end = {record['t_end']:g} s and write your run as a trajectory file "
        f"(`docs/trajectory-format.md` of tumbling-testbed): one row per sample of the output grid "
        f"t = 0, 1/{scene.output.rate:g} s, …, {record['t_end']:g} s ({record['samples']} rows), "
        "coordinates `q = [R, u (w first), p]` (Eq. 44), ω in body axes. The scene format is "
        "`docs/scene-format.md`; the conventions (frames, principal axes, what Q^C is) are "
        "`docs/errata.md`.",
        "",
        "Judge your file with `tumble judge scene.toml --trajectory YOURS.csv --reference .` "
        "(no plant runs; the pack's trajectory is the plant `reference`), or beside the built-in "
        "plants with `tumble judge scene.toml --trajectory YOURS.csv`.",
        "",
        "## Files",
        "",
        "- `scene.toml`: the scene.",
        "- `reference.csv`: the reference run, every column (motion, velocities, the controller's "
        "outputs `tau`, `F`, and the work and impulse integrals `W`, `I_L`, `I_P`).",
        "- `reference.json`: settings, SHA-256 of the files, the reference's estimated error.",
        "",
    ]
    lines += _controller(scene)
    lines += [
        "## Error definitions and acceptance thresholds",
        "",
        "Your run passes when every check's value is at most its threshold. Checks marked "
        "relative divide by the scale shown. A check needing columns your file lacks is "
        "reported `not judged: no ... columns`, never passed.",
        "",
        "| check | definition | threshold | unit |",
        "|---|---|---|---|",
    ]
    for name, th in thresholds.items():
        if name in _ERRORS:
            kind = " (relative)" if th.relative else ""
            lines.append(f"| {name} | {_ERRORS[name]} | {th.value:g}{kind} | {th.unit} |")
    lines += [
        "",
        "The first eight compare your run with the reference; the others judge your run alone "
        "(tracking laws for the controlled components, the quaternion norm, the balances of "
        "linear and angular momentum and energy; the balances need your `v`, `omega`, `pdot` "
        "columns, and the `work` columns when something does work on the system).",
        "",
        "## The reference's own accuracy",
        "",
        f"reference.csv is the paper's analytic model integrated by {ref['method']} at rtol "
        f"{ref['rtol']:g}, atol {ref['atol']:g}. Its error is estimated by self-convergence: the "
        f"same run at rtol {chk['rtol']:g}, atol {chk['atol']:g}, compared as an engine would be. "
        f"Each estimate must be at most {record['accuracy_margin']:g} × its threshold, so a "
        "difference from the reference is your engine's own to within 1 %.",
        "",
        "| quantity | estimated error | threshold | ratio | unit |",
        "|---|---|---|---|---|",
    ]
    for a in accuracy:
        d = a.to_dict()
        lines.append(
            f"| {a.quantity} | {_fmt(d['estimate'])} | {a.threshold:g} | {_fmt(d['ratio'])} | "
            f"{a.unit} |"
        )
    lines.append("")
    bad = [a.quantity for a in accuracy if not a.ok]
    if bad:
        lines += [
            f"**Not accurate enough** for {', '.join(bad)}: the estimate exceeds "
            f"{record['accuracy_margin']:g} × the threshold; judge those quantities with care.",
            "",
        ]
    else:
        lines += ["Every estimate is within that margin.", ""]
    return "\n".join(lines)


__all__ = ["render_readme"]
