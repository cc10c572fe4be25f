"""What a figure's caption says: the run it comes from (:class:`FigureContext`), and the sentences
every figure shares (what was left out as identically zero, why there is no control)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from validation.compare.checks import Subject
from validation.report.figures.style import PANEL_TITLES


@dataclass(frozen=True)
class FigureContext:
    """What every caption states about the run.

    Attributes:
        scene: scene name.
        horizon_s: the horizon asked for, s (None when unknown).
        rate_hz: output samples per second (None when unknown).
        settings: one sentence per plant naming its solver settings.
        controlled: whether the scene has a control requirement (None when unknown).
    """

    scene: str
    horizon_s: float | None = None
    rate_hz: float | None = None
    settings: tuple[str, ...] = ()
    controlled: bool | None = None

    @classmethod
    def from_meta(cls, meta: Mapping[str, Any], scene: str = "") -> FigureContext:
        """The context from a run's metadata (``validation.validate``'s ``meta``)."""
        sc = meta.get("scene", {}) or {}
        effects = sc.get("effects")
        return cls(
            scene=str(sc.get("name") or scene or "?"),
            horizon_s=_float_or_none(meta.get("horizon_s")),
            rate_hz=_float_or_none(meta.get("output_rate_hz")),
            settings=tuple(str(p["settings"]) for p in meta.get("plants", ()) if "settings" in p),
            controlled=(
                None if effects is None else any(str(e).startswith("control.") for e in effects)
            ),
        )

    def run_sentence(self) -> str:
        """``Plants: analytic DOP853 rtol 1e-12; MuJoCo RK4 dt 0.00025 s. Horizon 20 s, 100
        samples/s.`` (what is known)."""
        parts = []
        if self.settings:
            parts.append("Plants: " + "; ".join(self.settings) + ".")
        when = []
        if self.horizon_s is not None:
            when.append(f"Horizon {self.horizon_s:g} s")
        if self.rate_hz is not None:
            when.append(f"{self.rate_hz:g} samples/s")
        if when:
            parts.append(", ".join(when) + ".")
        return " ".join(parts)


def _float_or_none(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def subject_names(subjects: Sequence[Subject]) -> str:
    vals = [s.value for s in subjects]
    return vals[0] if len(vals) == 1 else ", ".join(vals[:-1]) + " and " + vals[-1]


def join_sentences(*sentences: str) -> str:
    return " ".join(s.strip() for s in sentences if s and s.strip())


def zero_sentence(zeros: Sequence[tuple[str, Sequence[Subject]]]) -> str:
    """``Not drawn, identically zero: attitude of analytic vs mujoco; ...`` (empty if none)."""
    if not zeros:
        return ""
    items = "; ".join(
        f"{PANEL_TITLES.get(n, n).split(':')[0]} of {subject_names(ss)}" for n, ss in zeros
    )
    return f"Not drawn, identically zero (a log axis has no place for zero): {items}."


def no_control_reason(ctx: FigureContext) -> str:
    if ctx.controlled is False:
        return "the scene has no control requirement, so every plant's control torque and rod forces are identically zero"
    return "every plant's control torque and rod forces are identically zero"


__all__ = ["FigureContext", "join_sentences", "no_control_reason", "subject_names", "zero_sentence"]
