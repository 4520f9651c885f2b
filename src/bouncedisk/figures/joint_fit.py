"""Figures of a joint fit (run-ups and load curves, :mod:`bouncedisk.fitting.loadpart`): the
measured load curve against the fitted model's band with the residuals (a companion of Fig. 5),
and which data pins which parameter (the identifiability intervals)."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .common import inadequate_note, shade

#: Colours and labels of the data sets in the identifiability figure (file's ``data_set`` order).
DATA_SET_STYLE = {"run-ups": "C0", "load curve": "C1", "both": "k"}
#: Display of every search coordinate: (label, transform to the displayed value).
COORDINATES = {
    "e": ("e", lambda v: v),
    "log10_r_phi": (r"$\log_{10} R_\varphi$", lambda v: v),
    "psi": (r"$\psi$ [rad]", lambda v: v),
    "omega_s": (r"$\omega_s$", lambda v: v),
    "log10_speed_scale": ("log10 speed scale", lambda v: v),
    "e_sigma": (r"$\sigma_e$ (restitution noise)", lambda v: v),
}


def data_word(fitted: xr.Dataset | None, attr: str = "curve_synthetic") -> str:
    """ "synthetic" when the fit file says its data were made by the model (the sidecar's
    ``synthetic: true``, recorded as ``attr``), else "measured"."""
    return "synthetic" if fitted is not None and int(fitted.attrs.get(attr, 0)) else "measured"


def _need_load(fit: xr.Dataset, what: str) -> None:
    if "load_speed_measured" not in fit:
        raise ValueError(f"{what}: the fit file has no load curve (fit with --load)")


def fig_fit_load(fit: xr.Dataset) -> Figure:
    """The measured load curves and the jointly fitted model (companion of Fig. 5).

    Top: every reading (mean speed over the window after a start from rest) with the error bar
    the likelihood gave it, the fitted model's ensemble mean with the 95 % interval of that mean
    (band) and its members' 2.5–97.5 % range (light band). Bottom: the residuals (measured minus
    fitted mean) with the members' band about zero. Several load curves are one series each,
    named by their number (the order of ``--load``) and drive frequency (docs/user_guide/fitting.md
    "Conditions"; the file's ``load_curve_conditions`` gives each curve's whole condition).
    """
    _need_load(fit, "fit_load")
    fig = Figure(figsize=(6.4, 6.0), layout="constrained")
    ax, rax = fig.subplots(2, 1, sharex=True, height_ratios=[2.2, 1.0])
    word = data_word(fit, "load_curve_synthetic")
    which = fit["load_curve_index"].values
    drive = fit["load_drive_frequency_hz"].values if "load_drive_frequency_hz" in fit else None
    several = len(np.unique(which)) > 1
    for n, k in enumerate(np.unique(which)):
        rows = np.flatnonzero(which == k)
        khz = f", {drive[rows[0]] / 1e3:.4g} kHz" if drive is not None else ""
        tag = f" (curve {k + 1}{khz})" if several else ""
        _load_series(ax, rax, fit, rows, (f"C{n}", "k" if n == 0 else f"C{n}"), word, tag)
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_ylabel("mean speed [rad/s]")
    ax.legend(fontsize=8, loc="upper right")
    a = fit.attrs
    ax.set_title(
        f"load curve: χ² {a.get('chi2_load', math.nan):.3g} on "
        f"{a.get('n_load_readings', len(which))} readings (joint fit)" + inadequate_note(a),
        fontsize=9,
    )
    rax.axhline(0.0, color="0.6", lw=1.0)
    rax.set_xlabel("load torque [mN·m]")
    rax.set_ylabel(f"{word} − fitted [rad/s]")
    return fig


def _load_series(ax, rax, fit: xr.Dataset, rows: np.ndarray, colors, word: str, tag: str) -> None:
    """One load curve's readings (``rows`` of the file's ``reading``) in :func:`fig_fit_load`:
    model colour ``colors[0]``, data colour ``colors[1]``, labels ending in ``tag``."""
    t = fit["load_torque"].values[rows] * 1e3  # mN·m
    order = np.argsort(t, kind="stable")
    t = t[order]

    def v(name):
        return fit[name].values[rows][order]

    model, data = colors
    mean = v("load_speed_fitted")
    band = (v("load_speed_band_low"), v("load_speed_band_high"))
    shade(ax, t, *band, model, f"fitted model: members' 95% range{tag}", alpha=0.15)
    shade(
        ax,
        t,
        v("load_speed_fitted_low"),
        v("load_speed_fitted_high"),
        model,
        f"fitted model: 95% interval of the mean{tag}",
        alpha=0.45,
    )
    ax.plot(t, mean, color=model, lw=1.2)
    bars = dict(fmt="o", ms=4, color=data, capsize=2)
    sigma = v("load_speed_sigma")
    ax.errorbar(
        t,
        v("load_speed_measured"),
        yerr=sigma,
        label=f"{word}{tag} (±1 sd in the likelihood)",
        **bars,
    )
    shade(rax, t, band[0] - mean, band[1] - mean, model, alpha=0.15)
    rax.errorbar(t, v("load_speed_measured") - mean, yerr=sigma, **bars)


def fig_fit_identifiability(fit: xr.Dataset) -> Figure:
    """Which data pins which parameter: per search coordinate, its 95 % interval from the
    run-ups alone, the load curves alone and both (bars over the search range), the estimate
    (dot) and, for synthetic data, the generating value (dashed line). A hatched bar is a flat
    profile: not identified by that data set. An inadequate fit (``identified = "no"``) has no
    intervals: no bars, and the title says so. The legend names every mark drawn.
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    _need_load(fit, "fit_identifiability")
    names = [str(n) for n in fit["parameter"].values]
    sets = [str(s) for s in fit["data_set"].values]
    fig = Figure(figsize=(6.4, 1.6 + 1.15 * len(names)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(names), 1))
    drawn = {"hatched": False, "truth": False}
    for j, (ax, name) in enumerate(zip(axes, names, strict=True)):
        label, fn = COORDINATES.get(name, (name, lambda x: x))
        lo_b, hi_b = float(fit["search_low"].values[j]), float(fit["search_high"].values[j])
        for k, ds_name in enumerate(sets):
            lo = fn(float(fit["interval_low"].values[k, j]))
            hi = fn(float(fit["interval_high"].values[k, j]))
            if not (math.isfinite(lo) and math.isfinite(hi)):
                continue
            ok = bool(fit["interval_identified"].values[k, j])
            drawn["hatched"] |= not ok
            y = len(sets) - 1 - k
            ax.barh(
                y,
                hi - lo,
                left=lo,
                height=0.6,
                color=DATA_SET_STYLE.get(ds_name, "0.5"),
                alpha=0.8 if ok else 0.3,
                hatch=None if ok else "//",
                edgecolor="k",
                lw=0.5,
            )
        est = _estimate(fit, name)
        if est is not None:
            ax.plot(
                [fn(est)] * len(sets), range(len(sets)), "o", color="w", mec="k", ms=4, zorder=3
            )
        truth = float(fit["generating_value"].values[j])
        if math.isfinite(truth):
            drawn["truth"] = True
            ax.axvline(fn(truth), color="C3", ls="--", lw=1.2)
        ax.set_xlim(fn(lo_b), fn(hi_b))
        ax.set_yticks(range(len(sets)), sets[::-1], fontsize=8)
        ax.set_xlabel(label, labelpad=1)
    handles = [
        Patch(color=DATA_SET_STYLE.get(s, "0.5"), alpha=0.8, label=f"95% interval: {s}")
        for s in sets
    ]
    if drawn["hatched"]:
        handles.append(Patch(facecolor="w", edgecolor="k", hatch="//", label="not identified"))
    handles.append(Line2D([], [], ls="", marker="o", color="w", mec="k", ms=4, label="estimate"))
    if drawn["truth"]:
        handles.append(Line2D([], [], color="C3", ls="--", lw=1.2, label="generating value"))
    fig.legend(handles=handles, loc="outside lower center", ncols=3, fontsize=7)
    title = "95% intervals by data set; the search range is the axis"
    if fit.attrs.get("identified", "yes") == "no":
        title = "NO INTERVALS: the fit is inadequate (the best point does not reproduce the data)"
    axes[0].set_title(title, fontsize=9)
    return fig


def _estimate(fit: xr.Dataset, name: str) -> float | None:
    """The fit's estimate of search coordinate ``name`` (from the public scalar variables)."""
    if name.startswith("log10_"):
        pub = name[6:]
        return math.log10(float(fit[pub])) if pub in fit else None
    return float(fit[name]) if name in fit else None
