"""Dynamics: Poincaré maps, bifurcation diagrams, regime maps, speed against ψ, the clipped
comparison.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from .common import COLORS, TWO_PI, _param, shade

#: A cloud of thousands of points (a map's every impact or period): small, translucent, and one
#: image in the PDF rather than a path per point (a path each is most of the PDF's drawing time).
CLOUD = {"ms": 1.2, "mew": 0, "alpha": 0.6, "rasterized": True}


def fig_poincare(datasets: dict[str, xr.Dataset]) -> Figure:
    """Impact maps (phase vs relative impact velocity) and stroboscopic maps, one column each."""
    fig = Figure(figsize=(4.2 * len(datasets), 7.5), layout="constrained")
    axes = fig.subplots(2, len(datasets), squeeze=False)
    for j, (label, ds) in enumerate(datasets.items()):
        impacts = ds["kind"].values == 0 if "kind" in ds else slice(None)
        ax = axes[0, j]
        n = int(np.size(ds["phase"].values[impacts]))
        ax.plot(
            ds["phase"].values[impacts],
            ds["v_rel"].values[impacts],
            ".",
            color="k",
            label=f"all {n} impacts",
            **CLOUD,
        )
        ax.plot(
            ds["phase"].values[impacts][-50:],
            ds["v_rel"].values[impacts][-50:],
            "o",
            ms=3,
            color=COLORS["fit"],
            label="last 50 impacts",
        )
        ax.set_xlim(0, TWO_PI)
        ax.set_xlabel(r"impact phase $\omega_s t$ mod $2\pi$")
        ax.set_ylabel(r"relative impact velocity $v_s - v^-$")
        ax.set_title(f"impact map, {label}", fontsize=10)
        ax.legend(
            fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.16), ncol=2, markerscale=2
        )  # below the axis: the map fills the panel
        ax = axes[1, j]
        if "strobe_u" in ds:
            su, sv = ds["strobe_u"].values, ds["strobe_v"].values
            ax.plot(su, sv, ".", color=COLORS["rotor"], label=f"all {su.size} periods", **CLOUD)
            ax.plot(su[-50:], sv[-50:], "o", ms=3, color=COLORS["fit"], label="last 50 periods")
            ax.margins(0.08)
            ax.legend(
                fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.16), ncol=2, markerscale=2
            )
        ax.set_xlabel("rotor position at phase 0")
        ax.set_ylabel("rotor velocity at phase 0")
        ax.set_title(f"stroboscopic map, {label}", fontsize=10)
    return fig


def _param_where(gamma_of_e, target: float) -> float:
    """``e`` in (0, 1) where the decreasing threshold ``gamma_of_e(e)`` equals ``target``."""
    from scipy.optimize import brentq

    f = lambda e: gamma_of_e(e) - target  # noqa: E731
    return brentq(f, 1e-9, 1 - 1e-9) if f(1e-9) > 0 > f(1 - 1e-9) else math.nan


def fig_bifurcation(up: xr.Dataset, down: xr.Dataset) -> Figure:
    """Impact phase against ``e`` by continuation up and down, with the Lyapunov exponent.

    Coexisting attractors appear as two branches; complete chatters (resets) are marked ×.
    The exponent is the ensemble mean with its 95 % interval; a cycle through a reset has
    exponent ``−∞`` (drawn as ▼ at the bottom). Dashed lines: the period-1 orbit's existence
    ``Γ_1 = π(1−e)/(1+e)`` and its doubling (docs/model.md "Classic results") at ``Γ = ω_s²``.
    """
    from ..analysis.observables import period_doubling_threshold, period_n_threshold

    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    ax, ax2 = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1.3])
    w = _param(up, "omega_s")
    styles = {"up": ("k", "sweep up"), "down": ("#e6550d", "sweep down")}
    for ds, key in ((up, "up"), (down, "down")):
        color, label = styles[key]
        e = ds["e"].values
        ph = ds["phase"].values
        chat = ds["is_chatter"].values.astype(bool)
        ee = np.broadcast_to(e[:, None], ph.shape)
        imp = ~chat & np.isfinite(ph)
        ax.plot(ee[imp], ph[imp], "o", color=color, label=label, **CLOUD)
        ax.plot(
            ee[chat],
            ph[chat],
            "x",
            ms=4,
            mew=0.8,
            color="#3182bd",
            label="complete chatter (reset)" if key == "up" else None,
        )
        lam = ds["lyapunov"].values
        shade(
            ax2, e, ds["lyapunov_ci_low"].values, ds["lyapunov_ci_high"].values, color, alpha=0.25
        )
        ax2.plot(e, lam, "-", color=color, lw=0.8, label=f"{label}, mean and 95% interval")
        reset = ds["lyapunov_reset_fraction"].values > 0.5
        down_label = f"{label}: −∞ (most members reset every cycle)"
        ax2.plot(e[reset], np.full(reset.sum(), -2.4), "v", ms=3, color=color, label=down_label)
    top = max(float(np.nanmax(ds["lyapunov_ci_high"].values, initial=0.0)) for ds in (up, down))
    g = w * w
    e1 = _param_where(lambda e: period_n_threshold(1, e), g)
    epd = _param_where(lambda e: period_doubling_threshold(1, e), g)
    thresholds = (
        (e1, r"$\Gamma_1$", "exists"),
        (epd, r"$\Gamma_{PD}$", "has doubled"),
    )
    for x, text, meaning in thresholds:
        if math.isfinite(x):
            ax.axvline(
                x,
                color="0.4",
                lw=0.7,
                ls="--",
                label=f"{text}(e) = $\\Gamma$ at e = {x:.3g}: period-1 {meaning} to its right",
            )
            ax2.axvline(x, color="0.4", lw=0.7, ls="--")
            ax.text(x + 0.004, 3.0, text, ha="left", va="center", fontsize=8, color="0.3")
    ax.set_ylim(0, TWO_PI)
    ax.set_ylabel(r"impact phase $\omega_s t$ mod $2\pi$")
    ax.set_title(
        f"bifurcation diagram by continuation, $\\omega_s$ = {w:.3g} ($\\Gamma$ = {g:.3g})",
        fontsize=10,
    )
    # above the panel: the phases fill it at every e
    fig.legend(
        *ax.get_legend_handles_labels(),
        loc="outside upper center",
        ncol=3,
        fontsize=7,
        markerscale=3,
    )
    ax2.axhline(0, color="k", lw=0.6)
    ax2.set_ylim(-2.6, max(1.5, 1.05 * top))  # holds every interval (the ▼ row at -2.4)
    ax2.set_ylabel("Lyapunov exponent\n(per impact; ▼ = −∞)")
    ax2.set_xlabel("coefficient of restitution $e$")
    # below the panel: the exponents fill it from the left edge to the right
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.32), ncol=2, fontsize=7)
    return fig


REGIME_COLORS = {
    0: "#bdbdbd",
    1: "#4daf4a",
    2: "#377eb8",
    3: "#ff7f00",
    4: "#e41a1c",
    5: "#984ea3",
}


#: Colour of the regime map's cells whose exponent is −∞ (reset every cycle): not a grey, which
#: the regime panel gives to ``unresolved``.
RESET_COLOR = "k"


def fig_regime_map(ds: xr.Dataset) -> Figure:
    """Regimes over ``(e, omega_s)``, the Lyapunov exponent and the chatter rate (ensembles).

    The regime panel's colour bar lists only the regimes that occur; the exponent panel draws
    an exponent of −∞ (no finite mean: a member reset every cycle) black, unlike any regime."""
    from ..analysis.observables import REGIMES

    fig = Figure(figsize=(15.0, 4.6), layout="constrained")
    ax, ax2, ax3 = fig.subplots(1, 3)
    e = ds["e"].values
    w = ds["omega_s"].values
    reg = ds["regime"].transpose("omega_s", "e").values
    codes = [c for c in sorted(REGIME_COLORS) if np.any(reg == c)]  # the classes drawn only
    cmap = ListedColormap([REGIME_COLORS[c] for c in codes])
    norm = BoundaryNorm(np.arange(-0.5, len(codes) + 0.5), cmap.N)
    index = np.searchsorted(codes, reg)  # each cell's class, as its place in the colour bar
    m = ax.pcolormesh(e, w, index, cmap=cmap, norm=norm, shading="nearest")
    cb = fig.colorbar(m, ax=ax, ticks=range(len(codes)))
    cb.ax.set_yticklabels([REGIMES[c] for c in codes], fontsize=7)
    per = ds["period_p"].transpose("omega_s", "e").values
    for i, wi in enumerate(w):
        for j, ej in enumerate(e):
            if reg[i, j] == 1 and per[i, j] > 1 and len(e) <= 40:
                ax.text(ej, wi, str(int(per[i, j])), ha="center", va="center", fontsize=5)
    members = ds.attrs.get("ensemble_members", "?")
    ax.set_title(
        f"regime, most common of {members} members (numbers: impacts per cycle)", fontsize=9
    )
    lam = ds["lyapunov"].transpose("omega_s", "e").values
    vmax = np.nanmax(np.abs(lam)) if np.isfinite(lam).any() else 1.0
    m2 = ax2.pcolormesh(e, w, lam, cmap="RdBu_r", vmin=-vmax, vmax=vmax, shading="nearest")
    fig.colorbar(m2, ax=ax2, label="Lyapunov exponent per impact (ensemble mean)")
    ax2.set_facecolor(RESET_COLOR)  # the cells without a finite mean
    ax2.set_title(
        "Lyapunov exponent between resets (black: every member resets every cycle, −∞)",
        fontsize=9,
    )
    rate = ds["chatter_rate"].transpose("omega_s", "e").values
    m3 = ax3.pcolormesh(e, w, rate, cmap="viridis", shading="nearest")
    fig.colorbar(m3, ax=ax3, label="complete chatters per unit time (ensemble mean)")
    ax3.set_title("chatter rate", fontsize=9)
    for a in (ax, ax2, ax3):
        a.set_xlabel("coefficient of restitution $e$")
        a.set_ylabel(r"stator frequency $\omega_s$")
    return fig


def fig_speed_vs_psi(ds: xr.Dataset) -> Figure:
    """Ensemble-mean rotor speed ``R_φ Ω̄`` against ``psi`` for several ``r_phi``, 95 % bands."""
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    psi = ds["psi"].values
    for r in ds["r_phi"].values:
        sel = ds.sel(r_phi=r)
        line = ax.plot(
            psi, r * sel["mean_omega"].values, ".-", lw=1, ms=3, label=f"$R_\\phi$ = {r:g}"
        )[0]
        shade(
            ax,
            psi,
            r * sel["mean_omega_ci_low"].values,
            r * sel["mean_omega_ci_high"].values,
            line.get_color(),
            alpha=0.3,
        )
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel(r"torsional phase $\psi$ [rad]")
    ax.set_ylabel(r"mean rotor speed $R_\phi\bar\Omega$ (stator units)")
    members = ds.attrs.get("ensemble_members", "?")
    r = ds["r_phi"]
    half = float(np.nanmax(r * (ds["mean_omega_ci_high"] - ds["mean_omega_ci_low"]) / 2))
    ax.set_title(
        f"motor curve: e = {_param(ds, 'e'):.3g}, $\\omega_s$ = {_param(ds, 'omega_s'):.3g}; "
        "bands: 95% "
        f"interval over {members} members (half-width at most {half:.2g})",
        fontsize=9,
    )
    ax.legend(fontsize=8)
    return fig


def fig_clipped_vs_bouncing(ds: xr.Dataset) -> Figure:
    """Rotor speed of the bouncing model beside the clipped-sinusoid spring-contact model."""
    psis = ds["psi"].values
    fig = Figure(figsize=(8.0, 2.6 * len(psis)), layout="constrained")
    axes = fig.subplots(len(psis), 1, sharex=True, squeeze=False)[:, 0]
    t = ds["time"].values
    for ax, p in zip(axes, psis, strict=True):
        if "omega_bouncing_ci_low" in ds:
            b = ds.sel(psi=p)
            shade(
                ax,
                t,
                b["omega_bouncing_p025"],
                b["omega_bouncing_p975"],
                "0.6",
                "bouncing: central 95% of members",
                alpha=0.3,
            )
            shade(
                ax,
                t,
                b["omega_bouncing_ci_low"],
                b["omega_bouncing_ci_high"],
                COLORS["rotor"],
                "bouncing: 95% interval of the ensemble mean",
                alpha=0.5,
            )
        for model, color in (("bouncing", COLORS["rotor"]), ("clipped", COLORS["fit"])):
            ax.plot(
                t,
                ds["omega_rotor"].sel(model=model, psi=p).values,
                color=color,
                lw=0.8,
                label=f"{model} model" + (" (one run)" if model == "bouncing" else ""),
            )
        ax.set_ylabel(r"$\Omega$")
        ax.set_title(f"$\\psi$ = {p:.3g}", fontsize=10)
    axes[-1].set_xlabel("time $t/t_c$")
    # one legend for every panel, below them: the runs fill each panel's corners
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=7)
    fig.suptitle(
        "bouncing disk vs clipped spring contact (refs. [2, 3] of the paper): "
        f"e = {_param(ds, 'e'):.3g}, $\\omega_s$ = {_param(ds, 'omega_s'):.3g}",
        fontsize=10,
    )
    return fig
