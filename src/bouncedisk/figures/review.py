"""What a reviewer checks on every panel of a figure, as a function: no empty panel, no data
outside the axes that should hold it, no legend over the data.

Only data drawn in data coordinates count (lines, markers, bands, images); reference lines and
spans drawn across the whole axis (``axhline``, ``axvspan``) and decorations do not. Axes turned
off (a schematic) and colour bars are not panels.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import Collection
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D

#: Relative slack of the axis limits (a marker on the limit is inside).
SLACK = 1e-9


def _points(ax: Axes) -> np.ndarray:
    """The finite data points of every artist drawn in ``ax``'s data coordinates, ``(n, 2)``."""
    pts = []
    for art in [*ax.lines, *ax.collections]:
        in_data = art.get_transform() is ax.transData
        offsets = isinstance(art, Collection) and art.get_offset_transform() is ax.transData
        if not (in_data or offsets) or not art.get_visible():
            continue
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
            continue
        pts.append(xy[np.all(np.isfinite(xy), axis=1)])
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
