"""What a reviewer checks on every panel of a figure, as a function: no empty panel, no data
outside the axes that should hold it, no legend over the data, no axis stretched by runs that
never became stationary (:func:`unsteady_dominance`), no legend or categorical colour bar naming
what is not drawn (:func:`legend_ghosts`), and, across figures, no quantity in two units
(:func:`unit_conflicts`).

Only data drawn in data coordinates count (lines, markers, bands, images); reference lines and
spans drawn across the whole axis (``axhline``, ``axvspan``) and decorations do not. Axes turned
off (a schematic) and colour bars are not panels.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import Collection
from matplotlib.colors import BoundaryNorm, to_rgba
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D

#: Relative slack of the axis limits (a marker on the limit is inside).
SLACK = 1e-9
#: The ``gid`` a drawing function gives an artist whose points are runs that never became
#: stationary (not settled, still drifting): :func:`unsteady_dominance` weighs them apart.
NOT_STATIONARY = "not-stationary"
#: Largest share of an axis's span that runs never stationary may take beyond the stationary
#: data's own range before the axis counts as theirs.
UNSTEADY_SHARE = 0.5
#: Words of a legend label that say its artist is such runs (when no ``gid`` says so).
UNSTEADY_WORDS = ("not stationary", "never stationary", "not settled", "unsettled")


def _artist_points(ax: Axes, art) -> np.ndarray:
    """The finite data points of one artist drawn in ``ax``'s data coordinates, ``(n, 2)``."""
    in_data = art.get_transform() is ax.transData
    offsets = isinstance(art, Collection) and art.get_offset_transform() is ax.transData
    if not (in_data or offsets) or not art.get_visible():
        return np.empty((0, 2))
    if isinstance(art, Line2D):
        xy = np.column_stack(
            [np.asarray(art.get_xdata(), float), np.asarray(art.get_ydata(), float)]
        )
    elif isinstance(art, Collection):
        paths = art.get_paths()
        xy = np.vstack([p.vertices for p in paths]) if paths else np.empty((0, 2))
        offs = np.asarray(art.get_offsets(), float).reshape(-1, 2)
        if offsets and not in_data:
            xy = offs
    else:
        return np.empty((0, 2))
    return xy[np.all(np.isfinite(xy), axis=1)]


def _points(ax: Axes, keep=lambda art: True) -> np.ndarray:
    """The finite data points of every artist drawn in ``ax``'s data coordinates (those
    ``keep`` accepts), ``(n, 2)``."""
    pts = [_artist_points(ax, a) for a in [*ax.lines, *ax.collections] if keep(a)]
    return np.vstack(pts) if pts else np.empty((0, 2))


def _is_panel(ax: Axes) -> bool:
    return ax.axison and not hasattr(ax, "_colorbar")


def _outside(ax: Axes, pts: np.ndarray) -> int:
    """How many of ``pts`` lie outside the axis limits (on a log axis, also at or below 0)."""
    out = np.zeros(len(pts), bool)
    for j, (lo, hi), scale in (
        (0, ax.get_xlim(), ax.get_xscale()),
        (1, ax.get_ylim(), ax.get_yscale()),
    ):
        lo, hi = min(lo, hi), max(lo, hi)
        pad = SLACK * max(abs(lo), abs(hi), 1e-300)
        v = pts[:, j]
        out |= (v < lo - pad) | (v > hi + pad)
        if scale == "log":
            out |= v <= 0
    return int(out.sum())


def panel_problems(fig: Figure) -> list[str]:
    """Every panel of ``fig`` without data, or with data outside its limits, as a message.

    A panel has data when an artist in its data coordinates has a finite point or it shows an
    image. Data outside the limits are drawn nowhere: the axis does not hold its data.
    """
    problems = []
    for k, ax in enumerate(fig.axes):
        if not _is_panel(ax):
            continue
        name = ax.get_title() or ax.get_ylabel() or f"axes {k}"
        pts = _points(ax)
        if len(pts) == 0 and not any(isinstance(a, AxesImage) for a in ax.images):
            problems.append(f"{name}: empty (no data drawn)")
            continue
        n = _outside(ax, pts)
        if n:
            problems.append(f"{name}: {n} of {len(pts)} data points outside the axis limits")
    return problems


def legend_overlaps(fig: Figure) -> list[str]:
    """Every legend inside its panel that covers data points (in display coordinates)."""
    fig.draw_without_rendering()  # the layout, as saved
    problems = []
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None or not _is_panel(ax):
            continue
        box = legend.get_window_extent()
        pts = _points(ax)
        if not len(pts):
            continue
        shown = ax.transData.transform(pts)
        inside = (
            (shown[:, 0] > box.x0)
            & (shown[:, 0] < box.x1)
            & (shown[:, 1] > box.y0)
            & (shown[:, 1] < box.y1)
        )
        if inside.any():
            name = ax.get_title() or ax.get_ylabel()
            problems.append(f"{name}: the legend covers {int(inside.sum())} data points")
    return problems


def _unsteady(art) -> bool:
    """Whether an artist draws runs that never became stationary (its gid, else its label)."""
    if art.get_gid() == NOT_STATIONARY:
        return True
    label = str(art.get_label() or "").lower()
    return not label.startswith("_") and any(w in label for w in UNSTEADY_WORDS)


def _room(steady: np.ndarray, unsteady: np.ndarray, lo: float, hi: float, log: bool) -> float:
    """The share of the span ``[lo, hi]`` that ``unsteady`` values take beyond the range of
    ``steady`` ones (in log10 on a log axis)."""
    u = unsteady[(unsteady >= lo) & (unsteady <= hi)]
    if log:
        u, steady = u[u > 0], steady[steady > 0]
        if lo <= 0:
            return 0.0
    if not len(u) or not len(steady) or hi <= lo:
        return 0.0
    f = np.log10 if log else np.asarray
    room = max(0.0, float(f(steady.min()) - f(u.min()))) + max(
        0.0, float(f(u.max()) - f(steady.max()))
    )
    return room / float(f(hi) - f(lo))


def unsteady_dominance(fig: Figure) -> list[str]:
    """Every panel whose axis span is mostly the room taken by runs that never became
    stationary: beyond the stationary data's own range, they take more than
    :data:`UNSTEADY_SHARE` of the x or y span (the operating curve squashed into the rest)."""
    problems = []
    for k, ax in enumerate(fig.axes):
        if not _is_panel(ax):
            continue
        steady = _points(ax, lambda a: not _unsteady(a))
        unsteady = _points(ax, _unsteady)
        limits = ((ax.get_xlim(), ax.get_xscale()), (ax.get_ylim(), ax.get_yscale()))
        for j, ((lo, hi), scale) in enumerate(limits):
            lo, hi = sorted((lo, hi))
            share = _room(steady[:, j], unsteady[:, j], lo, hi, scale == "log")
            if share > UNSTEADY_SHARE:
                name = ax.get_title() or ax.get_ylabel() or f"axes {k}"
                problems.append(
                    f"{name}: runs never stationary take {100 * share:.0f} % of the {'xy'[j]} span"
                )
    return problems


def _colors_of(art) -> list[tuple]:
    """The RGBA colours an artist shows (line, marker faces and edges, collection faces and
    edges), with opaque alpha: a proxy matches its drawn artist whatever the transparency."""
    out = []
    if isinstance(art, Line2D):
        blank = ("None", "none", " ", "", None)
        if art.get_linestyle() in blank and art.get_marker() in blank:
            return []  # a text-only legend entry: no colour to match
        for c in (art.get_color(), art.get_markerfacecolor(), art.get_markeredgecolor()):
            if isinstance(c, str) and c == "none":
                continue
            out.append(to_rgba(c))
    elif isinstance(art, Collection):
        for arr in (art.get_facecolors(), art.get_edgecolors()):
            out += [tuple(c) for c in np.asarray(arr).reshape(-1, 4)]
    return [(round(r, 3), round(g, 3), round(b, 3)) for r, g, b, _a in out]


def _drawn_colors(fig: Figure) -> set[tuple]:
    """Every colour shown by an artist with finite data in a panel of ``fig``."""
    colors = set()
    for ax in fig.axes:
        if not _is_panel(ax):
            continue
        for art in [*ax.lines, *ax.collections]:
            if not art.get_visible():
                continue
            if isinstance(art, Collection) and art.get_array() is not None:
                colors |= _mapped_colors(art)
                continue
            if _is_drawn(ax, art):
                colors |= set(_colors_of(art))
    return colors


def _is_drawn(ax: Axes, art) -> bool:
    """Whether an artist shows anything: data points, or a reference line or band across the
    axis (``axvline``, ``axhspan``: not data, but drawn)."""
    if len(_artist_points(ax, art)):
        return True
    if isinstance(art, Line2D):
        xy = np.column_stack(
            [np.asarray(art.get_xdata(), float), np.asarray(art.get_ydata(), float)]
        )
        return bool(np.all(np.isfinite(xy), axis=1).any())
    if isinstance(art, Collection) and art.get_offset_transform() is not ax.transData:
        return any(len(p.vertices) for p in art.get_paths())  # a band, not markers at points
    return False


def _mapped_colors(art) -> set[tuple]:
    """The colours a colour-mapped collection (a scatter with ``c=``) shows."""
    values = np.ma.masked_invalid(np.asarray(art.get_array(), float)).compressed()
    if not values.size:
        return set()
    rgba = art.cmap(art.norm(values))
    return {(round(r, 3), round(g, 3), round(b, 3)) for r, g, b, _a in rgba}


def _legends(fig: Figure) -> list:
    return [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)


def legend_ghosts(fig: Figure) -> list[str]:
    """Every legend entry whose artist is not drawn (no finite point, and no drawn artist of
    its colour: a proxy entry must match something drawn), and every tick of a categorical
    colour bar (a :class:`~matplotlib.colors.BoundaryNorm`) whose class no cell shows."""
    drawn = _drawn_colors(fig)
    problems = []
    for legend in _legends(fig):
        for handle, text in zip(legend.legend_handles, legend.get_texts(), strict=False):
            if handle is None:
                continue
            colors = set(_colors_of(handle))
            if colors and not colors & drawn:
                problems.append(f"legend names {text.get_text()!r}, which is not drawn")
    for ax in fig.axes:
        cb = getattr(ax, "_colorbar", None)
        if cb is None or not isinstance(cb.mappable.norm, BoundaryNorm):
            continue
        values = np.ma.masked_invalid(np.asarray(cb.mappable.get_array(), float)).compressed()
        for tick, label in zip(cb.get_ticks(), cb.ax.get_yticklabels(), strict=False):
            if not np.any(np.isclose(values, tick)):
                problems.append(f"colour bar names {label.get_text()!r}, which no cell shows")
    return problems


_MATH = re.compile(r"\$[^$]*\$")
_UNIT = re.compile(r"\s*(\[([^\]]*)\]|\(([^)]*)\))\s*$")


def _quantity(label: str) -> tuple[str, str]:
    """``(quantity, unit)`` of an axis label ``NAME [UNIT]`` or ``NAME (UNIT)``: the words of
    the name (mathtext and case left out) and the unit as written, ``""`` without one."""
    m = _UNIT.search(label)
    unit = ""
    if m:
        unit = (m.group(2) if m.group(2) is not None else m.group(3)).strip()
        label = label[: m.start()]
    name = " ".join(_MATH.sub(" ", label).lower().split())
    return name, unit


def unit_conflicts(figures: Mapping[str, Figure]) -> list[str]:
    """Every quantity that two axis or colour-bar labels of ``figures`` (name -> figure) name
    alike but give in different units (``mean speed [rad/s]`` beside ``mean speed``): one
    quantity, one unit, across a set of figures a reader compares."""
    seen: dict[str, dict[str, str]] = {}
    for fig_name, fig in figures.items():
        for ax in fig.axes:
            for label in (ax.get_xlabel(), ax.get_ylabel()):
                name, unit = _quantity(label)
                if name:
                    seen.setdefault(name, {}).setdefault(unit, fig_name)
    return [
        f"{name!r} in {len(units)} units: "
        + ", ".join(f"{u or 'none'} ({where})" for u, where in units.items())
        for name, units in seen.items()
        if len(units) > 1
    ]
