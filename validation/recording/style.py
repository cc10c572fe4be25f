"""What the recordings share: the timeline, one colour per plant, entity-path slugs, and the
``log10`` of errors (exact zeros left out).

Every plant keeps one colour everywhere (its body in the 3D views, its trail, its curves in the
plots): analytic blue, MuJoCo orange, Pinocchio green, as in the report's figures (matplotlib's
``tab10``); a pair of plants has a colour of its own. Beyond the built-ins (a plugin, a label read
from a file), a plant takes :data:`EXTRA_PLANT_COLORS` ``[(rank - 3) % 8]`` by its report rank
(:func:`mj_bridge.registry.rank`: the plugins by name, then any other label), and a pair with such a
plant the mean of its two plants' colours at 80 % brightness (:func:`plant_color`).
"""

from __future__ import annotations

import re
import unicodedata

import numpy as np

from validation.compare.checks import Subject

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
EXTRA_PLANT_COLORS: tuple[tuple[str, RGBA], ...] = (
    ("pink", (227, 119, 194, 255)),
    ("olive", (188, 189, 34, 255)),
    ("cyan", (23, 190, 207, 255)),
    ("indigo", (57, 59, 121, 255)),
    ("gold", (189, 158, 57, 255)),
    ("plum", (123, 65, 115, 255)),
    ("moss", (99, 121, 57, 255)),
    ("brick", (173, 73, 74, 255)),
)
"""The colours of the plants after the three built-ins, in rank order, repeating after eight:
``tab10``'s pink, olive and cyan, then ``tab20b``'s darkest shades (none is a built-in plant's or
pair's colour, nor grey, the colour of thresholds)."""

# The reference plant's parts; the others are drawn in their plant's colour (rrd_world).
ROD_RGBA: RGBA = (150, 150, 160, 255)
MASS_RGBA: RGBA = (230, 80, 60, 255)
OMEGA_RGBA: RGBA = (40, 170, 80, 255)  # "the green arrow" of the demo's narrative
TORQUE_RGBA: RGBA = (200, 60, 200, 255)  # "the purple arrow"
THRESHOLD_RGBA: RGBA = (128, 128, 128, 255)
GHOST_ALPHA = 110
"""Opacity (of 255) of the other plants' masses, rods and arrows over the reference plant's."""


def _extra(name: str) -> tuple[str, RGBA]:
    # deferred: mj_bridge.registry reads installed metadata (importlib.metadata, ~20 ms by python -X importtime), paid only when plants are ordered
    from mj_bridge.registry import rank

    return EXTRA_PLANT_COLORS[(rank(name) - 3) % len(EXTRA_PLANT_COLORS)]


def plant_color(name: str) -> RGBA:
    """The colour of plant ``name`` (any plant name) or pair (``"analytic vs mujoco"``): the
    built-ins' and their pairs' from :data:`PLANT_COLOR`, any other plant's from
    :data:`EXTRA_PLANT_COLORS` by its rank, any other pair the mean of its plants' colours at 80 %
    brightness; grey for a text that is no subject."""
    try:
        subject = Subject(name)
    except ValueError:
        return (127, 127, 127, 255)
    if subject in PLANT_COLOR:
        return PLANT_COLOR[subject]
    if subject.is_pair:
        a, b = (plant_color(p) for p in subject.plants)
        r, g, b_ = (int(0.4 * (x + y)) for x, y in zip(a[:3], b[:3], strict=True))
        return (r, g, b_, 255)
    return _extra(subject)[1]


def plant_color_name(name: str) -> str:
    """The name of plant ``name``'s colour, as a narrative says it (``"blue"``; ``"grey"`` for a
    pair or a text that is no plant)."""
    try:
        subject = Subject(name)
    except ValueError:
        return "grey"
    if subject in PLANT_COLOR_NAME:
        return PLANT_COLOR_NAME[subject]
    return "grey" if subject.is_pair else _extra(subject)[0]


COLOR_WORDS: tuple[tuple[str, tuple[int, int, int]], ...] = (
    ("blue", (31, 119, 180)),
    ("orange", (255, 127, 14)),
    ("green", (44, 160, 44)),
    ("red", (214, 39, 40)),
    ("purple", (148, 103, 189)),
    ("brown", (140, 86, 75)),
    ("pink", (227, 119, 194)),
    ("grey", (128, 128, 128)),
    ("olive", (188, 189, 34)),
    ("cyan", (23, 190, 207)),
)
"""matplotlib's tab10 by name: the colours of the plants and of the built-in pairs."""


def color_word(rgba: RGBA) -> str:
    """The name of the :data:`COLOR_WORDS` colour nearest ``rgba`` (a plant's or a pair's colour
    as a plot key says it: ``"red"`` for analytic vs mujoco)."""
    rgb = np.array(rgba[:3], float)
    return min(COLOR_WORDS, key=lambda w: float(np.sum((np.array(w[1]) - rgb) ** 2)))[0]


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


# ----------------------------------------------------------------------------------------------
# Text the viewer draws
# ----------------------------------------------------------------------------------------------


def _chars(*spans: tuple[int, int]) -> frozenset[str]:
    return frozenset(chr(c) for a, b in spans for c in range(a, b + 1))


VIEWER_CHARACTERS: frozenset[str] = _chars(
    (0x20, 0x7E),  # ASCII
    (0xA1, 0xAC),  # ¡ … ¬ (Latin-1, no soft hyphen)
    (0xAE, 0xFF),  # ® … ÿ: ° ± ² ³ µ · ¹ × ÷ and the accented letters
    (0x391, 0x3A1),  # Greek capitals
    (0x3A3, 0x3A9),
    (0x3B1, 0x3C9),  # Greek small letters
    (0x2013, 0x2014),  # – —
    (0x2018, 0x201E),  # quotes
    (0x2022, 0x2022),  # •
    (0x2026, 0x2026),  # …
    (0x2032, 0x2033),  # ′ ″
    (0x2070, 0x2070),  # ⁰
    (0x2074, 0x207A),  # ⁴ … ⁹ ⁺
    (0x2080, 0x2089),  # ₀ … ₉
    (0x2190, 0x2193),  # ← ↑ → ↓
    (0x2202, 0x2202),  # ∂
    (0x2211, 0x2212),  # ∑ −
    (0x221A, 0x221A),  # √
    (0x221E, 0x221E),  # ∞
    (0x2248, 0x2248),  # ≈
    (0x2260, 0x2260),  # ≠
    (0x2264, 0x2265),  # ≤ ≥
    (0x25B2, 0x25B3),  # ▲ △
    (0x25B6, 0x25B7),  # ▶ ▷
    (0x25BC, 0x25BD),  # ▼ ▽
    (0x2713, 0x2713),  # ✓
    (0x2717, 0x2717),  # ✗
)
"""The characters every string a recording carries may use (besides the newline of a text
document): the viewer of rerun-sdk 0.41 draws text in the fonts it bundles, Inter (proportional)
and JetBrains Mono (monospace), and nothing else; a character outside them is drawn as a box, or
makes the headless viewer (``rerun --headless --screenshot-to``) stop with "No glyph for …". This
set lies in both fonts (``tests/validation/recording/test_viewer.py`` reads their character maps out of the installed
``rerun`` binary), so a string renders in either. Combining marks are left out: the viewer lays
out one glyph per character, so a mark would not sit over its letter."""

REPLACEMENT = "?"
"""What :func:`viewer_text` writes for a character it has no spelling for."""

_SPELLED = {
    "\u0304": "bar",  # ω̄ -> ωbar (the paper's requirement)
    "\u0305": "bar",
    "\u0307": "dot",  # ṗ -> pdot
    "\u0308": "ddot",
    "\u0302": "hat",
    "\u0303": "tilde",
    "⊗": "(x)",
    "✕": "×",
    "⋅": "·",
    "∙": "·",
    "∥": "||",
    "‖": "||",
    "∈": " in ",
    "≡": "=",
    "½": "1/2",
    "\u00ad": "",
    "\t": " ",
}
"""Spellings, within :data:`VIEWER_CHARACTERS`, of the characters the project's own texts use."""


def _script(c: str) -> str | None:
    """``^`` or ``_`` for a superscript or subscript character, else None."""
    tag = unicodedata.decomposition(c).split(" ", 1)[0]
    return {"<super>": "^", "<sub>": "_"}.get(tag)


def _spell(c: str) -> str:
    """A character outside :data:`VIEWER_CHARACTERS` spelled with characters inside it."""
    if c in _SPELLED:
        return _SPELLED[c]
    parts = unicodedata.normalize("NFKD", c)
    out = "".join(
        _SPELLED.get(p, "") if unicodedata.combining(p) else p
        for p in parts
        if p in VIEWER_CHARACTERS or unicodedata.combining(p)
    )
    return out if out and all(p in VIEWER_CHARACTERS for p in out) else REPLACEMENT


def viewer_text(text: str, newlines: bool = False) -> str:
    """``text`` in :data:`VIEWER_CHARACTERS` only, for a label, a name, a view's title or (with
    ``newlines``) a text document: ``uᵀu`` -> ``u^T u``, ``10⁻¹²`` -> ``10^-12``, ``ω̄`` ->
    ``ωbar``, ``ṗ`` -> ``pdot``, ``⊗`` -> ``(x)``; a character with no spelling becomes
    :data:`REPLACEMENT`. A text already inside the set is returned unchanged."""
    text = unicodedata.normalize("NFC", text)
    out: list[str] = []
    i = 0
    while i < len(text):
        c = text[i]
        if c in VIEWER_CHARACTERS or (newlines and c == "\n"):
            out.append(c)
            i += 1
            continue
        mark = _script(c)
        if mark is None:
            out.append(_spell(c))
            i += 1
            continue
        j = i  # a run of super- or subscripts with one outside the set: all of it, after ^ or _
        while j < len(text) and _script(text[j]) == mark:
            j += 1
        run = unicodedata.normalize("NFKC", text[i:j])
        out.append(mark + "".join(ch if ch in VIEWER_CHARACTERS else REPLACEMENT for ch in run))
        if j < len(text) and text[j].isalnum():
            out.append(" ")
        i = j
    return "".join(out)


__all__ = [
    "COLOR_WORDS",
    "EXTRA_PLANT_COLORS",
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
    "VIEWER_CHARACTERS",
    "color_word",
    "entity_root",
    "log10_nonzero",
    "plant_color",
    "plant_color_name",
    "power_of_ten",
    "shade",
    "slug",
    "toward",
    "unit_text",
    "viewer_text",
]
