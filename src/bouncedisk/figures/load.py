"""Figures of the motor under load: the torque–speed curve, output power and efficiency
(docs/model.md "The motor under load"), each with its 95 % band and both continuation branches."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .common import shade

#: Colours of the continuation branches.
BRANCH_STYLE = {"up": ("C0", "loads increasing"), "down": ("C3", "loads decreasing")}
#: What the figure says when there is no stall torque or no maximum (the file's states).
STATE_TEXT = {
    "beyond_largest_load": "beyond the largest load",
    "below_smallest_load": "below the smallest load",
    "backwards_at_no_load": "none: runs backwards at no load",
    "at_smallest_load": "at the smallest load",
    "none": "none (no finite values)",
}


def _units(ds: xr.Dataset) -> tuple[float, float, float, str, str, str]:
    """Unit factors and labels: a lab's units for a physical scene (mN·m, rad/s, mW, from its
    scales), else nondimensional."""
    if "torque_scale_Nm" in ds.attrs:
        kt, kw = float(ds.attrs["torque_scale_Nm"]), float(ds.attrs["omega_scale_rad_s"])
        return (
            1e3 * kt,
            kw,
            1e3 * kt * kw,
            "load torque [mN·m]",
            "mean speed [rad/s]",
            "output power [mW]",
        )
    return (
        1.0,
        1.0,
        1.0,
        r"load torque $\tau_L$ (units of $\mu m_r g_{eff} r_{eff}$)",
        r"mean speed $\bar\Omega$ (design maps: $R_\phi\bar\Omega$)",
        r"output power $\tau_L\bar\Omega$ (maps: $\times R_\phi$)",
    )


def _zero_width(ds: xr.Dataset) -> bool:
    """Are the mean speed's 95 % bands of zero width at every load (a periodic attractor)?"""
    width = ds["mean_omega_ci95_high"] - ds["mean_omega_ci95_low"]
    scale = float(np.nanmax(np.abs(ds["mean_omega"].values)) or 1.0)
    return bool(np.all(np.nan_to_num(width.values) <= 1e-6 * scale))


def fig_torque_speed(ds: xr.Dataset) -> Figure:
    """The motor's load characteristic (``bouncedisk torque-speed`` file).

    Three panels against the load torque: the mean rotor speed, the output power
    ``P_out = τ_L Ω̄`` and the friction drive's efficiency ``W_L / W_t`` up to the stall (past
    it the load drives the rotor and the ratio is no efficiency); each branch of the
    continuation sweep with the 95 % interval of its ensemble mean as a band. The stall torque
    and the maximum-power point are marked with their intervals where they were found, and said
    to lie beyond the loads (or to be absent) where they were not (the file's
    ``stall_torque_state`` and ``max_power_state``).
    """
    kt, kw, kp, xlab, ylab, plab = _units(ds)
    tu, wu, pu = (" mN·m", " rad/s", " mW") if "torque_scale_Nm" in ds.attrs else ("", "", "")
    load = ds["load_torque"].values * kt
    steady = stationary(ds)
    fig = Figure(figsize=(7.5, 8.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        ("mean_omega", kw, ylab),
        ("power_out", kp, plab),
        ("efficiency_torsion", 1.0, "efficiency $W_L/W_t$ (loads below stall)"),
    )
    for ax, (name, k, label) in zip(axes, panels, strict=True):
        for b, branch in enumerate(ds["branch"].values):
            color, text = BRANCH_STYLE.get(str(branch), ("k", str(branch)))
            sel = ds.sel(branch=branch)
            keep = steady[b] & (
                sel["mean_omega"].values > 0.0 if name == "efficiency_torsion" else True
            )
            low = np.where(keep, sel[f"{name}_ci95_low"].values, np.nan) * k
            high = np.where(keep, sel[f"{name}_ci95_high"].values, np.nan) * k
            shade(ax, load, low, high, color, alpha=0.25)
            ax.plot(
                load,
                np.where(keep, sel[name].values, np.nan) * k,
                "o-",
                ms=3,
                lw=1.0,
                color=color,
                label=text,
            )
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_ylabel(label)
    if not steady.all():  # the readings that are no stationary speed: named, not drawn
        gone = ~steady.all(axis=0)
        for ax in axes:
            for x in load[gone]:
                ax.axvline(x, color="0.85", lw=2.0, zorder=0)
        n = int((~steady).sum())
        axes[0].plot(
            [],
            [],
            "|",
            color="0.85",
            ms=10,
            mew=2,
            label=f"{n} readings not stationary (grey lines): not drawn",
        )
    _stall(axes[0], ds, kt, tu)
    _max_power(axes[1], ds, kt, kp, tu, pu)
    axes[0].legend(fontsize=8, loc="best")
    axes[1].legend(fontsize=8, loc="best")
    axes[2].set_xlabel(xlab)
    members = ds.sizes.get("member", 0)
    if _zero_width(ds):
        bands = "95% bands of zero width: a periodic attractor"
    else:
        width = (ds["mean_omega_ci95_high"] - ds["mean_omega_ci95_low"]).values
        width = np.where(steady, width, np.nan)
        half = np.nanmax(width) / 2 * kw
        bands = f"95% bands, the mean speed's half-width at most {half:.2g}{wu}"
    about = ds.attrs.get("motor_description")  # a fitted motor's load file says what it is
    head = f"Load characteristic of {about}\n" if about else "Load characteristic: "
    fig.suptitle(
        f"{head}e = {ds.attrs.get('e', np.nan):.3g}, "
        f"$\\omega_s$ = {ds.attrs.get('omega_s', np.nan):.4g}, "
        f"$R_\\phi$ = {ds.attrs.get('r_phi', np.nan):.3g}, $\\psi$ = {ds.attrs.get('psi', np.nan):.3g}"
        f"\n({members} members, {bands})",
        fontsize=10,
    )
    return fig


def stationary(ds: xr.Dataset) -> np.ndarray:
    """Per branch and load ``(branch, load)``: is its reading a stationary speed? The file's
    ``settled``; in a file without it, not past the momentum bound ``τ_L = 1`` (docs/model.md
    "The motor under load")."""
    from ..studies.load_summary import MOMENTUM_BOUND

    if "settled" in ds:
        return ds["settled"].values.astype(bool)  # (branch, load), as written
    steady = ds["load_torque"].values <= MOMENTUM_BOUND
    return np.tile(steady, (len(ds["branch"]), 1))


def _interval(ds: xr.Dataset, name: str) -> tuple[float, float]:
    lo, hi = np.asarray(ds.attrs.get(f"{name}_ci95", [np.nan, np.nan]), dtype=float)
    return float(lo), float(hi)


def _stall(ax, ds: xr.Dataset, kt: float, tu: str) -> None:
    """The stall torque: a line with its interval shaded, or a note where it lies."""
    x = float(ds.attrs.get("stall_torque", np.nan))
    state = str(ds.attrs.get("stall_torque_state", "found" if np.isfinite(x) else "none"))
    if state != "found" or not np.isfinite(x):
        ax.plot([], [], " ", label=f"stall torque: {STATE_TEXT.get(state, state)}")
        return
    lo, hi = _interval(ds, "stall_torque")
    ax.axvline(x * kt, color="k", lw=0.8, ls="--", label=f"stall torque {x * kt:.3g}{tu}")
    if np.isfinite(lo) and np.isfinite(hi):
        ax.axvspan(
            lo * kt,
            hi * kt,
            color="k",
            alpha=0.12,
            lw=0,
            label=f"its 95% interval [{lo * kt:.3g}, {hi * kt:.3g}]",
        )


def _max_power(ax, ds: xr.Dataset, kt: float, kp: float, tu: str, pu: str) -> None:
    """The maximum-power point (a star) with its load's interval, where the power has a
    maximum among the loads; a note where it has none."""
    x = float(ds.attrs.get("max_power_load", np.nan))
    state = str(ds.attrs.get("max_power_state", "found" if np.isfinite(x) else "none"))
    if state != "found" or not np.isfinite(x):
        ax.plot([], [], " ", label=f"max. power: {STATE_TEXT.get(state, state)}")
        return
    p = float(ds.attrs.get("max_power", np.nan)) * kp
    lo, hi = _interval(ds, "max_power_load")
    where = (
        f" (located in [{lo * kt:.3g}, {hi * kt:.3g}])"
        if np.isfinite(lo) and np.isfinite(hi)
        else ""
    )
    ax.plot(
        [x * kt], [p], "k*", ms=9, label=f"max. power {p:.3g}{pu} at load {x * kt:.3g}{tu}{where}"
    )
    if np.isfinite(lo) and np.isfinite(hi):
        ax.axvspan(lo * kt, hi * kt, color="k", alpha=0.12, lw=0, label="95% interval of its load")
