"""Figures of the motor under load: the torque–speed curve, output power and efficiency
(docs/model.md "The motor under load"), each with its 95 % band and both continuation branches."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

#: Colours of the continuation branches.
BRANCH_STYLE = {"up": ("C0", "loads increasing"), "down": ("C3", "loads decreasing")}


def _si(ds: xr.Dataset) -> tuple[float, float, float, str, str, str]:
    """Unit factors and labels: SI for a physical scene (its scales), else nondimensional."""
    if "torque_scale_Nm" in ds.attrs:
        return (
            float(ds.attrs["torque_scale_Nm"]),
            float(ds.attrs["omega_scale_rad_s"]),
            float(ds.attrs["torque_scale_Nm"]) * float(ds.attrs["omega_scale_rad_s"]),
            "load torque [N·m]",
            "mean speed [rad/s]",
            "output power [W]",
        )
    return (
        1.0,
        1.0,
        1.0,
        r"load torque $\tau_L$",
        r"mean speed $\bar\Omega$",
        r"power $\tau_L\bar\Omega$",
    )


def fig_torque_speed(ds: xr.Dataset) -> Figure:
    """The motor's load characteristic (``bouncedisk torque-speed`` file).

    Three panels against the load torque: the mean rotor speed, the output power
    ``P_out = τ_L Ω̄`` and the friction drive's efficiency ``W_L / W_t``; each branch of the
    continuation sweep with the 95 % interval of its ensemble mean as a band. The stall torque
    and the maximum-power point are marked with their bootstrap intervals.
    """
    kt, kw, kp, xlab, ylab, plab = _si(ds)
    load = ds["load_torque"].values * kt
    fig = Figure(figsize=(7.5, 8.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        ("mean_omega", kw, ylab),
        ("power_out", kp, plab),
        ("efficiency_torsion", 1.0, "efficiency $W_L/W_t$"),
    )
    for ax, (name, k, label) in zip(axes, panels, strict=True):
        for branch in ds["branch"].values:
            color, text = BRANCH_STYLE.get(str(branch), ("k", str(branch)))
            sel = ds.sel(branch=branch)
            ax.fill_between(load, sel[f"{name}_ci95_low"] * k, sel[f"{name}_ci95_high"] * k,
                            color=color, alpha=0.25, lw=0)  # fmt: skip
            ax.plot(load, sel[name] * k, "o-", ms=3, lw=1.0, color=color, label=text)
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_ylabel(label)
    _mark(axes[0], ds, "stall_torque", kt, None, "stall torque")
    _mark(
        axes[1],
        ds,
        "max_power_load",
        kt,
        ds.attrs.get("max_power", np.nan) * kp,
        "max. power at load",
    )
    axes[0].legend(fontsize=8, loc="upper right")
    axes[2].set_xlabel(xlab)
    eff = ds["efficiency_torsion"].values
    if np.isfinite(eff).any():
        top = np.nanmax(eff)
        axes[2].set_ylim(min(0.0, np.nanmin(eff[eff > -1.0], initial=0.0)), max(top * 1.2, 0.05))
    members = ds.sizes.get("member", 0)
    fig.suptitle(
        f"Load characteristic: e = {ds.attrs.get('e', np.nan):.3g}, "
        f"$\\omega_s$ = {ds.attrs.get('omega_s', np.nan):.4g}, "
        f"$R_\\phi$ = {ds.attrs.get('r_phi', np.nan):.3g}, $\\psi$ = {ds.attrs.get('psi', np.nan):.3g} "
        f"({members} members, 95% bands)",
        fontsize=10,
    )
    return fig


def _mark(ax, ds: xr.Dataset, name: str, scale: float, level: float | None, label: str) -> None:
    """A vertical line at a derived load with its interval shaded (if the file has it)."""
    x = ds.attrs.get(name)
    if x is None or not np.isfinite(x):
        return
    lo, hi = np.asarray(ds.attrs.get(f"{name}_ci95", [np.nan, np.nan]), dtype=float)
    ax.axvline(x * scale, color="k", lw=0.8, ls="--", label=f"{label} {x * scale:.3g}")
    if np.isfinite(lo) and np.isfinite(hi):
        ax.axvspan(lo * scale, hi * scale, color="k", alpha=0.12, lw=0)
    if level is not None and np.isfinite(level):
        ax.plot([x * scale], [level], "k*", ms=8)
    ax.legend(fontsize=8, loc="best")
