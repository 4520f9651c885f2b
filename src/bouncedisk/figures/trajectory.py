"""A run's trajectory (paper Fig. 3), with its ensemble band."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .common import COLORS, _title, shade


def _zero_width(low: np.ndarray, high: np.ndarray) -> bool:
    """Is a band too narrow to see (below a thousandth of its values' range) everywhere?"""
    span = float(np.nanmax(high) - np.nanmin(low)) or 1.0
    return bool(np.nanmax(high - low) <= 1e-3 * span)


def _band_end(band_t: np.ndarray, run_t: np.ndarray, stop: str | None) -> str:
    """The legend's word on a band that ends before the run: the band covers only the times
    every member reached, and a run that stops at a number of impacts stops at its own time."""
    if band_t[-1] >= run_t[-1] - 1e-6 * max(1.0, abs(run_t[-1])):
        return ""
    why = ""
    if stop and str(stop).startswith("impacts = "):
        why = f"; each run stops after {str(stop)[len('impacts = ') :]} impacts"
    elif stop:
        why = f"; each run stops at {stop}"
    return f",\nto t = {band_t[-1]:.4g}, the end of the shortest member{why}"


def fig_trajectory(ds: xr.Dataset, band: xr.Dataset | None = None, window: float = 40.0) -> Figure:
    """Paper Figs. 3–4: rotor and stator flight paths and the rotor angular velocity.

    With ``band`` (:func:`bouncedisk.analysis.bands.omega_band`), the ensemble's spread of ``Ω`` (central
    95 % of the members) and the 95 % interval of its mean are drawn behind the single run.

    Raises
    ------
    ValueError
        ``ds`` holds no dense trajectory (its scene asked for none: ``outputs.trajectory``).
    """
    if "time" not in ds or "u_stator" not in ds:
        raise ValueError(
            f"{ds.attrs.get('scene_name', 'the simulation')}: no dense trajectory to draw; give "
            "its scene outputs: {trajectory: {dt: 0.01}} (docs/formats.md)"
        )
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
        ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)  # beside the paths
    axes[1].set_xlabel("time $t/t_c$")
    if "omega_rotor" in ds:
        if band is not None:
            bt = band["time"].values
            k = band.sizes["member"]
            zero = _zero_width(band["omega_p025"].values, band["omega_p975"].values)
            note = " (zero width: the members coincide)" if zero else ""
            note += _band_end(bt, t, band.attrs.get("stop"))
            shade(
                axes[2],
                bt,
                band["omega_p025"],
                band["omega_p975"],
                "0.6",
                f"central 95% of {k} members{note}",
                alpha=0.3,
            )
            shade(
                axes[2],
                bt,
                band["omega_ci_low"],
                band["omega_ci_high"],
                COLORS["fit"],
                "95% interval of the ensemble mean",
                alpha=0.45,
            )
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
