"""What the recordings share: the timeline, one colour per plant, entity-path slugs, and the
``log10`` of errors (exact zeros left out).

Every plant keeps one colour everywhere (its body in the 3D views, its trail, its curves in the
plots): analytic blue, MuJoCo orange, Pinocchio green, as in the report's figures (matplotlib's
``tab10``); a pair of plants has a colour of its own.
"""

from __future__ import annotations

import re

import numpy as np

from validation.compare import Subject

TIMELINE = "sim_time"
"""The only timeline of a recording: simulated time, s."""

RGBA = tuple[int, int, int, int]

PLANT_COLOR: dict[Subject, RGBA] = {
    Subject.ANALYTIC: (31, 119, 180, 255),
    Subject.MUJOCO: (255, 127, 14, 255),
    Subject.PINOCCHIO: (44, 160, 44, 255),
    Subject.BOTH: (214, 39, 40, 255),
    Subject.ANALYTIC_PINOCCHIO: (148, 103, 189, 255),
    Subject.MUJOCO_PINOCCHIO: (140, 86, 75, 255),
}
PLANT_COLOR_NAME: dict[Subject, str] = {
    Subject.ANALYTIC: "blue",
    Subject.MUJOCO: "orange",
    Subject.PINOCCHIO: "green",
}

# The reference plant's parts; the others are drawn in their plant's colour (rrd_world).
ROD_RGBA: RGBA = (150, 150, 160, 255)
MASS_RGBA: RGBA = (230, 80, 60, 255)
OMEGA_RGBA: RGBA = (40, 170, 80, 255)  # "the green arrow" of the demo's narrative
TORQUE_RGBA: RGBA = (200, 60, 200, 255)  # "the purple arrow"
THRESHOLD_RGBA: RGBA = (128, 128, 128, 255)
GHOST_ALPHA = 110
"""Opacity (of 255) of the other plants' masses, rods and arrows over the reference plant's."""


def plant_color(name: str) -> RGBA:
    """The colour of plant ``name`` (an engine name) or pair (``"analytic vs mujoco"``)."""
    try:
        return PLANT_COLOR[Subject(name)]
    except ValueError:
        return (127, 127, 127, 255)


def shade(rgba: RGBA, j: int) -> RGBA:
    """The ``j``-th shade of a colour: component j of a vector, or quantity j in one plot."""
    base = np.array(rgba[:3], float)
    f = [1.0, 0.65, 0.35, 0.8, 0.5, 0.2][j % 6]
    c = base * f + 255 * (1 - f) * (0.3 if j % 2 else 0.0)
    return (*np.clip(c, 0, 255).astype(int).tolist(), 255)


def toward(rgba: RGBA, tint: RGBA, alpha: int = GHOST_ALPHA) -> RGBA:
    """``rgba`` half way to ``tint``, with opacity ``alpha``: another plant's arrow or mass."""
    r, g, b, _ = rgba
    tr, tg, tb = tint[:3]
    return (int(0.5 * r + 0.5 * tr), int(0.5 * g + 0.5 * tg), int(0.5 * b + 0.5 * tb), alpha)


def entity_root(prefix: str) -> str:
    """The entity path under which a run is logged: ``""`` for ``""``, ``/step1`` for ``step1``."""
    p = prefix.strip("/")
    return f"/{p}" if p else ""


def slug(text: str) -> str:
    """An entity-path part for a unit or a name: ``N·m`` -> ``N_m``, ``kg·m²/s`` ->
    ``kg_m2_per_s``, ``1`` -> ``dimensionless``; ASCII letters, digits and ``_`` only."""
    if text in ("", "1"):
        return "dimensionless"
    s = text.replace("²", "2").replace("³", "3").replace("/", "_per_").replace("·", "_")
    return re.sub(r"[^A-Za-z0-9_]+", "_", s).strip("_") or "x"


def unit_text(unit: str) -> str:
    """A unit as printed after a quantity: ``(m)``; nothing for a dimensionless one."""
    return "" if unit in ("", "1") else f" ({unit})"


def log10_nonzero(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(t, log10 |v|)`` at the samples where ``v`` is not an exact zero, shapes (M,), M <= N.

    An exact zero (two plants agreeing to the last bit) has no logarithm: it is left out of the
    plot rather than drawn at an arbitrary floor. Non-finite values are kept (a diverged run
    shows as such)."""
    t = np.asarray(t, float)
    v = np.abs(np.asarray(values, float))
    keep = v != 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return t[keep], np.log10(v[keep])


def power_of_ten(k: float) -> str:
    """``1e6`` for 10⁶, ``1`` for 1: how an exaggeration factor is printed."""
    if k == 1:
        return "1"
    e = round(float(np.log10(k)))
    return f"1e{e}" if np.isclose(k, 10.0**e) else f"{k:.3g}"


__all__ = [
    "GHOST_ALPHA",
    "MASS_RGBA",
    "OMEGA_RGBA",
    "PLANT_COLOR",
    "PLANT_COLOR_NAME",
    "RGBA",
    "ROD_RGBA",
    "THRESHOLD_RGBA",
    "TIMELINE",
    "TORQUE_RGBA",
    "entity_root",
    "log10_nonzero",
    "plant_color",
    "power_of_ten",
    "shade",
    "slug",
    "toward",
    "unit_text",
]
