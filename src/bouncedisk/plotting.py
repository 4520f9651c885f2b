"""Figures: one function per figure, each a pure function of Datasets returning a Figure.

Figures are built on :class:`matplotlib.figure.Figure` (no pyplot state), so they work under any
backend; :func:`save_figure` writes PDF and PNG atomically.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, FancyArrowPatch, Rectangle
from matplotlib.ticker import NullFormatter

from .atomic import atomic_path
from .datasets import open_checked, open_simulation
from .figure_registry import FIGURES as DECLARED
from .figure_registry import FigureDecl
from .plot_fit_load import fig_fit_identifiability, fig_fit_load  # noqa: F401  (through FIGURES)
from .plot_load import fig_torque_speed  # noqa: F401  (drawn through FIGURES)

TWO_PI = 2 * math.pi
COLORS = {"rotor": "#1f77b4", "stator": "#7f7f7f", "fit": "#d62728", "data": "#2ca02c"}


def save_figure(fig: Figure, *paths: str | Path, dpi: int = 150) -> None:
    """Save ``fig`` to each path (format from the suffix), atomically."""
    for p in paths:
        with atomic_path(p) as tmp:
            fig.savefig(tmp, dpi=dpi, format=Path(p).suffix.lstrip("."), bbox_inches="tight")


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
        f"e = {a.get('e'):.3g}, ω_s = {a.get('omega_s'):.3g}, R_φ = {a.get('r_phi'):.3g}, "
        f"ψ = {a.get('psi'):.3g}"
    )


def fig2_schematic() -> Figure:
    """Paper Fig. 2: the stator–rotor interface, the rotor simplified as a bouncing disk."""
    fig = Figure(figsize=(6.0, 4.2))
    ax = fig.add_subplot()
    ax.set_xlim(-3, 3)
    ax.set_ylim(-2.6, 2.4)
    ax.set_aspect("equal")
    ax.axis("off")
    # pretwisted beam (stator) and its tip
    ax.add_patch(Rectangle((-0.6, -2.5), 1.2, 2.0, fc="#d9d9d9", ec="k"))
    for y in np.linspace(-2.4, -0.6, 7):
        ax.plot([-0.6, 0.6], [y, y + 0.25], color="#9e9e9e", lw=0.8)
    ax.add_patch(Rectangle((-1.2, -0.5), 2.4, 0.35, fc="#bdbdbd", ec="k"))
    # rotor disk in flight above the stator
    ax.add_patch(Ellipse((0, 0.55), 3.4, 0.5, fc="#9ecae1", ec="k"))
    ax.add_patch(Rectangle((-1.7, 0.55), 3.4, 0.45, fc="#9ecae1", ec="none"))
    ax.add_patch(Ellipse((0, 1.0), 3.4, 0.5, fc="#c6dbef", ec="k"))
    ax.plot([-1.7, -1.7], [0.55, 1.0], "k", lw=1)
    ax.plot([1.7, 1.7], [0.55, 1.0], "k", lw=1)
    # contact radius on the stator face
    ax.annotate("", xy=(1.2, -0.32), xytext=(0, -0.32), arrowprops=dict(arrowstyle="<->", lw=1))
    ax.text(0.6, -0.28, "$r_c$", ha="center", va="bottom", fontsize=10)

    def arrow(x0, y0, x1, y1, **kw):
        ax.add_patch(FancyArrowPatch((x0, y0), (x1, y1), mutation_scale=12, lw=1.4, **kw))

    arrow(-2.3, -1.3, -2.3, -0.3, arrowstyle="<->", color="k")
    ax.text(-2.45, -0.8, r"$u_s = U_0\sin\omega t$", ha="right", va="center", fontsize=10)
    arrow(1.6, -1.45, 2.5, -1.15, arrowstyle="<->", color="k", connectionstyle="arc3,rad=0.4")
    ax.text(2.55, -1.55, r"$\phi_s = \Phi_0\sin(\omega t+\psi)$", ha="left", fontsize=10)
    arrow(0, 2.2, 0, 1.45, arrowstyle="->", color="k")
    ax.text(0.12, 1.85, r"$m_r g$ (+ preload)", fontsize=10)
    arrow(-2.2, 0.75, -2.2, 1.55, arrowstyle="->", color=COLORS["rotor"])
    ax.text(-2.3, 1.6, r"$u_r$", color=COLORS["rotor"], ha="right", fontsize=11)
    arrow(
        1.9, 1.2, 2.6, 0.7, arrowstyle="->", color=COLORS["rotor"], connectionstyle="arc3,rad=-0.5"
    )
    ax.text(2.65, 0.95, r"$\dot\phi_r$", color=COLORS["rotor"], fontsize=11)
    ax.text(0, 0.3, "rotor ($m_r$, $J_r = m_r r_g^2$)", ha="center", va="top", fontsize=9)
    ax.text(0, -1.5, "pretwisted beam\n(stator)", ha="center", fontsize=9)
    ax.text(-2.9, 2.2, "impact: $e$, friction: $\\mu$, $r_{eff} = 2r_c/3$", fontsize=9)
    return fig


def _band(ax, t, low, high, color, label, alpha=0.25) -> None:
    """A shaded band between ``low`` and ``high``."""
    ax.fill_between(t, low, high, color=color, alpha=alpha, lw=0, label=label)


def fig_trajectory(ds: xr.Dataset, band: xr.Dataset | None = None, window: float = 40.0) -> Figure:
    """Paper Figs. 3–4: rotor and stator flight paths and the rotor angular velocity.

    With ``band`` (:func:`bouncedisk.bands.omega_band`), the ensemble's spread of ``Ω`` (central
    95 % of the members) and the 95 % interval of its mean are drawn behind the single run.
    """
    t = ds["time"].values
    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    axes = fig.subplots(3, 1)
    first = t <= t[0] + window
    last = t >= t[-1] - window
    for ax, sel, label in ((axes[0], first, "start"), (axes[1], last, "end of the run")):
        ax.plot(t[sel], ds["u_stator"].values[sel], color=COLORS["stator"], lw=0.8, label="stator")
        ax.plot(t[sel], ds["u_rotor"].values[sel], color=COLORS["rotor"], lw=1.0, label="rotor")
        ax.set_ylabel("axial position $u/U_0$")
        ax.set_title(f"flight paths, {label}", fontsize=10)
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("time $t/t_c$")
    if "omega_rotor" in ds:
        if band is not None:
            bt = band["time"].values
            k = band.sizes["member"]
            _band(axes[2], bt, band["omega_p025"], band["omega_p975"], "0.6",
                  f"central 95% of {k} members", alpha=0.3)  # fmt: skip
            _band(axes[2], bt, band["omega_ci_low"], band["omega_ci_high"], COLORS["fit"],
                  "95% interval of the ensemble mean", alpha=0.45)  # fmt: skip
        axes[2].plot(t, ds["omega_rotor"].values, color=COLORS["rotor"], lw=0.8, label="this run")
        if "t_impact" in ds:
            axes[2].plot(
                ds["t_impact"].values,
                ds["omega_after"].values,
                ".",
                ms=2,
                color="k",
                label="after each impact",
            )
        axes[2].legend(loc="lower right", fontsize=7)
        axes[2].set_ylabel(r"rotor angular velocity $\Omega$")
    axes[2].set_xlabel("time $t/t_c$")
    fig.suptitle(f"Bouncing disk: {_title(ds)}", fontsize=11)
    return fig


def fig5_motor(
    curve: pd.DataFrame,
    simulated: pd.DataFrame | None = None,
    fitted: xr.Dataset | None = None,
    sim_label: str = "simulation",
) -> Figure:
    """Paper Fig. 5: measured rotor speed beside the bouncing-disk model fitted to it.

    Parameters
    ----------
    curve : DataFrame
        Measured ``time_s``, ``omega_rad_s`` (for a fit of several run-ups, the fit file's
        ``omega_measured``, their mean, is drawn instead: the data the fit compares with).
    simulated : DataFrame, optional
        Model speed ``time_s``, ``omega_rad_s`` (unfitted scales) when no fit is given.
    fitted : Dataset, optional
        A fit file (INTERFACES.md): ``omega_measured``, ``omega_fitted`` (the fitted model's
        ensemble mean) on ``time``, with ``omega_fitted_low``/``omega_fitted_high`` (its 95 %
        interval) and both first-order trends when present. The residual panel shows the data
        minus the ensemble mean, with the members' central 95 % (plus the measurement noise)
        as the band a single realization should stay in.
    """
    fig = Figure(figsize=(8.0, 5.5 if fitted is not None else 4.0), layout="constrained")
    if fitted is not None:
        ax, axr = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    else:
        ax, axr = fig.add_subplot(), None
    runs = int(fitted.attrs.get("runs", 1)) if fitted is not None else 1
    if runs > 1:  # run-ups fitted together: the data the fit compares with is their mean
        ax.plot(fitted["time"], fitted["omega_measured"], color=COLORS["data"], lw=0.6,
                label=f"measured: mean of {runs} run-ups")  # fmt: skip
    else:
        ax.plot(curve["time_s"], curve["omega_rad_s"], color=COLORS["data"], lw=0.6,
                label="measured (prototype curve)")  # fmt: skip
    if fitted is not None:
        _fig5_fitted(ax, axr, fitted)
    elif simulated is not None:
        ax.plot(simulated["time_s"], simulated["omega_rad_s"], color=COLORS["rotor"], lw=0.8,
                label=sim_label)  # fmt: skip
        ax.set_xlabel("time [s]")
    ax.set_ylabel("rotor angular velocity [rad/s]")
    ax.legend(loc="lower right", fontsize=8)
    return fig


def _fig5_fitted(ax, axr, fitted: xr.Dataset) -> None:
    """Fig. 5's fitted model, trends and residual panel."""
    t = fitted["time"].values
    mean = fitted["omega_fitted"].values
    if "omega_fitted_low" in fitted:
        ax.fill_between(t, fitted["omega_fitted_low"].values, fitted["omega_fitted_high"].values,
                        color=COLORS["fit"], alpha=0.35, lw=0,
                        label="fitted model: 95% interval of the ensemble mean")  # fmt: skip
    ax.plot(t, mean, color=COLORS["fit"], lw=0.9, label="fitted model: ensemble mean")
    for name, style, label in (
        ("trend_measured", "--", "first-order trend of the data"),
        ("trend_fitted", ":", "first-order trend of the fitted model"),
    ):
        if name in fitted:
            ax.plot(t, fitted[name].values, style, color="k", lw=1, label=label)
    resid = fitted["omega_measured"].values - mean
    if "residual_band_low" in fitted:
        axr.fill_between(t, fitted["residual_band_low"].values,
                         fitted["residual_band_high"].values, color=COLORS["fit"], alpha=0.3,
                         lw=0, label="95% of the members + noise")  # fmt: skip
        if "residual_outside_fraction" in fitted.attrs:
            a = fitted.attrs
            axr.set_title(f"outside the band: {100 * a['residual_outside_fraction']:.1f} % of the "
                          f"samples, longest run {1e3 * a['residual_longest_run_s']:.2g} ms",
                          fontsize=7)  # fmt: skip
        axr.legend(loc="upper right", fontsize=7)
    axr.plot(t, resid, color="k", lw=0.4)
    axr.axhline(0, color=COLORS["fit"], lw=0.8)
    axr.set_ylabel("data − model [rad/s]")
    axr.set_xlabel("time [s]")
    a = fitted.attrs
    ax.set_title(
        f"data: S = {a.get('steady_speed_rad_s', float('nan')):.4g} rad/s, "
        f"τ = {a.get('time_constant_s', float('nan')):.3g} s; fitted model: "
        f"S = {a.get('model_steady_speed_rad_s', float('nan')):.4g} rad/s, "
        f"τ = {a.get('model_time_constant_s', float('nan')):.3g} s; "
        f"not identified: {a.get('not_identified', '?')}"
        + (
            f"\nFIT INADEQUATE: chi2 {a.get('chi2', float('nan')):.4g} on "
            f"{a.get('n_statistics', '?')} statistics (p = {a.get('chi2_p_value', float('nan')):.2g})"
            if not a.get("fit_adequate", 1)
            else ""
        ),
        fontsize=8,
        color="black" if a.get("fit_adequate", 1) else "darkred",
    )


def fig_fit_profiles(fitted: xr.Dataset) -> Figure:
    """Profile likelihoods of the fitted parameters: ``Δχ²`` against each parameter.

    The dashed line is the 95 % threshold ``χ²₁(0.95) = 3.84``; the shaded span is the reported
    interval, the marker the estimate. A profile that stays under the line over the whole search
    range is "not identified".
    """
    names = [n for n in ("e", "r_phi", "psi", "omega_s", "speed_scale")
             if f"profile_chi2_{n}" in fitted]  # fmt: skip
    fig = Figure(figsize=(3.0 * max(1, len(names)), 3.2), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, max(1, len(names)), squeeze=False)[0])
    for ax, n in zip(axes, names, strict=False):
        x = fitted[f"profile_{n}"].values
        y = fitted[f"profile_chi2_{n}"].values
        a = fitted[n].attrs
        ax.axvspan(a["ci_low"], a["ci_high"], color=COLORS["fit"], alpha=0.2, lw=0)
        ax.plot(x, y, "o-", color=COLORS["fit"], ms=3, lw=1)
        ax.axhline(3.841, ls="--", color="k", lw=0.8)
        ax.plot([float(fitted[n])], [0.0], "k*", ms=8)
        ax.set_xlim(a["search_low"], a["search_high"])
        if n in ("r_phi", "speed_scale"):
            ax.set_xscale("log")
        ax.set_ylim(-0.5, max(10.0, min(float(np.nanmax(y)) * 1.05, 50.0)))
        ax.set_xlabel(f"{n} [{a['units']}]")
        tag = "" if a.get("identified", 1) else " (not identified)"
        ax.set_title(f"{n}: 95% [{a['ci_low']:.3g}, {a['ci_high']:.3g}]{tag}", fontsize=8)
    axes[0].set_ylabel("Δχ² (profile)")
    return fig


def fig_poincare(datasets: dict[str, xr.Dataset]) -> Figure:
    """Impact maps (phase vs relative impact velocity) and stroboscopic maps, one column each."""
    fig = Figure(figsize=(4.2 * len(datasets), 7.5), layout="constrained")
    axes = fig.subplots(2, len(datasets), squeeze=False)
    for j, (label, ds) in enumerate(datasets.items()):
        impacts = ds["kind"].values == 0 if "kind" in ds else slice(None)
        ax = axes[0, j]
        ax.plot(ds["phase"].values[impacts], ds["v_rel"].values[impacts], ",", color="k", alpha=0.6)
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
        ax.legend(fontsize=8, loc="upper right")
        ax = axes[1, j]
        if "strobe_u" in ds:
            su, sv = ds["strobe_u"].values, ds["strobe_v"].values
            ax.plot(su, sv, ".", ms=1.0, color=COLORS["rotor"])
            ax.plot(su[-50:], sv[-50:], "o", ms=3, color=COLORS["fit"], label="last 50 periods")
            ax.margins(0.08)
            ax.legend(fontsize=8, loc="best")
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
    ``Γ_1 = π(1−e)/(1+e)`` and its doubling (MODEL.md "Classic results") at ``Γ = ω_s²``.
    """
    from .observables import period_doubling_threshold, period_n_threshold

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
        ax.plot(ee[imp], ph[imp], "o", ms=1.2, mew=0, color=color, alpha=0.6, label=label)
        ax.plot(ee[chat], ph[chat], "x", ms=4, mew=0.8, color="#3182bd",
                label="complete chatter (reset)" if key == "up" else None)  # fmt: skip
        lam = ds["lyapunov"].values
        ax2.fill_between(e, ds["lyapunov_ci_low"].values, ds["lyapunov_ci_high"].values,
                         color=color, alpha=0.25, lw=0)  # fmt: skip
        ax2.plot(e, lam, "-", color=color, lw=0.8, label=f"{label}, mean and 95% interval")
        reset = ds["lyapunov_reset_fraction"].values > 0.5
        ax2.plot(e[reset], np.full(reset.sum(), -2.4), "v", ms=3, color=color)
    g = w * w
    e1 = _param_where(lambda e: period_n_threshold(1, e), g)
    epd = _param_where(lambda e: period_doubling_threshold(1, e), g)
    for x, text in ((e1, "Γ₁"), (epd, "Γ_PD")):
        if math.isfinite(x):
            for a in (ax, ax2):
                a.axvline(x, color="0.4", lw=0.7, ls="--")
            ax.text(x + 0.004, 3.0, text, ha="left", va="center", fontsize=8, color="0.3")
    ax.set_ylim(0, TWO_PI)
    ax.set_ylabel(r"impact phase $\omega_s t$ mod $2\pi$")
    ax.set_title(f"bifurcation diagram by continuation, ω_s = {w:.3g} (Γ = {g:.3g})", fontsize=10)
    ax.legend(loc="upper right", fontsize=7, markerscale=3)
    ax2.axhline(0, color="k", lw=0.6)
    ax2.set_ylim(-2.6, 1.5)
    ax2.set_ylabel("Lyapunov exponent\n(per impact; ▼ = −∞)")
    ax2.set_xlabel("coefficient of restitution $e$")
    ax2.legend(loc="upper left", fontsize=7)
    return fig


REGIME_COLORS = {
    0: "#bdbdbd",
    1: "#4daf4a",
    2: "#377eb8",
    3: "#ff7f00",
    4: "#e41a1c",
    5: "#984ea3",
}


def fig_regime_map(ds: xr.Dataset) -> Figure:
    """Regimes over ``(e, omega_s)``, the Lyapunov exponent and the chatter rate (ensembles)."""
    from .observables import REGIMES

    fig = Figure(figsize=(15.0, 4.6), layout="constrained")
    ax, ax2, ax3 = fig.subplots(1, 3)
    e = ds["e"].values
    w = ds["omega_s"].values
    reg = ds["regime"].transpose("omega_s", "e").values
    codes = sorted(REGIME_COLORS)
    cmap = ListedColormap([REGIME_COLORS[c] for c in codes])
    norm = BoundaryNorm(np.arange(-0.5, len(codes) + 0.5), cmap.N)
    m = ax.pcolormesh(e, w, reg, cmap=cmap, norm=norm, shading="nearest")
    cb = fig.colorbar(m, ax=ax, ticks=codes)
    cb.ax.set_yticklabels([REGIMES[c] for c in codes], fontsize=7)
    per = ds["period_p"].transpose("omega_s", "e").values
    for i, wi in enumerate(w):
        for j, ej in enumerate(e):
            if reg[i, j] == 1 and per[i, j] > 1 and len(e) <= 40:
                ax.text(ej, wi, str(int(per[i, j])), ha="center", va="center", fontsize=5)
    members = ds.attrs.get("ensemble_members", "?")
    ax.set_title(f"regime, most common of {members} members (numbers: impacts per cycle)",
                 fontsize=9)  # fmt: skip
    lam = ds["lyapunov"].transpose("omega_s", "e").values
    vmax = np.nanmax(np.abs(lam)) if np.isfinite(lam).any() else 1.0
    m2 = ax2.pcolormesh(e, w, lam, cmap="RdBu_r", vmin=-vmax, vmax=vmax, shading="nearest")
    fig.colorbar(m2, ax=ax2, label="Lyapunov exponent per impact (ensemble mean)")
    ax2.set_facecolor("0.8")
    ax2.set_title("Lyapunov exponent between resets (grey: reset every cycle, −∞)", fontsize=9)
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
        line = ax.plot(psi, r * sel["mean_omega"].values, ".-", lw=1, ms=3,
                       label=f"$R_\\phi$ = {r:g}")[0]  # fmt: skip
        ax.fill_between(psi, r * sel["mean_omega_ci_low"].values,
                        r * sel["mean_omega_ci_high"].values, color=line.get_color(),
                        alpha=0.3, lw=0)  # fmt: skip
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel(r"torsional phase $\psi$ [rad]")
    ax.set_ylabel(r"mean rotor speed $R_\phi\bar\Omega$ (stator units)")
    members = ds.attrs.get("ensemble_members", "?")
    r = ds["r_phi"]
    half = float(np.nanmax(r * (ds["mean_omega_ci_high"] - ds["mean_omega_ci_low"]) / 2))
    ax.set_title(
        f"motor curve: e = {_param(ds, 'e'):.3g}, ω_s = {_param(ds, 'omega_s'):.3g}; bands: 95% "
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
            _band(ax, t, b["omega_bouncing_p025"], b["omega_bouncing_p975"], "0.6",
                  "bouncing: central 95% of members", alpha=0.3)  # fmt: skip
            _band(ax, t, b["omega_bouncing_ci_low"], b["omega_bouncing_ci_high"], COLORS["rotor"],
                  "bouncing: 95% interval of the ensemble mean", alpha=0.5)  # fmt: skip
        for model, color in (("bouncing", COLORS["rotor"]), ("clipped", COLORS["fit"])):
            ax.plot(
                t,
                ds["omega_rotor"].sel(model=model, psi=p).values,
                color=color,
                lw=0.8,
                label=f"{model} model" + (" (one run)" if model == "bouncing" else ""),
            )
        ax.set_ylabel(r"$\Omega$")
        ax.set_title(f"ψ = {p:.3g}", fontsize=10)
        ax.legend(fontsize=7, loc="lower right", ncol=2)
    axes[-1].set_xlabel("time $t/t_c$")
    fig.suptitle(
        "bouncing disk vs clipped spring contact (refs. [2, 3] of the paper): "
        f"e = {_param(ds, 'e'):.3g}, ω_s = {_param(ds, 'omega_s'):.3g}",
        fontsize=10,
    )
    return fig


def fig_work_precision(table: pd.DataFrame) -> Figure:
    """Error against CPU time, one line per solver and case (log–log)."""
    cases = list(dict.fromkeys(table["case"]))
    fig = Figure(figsize=(5.5 * len(cases), 4.5), layout="constrained")
    axes = fig.subplots(1, len(cases), squeeze=False)[0]
    for ax, case in zip(axes, cases, strict=True):
        sub = table[table["case"] == case]
        for solver, g in sub.groupby("solver", sort=False):
            g = g.sort_values("cpu_s")
            ax.loglog(g["cpu_s"], g["error"].clip(lower=1e-17), "o-", ms=4, lw=1, label=solver)
        ax.set_xlabel("CPU time [s]")
        ax.set_ylabel("max error in impact times (first 20)")
        ax.set_title(case, fontsize=10)
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    return fig


def fig_scaling(table: pd.DataFrame) -> Figure:
    """Cost per impact against omega_s, total time and memory against the number of impacts."""
    fig = Figure(figsize=(13.0, 4.0), layout="constrained")
    a1, a2, a3 = fig.subplots(1, 3)
    w = table[table["study"] == "omega"]
    a1.semilogx(w["omega_s"], 1e9 * w["s_per_impact"], "o-")
    a1.set_xlabel(r"$\omega_s$")
    a1.set_ylabel("time per impact [ns]")
    a1.set_ylim(bottom=0)
    n = table[table["study"] == "impacts"]
    a2.loglog(n["n_impacts"], n["seconds"], "o-", label="measured")
    if len(n):
        x = n["n_impacts"].values
        a2.loglog(x, n["seconds"].values[-1] * x / x[-1], "--", color="k", lw=0.8, label="linear")
    a2.set_xlabel("impacts")
    a2.set_ylabel("wall time [s]")
    a2.legend(fontsize=8)
    m = table[table["study"] == "memory"]
    a3.loglog(m["n_impacts"], m["peak_mb"], "o-")
    a3.set_xlabel("impacts (events only, streamed to netCDF)")
    a3.set_ylabel("peak memory [MB]")
    return fig


def fig_stats_cost(table: pd.DataFrame, singles: pd.DataFrame) -> Figure:
    """What statistics cost: CI half-width of the mean rotor speed against CPU time.

    Left: the half-width for each averaging time against the CPU time of the ensemble (members ×
    duration), with the ``1/sqrt(cost)`` slope; the grey band is ± the standard deviation of
    single runs whose ``e`` differs by 1e-9 steps. Right: those single runs' averages beside the
    largest ensemble's mean and 95 % interval.
    """
    fig = Figure(figsize=(11.0, 4.3), layout="constrained")
    ax, ax2 = fig.subplots(1, 2)
    for d, grp in table.groupby("duration"):
        ax.loglog(grp["cpu_s"], grp["half_width"], "o-", ms=4, label=f"duration {d:g}")
    x = np.array([table["cpu_s"].min(), table["cpu_s"].max()])
    ref = table.loc[table["cpu_s"].idxmin()]
    ax.loglog(x, ref["half_width"] * np.sqrt(ref["cpu_s"] / x), "k--", lw=0.8,
              label=r"$\propto 1/\sqrt{\mathrm{CPU}}$")  # fmt: skip
    sd = float(singles["mean_omega"].std(ddof=1))
    ax.axhspan(sd * 0.98, sd * 1.02, color="0.5", alpha=0.5,
               label=f"scatter of single runs (sd {sd:.2f})")  # fmt: skip
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("CPU time of the ensemble [s] (one core)")
    ax.set_ylabel(r"95% half-width of the mean rotor speed $\bar\Omega$")
    ax.legend(fontsize=7)
    ax.set_title("cost of a confidence interval", fontsize=10)
    best = table.loc[table["member_time"].idxmax()]
    ax2.axhspan(best["ci_low"], best["ci_high"], color=COLORS["fit"], alpha=0.3,
                label=f"ensemble: {int(best['members'])} members × {best['duration']:g}, 95%")  # fmt: skip
    ax2.axhline(best["mean_omega"], color=COLORS["fit"], lw=1)
    ax2.plot(singles["de"] * 1e9, singles["mean_omega"], "o", color=COLORS["rotor"],
             label="single runs (no noise)")  # fmt: skip
    ax2.set_xlabel(r"change of $e$ [$10^{-9}$]")
    ax2.set_ylabel(r"time-averaged rotor speed $\bar\Omega$")
    ax2.set_title("single runs jump; the ensemble statistic does not", fontsize=10)
    ax2.legend(fontsize=7)
    return fig


def _short(output: str) -> str:
    """An output's name as an axis label."""
    return output.replace("_", " ")


def fig_sensitivity_indices(ds: xr.Dataset) -> Figure:
    """First-order and total Sobol' indices of every output with SALib's 95 % bootstrap
    intervals, and the share of each output's variance that is ensemble noise."""
    outputs = ds["output"].values.tolist()
    names = ds["parameter"].values.tolist()
    ncol = min(3, len(outputs))
    nrow = math.ceil(len(outputs) / ncol)
    fig = Figure(figsize=(4.6 * ncol, 3.4 * nrow), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False).ravel())
    pos = np.arange(len(names))
    for ax, o in zip(axes, outputs, strict=False):
        row = ds.sel(output=o)
        for k, (key, color) in enumerate((("S1", "#1f77b4"), ("ST", "#ff7f0e"))):
            ax.bar(pos + (k - 0.5) * 0.38, row[key].values, 0.38, color=color,
                   yerr=row[f"{key}_conf"].values, capsize=3, label=key)  # fmt: skip
        share = float(row["noise_share"])
        undefined = int(row["n_undefined"])
        note = (f"undefined at {undefined} points: no indices" if undefined
                else f"ensemble noise: {100 * share:.1f} % of the variance")  # fmt: skip
        ax.set_title(f"{_short(o)}\n{note}", fontsize=9)
        ax.set_xticks(pos, names, fontsize=8)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylim(-0.1, 1.1)
    for ax in axes[len(outputs) :]:
        ax.set_visible(False)
    axes[0].legend(fontsize=8)
    axes[0].set_ylabel("Sobol' index (95 % bootstrap interval)")
    fig.suptitle(f"Sobol' indices over {ds.attrs.get('n_points', '?')} points (SALib)", fontsize=10)
    return fig


def fig_sensitivity_scatter(ds: xr.Dataset) -> Figure:
    """Each output against each sampled parameter, every point coloured by its regime."""
    from .observables import REGIMES

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
                ax.set_xlabel(p)
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
    ``e``, with the best operating point and its 95 % interval (hollow: not resolved from it)."""
    from .sensitivity import BEST_BY, MAP_OUTPUTS, best_point

    outputs = [o for o in MAP_OUTPUTS if o in ds]
    n_psi, n_r = int(ds.attrs["map_n_psi"]), int(ds.attrs["map_n_r_phi"])
    maps = [ds.isel(map=k) for k in range(ds.sizes["map"])]
    best_by = next(b for b in BEST_BY if b in ds)
    w = ds.attrs.get("map_omega_s")
    w_label = rf"$\omega_s$ = {float(w):g}" if w is not None else ""
    fig = Figure(figsize=(4.8 * len(maps), 3.4 * len(outputs)), layout="constrained")
    axes = fig.subplots(len(outputs), len(maps), squeeze=False)
    for j, m in enumerate(maps):
        xp, xr_ = (m["x"].sel(parameter=p).values for p in ("psi", "log10_r_phi"))
        psi, lr = xp.reshape(n_psi, n_r)[:, 0], xr_.reshape(n_psi, n_r)[0]
        best = best_point(m, best_by)
        for i, o in enumerate(outputs):
            ax = axes[i, j]
            z = m[o].values.reshape(n_psi, n_r).T
            mesh = ax.pcolormesh(psi, lr, z, shading="nearest", cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=_short(o))
            if best["index"] is not None:
                near = [k for k in best["indistinguishable"] if k != best["index"]]
                ax.scatter(xp[near], xr_[near], s=14, facecolors="none", edgecolors="w", lw=0.7)
                ax.plot(xp[best["index"]], xr_[best["index"]], "r*", ms=12)
            ax.set_xlabel(r"$\psi$")
            ax.set_ylabel(r"$\log_{10} R_\phi$")
            ax.set_title(f"e = {float(m['map_e']):g}, {w_label}", fontsize=9)
        if best["index"] is not None:
            lo, hi = best["ci95"]
            axes[0, j].text(0.02, 0.02, f"best {_short(best_by)}: {best['value']:.3g} [{lo:.3g}, {hi:.3g}]",
                            transform=axes[0, j].transAxes, fontsize=7, color="w")  # fmt: skip
    return fig


# ----------------------------------------------------------------------------- the registry
Opener = Callable[[str], Any]


def _netcdf(*required: str, what: str = "netCDF") -> Opener:
    """An opener of a netCDF file that must hold the variables ``required``."""

    def open_(path: str) -> xr.Dataset:
        return open_checked(path, required=required, what=what)

    return open_


def _curve(path: str) -> dict[str, np.ndarray]:
    """A motor curve (CSV and sidecar) as the columns :func:`fig5_motor` draws."""
    from .curves import read_curve

    curve = read_curve(path)
    return {"time_s": curve.time, "omega_rad_s": curve.omega}


def _fig5_with_fit(curve: dict[str, np.ndarray], fit: xr.Dataset) -> Figure:
    """Fig. 5 from the curve and its fit file (:func:`fig5_motor`)."""
    return fig5_motor(curve, fitted=fit)


def _poincare_labelled(maps: Sequence[xr.Dataset], labels: Sequence[str]) -> Figure:
    """The Poincaré maps, each under its label (:func:`fig_poincare`)."""
    return fig_poincare(dict(zip(labels, maps, strict=True)))


@dataclass(frozen=True)
class FigureSpec:
    """How one kind of figure is drawn from files: a :class:`~.figure_registry.FigureDecl` resolved.

    Attributes
    ----------
    draw : callable
        Called as ``draw(*opened, **params)``: the opened inputs in the order of ``inputs``,
        then the figure's parameters (e.g. ``labels``); returns the Figure.
    inputs : mapping
        Input name -> the function that opens one path of it (a list of paths opens each).
    params : tuple of str
        The names of the parameters ``draw`` takes besides the inputs.
    """

    draw: Callable[..., Figure]
    inputs: Mapping[str, Opener] = field(default_factory=dict)
    params: tuple[str, ...] = ()


#: The openers of the figures' inputs, by the names :mod:`bouncedisk.figure_registry` gives.
OPENERS: dict[str, Opener] = {
    "simulation": open_simulation,
    "band": _netcdf("omega_mean", "omega_ci_low", what="band"),
    "curve": _curve,
    "fit": _netcdf("omega_measured", "omega_fitted", what="fit"),
    "poincare_map": _netcdf("phase", "v_rel"),
    "branch": _netcdf("phase", "is_chatter", "lyapunov"),
    "regime_sweep": _netcdf("regime", "lyapunov"),
    "psi_sweep": _netcdf("mean_omega", "mean_omega_ci_low"),
    "clipped_study": _netcdf("omega_rotor"),
    "csv": pd.read_csv,
    "sensitivity_indices": _netcdf("S1", "ST", "noise_share", what="sensitivity indices"),
    "sensitivity_points": _netcdf("x", "regime", what="sensitivity study"),
    "design_maps": _netcdf("x", "map_e", what="design maps"),
    "load_curve": _netcdf("mean_omega", "power_out", what="load curve"),
}


def _resolve(decl: FigureDecl) -> FigureSpec:
    """The drawing function and openers ``decl`` names, looked up in this module."""
    return FigureSpec(
        globals()[decl.draw], {key: OPENERS[o] for key, o in decl.inputs.items()}, decl.params
    )


#: Every figure the package draws, by name: :data:`bouncedisk.figure_registry.FIGURES` resolved.
FIGURES: dict[str, FigureSpec] = {name: _resolve(d) for name, d in DECLARED.items()}


def draw_figure(
    name: str, paths: Mapping[str, str | Sequence[str]], params: Mapping[str, Any] | None = None
) -> Figure:
    """Open the inputs of figure ``name`` (a key of :data:`FIGURES`) and draw it.

    Parameters
    ----------
    name : str
        The figure's kind, a key of :data:`FIGURES`.
    paths : mapping
        Input name -> a path, or a list of paths; exactly the inputs the figure takes.
    params : mapping, optional
        Exactly the parameters the figure takes (``FigureSpec.params``).

    Raises
    ------
    ValueError
        An unknown figure, or inputs or parameters other than the figure's.
    """
    spec = FIGURES.get(name)
    if spec is None:
        raise ValueError(f"unknown figure {name!r}; known figures: {', '.join(sorted(FIGURES))}")
    params = dict(params or {})
    for what, given, wanted in (
        ("inputs", set(paths), set(spec.inputs)),
        ("parameters", set(params), set(spec.params)),
    ):
        if given != wanted:
            raise ValueError(
                f"figure {name!r} takes the {what} {sorted(wanted)}, given {sorted(given)}"
            )
    opened = [
        [opener(str(p)) for p in paths[key]]
        if isinstance(paths[key], Sequence) and not isinstance(paths[key], str)
        else opener(str(paths[key]))
        for key, opener in spec.inputs.items()
    ]
    return spec.draw(*opened, **params)
