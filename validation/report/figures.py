"""The figures of a validation run, each with its caption (matplotlib, Agg, no pyplot state).

* ``errors``: the differences between each pair of plants over time, one panel per compared
  quantity, log axes, drawn as they are checked: absolute for the state, and for the control torque
  and rod forces divided by the reference plant's largest magnitude (relative); the thresholds of
  :mod:`validation.compare.thresholds` as dotted lines;
* ``tracking``: each plant's tracking errors and their deviations from the closed-form error
  dynamics (Eq. 84 with ``docs/errata.md`` item 3, and Eq. 78), log axes, with thresholds;
* ``invariants``: each plant's quaternion norm error (absolute) and its balances of linear
  momentum, angular momentum and energy divided by their scales (relative, as checked), log axes,
  with thresholds;
* ``control``: the reference plant's control torque (body axes) and rod forces in engineering
  units, and below, for each other plant, its relative distance from the reference (log axes): the
  plants agree to ~1e-12, so their curves drawn on one linear axis would hide under each other.

A panel whose every curve is identically zero is left out (a log axis has no place for zero) and
the caption says which and why; a figure with nothing to show is not drawn, and its caption says
why (an uncontrolled scene has no control and no tracking figure). Curves that coincide are told
apart by their markers, staggered along the time axis. Legends stand outside the data.

The layout is fixed, in inches, from the figure's size (:class:`_Layout`): no layout engine, titles
at a set height, y labels at one offset measured from the widest tick label, log ticks labelled
``10⁻¹²`` in plain text and made only inside the view. A layout engine, automatic title placement
and math text tick labels lay out every text several times over: with them the four figures of a
default run took 2.7x as long to draw and write.

Every drawing renders to PNG, SVG or PDF (:class:`FigureFormat`) without a time stamp in the file.
"""

from __future__ import annotations

import functools
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from analytic.trajectory import Trajectory
from validation.compare.checks import Check, Comparison, Group, Series, Subject
from validation.compare.thresholds import Threshold, thresholds_for


class FigureFormat(StrEnum):
    """A file format a figure is written in (the file's extension)."""

    PNG = "png"
    SVG = "svg"
    PDF = "pdf"


DEFAULT_FORMATS = (FigureFormat.PNG,)
FIGURES = ("errors", "tracking", "invariants", "control")
PNG_DPI = 150  # pixels per inch of the PNG files (10 in wide: 1500 px)
WIDTH_IN = 10.0  # figure width, in
ROW_IN = 2.3  # height of one panel, in
MARKERS_PER_CURVE = 12  # markers on each curve, staggered between curves so coinciding ones show
PNG_COMPRESS_LEVEL = 3  # zlib level of the PNGs (Pillow's default 6: 1.6x the time, 8 % smaller)
SVG_HASH_SALT = "validation.report.figures"  # salt of the SVG element ids (matplotlib: a random uuid)
TEXT_RASTER = {"text.hinting": "no_hinting"}
"""How Agg rasterises text: glyphs unhinted. Matplotlib's default (FreeType hinting each glyph to
the pixel grid) looks the same at 150 dpi and adds about a sixth to the drawing time."""

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
_SUBSCRIPT = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")

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
    "energy": "energy balance |E − E(0) − W| / max(|E|, |W|)",
}
"""Panel titles: the quantity drawn, as it is checked (``a`` the pair's reference plant)."""


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


@dataclass(frozen=True)
class Drawing:
    """One figure and its caption; ``figure`` is None when there was nothing to draw, and the
    caption then says why (a sentence, ``The scene has no control requirement, ...``)."""

    name: str
    caption: str
    figure: Any = None

    @property
    def drawn(self) -> bool:
        return self.figure is not None

    def render(self, fmt: FigureFormat | str = FigureFormat.PNG) -> bytes:
        """The figure's file content in ``fmt``: no time stamp, and SVG element ids drawn from a
        fixed salt rather than a random one, so equal figures give equal files; text rasterised
        as :data:`TEXT_RASTER` says."""
        # deferred: matplotlib ~0.4 s (python -X importtime): the report imports this module, a worker draws
        import matplotlib as mpl

        if self.figure is None:
            raise ValueError(f"figure {self.name!r}: not drawn ({self.caption})")
        fmt = FigureFormat(fmt)
        if fmt is FigureFormat.PNG:
            return _png(self.figure)
        metadata = {FigureFormat.SVG: {"Date": None}, FigureFormat.PDF: {"CreationDate": None}}[fmt]
        buf = io.BytesIO()
        with mpl.rc_context({"svg.hashsalt": SVG_HASH_SALT, **TEXT_RASTER}):
            self.figure.savefig(buf, format=fmt.value, dpi=PNG_DPI, metadata=metadata)
        return buf.getvalue()


def _png(figure: Any) -> bytes:
    """``figure`` as PNG: the pixels matplotlib's Agg renderer draws at :data:`PNG_DPI`, written as
    RGB when every pixel is opaque (the figures have an opaque background), else RGBA.

    matplotlib's ``savefig`` always writes RGBA, and Pillow's PNG row filters then take twice as
    long as for RGB, which carries the same picture when the alpha channel is all 255; the file
    records the resolution and no time stamp or software version."""
    import matplotlib as mpl
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    with mpl.rc_context(TEXT_RASTER):
        canvas = FigureCanvasAgg(figure)
        canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())
    image = Image.fromarray(rgba[..., :3] if (rgba[..., 3] == 255).all() else rgba)
    buf = io.BytesIO()
    image.save(buf, format="png", compress_level=PNG_COMPRESS_LEVEL, dpi=(PNG_DPI, PNG_DPI))
    return buf.getvalue()


def parse_formats(text: str) -> tuple[FigureFormat, ...]:
    """``"png,svg"`` -> the formats, in order, once each; ValueError naming ``figure_format``."""
    out: list[FigureFormat] = []
    for part in str(text).split(","):
        name = part.strip().lower()
        try:
            fmt = FigureFormat(name)
        except ValueError:
            known = ", ".join(f.value for f in FigureFormat)
            raise ValueError(
                f"figure_format: unknown format {part.strip()!r} (known: {known})"
            ) from None
        if fmt not in out:
            out.append(fmt)
    return tuple(out)


# ----------------------------------------------------------------------------------------------
# Drawing helpers
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Layout:
    """Fixed margins of a figure, in inches (figure width :data:`WIDTH_IN`).

    Attributes:
        left_in: room left of the panels for the y tick labels and label (widened when a tick
            label needs more, :func:`_place_axis_labels`).
        right_in: room right of the panels (a side legend's width, or a small margin).
        top_in: room above the first panel: the figure's title and the panel's title.
        gap_in: room between panels: the lower panel's title.
        bottom_in: room below the last panel: x tick labels, the x label and the figure legend.
    """

    left_in: float = 0.9
    right_in: float = 0.25
    top_in: float = 0.62
    gap_in: float = 0.4
    bottom_in: float = 0.55


FIGURE_LEGEND_IN = 0.3  # height of the one-row legend below the panels, in
SIDE_LEGEND_IN = 1.8  # width reserved right of the panels for their side legends, in
SUPTITLE_TOP_IN = 0.08  # from the figure's top edge to its title's top, in
TITLE_PAD_PT = 5.0  # from a panel's top edge to its title's baseline, points
FIGURE_TITLE_PT = 12.0  # font sizes, points
PANEL_TITLE_PT = 10.0


def _figure(
    nrows: int,
    title: str,
    height_rows: Sequence[float] | None = None,
    *,
    side_legends: bool = False,
):
    """A figure of ``nrows`` panels stacked over a shared time axis, laid out once in inches: a
    legend row below the panels, or with ``side_legends`` room on the right for one legend per
    panel."""
    from matplotlib.figure import Figure

    ratios = list(height_rows) if height_rows is not None else [1.0] * nrows
    layout = _Layout(
        right_in=SIDE_LEGEND_IN if side_legends else _Layout.right_in,
        bottom_in=_Layout.bottom_in + (0.0 if side_legends else FIGURE_LEGEND_IN),
    )
    height = ROW_IN * sum(ratios) + 1.0
    fig = Figure(figsize=(WIDTH_IN, height), dpi=PNG_DPI)
    panels_in = height - layout.top_in - layout.bottom_in - (nrows - 1) * layout.gap_in
    axes = fig.subplots(
        nrows,
        1,
        sharex=True,
        squeeze=False,
        gridspec_kw={
            "left": layout.left_in / WIDTH_IN,
            "right": 1.0 - layout.right_in / WIDTH_IN,
            "top": 1.0 - layout.top_in / height,
            "bottom": layout.bottom_in / height,
            "hspace": layout.gap_in / (panels_in / nrows),
            "height_ratios": ratios,
        },
    )[:, 0]
    fig.suptitle(title, fontsize=FIGURE_TITLE_PT, y=1.0 - SUPTITLE_TOP_IN / height, va="top")
    return fig, axes


def _title(ax, text: str) -> None:
    """The panel's title, left, at a set height above it (no search for overlapping labels:
    the layout leaves it room)."""
    ax.set_title(text, fontsize=PANEL_TITLE_PT, loc="left", y=1.0, pad=TITLE_PAD_PT)


_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def _power_of_ten(x: float, pos: int | None = None) -> str:
    """A log axis' tick label in plain text: ``1e-12`` -> ``10⁻¹²`` (other values as ``%g``)."""
    if not (x > 0 and math.isfinite(x)):
        return ""
    e = round(math.log10(x))
    if math.isclose(x, 10.0**e, rel_tol=1e-9):
        return "10" + str(e).translate(_SUPERSCRIPT)
    return f"{x:g}"


@functools.lru_cache(maxsize=512)
def _text_size_pt(text: str, size: float | str) -> tuple[float, float]:
    """(width, height) of one line of ``text`` in the default font at ``size``, points (cached:
    the figures use matplotlib's default font throughout)."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    prop = FontProperties(size=size)
    w, h, _ = text_to_path.get_text_width_height_descent(text, prop, ismath=False)
    _, lp, _ = text_to_path.get_text_width_height_descent("lp", prop, ismath=False)
    return w, max(h, lp)


def _widest_ytick_label_pt(ax) -> float:
    """Width of the widest major y tick label the panel will draw, points (0 if none)."""
    import matplotlib as mpl

    lo, hi = sorted(ax.get_ybound())
    locs = [v for v in ax.yaxis.get_majorticklocs() if lo <= v <= hi]
    if not locs:
        return 0.0
    size = mpl.rcParams["ytick.labelsize"]
    return max(_text_size_pt(s, size)[0] for s in ax.yaxis.get_major_formatter().format_ticks(locs))


def _in_view(base):
    """``base``, a tick locator, keeping only the ticks inside the view: matplotlib makes a tick
    object (two lines, a grid line, two labels) for every location its locator returns, drawn or
    not, and the usual locators return one beyond each end. (A class made here, not at import:
    this module imports matplotlib only when it draws.)"""
    from matplotlib.ticker import Locator

    class InView(Locator):
        def set_axis(self, axis):
            super().set_axis(axis)
            base.set_axis(axis)

        def __call__(self):
            return self._inside(base(), *self.axis.get_view_interval())

        def tick_values(self, vmin, vmax):
            return self._inside(base.tick_values(vmin, vmax), vmin, vmax)

        def nonsingular(self, v0, v1):
            return base.nonsingular(v0, v1)

        def view_limits(self, vmin, vmax):
            return base.view_limits(vmin, vmax)

        def _inside(self, locs, vmin, vmax):
            locs = np.asarray(locs, float)
            if self.axis is None or not locs.size:
                return locs
            to_screen = self.axis.get_transform()  # the scale: log ticks compare in log space
            lo, hi = sorted(to_screen.transform(np.array([vmin, vmax], float)))
            t = to_screen.transform(locs)
            tol = 1e-9 * (hi - lo)
            with np.errstate(invalid="ignore"):
                return locs[(t >= lo - tol) & (t <= hi + tol)]

    return InView()


def _finish_axes(fig, axes) -> None:
    """After every panel is drawn into: ticks only inside the view (:func:`_in_view`), and the
    axis labels placed (:func:`_place_axis_labels`)."""
    for ax in axes:
        ax.yaxis.set_major_locator(_in_view(ax.yaxis.get_major_locator()))
    axes[-1].xaxis.set_major_locator(_in_view(axes[-1].xaxis.get_major_locator()))  # shared
    _place_axis_labels(fig, axes)


def _place_axis_labels(fig, axes) -> None:
    """Put every panel's y label at one offset left of the panels, just beyond the widest tick
    label of all panels (aligned, as a layout engine would), widening the left margin if that
    label needs it; the x label below the last panel's tick labels. Fixed positions: matplotlib
    then skips measuring every tick label for them at each draw."""
    import matplotlib as mpl

    rc = mpl.rcParams
    tick_pt = max(rc["ytick.major.size"], rc["ytick.minor.size"]) + rc["ytick.major.pad"]
    widest = max(_widest_ytick_label_pt(ax) for ax in axes)
    offset_in = (tick_pt + widest + rc["axes.labelpad"]) / 72.0
    label_in = _text_size_pt("1 (relative)", rc["axes.labelsize"])[1] / 72.0
    fig_w, fig_h = fig.get_size_inches()
    gs = axes[0].get_subplotspec().get_gridspec()
    need = (offset_in + label_in) / fig_w + 0.1 / fig_w
    if gs.left < need:
        gs.update(left=need)  # repositions the axes of pyplot's figures only
        for ax in axes:
            ax.set_position(ax.get_subplotspec().get_position(fig))
    width_in = (gs.right - gs.left) * fig_w
    for ax in axes:
        ax.yaxis.set_label_coords(-offset_in / width_in, 0.5)
    ax = axes[-1]
    height_in = ax.get_position().height * fig_h
    xtick_in = (
        rc["xtick.major.size"]
        + rc["xtick.major.pad"]
        + _text_size_pt("0", rc["xtick.labelsize"])[1]
        + rc["axes.labelpad"]
    ) / 72.0
    ax.xaxis.set_label_coords(0.5, -xtick_in / height_in)


def _markevery(n: int, k: int) -> tuple[int, int]:
    """Every ``n // MARKERS_PER_CURVE``-th sample, the k-th curve offset by a third of that."""
    step = max(n // MARKERS_PER_CURVE, 1)
    return ((k * step) // 3 % step, step)


def _line(ax, t: np.ndarray, v: np.ndarray, subject: Subject, k: int, label: str, **kw):
    style = plant_style(subject)
    style.update(kw)
    return ax.plot(
        t,
        v,
        label=label,
        linewidth=1.0,
        markersize=4,
        markerfacecolor="none",
        markevery=_markevery(len(t), k),
        **style,
    )[0]


def _log_axis(ax, values: Sequence[np.ndarray]) -> None:
    """A log y axis with limits a factor 5 beyond the positive finite ``values``, set before any
    line is drawn (autoscale would warn on a constant series, such as a threshold alone); decades
    labelled ``10⁻¹²`` (:func:`_power_of_ten`), minor ticks unlabelled (the limits span more than
    a decade, so at least one decade is labelled)."""
    from matplotlib.ticker import NullFormatter

    pos = [np.asarray(v, float).ravel() for v in values]
    allpos = np.concatenate(pos) if pos else np.zeros(0)
    allpos = allpos[(allpos > 0) & np.isfinite(allpos)]
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(_power_of_ten)
    ax.yaxis.set_minor_formatter(NullFormatter())
    if allpos.size:
        ax.set_ylim(allpos.min() / 5, allpos.max() * 5)
    else:
        ax.set_ylim(1e-16, 1.0)
    ax.grid(True, which="major", alpha=0.3)


def _log_panel(
    ax, curves: Sequence[tuple[Subject, np.ndarray, np.ndarray]], threshold: float | None
) -> list[Subject]:
    """Positive values on a log axis; returns the subjects whose curve is identically zero (not
    drawn: a log axis has no place for zero, the caption says so)."""
    limit = [np.array([threshold])] if threshold is not None and threshold > 0 else []
    _log_axis(ax, [np.asarray(v, float) for _, _, v in curves] + limit)
    zero: list[Subject] = []
    for k, (subject, t, values) in enumerate(curves):
        v = np.asarray(values, float)
        if not np.any(v):
            zero.append(subject)
            continue
        _line(ax, t, np.where(v > 0, v, np.nan), subject, k, subject.value)
    if limit:
        ax.axhline(threshold, label="threshold", **THRESHOLD_STYLE)
    return zero


def _figure_legend(fig, axes) -> None:
    """One legend for the whole figure, in the row kept for it below the panels (every panel
    shows the same curves); then the axes are finished (:func:`_finish_axes`)."""
    handles: dict[str, Any] = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    if handles:
        fig.legend(
            list(handles.values()),
            list(handles),
            loc="lower center",
            bbox_to_anchor=(0.5, 0.0),
            ncols=min(len(handles), 4),
            fontsize=9,
            frameon=False,
        )
    _finish_axes(fig, axes)


def _side_legend(ax) -> None:
    """A legend to the right of the panel, outside the data."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8)


def prepare_drawing() -> None:
    """Draw and encode one small throw-away figure with the figures' own helpers, so that what a
    process's first figure would otherwise load while it draws (the fonts at the figures' sizes,
    glyph and text-layout caches, the log-axis tick machinery, the PNG encoder) is loaded now.

    ``tumble validate`` calls it at idle priority while the plants run; the evidence workers
    forked afterwards inherit all of it, and their first figure costs what a second one would
    (measured on the error figure: 0.9-1.25 s first in a process, 0.55-0.6 s after this)."""
    fig, axes = _figure(1, "prepare")
    t = np.linspace(0.0, 1.0, 5)
    _log_panel(axes[0], [(Subject.BOTH, t, 10.0**-t)], 1e-3)
    axes[0].set_ylabel("m")
    _title(axes[0], "prepare")
    axes[-1].set_xlabel("t (s)")
    _figure_legend(fig, axes)
    Drawing("prepare", "", fig).render(FigureFormat.PNG)


def _checks_by_series(cmp: Comparison) -> dict[str, Check]:
    return {c.series: c for c in cmp.checks if c.series}


def _as_checked(s: Series, checks: Mapping[str, Check]) -> np.ndarray:
    """The series as its check sees it: divided by the check's scale for a relative check."""
    c = checks.get(s.key)
    return s.values / c.scale if c is not None and c.scale > 0 else s.values


def _threshold(cmp: Comparison, name: str) -> Threshold | None:
    return cmp.thresholds.get(name)


def _names(subjects: Sequence[Subject]) -> str:
    vals = [s.value for s in subjects]
    return vals[0] if len(vals) == 1 else ", ".join(vals[:-1]) + " and " + vals[-1]


def _caption(*sentences: str) -> str:
    return " ".join(s.strip() for s in sentences if s and s.strip())


def _zero_sentence(zeros: Sequence[tuple[str, Sequence[Subject]]]) -> str:
    """``Not drawn, identically zero: attitude of analytic vs mujoco; ...`` (empty if none)."""
    if not zeros:
        return ""
    items = "; ".join(f"{PANEL_TITLES.get(n, n).split(':')[0]} of {_names(ss)}" for n, ss in zeros)
    return f"Not drawn, identically zero (a log axis has no place for zero): {items}."


def _no_control_reason(ctx: FigureContext) -> str:
    if ctx.controlled is False:
        return "the scene has no control requirement, so every plant's control torque and rod forces are identically zero"
    return "every plant's control torque and rod forces are identically zero"


# ----------------------------------------------------------------------------------------------
# The figures
# ----------------------------------------------------------------------------------------------


def figure_errors(cmp: Comparison, ctx: FigureContext | None = None) -> Drawing:
    """Differences between each pair of plants over time, as checked, with their thresholds."""
    ctx = ctx or FigureContext(cmp.scene)
    diffs = [s for s in cmp.series if s.group is Group.DIFFERENCE]
    if not diffs:
        return Drawing("errors", "Only one plant ran, so there is no pair to compare.")
    rows: dict[str, list[Series]] = {}
    for s in diffs:
        rows.setdefault(s.name, []).append(s)
    checks = _checks_by_series(cmp)
    kept = {n: ss for n, ss in rows.items() if any(np.any(s.values) for s in ss)}
    left_out = [n for n in rows if n not in kept]
    control_out = [n for n in left_out if n in ("control_torque", "rod_forces")]
    if ctx.controlled is not False:
        control_out = []  # zero without a reason the scene gives: said as plain zeros below
    other_out = [n for n in left_out if n not in control_out]

    def names(ns: Sequence[str]) -> str:
        return ", ".join(PANEL_TITLES.get(n, n).split(":")[0] for n in ns)

    why_out = _caption(
        f"Left out: {names(control_out)} ({_no_control_reason(ctx)})." if control_out else "",
        f"Left out, identically zero for every pair: {names(other_out)}." if other_out else "",
    )
    pairs = list(dict.fromkeys(s.subject for s in diffs))
    intro = (
        f"Differences between {'the plants' if len(pairs) == 1 else 'each pair of plants'} "
        f"({_names(pairs)}; a = the first-named plant of a pair, b = the second) over time, log "
        "axes, one panel per compared quantity, drawn as it is checked: the absolute distance "
        "for the state, and for the control torque and rod forces the distance divided by the "
        "first plant's largest magnitude (relative, dimensionless). Dotted black: the threshold "
        "(validation/compare/thresholds.py, or the scene's [thresholds])."
    )
    if not kept:
        return Drawing("errors", _caption(why_out, ctx.run_sentence()))
    fig, axes = _figure(len(kept), f"{ctx.scene}: differences between the plants")
    zeros: list[tuple[str, list[Subject]]] = []
    for ax, (name, ss) in zip(axes, kept.items(), strict=True):
        th = _threshold(cmp, name)
        z = _log_panel(
            ax, [(s.subject, s.t, _as_checked(s, checks)) for s in ss], th.value if th else None
        )
        if z:
            zeros.append((name, z))
        unit = "1 (relative)" if th is not None and th.relative else ss[0].unit
        ax.set_ylabel(unit)
        limit = f"; threshold {th.value:g}" if th is not None else ""
        _title(ax, f"{PANEL_TITLES.get(name, ss[0].label)}{limit}")
    axes[-1].set_xlabel("t (s)")
    _figure_legend(fig, axes)
    return Drawing(
        "errors", _caption(intro, why_out, _zero_sentence(zeros), ctx.run_sentence()), fig
    )


def _plant_rows(cmp: Comparison, names: Sequence[str]) -> list[tuple[str, list[Series]]]:
    rows = []
    for name in names:
        ss = [s for s in cmp.series if not s.subject.is_pair and s.name == name]
        if ss:
            rows.append((name, ss))
    return rows


def figure_tracking(cmp: Comparison, ctx: FigureContext | None = None) -> Drawing:
    """Each plant's tracking errors and their deviation from the closed-form laws; log axes."""
    ctx = ctx or FigureContext(cmp.scene)
    rows = _plant_rows(cmp, ("e_omega", "e_omega_law", "e_p", "e_p_law"))
    if not rows:
        why = (
            "the scene has no control requirement"
            if ctx.controlled is False
            else "no plant tracks a requirement"
        )
        return Drawing(
            "tracking", f"{why[0].upper()}{why[1:]}, so there is no tracking error to draw."
        )
    limits = {"e_omega_law": "tracking_omega", "e_p_law": "tracking_p"}
    fig, axes = _figure(len(rows), f"{ctx.scene}: tracking errors of each plant")
    zeros: list[tuple[str, list[Subject]]] = []
    for ax, (name, ss) in zip(axes, rows, strict=True):
        th = _threshold(cmp, limits[name]) if name in limits else None
        z = _log_panel(ax, [(s.subject, s.t, s.values) for s in ss], th.value if th else None)
        if z:
            zeros.append((name, z))
        ax.set_ylabel(ss[0].unit)
        limit = f"; threshold {th.value:g} {th.unit}" if th is not None else ""
        _title(ax, f"{PANEL_TITLES.get(name, ss[0].label)}{limit}")
    axes[-1].set_xlabel("t (s)")
    _figure_legend(fig, axes)
    caption = _caption(
        "Tracking errors of each plant over time (log axes): the angular-velocity error "
        "e_ω = ω − ω̄ (rad/s, body axes) and the largest position error of the controlled masses "
        "(m), each followed by its deviation from the closed-form error dynamics the controller "
        "imposes, e_ω(t) = exp(−γt) e_ω(0) (Eq. 84; docs/errata.md, item 3) and ë + αė + βe = 0 "
        "(Eq. 78). Dotted black: the threshold. Where the plants' curves coincide, the markers "
        "(staggered in time) tell them apart.",
        _zero_sentence(zeros),
        ctx.run_sentence(),
    )
    return Drawing("tracking", caption, fig)


def figure_invariants(cmp: Comparison, ctx: FigureContext | None = None) -> Drawing:
    """Quaternion norm error and the relative balances of each plant, with their thresholds."""
    ctx = ctx or FigureContext(cmp.scene)
    rows = _plant_rows(cmp, ("quat_norm", "linear_momentum", "angular_momentum", "energy"))
    if not rows:
        return Drawing("invariants", "No plant's trajectory was compared.")
    checks = _checks_by_series(cmp)
    fig, axes = _figure(len(rows), f"{ctx.scene}: invariants of each plant, as checked")
    zeros: list[tuple[str, list[Subject]]] = []
    for ax, (name, ss) in zip(axes, rows, strict=True):
        th = _threshold(cmp, name)
        z = _log_panel(
            ax, [(s.subject, s.t, _as_checked(s, checks)) for s in ss], th.value if th else None
        )
        if z:
            zeros.append((name, z))
        ax.set_ylabel("1 (relative)" if th is not None and th.relative else ss[0].unit)
        limit = f"; threshold {th.value:g}" if th is not None else ""
        _title(ax, f"{PANEL_TITLES.get(name, ss[0].label)}{limit}")
    axes[-1].set_xlabel("t (s)")
    _figure_legend(fig, axes)
    caption = _caption(
        "Invariants of each plant over time (log axes), drawn as they are checked: the "
        "quaternion norm error |uᵀu − 1| (absolute), and the balances of linear momentum "
        "(against gravity), angular momentum about the system's centre of mass (against the "
        "impulse of the control torque) and energy (against the work of the control), each "
        "divided by the largest magnitude of what it balances (relative; the divisor is named "
        "in each panel). Dotted black: the threshold.",
        _zero_sentence(zeros),
        ctx.run_sentence(),
    )
    return Drawing("invariants", caption, fig)


def _eng(maxabs: float) -> tuple[float, str]:
    """(divisor, SI prefix) that bring ``maxabs`` into [1, 1000): 9.9e9 -> (1e9, "G")."""
    from matplotlib.ticker import EngFormatter

    if not (maxabs > 0 and math.isfinite(maxabs)):
        return 1.0, ""
    exp = int(np.clip(3 * math.floor(math.log10(maxabs) / 3), -24, 24))
    return 10.0**exp, EngFormatter.ENG_PREFIXES[exp]


def _linear_axis(ax) -> None:
    """A linear y axis: the zero line, a grid, and tick labels without an offset (an offset, as
    ``+5e2`` above the axis for a nearly constant force, would stand where the title is)."""
    ax.axhline(0.0, color="0.6", linewidth=0.6)
    ax.grid(True, alpha=0.3)
    ax.ticklabel_format(axis="y", useOffset=False)


def _common_samples(a: Trajectory, b: Trajectory) -> int:
    """Leading samples at the same times (0 when the grids differ from the start)."""
    k = min(a.t.shape[0], b.t.shape[0])
    same = np.isclose(a.t[:k], b.t[:k], rtol=1e-9, atol=1e-12)
    return int(np.argmin(same)) if not same.all() else k


def figure_control(
    plants: Sequence[Trajectory],
    ctx: FigureContext | None = None,
    thresholds: Mapping[str, Threshold] | None = None,
) -> Drawing:
    """The reference plant's control torque and rod forces, and every other plant's relative
    distance from them (log axes) with the thresholds; not drawn without control."""
    plants = [p for p in plants if p.t.size]
    if not plants:
        return Drawing("control", "No plant produced a sample.")
    ctx = ctx or FigureContext(plants[0].scene)
    if not any(np.any(p.torque) or np.any(p.rod_forces) for p in plants):
        why = _no_control_reason(ctx)
        return Drawing("control", f"{why[0].upper()}{why[1:]}.")
    th = dict(thresholds) if thresholds is not None else thresholds_for(None)
    ref, others = plants[0], plants[1:]
    n = ref.n
    has_tau = any(np.any(p.torque) for p in plants)
    has_f = bool(n) and any(np.any(p.rod_forces) for p in plants)
    per_other = int(has_tau) + int(has_f)  # one distance panel per force kind and other plant
    nrows = int(has_tau) + int(has_f) + per_other * len(others)
    fig, axes = _figure(nrows, f"{ctx.scene}: control forces", side_legends=True)
    refname = ref.engine
    colors = [f"C{j}" for j in range(10)]
    row = 0
    units = []
    if has_tau:
        ax = axes[row]
        row += 1
        div, prefix = _eng(float(np.max(np.abs(ref.torque), initial=0.0)))
        for j in range(3):
            ax.plot(
                ref.t,
                ref.torque[:, j] / div,
                color=colors[j],
                linewidth=1.2,
                label=f"$\\tau_{'xyz'[j]}$",
            )
        ax.set_ylabel(f"τ ({prefix}N·m)")
        _title(ax, f"{refname} plant: control torque τ, body axes")
        _linear_axis(ax)
        _side_legend(ax)
        units.append(f"{prefix}N·m")
    if has_f:
        ax = axes[row]
        row += 1
        div, fprefix = _eng(float(np.max(np.abs(ref.rod_forces), initial=0.0)))
        for i in range(n):
            ax.plot(
                ref.t,
                ref.rod_forces[:, i] / div,
                color=colors[(3 + i) % 10],
                linewidth=1.2,
                label=f"$F_{{{i + 1}}}$",
            )
        ax.set_ylabel(f"F ({fprefix}N)")
        _title(ax, f"{refname} plant: rod force on each mass")
        _linear_axis(ax)
        _side_legend(ax)
        units.append(f"{fprefix}N")
    zero_rows: list[str] = []
    for other in others:
        k = _common_samples(ref, other)
        t = ref.t[:k]
        panels = []  # (what, threshold name, curves, labels)
        if has_tau:
            tau_scale = max(
                float(np.max(np.linalg.norm(ref.torque[:k], axis=1), initial=0.0)),
                th["control_torque"].floor,
            )
            dtau = np.linalg.norm(other.torque[:k] - ref.torque[:k], axis=1) / tau_scale
            panels.append(("control torque", "control_torque", [dtau], ["‖Δτ‖₂ / max‖τ‖₂"]))
        if has_f:
            f_scale = max(
                float(np.max(np.abs(ref.rod_forces[:k]), initial=0.0)), th["rod_forces"].floor
            )
            curves = [
                np.abs(other.rod_forces[:k, i] - ref.rod_forces[:k, i]) / f_scale for i in range(n)
            ]
            labels = [f"|ΔF{str(i + 1).translate(_SUBSCRIPT)}| / max|F|" for i in range(n)]
            panels.append(("rod forces", "rod_forces", curves, labels))
        for what, th_name, curves, labels in panels:
            ax = axes[row]
            row += 1
            limit = th[th_name].value
            _log_axis(ax, [*curves, np.asarray([limit], float)])
            for j, (v, lab) in enumerate(zip(curves, labels, strict=True)):
                if not np.any(v):
                    zero_rows.append(f"{lab} of {other.engine}")
                    continue
                color = "tab:brown" if th_name == "control_torque" else colors[(3 + j) % 10]
                ax.plot(t, np.where(v > 0, v, np.nan), color=color, linewidth=1.0, label=lab)
            ax.axhline(limit, label="threshold", **THRESHOLD_STYLE)
            ax.set_ylabel("1 (relative)")
            _title(
                ax,
                f"{other.engine} − {refname}: {what}, relative to the {refname} plant's "
                "largest",
            )
            ax.grid(True, which="major", alpha=0.3)
            _side_legend(ax)
    axes[-1].set_xlabel("t (s)")
    _finish_axes(fig, axes)
    drawn = [
        x
        for x, on in (
            ("control torque τ (body axes)", has_tau),
            ("the rod force F_i on each mass", has_f),
        )
        if on
    ]
    sentences = [
        f"Control forces. Top: the {refname} plant's {' and '.join(drawn)}, in "
        f"{' and '.join(units)}; this plant is the reference."
    ]
    if not has_tau:
        sentences.append("No control torque is drawn: neither plant applies one.")
    if others:
        sentences.append(
            "Below, for each other plant, its distance from the reference relative to the "
            "reference's largest magnitude, one panel per force so that no curve hides another: "
            + " and ".join(
                x
                for x, on in (
                    ("‖τ − τ_ref‖₂ / max‖τ_ref‖₂", has_tau),
                    ("|F_i − F_ref,i| / max_i |F_ref,i|", has_f),
                )
                if on
            )
            + " (log axes; dotted black: the threshold). Drawn on the reference's axes, the other "
            "plants' forces would hide under its curves: they agree to these relative distances."
        )
    if zero_rows:
        sentences.append(f"Not drawn, identically zero: {'; '.join(zero_rows)}.")
    sentences.append(ctx.run_sentence())
    return Drawing("control", _caption(*sentences), fig)


__all__ = [
    "DEFAULT_FORMATS",
    "FIGURES",
    "PLANT_STYLE",
    "Drawing",
    "FigureContext",
    "FigureFormat",
    "figure_control",
    "figure_errors",
    "figure_invariants",
    "figure_tracking",
    "parse_formats",
    "plant_style",
]
