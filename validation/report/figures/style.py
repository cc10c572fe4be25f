"""How the figures draw each plant and pair (colour, line style, marker: :func:`plant_style`), a
threshold, and what each panel is titled (:data:`PANEL_TITLES`: the quantity as it is checked)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from validation.compare.checks import Subject

PLANT_STYLE: Mapping[Subject, Mapping[str, Any]] = {
    Subject.ANALYTIC: {"color": "tab:blue", "linestyle": "-", "marker": "o"},
    Subject.MUJOCO: {"color": "tab:orange", "linestyle": "--", "marker": "s"},
    Subject.PINOCCHIO: {"color": "tab:green", "linestyle": ":", "marker": "^"},
    Subject.BOTH: {"color": "tab:red", "linestyle": "-", "marker": "o"},
    Subject.ANALYTIC_PINOCCHIO: {"color": "tab:purple", "linestyle": "--", "marker": "s"},
    Subject.MUJOCO_PINOCCHIO: {"color": "tab:cyan", "linestyle": "-.", "marker": "^"},
}
"""Colour, line style and marker of the built-in plants and their pairs (:func:`plant_style`
for any other)."""

LINESTYLES = ("-", "--", ":", "-.")
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def plant_style(subject: str) -> dict[str, Any]:
    """Colour, line style and marker of plant or pair ``subject``: :data:`PLANT_STYLE` for the
    built-ins and their pairs; for any other, the recording's colour
    (:func:`validation.recording.style.plant_color`: one palette for both) and, by the report rank
    of its (last) plant (:func:`mj_bridge.registry.rank`), the line style and marker of
    :data:`LINESTYLES` and :data:`MARKERS` in turn."""
    from mj_bridge.registry import rank
    from validation.recording.style import plant_color

    subject = Subject(subject)
    if subject in PLANT_STYLE:
        return dict(PLANT_STYLE[subject])
    r = rank(subject.plants[-1]) + (len(subject.plants) - 1)
    rgba = plant_color(subject)
    return {
        "color": tuple(c / 255 for c in rgba),
        "linestyle": LINESTYLES[r % len(LINESTYLES)],
        "marker": MARKERS[r % len(MARKERS)],
    }


THRESHOLD_STYLE = {"color": "k", "linestyle": ":", "linewidth": 1.2}
SUBSCRIPT = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")

RELATIVE_TO: Mapping[str, str] = {
    "control_torque": "max‖τ_ref‖₂",
    "rod_forces": "max_i |F_ref,i|",
    "linear_momentum": "max‖P‖₂",
    "angular_momentum": "max(‖L‖₂, ‖∫Sτ dt‖₂)",
    "energy": "max(|E|, |W|)",
}
"""What each relative check divides by (the scales of :func:`validation.compare.checks.compare`)."""

PANEL_TITLES: Mapping[str, str] = {
    "position_C": "position of C: ‖R_a − R_b‖₂",
    "attitude": "attitude: angle of conj(u_a) ⊗ u_b",
    "rod_positions": "rod positions: max_i |p_a,i − p_b,i|",
    "velocity_C": "velocity of C: ‖Ṙ_a − Ṙ_b‖₂",
    "rod_velocities": "rod velocities: max_i |ṗ_a,i − ṗ_b,i|",
    "angular_velocity": "body angular velocity: ‖ω_a − ω_b‖₂",
    "control_torque": "control torque: ‖τ_a − τ_b‖₂ / max‖τ_a‖₂",
    "rod_forces": "rod forces: max_i |F_a,i − F_b,i| / max_i |F_a,i|",
    "e_omega": "tracking error ‖ω − ω̄‖₂",
    "e_omega_law": "deviation from Eq. 84: ‖e_ω − exp(−γt) e_ω(0)‖₂",
    "e_p": "tracking error max_i |p_i − p̄_i| (controlled masses)",
    "e_p_law": "deviation from Eq. 78: max_i |e_p,i − e_ref,i|, ë + αė + βe = 0",
    "quat_norm": "quaternion norm error |uᵀu − 1|",
    "linear_momentum": "linear momentum balance ‖P − P_expected‖₂ / max‖P‖₂",
    "angular_momentum": "angular momentum balance ‖L − L(0) − ∫Sτ dt‖₂ / max(‖L‖₂, ‖∫Sτ dt‖₂)",
    "energy": "energy balance |E − E(0) + D − W| / max(|E|, |W|, |D|)",
}
"""Panel titles: the quantity drawn, as it is checked (``a`` the pair's reference plant)."""


__all__ = [
    "LINESTYLES",
    "MARKERS",
    "PANEL_TITLES",
    "PLANT_STYLE",
    "RELATIVE_TO",
    "SUBSCRIPT",
    "THRESHOLD_STYLE",
    "plant_style",
]
