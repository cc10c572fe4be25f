"""Known findings: disagreements already understood, listed apart from new ones.

Each is recognised from the disagreement, the scene the campaign found it in **and** the minimal
scene it was shrunk to, never from a number of a past run. Both scenes must fit: a shrink may slide
into a known finding's corner (a Pinocchio outlier at 200 rad/s with the rod 1.5 m off C, shrunk
with the offset zeroed, still shows a Pinocchio outlier, now the rod-through-C one), and the
finding in the scene found would then hide behind the known one:

* :data:`ROD_THROUGH_C`: the rod passes through C (zero offset) and Pinocchio is the one out of
  step: ``pin.aba`` returns round-off accelerations along a rod through C that seed its spring
  modes (the hard case ``hard/rod_through_C``, ``docs/hard_cases.md``);
* :data:`FAST_SPIN_ANALYTIC`: a spin of :data:`FAST_SPIN` rad/s or more, and the analytic plant is
  the one out of step: its default tolerance (DOP853, rtol 1e-12) is not tight enough at fast
  spin (the hard case ``hard/fast_spin_intermediate``: 200 rad/s about the intermediate axis).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from validation.studies.fuzz.judge import Disagreement, Kind
from validation.studies.fuzz.space import drivers

FAST_SPIN = 100.0
"""Spin rate, rad/s, from which an analytic-plant outlier is the known fast-spin finding (half
the 200 rad/s of ``hard/fast_spin_intermediate``: the same limit shows at lower rates on
shorter-period scenes)."""


@dataclass(frozen=True)
class Known:
    """A known finding: its name, one sentence why, and its recogniser."""

    name: str
    why: str
    matches: Callable[[dict[str, Any], Disagreement], bool]


def _names(d: Disagreement, plant: str) -> bool:
    if d.plant:
        return d.plant == plant
    # a failed check names a plant only when it is that plant's own (``pinocchio.energy``): a
    # failed pair (``mujoco_vs_pinocchio.rod_velocities``) does not say which of the two is off
    # (a 100-scene campaign's MuJoCo fixed-step error on a rod through C failed that pair)
    subject = d.what.split(".", 1)[0] if d.kind is Kind.CHECK else ""
    return subject == plant


def _rod_through_c(data: dict[str, Any], d: Disagreement) -> bool:
    return drivers(data).n > 0 and drivers(data).offset == 0.0 and _names(d, "pinocchio")


def _fast_spin(data: dict[str, Any], d: Disagreement) -> bool:
    return drivers(data).spin >= FAST_SPIN and _names(d, "analytic")


ROD_THROUGH_C = Known(
    "rod_through_C",
    "the rod through C: Pinocchio's round-off accelerations at p = 0 seed the spring modes "
    "(hard/rod_through_C)",
    _rod_through_c,
)
FAST_SPIN_ANALYTIC = Known(
    "fast_spin_analytic",
    "a spin of a few hundred rad/s: the analytic plant's default tolerance (rtol 1e-12) makes it "
    "the outlier (hard/fast_spin_intermediate)",
    _fast_spin,
)
KNOWN = (ROD_THROUGH_C, FAST_SPIN_ANALYTIC)


def recognise(found: dict[str, Any], minimal: dict[str, Any], d: Disagreement) -> str:
    """The name of the known finding ``d`` is, shown by the campaign scene ``found`` and by its
    shrunk ``minimal`` scene (scene files' dicts), or "" when new (module docstring)."""
    for k in KNOWN:
        if k.matches(found, d) and k.matches(minimal, d):
            return k.name
    return ""


__all__ = ["FAST_SPIN", "FAST_SPIN_ANALYTIC", "KNOWN", "ROD_THROUGH_C", "Known", "recognise"]
