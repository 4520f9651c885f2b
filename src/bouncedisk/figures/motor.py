"""The motor's run-up against a measured curve (Fig. 5) and fit profiles."""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FormatStrFormatter, NullLocator

from .common import COLORS, inadequate_note, shade
from .joint_fit import data_word


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
        A fit file (docs/formats.md): ``omega_measured``, ``omega_fitted`` (the fitted model's
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
        t, y = fitted["time"], fitted["omega_measured"]
        what = f"{data_word(fitted)}: mean of {runs} run-ups"
    else:
        t, y, what = curve["time_s"], curve["omega_rad_s"], f"{data_word(fitted)} (prototype curve)"
    ax.plot(t, y, color=COLORS["data"], lw=0.6, label=what)
    if fitted is not None:
        _fig5_fitted(ax, axr, fitted)
    elif simulated is not None:
        ax.plot(
            simulated["time_s"],
            simulated["omega_rad_s"],
            color=COLORS["rotor"],
            lw=0.8,
            label=sim_label,
        )
        ax.set_xlabel("time [s]")
    ax.set_ylabel("rotor angular velocity [rad/s]")
    ax.legend(loc="lower right", fontsize=8)
    return fig


def _from_start(trend: np.ndarray, start: float) -> np.ndarray:
    """A rising first-order trend from where it reaches the run-up's first reading ``start``
    (NaN before): its fitted start can lie below the rotor's, at a foot that is not first order.
    Any other trend is drawn whole."""
    y = np.array(trend, float)
    if len(y) and y[-1] > y[0] and np.any(y >= start):
        y[: int(np.argmax(y >= start))] = np.nan
    return y


def _fig5_fitted(ax, axr, fitted: xr.Dataset) -> None:
    """Fig. 5's fitted model, trends and residual panel."""
    t = fitted["time"].values
    mean = fitted["omega_fitted"].values
    if "omega_fitted_low" in fitted:
        shade(
            ax,
            t,
            fitted["omega_fitted_low"].values,
            fitted["omega_fitted_high"].values,
            COLORS["fit"],
            "fitted model: 95% interval of the ensemble mean",
            alpha=0.35,
        )
    ax.plot(t, mean, color=COLORS["fit"], lw=0.9, label="fitted model: ensemble mean")
    for name, style, label in (
        ("trend_measured", "--", "first-order trend of the data"),
        ("trend_fitted", ":", "first-order trend of the fitted model"),
    ):
        if name in fitted:
            ax.plot(
                t,
                _from_start(fitted[name].values, fitted["omega_measured"].values[0]),
                style,
                color="k",
                lw=1,
                label=label,
            )
    resid = fitted["omega_measured"].values - mean
    if "residual_band_low" in fitted:
        shade(
            axr,
            t,
            fitted["residual_band_low"].values,
            fitted["residual_band_high"].values,
            COLORS["fit"],
            "95% of the members + noise",
            alpha=0.3,
        )
        # said in the title, not a legend over the residuals
        title = "band: 95% of the members + noise"
        if "residual_outside_fraction" in fitted.attrs:
            a = fitted.attrs
            title += (
                f"; outside it: {100 * a['residual_outside_fraction']:.1f} % of the "
                f"samples, longest run {1e3 * a['residual_longest_run_s']:.2g} ms"
            )
        axr.set_title(title, fontsize=7)
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
        f"not identified: {a.get('not_identified', '?')}" + inadequate_note(a),
        fontsize=8,
        color="black" if a.get("fit_adequate", 1) else "darkred",
    )


#: Parameter names as the figures write them.
PARAM_LABELS = {
    "e": "$e$",
    "r_phi": r"$R_\phi$",
    "psi": r"$\psi$",
    "omega_s": r"$\omega_s$",
    "speed_scale": "speed scale",
    "e_sigma": r"$\sigma_e$",
}


def fig_fit_profiles(fitted: xr.Dataset) -> Figure:
    """Profile likelihoods of the fitted parameters: ``Δχ²`` against each parameter.

    The dashed line is where the file's intervals accept a point: each parameter's ``delta_chi2``
    (``χ²₁(0.95) = 3.84``, scaled by ``χ²/dof`` when the fit's ``χ²`` exceeds its degrees of
    freedom) above the intervals' reference ``chi2_reference`` (the best ``χ²``, or the level on
    fresh members when that is higher; docs/fitting_method.md "The intervals"), drawn above the
    best ``χ²`` as every profile is; the shaded span is the reported
    interval, the star the estimate. An interval widened to other acceptable points (the
    parameter's ``multimodal = 1``: several basins) reaches beyond where its profile crosses the
    line, and the panel's title says so. A profile that stays under the line over the whole search
    range is "not identified". Each panel is zoomed on its interval (half its width beyond either
    end, within the search range) so that the profile's curvature shows; an inadequate fit (the
    file's ``identified = "no"``) has no interval: the panel shows the profiled range and says so.
    The axis is linear up to 10 and logarithmic above, so that it holds every profile point shown
    and still shows the threshold. A last panel, the waterfall, shows the ``χ²`` each start of
    the local search ended at (the file's ``start_chi2``) above the best, against the same line:
    the starts under it ended where the intervals accept a point.
    """
    names = [
        n
        for n in ("e", "r_phi", "psi", "omega_s", "speed_scale", "e_sigma")
        if f"profile_chi2_{n}" in fitted
    ]
    falls = int("start_chi2" in fitted and fitted.sizes.get("start", 0) > 0)
    panels = max(1, len(names)) + falls
    fig = Figure(figsize=(3.0 * panels, 3.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, panels, squeeze=False)[0])
    for ax, n in zip(axes, names, strict=False):
        _profile_panel(ax, fitted, n)
    if falls:
        _waterfall_panel(axes[-1], fitted)
    axes[0].set_ylabel("Δχ² (profile)")
    if names:
        fig.legend(
            *axes[0].get_legend_handles_labels(), loc="outside upper center", ncol=4, fontsize=7
        )
    return fig


def _profile_panel(ax, fitted: xr.Dataset, n: str) -> None:
    """One parameter's profile in :func:`fig_fit_profiles`."""
    x = fitted[f"profile_{n}"].values
    y = fitted[f"profile_chi2_{n}"].values
    a = fitted[n].attrs
    log = n in ("r_phi", "speed_scale")
    has_ci = bool(np.isfinite(a["ci_low"]) and np.isfinite(a["ci_high"]))
    if has_ci:
        ax.axvspan(
            a["ci_low"], a["ci_high"], color=COLORS["fit"], alpha=0.2, lw=0, label="95% interval"
        )
    ax.plot(x, y, "o-", color=COLORS["fit"], ms=3, lw=1, label="profile")
    thr = float(a["delta_chi2"])
    ax.axhline(_offset(fitted) + thr, ls="--", color="k", lw=0.8, label=_line_label(fitted, thr))
    ax.plot([float(fitted[n])], [0.0], "k*", ms=8, label="estimate")
    lo, hi = (a["ci_low"], a["ci_high"]) if has_ci else (np.nanmin(x), np.nanmax(x))
    ax.set_xlim(*_zoom(lo, hi, a["search_low"], a["search_high"], log))
    if log:  # a zoom inside one decade: three labelled ticks, not every minor one
        ax.set_xscale("log")
        ax.set_xticks(np.geomspace(*ax.get_xlim(), 5)[1:-1])
        ax.xaxis.set_major_formatter(FormatStrFormatter("%.3g"))
        ax.xaxis.set_minor_locator(NullLocator())
    shown = (x >= ax.get_xlim()[0]) & (x <= ax.get_xlim()[1]) & np.isfinite(y)
    top = float(np.max(y[shown])) if shown.any() else 10.0
    _delta_axis(ax, max(top, _offset(fitted) + thr))
    label = PARAM_LABELS.get(n, n)
    ax.set_xlabel(f"{label} [{a['units']}]")
    tag = "" if a.get("identified", 1) else " (not identified)"
    if has_ci and a.get("multimodal", 0):
        tag += "\nwidened: several basins"
    ci = f"95% [{a['ci_low']:.3g}, {a['ci_high']:.3g}]" if has_ci else "no interval: inadequate fit"
    ax.set_title(f"{label}: {ci}{tag}", fontsize=8)


def _delta_axis(ax, top: float) -> None:
    """A ``Δχ²`` axis up to ``top``: linear up to 10 (where the thresholds lie), logarithmic
    above, labelled at round values."""
    ax.set_yscale("symlog", linthresh=10.0)
    ax.set_ylim(-0.5, max(10.0, top * 1.3))
    steps = (0, 2, 4, 6, 8, 10, 20, 50, 100, 200, 500, 1000, 10**4, 10**5, 10**6)
    ticks = [t for t in steps if t <= top * 1.3]
    ax.yaxis.set_major_locator(FixedLocator(ticks))
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_locator(NullLocator())


def _offset(fitted: xr.Dataset) -> float:
    """How far the intervals' reference ``χ²`` lies above the best (0 for a file without it)."""
    a = fitted.attrs
    return float(a["chi2_reference"]) - float(a["chi2"]) if "chi2_reference" in a else 0.0


def _line_label(fitted: xr.Dataset, thr: float) -> str:
    """The legend of the acceptance line: its threshold, and the reference when not the best."""
    off = _offset(fitted)
    level = f" above the level on fresh members (+{off:.3g})" if off > 0 else ""
    return f"95% threshold Δχ² = {thr:.3g}{level}"


def _waterfall_panel(ax, fitted: xr.Dataset) -> None:
    """The local search's starts in :func:`fig_fit_profiles`: each start's end ``χ²`` above the
    best (the file's ``start_chi2``), best first, against the line where the intervals accept a
    point (``chi2_reference`` + ``delta_chi2``); the title counts the starts under it
    (``starts_accepted``)."""
    above = fitted["start_chi2"].values - float(fitted.attrs["chi2"])
    rank = np.arange(1, len(above) + 1)
    ax.plot(rank, np.maximum(above, 0.0), "s-", color=COLORS["fit"], ms=4, lw=1)
    line = _offset(fitted) + float(fitted.attrs["delta_chi2"])
    ax.axhline(line, ls="--", color="k", lw=0.8)
    _delta_axis(ax, max(float(np.max(above)), line))
    ax.set_xticks(rank)
    ax.set_xlabel("local-search start, best first")
    ax.set_ylabel("χ² at its end − best χ²")
    a = fitted.attrs
    ax.set_title(
        f"waterfall: {a['starts_accepted']} of {a['starts']} starts end\nwhere the intervals accept",
        fontsize=8,
    )


def _zoom(lo: float, hi: float, low: float, high: float, log: bool) -> tuple[float, float]:
    """The axis range of a profile panel: ``[lo, hi]`` widened by half its width on each side
    (in log for a log axis), within the search range ``[low, high]``."""
    f, g = (np.log10, lambda v: 10.0**v) if log else (lambda v: v, lambda v: v)
    a, b = f(lo), f(hi)
    pad = 0.5 * (b - a) if b > a else 0.05 * (f(high) - f(low))
    return float(g(max(f(low), a - pad))), float(g(min(f(high), b + pad)))
