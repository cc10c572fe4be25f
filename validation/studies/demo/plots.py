"""The demo's plots and colours: which plots a tab can show (:class:`Plot`, their names, which are
control plots and which log10 of a magnitude), and the demo's own colours (:class:`Hue`), in one
place for the recording and the figures alike."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


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
DEMO_PLOTS = frozenset({Plot.OMEGA, Plot.MASS_POSITIONS, Plot.INVARIANTS})
"""The plots the demo logs itself; the others are :func:`validation.recording.recording.log_run`'s, drawn
in the figures with the same names and colours."""


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


__all__ = [
    "CONTROL_PLOTS",
    "DEMO_PLOTS",
    "DRIFT_KEY",
    "DRIFT_QUANTITIES",
    "LOG_PLOTS",
    "OTHER_PLANT_LIGHTEN",
    "PLOT_NAMES",
    "REQUIREMENT_HUE",
    "SERIES_HUES",
    "WITHOUT_HUE",
    "WITH_HUE",
    "Hue",
    "Plot",
]
