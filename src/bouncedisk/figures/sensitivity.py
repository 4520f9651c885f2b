"""The global sensitivity study: Sobol' indices, scatter, design maps."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from .dynamics import REGIME_COLORS
from .joint_fit import COORDINATES

#: The outputs as the figures write them (one convention: speeds and powers times R_phi).
LABELS = {
    "no_load_speed": r"no-load speed $R_\phi\bar\Omega$",
    "log10_tau": r"$\log_{10}\tau$ (run-up)",
    "chatter_rate": "chatter rate",
    "stall_torque": r"stall torque $\tau_L$",
    "max_power": r"max. power $R_\phi\tau_L\bar\Omega$",
    "efficiency_at_max_power": "efficiency at max. power",
}


#: An index beyond [0, 1] by more than this is named in its panel (every one is drawn clipped).
CLIP_NOTE = 0.02


def _short(output: str) -> str:
    """An output's name as an axis label."""
    return LABELS.get(output, output.replace("_", " "))


def _parameter(name: str) -> str:
    """A sampled parameter as the figures write it (the fit's coordinates' labels)."""
    return COORDINATES[name][0] if name in COORDINATES else name


def fig_sensitivity_indices(ds: xr.Dataset) -> Figure:
    """First-order and total Sobol' indices of every output with their 95 % bootstrap intervals,
    the sample size and the share of each output's variance that is ensemble noise. An index
    whose interval is wider than ``±resolved_half_width`` is drawn grey (not resolved). The
    title says when the load figures are in each motor's own running direction (attribute
    ``load_direction``, :class:`bouncedisk.studies.sensitivity.MotorModel`)."""
    outputs = ds["output"].values.tolist()
    names = ds["parameter"].values.tolist()
    ncol = min(3, len(outputs))
    nrow = math.ceil(len(outputs) / ncol)
    fig = Figure(figsize=(4.6 * ncol, 3.4 * nrow), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False).ravel())
    pos = np.arange(len(names))
    limit = float(ds.attrs.get("resolved_half_width", math.inf))
    for ax, o in zip(axes, outputs, strict=False):
        row = ds.sel(output=o)
        clipped = []
        for k, (key, color) in enumerate((("S1", "#1f77b4"), ("ST", "#ff7f0e"))):
            conf, value = row[f"{key}_conf"].values, row[key].values
            colors = [color if c <= limit else "#bbbbbb" for c in conf]
            shown = np.clip(value, 0.0, 1.0)  # an index is a share of the variance: in [0, 1]
            x = pos + (k - 0.5) * 0.38
            ax.bar(x, shown, 0.38, color=colors, label=key)
            ax.errorbar(
                x,
                shown,
                yerr=[
                    shown - np.clip(value - conf, -0.1, 1.1),
                    np.clip(value + conf, -0.1, 1.1) - shown,
                ],
                fmt="none",
                ecolor="k",
                capsize=3,
                lw=0.8,
            )
            out = np.flatnonzero((value > 1.0 + CLIP_NOTE) | (value < -CLIP_NOTE))
            clipped += [
                f"{key}({_parameter(names[i])}) = {value[i]:.2f} ±{conf[i]:.2f}" for i in out
            ]
        share = float(row["noise_share"])
        undefined = int(row["n_undefined"])
        note = f"ensemble noise: {100 * share:.1f} % of the variance"
        if undefined:
            analysed = np.isfinite(row["ST"].values).any()
            note = (
                f"undefined at {undefined} points (their base samples left out)\n{note}"
                if analysed
                else f"undefined at {undefined} points: no indices"
            )
        ax.set_title(f"{_short(o)}\n{note}", fontsize=9)
        ax.set_xticks(pos, [_parameter(n) for n in names], fontsize=8)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylim(-0.12, 1.12)
        if clipped:
            ax.text(
                0.5,
                0.02,
                "drawn clipped to [0, 1]: " + "; ".join(clipped),
                transform=ax.transAxes,
                fontsize=6,
                ha="center",
                va="bottom",
            )
    for ax in axes[len(outputs) :]:
        ax.set_visible(False)
    handles = [
        Rectangle((0, 0), 1, 1, color=c, label=lab)
        for c, lab in (
            ("#1f77b4", "S1 (RBD-FAST)"),
            ("#ff7f0e", "ST (Jansen)"),
            ("#bbbbbb", f"not resolved (half-width > {limit:g})"),
        )
    ]
    axes[0].legend(handles=handles, fontsize=7, loc="upper left")
    axes[0].set_ylabel("Sobol' index (95 % bootstrap interval)")
    n = ds.attrs.get("n_points", "?")
    base = int(n) // (len(names) + 2) if str(n).isdigit() else "?"
    running = str(ds.attrs.get("load_direction", "")).startswith("running")
    from ..studies.sensitivity_settings import FULL_MIN_BASE_SAMPLES

    small = not isinstance(base, int) or base < FULL_MIN_BASE_SAMPLES
    fig.suptitle(
        f"Sobol' indices from {n} points (SALib, N = {base} base samples); "
        f"grey: interval wider than ±{limit:g}; indices outside [0, 1] drawn clipped"
        + (
            "\nthe total indices are resolved only by the full study (config sensitivity: full)"
            if small
            else ""
        )
        + (
            "\nstall torque, power, efficiency: each motor loaded against its own "
            "running direction ($\\psi \\to \\psi + \\pi$ mirrors it)"
            if running
            else ""
        ),
        fontsize=10,
    )
    return fig


def fig_sensitivity_scatter(ds: xr.Dataset) -> Figure:
    """Each output against each sampled parameter, every point coloured by its regime."""
    from ..analysis.observables import REGIMES

    outputs = [o for o in str(ds.attrs["outputs"]).split(",") if o]
    names = ds["parameter"].values.tolist()
    fig = Figure(figsize=(3.0 * len(names), 2.3 * len(outputs)), layout="constrained")
    axes = fig.subplots(len(outputs), len(names), squeeze=False)
    regime = ds["regime"].values
    colors = [REGIME_COLORS.get(int(c), "k") for c in regime]
    for i, o in enumerate(outputs):
        for j, p in enumerate(names):
            ax = axes[i, j]
            ax.scatter(ds["x"].sel(parameter=p).values, ds[o].values, s=5, c=colors, lw=0)
            if i == len(outputs) - 1:
                ax.set_xlabel(_parameter(p))
            if j == 0:
                ax.set_ylabel(_short(o), fontsize=8)
    handles = [
        Rectangle((0, 0), 1, 1, color=REGIME_COLORS[c], label=REGIMES[c])
        for c in sorted(set(int(c) for c in regime))
    ]
    fig.legend(handles=handles, loc="outside upper center", ncol=len(handles), fontsize=8)
    return fig


def fig_design_maps(ds: xr.Dataset) -> Figure:
    """No-load speed, stall torque and efficiency over ``(psi, log10 R_phi)`` for each map's
    ``e``, with the best operating point and its 95 % interval (hollow: not resolved from it).

    Where the motor runs backwards at no load (mean speed ``<= 0``) its stall torque and
    efficiency are not figures of a motor: those cells are crossed out; a stall beyond the
    largest load asked for is undefined (blank) and ringed."""
    from ..studies.sensitivity import BEST_BY, MAP_OUTPUTS, best_point

    outputs = [o for o in MAP_OUTPUTS if o in ds]
    n_psi, n_r = int(ds.attrs["map_n_psi"]), int(ds.attrs["map_n_r_phi"])
    maps = [ds.isel(map=k) for k in range(ds.sizes["map"])]
    best_by = next(b for b in BEST_BY if b in ds)
    w = ds.attrs.get("map_omega_s")
    w_label = rf"$\omega_s$ = {float(w):g}" if w is not None else ""
    fig = Figure(figsize=(4.8 * len(maps), 3.4 * len(outputs) + 0.4), layout="constrained")
    axes = fig.subplots(len(outputs), len(maps), squeeze=False)
    rings, edge = False, False
    for j, m in enumerate(maps):
        xp, xr_ = (m["x"].sel(parameter=p).values for p in ("psi", "log10_r_phi"))
        psi, lr = xp.reshape(n_psi, n_r)[:, 0], xr_.reshape(n_psi, n_r)[0]
        best = best_point(m, best_by)
        backwards = m["no_load_speed"].values <= 0.0
        for i, o in enumerate(outputs):
            ax = axes[i, j]
            z = m[o].values
            if o != "no_load_speed":
                z = np.where(backwards, np.nan, z)
                ax.scatter(xp[backwards], xr_[backwards], marker="x", c="k", s=18, lw=0.8)
            beyond = ~np.isfinite(m[o].values) & ~backwards
            rings |= bool(beyond.any())
            ax.scatter(
                xp[beyond], xr_[beyond], marker="o", s=30, facecolors="none", edgecolors="k", lw=0.8
            )
            mesh = ax.pcolormesh(
                psi, lr, z.reshape(n_psi, n_r).T, shading="nearest", cmap="viridis"
            )
            fig.colorbar(mesh, ax=ax, label=_short(o))
            if best["index"] is not None:
                near = [k for k in best["indistinguishable"] if k != best["index"]]
                ax.scatter(xp[near], xr_[near], s=14, facecolors="none", edgecolors="w", lw=0.7)
                ax.plot(xp[best["index"]], xr_[best["index"]], "r*", ms=12)
            ax.set_xlabel(r"$\psi$ (rad)")
            ax.set_ylabel(r"$\log_{10} R_\phi$")
            ax.set_title(f"e = {float(m['map_e']):g}, {w_label}", fontsize=9)
        if best["index"] is not None:
            lo, hi = best["ci95"]
            i = best["index"]
            at_edge = xr_[i] in (xr_.min(), xr_.max()) or xp[i] in (xp.min(), xp.max())
            edge |= bool(at_edge)
            where = "\n(at the edge of the swept range)" if at_edge else ""
            # in the half of the panel away from the star, so that it never covers it
            low_star = xr_[i] - xr_.min() < 0.5 * (xr_.max() - xr_.min())
            axes[0, j].text(
                0.02,
                0.98 if low_star else 0.02,
                f"best {_short(best_by)}: {best['value']:.3g} [{lo:.3g}, {hi:.3g}]{where}",
                transform=axes[0, j].transAxes,
                va="top" if low_star else "bottom",
                fontsize=7,
                color="w",
                bbox={"facecolor": "k", "alpha": 0.4, "lw": 0, "pad": 1},
                in_layout=False,  # inside the axes: the layout must not shrink them for it
            )
    # one map: a clause per line, the figure being one panel wide
    sep = "\n" if len(maps) == 1 else "; "
    fig.suptitle(
        f"red star: largest {_short(best_by)}"
        + (f"{sep}(at the edge: the maximum may lie outside the swept range)" if edge else "")
        + f"{sep}white rings: points whose 95 % interval reaches it\nx: runs backwards at no load"
        + (f"{sep}black ring: no stall up to the largest load" if rings else "")
        + f"\nspeeds and powers times $R_\\phi$ (units $\\Phi_0/t_c$){sep}the torque–speed "
        "curves draw $\\bar\\Omega$ and $\\tau_L\\bar\\Omega$, these divided by $R_\\phi$",
        fontsize=8,
    )
    return fig
