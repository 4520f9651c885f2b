"""Figures of coexisting motions (``bouncedisk basins``; docs/formats.md "Basins file"): the basin
map over the starts, and the start-up under load with its 95 % Wilson band."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from .common import shade

#: Colour of the starts that have not settled within the window (label -1).
UNSETTLED = "0.75"


def _axis(ds: xr.Dataset) -> tuple[str, str]:
    """The map's vertical axis: the initial speed, or the height when one speed is given."""
    if np.asarray(ds.attrs.get("speeds", [0.0])).size > 1:
        return "speed", r"initial rotor speed $\Omega_0$"
    return "height", "initial height above the stator"


def _entry(ax, color: str, text: str, drawn: bool, why: str) -> None:
    """A legend entry: a square of ``color`` when starts of that colour are drawn, else the
    text alone with ``why`` (a legend names nothing that is not drawn)."""
    if drawn:
        ax.scatter([], [], color=color, marker="s", label=text)
    else:
        ax.plot([], [], ls="none", marker="none", label=f"{text} ({why})")


def fig_basin_map(ds: xr.Dataset) -> Figure:
    """The basin map: every start over (stator phase at switch-on, initial speed or height),
    coloured by the attractor it reaches (grey: not settled), the first height (or speed) only;
    the legend gives each attractor's mean speed, regime and basin fraction with its interval."""
    from ..analysis.observables import REGIMES

    name, ylabel = _axis(ds)
    other = "height" if name == "speed" else "speed"
    sel = ds["start"].values[ds[other].values == ds[other].values.min()]
    sub = ds.sel(start=sel)
    n_att = int(ds.sizes.get("attractor", 0))
    colors = [UNSETTLED] + [f"C{k % 10}" for k in range(n_att)]
    cmap = ListedColormap(colors)
    norm = BoundaryNorm(np.arange(-1.5, n_att + 0.5), cmap.N)
    fig = Figure(figsize=(7.5, 4.6), layout="constrained")
    ax = fig.subplots()
    x = sub["phase"].values
    y = sub[name].values
    drawn = set(sub["label"].values.tolist())
    ax.scatter(x, y, c=sub["label"].values, cmap=cmap, norm=norm, s=40, marker="s")
    for k in range(n_att):
        a = ds.sel(attractor=k)
        lo, hi = float(a["attractor_fraction_ci95_low"]), float(a["attractor_fraction_ci95_high"])
        reg = REGIMES[int(a["attractor_regime"])]
        p, q = int(a["attractor_period_p"]), int(a["attractor_period_q"])
        reg += f" {p}/{q}" if p else ""
        text = (
            f"{k}: speed {float(a['attractor_mean_speed']):.4g}, {reg}, "
            f"{float(a['attractor_fraction']):.2f} [{lo:.2f}, {hi:.2f}]"
        )
        _entry(ax, colors[k + 1], text, k in drawn, "reached from none of the starts drawn")
    u = ds.attrs.get("unsettled_fraction", np.nan)
    ulo, uhi = np.ravel(ds.attrs.get("unsettled_fraction_ci95", [np.nan, np.nan]))
    text = f"not settled: {u:.2f} [{ulo:.2f}, {uhi:.2f}]"
    _entry(ax, UNSETTLED, text, -1 in drawn, "none among the starts drawn")
    ax.set_xlabel("stator phase at switch-on [rad]")
    ax.set_ylabel(ylabel)
    ax.set_xlim(-0.2, 2 * np.pi)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.15), ncol=1)
    load = ds.attrs.get("load_torque", 0.0)
    _title(
        ax,
        ds,
        f"Basins: e = {ds.attrs.get('e', np.nan):.3g}, load {load:.3g}",
        "starts",
        "fractions with 95% Wilson intervals",
    )
    return fig


def fig_startup(ds: xr.Dataset) -> Figure:
    """Start-up under load: the fractions of starts from rest that settle on the fast branch and
    on a slower one (the slow branch) against the load torque, with their 95 % Wilson bands, and
    the fraction not settled."""
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.subplots()
    load = ds["load_torque"].values
    fast = f"{ds.attrs.get('fast_above', np.nan):g}"
    curves = [
        ("fast_fraction", "C0", rf"settled on the fast branch (mean speed $\geq$ {fast})"),
        ("slow_fraction", "C1", f"settled on the slow branch (mean speed < {fast})"),
        ("unsettled_fraction", "0.5", "not settled within the longest window"),
    ]
    for name, color, label in (c for c in curves if c[0] in ds):
        shade(ax, load, ds[f"{name}_ci95_low"], ds[f"{name}_ci95_high"], color)
        ax.plot(load, ds[name], "o-", ms=3, lw=1.0, color=color, label=label)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(r"load torque $\tau_L$")
    ax.set_ylabel("fraction of starts from rest")
    ax.legend(fontsize=8)
    head = (
        f"Start-up under load: e = {ds.attrs.get('e', np.nan):.3g}, "
        f"$\\omega_s$ = {ds.attrs.get('omega_s', np.nan):.4g}"
    )
    _title(ax, ds, head, "starts per load", "95% Wilson bands")
    return fig


def _title(ax, ds: xr.Dataset, head: str, starts: str, bands: str) -> None:
    """``head, N <starts>, window [a, b]`` (doubled up to ``2^extend`` times for a start not
    settled in it) ``(<bands>)`` over ``ax``."""
    window = np.ravel(ds.attrs.get("window", [np.nan, np.nan]))
    extend = int(ds.attrs.get("extend", 0))
    longer = f", doubled up to {2**extend}x until settled" if extend else ""
    ax.set_title(
        f"{head}, {ds.sizes['start']} {starts}\nwindow [{window[0]:g}, {window[1]:g}]{longer} "
        f"({bands})",
        fontsize=9,
    )
