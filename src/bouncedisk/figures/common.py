"""What every figure shares: colours, parameter labels, saving atomically."""

from __future__ import annotations

import math
from pathlib import Path

import xarray as xr
from matplotlib import rc_context, rcParams
from matplotlib.figure import Figure

from ..io.atomic import atomic_path

TWO_PI = 2 * math.pi
COLORS = {"rotor": "#1f77b4", "stator": "#7f7f7f", "fit": "#d62728", "data": "#2ca02c"}


def shade(ax, x, low, high, color, label: str | None = None, alpha: float = 0.25) -> None:
    """A shaded band between ``low`` and ``high`` over ``x`` (an interval, no edge line)."""
    ax.fill_between(x, low, high, color=color, alpha=alpha, lw=0, label=label)


def save_figure(fig: Figure, *paths: str | Path, dpi: int = 150) -> None:
    """Save ``fig`` to each path (format from the suffix), atomically, cropped to its content.

    The first save lays the figure out (its layout engine) and crops it to the tight box; the
    others reuse that layout and box (measured once, after the first save), so each further
    format costs one drawing where a save of its own lays out, measures and draws. After more
    than one path the figure keeps its layout and has no layout engine.
    """
    box = "tight"
    # no rc setting may bring a layout engine back between the saves (matplotlib restores the
    # engine it removes for a save through rcParams)
    with rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        for k, p in enumerate(paths):
            with atomic_path(p) as tmp:
                fig.savefig(tmp, dpi=dpi, format=Path(p).suffix.lstrip("."), bbox_inches=box)
            if k == 0 and len(paths) > 1:
                box = fig.get_tightbbox().padded(rcParams["savefig.pad_inches"])
                fig.set_layout_engine(None)  # no engine: the layout stays as drawn


def _param(ds: xr.Dataset, name: str) -> float:
    """A parameter from the attributes, or from a scalar coordinate (a slice of a sweep)."""
    if name in ds.attrs:
        return float(ds.attrs[name])
    if name in ds.coords and ds[name].size == 1:
        return float(ds[name].values)
    return math.nan


def _title(ds: xr.Dataset) -> str:
    a = ds.attrs
    return (
        f"e = {a.get('e'):.3g}, $\\omega_s$ = {a.get('omega_s'):.3g}, "
        f"$R_\\phi$ = {a.get('r_phi'):.3g}, $\\psi$ = {a.get('psi'):.3g}"
    )


def inadequate_note(attrs: dict) -> str:
    """A fit figure's title line for an inadequate fit (its ``fit_adequate`` 0: the best point
    does not reproduce the data, docs/fitting_method.md), else empty."""
    if attrs.get("fit_adequate", 1):
        return ""
    return (
        f"\nFIT INADEQUATE: χ² {attrs.get('chi2', float('nan')):.4g} on "
        f"{attrs.get('n_statistics', '?')} statistics (p = {attrs.get('chi2_p_value', float('nan')):.2g})"
    )
