"""What accuracy and statistics cost: work–precision, scaling, stats cost."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter

from .common import COLORS

#: Where an error of 0 (identical to the reference) is drawn on the log axis.
ZERO_ERROR = 1e-17


def fig_work_precision(table: pd.DataFrame) -> Figure:
    """Error against CPU time, one line per solver and case (log–log).

    Errors are measured against the exact engine at ``tol = 1e-14``
    (:mod:`bouncedisk.studies.work_precision`): the exact engine's own errors below about
    ``1e-14`` are the rounding of double-precision impact times, and a run identical to the
    reference (error 0) is drawn at :data:`ZERO_ERROR` as an open triangle.
    """
    cases = list(dict.fromkeys(table["case"]))
    fig = Figure(figsize=(5.5 * len(cases), 4.8), layout="constrained")
    axes = fig.subplots(1, len(cases), squeeze=False)[0]
    for ax, case in zip(axes, cases, strict=True):
        sub = table[table["case"] == case]
        for solver, g in sub.groupby("solver", sort=False):
            g = g.sort_values("cpu_s")
            line = ax.loglog(
                g["cpu_s"], g["error"].clip(lower=ZERO_ERROR), "o-", ms=4, lw=1, label=solver
            )
            zero = g[g["error"] == 0.0]
            ax.plot(
                zero["cpu_s"],
                np.full(len(zero), ZERO_ERROR),
                "v",
                mfc="none",
                ms=8,
                color=line[0].get_color(),
            )
        ax.axhspan(
            ZERO_ERROR / 3,
            1e-14,
            color="0.85",
            lw=0,
            zorder=0,
            label="double-precision rounding;\n▽ identical to the reference (0)",
        )
        ax.set_xlabel("CPU time [s]")
        ax.set_ylabel("max error in impact times (first 20)")
        ax.set_title(case.replace("omega_s", r"$\omega_s$"), fontsize=10)
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("Errors against the exact engine at tol 1e-14 (the reference)", fontsize=10)
    return fig


def _scene_of(rows: pd.DataFrame, swept: str = "") -> str:
    """``e = …, ω_s = …`` of a study's rows (``ω_s`` left out when it is the swept one); the
    bare engine, impacts and contact only, unless the rows say otherwise."""
    parts = []
    if "e" in rows and rows["e"].notna().any():
        parts.append(f"e = {float(rows['e'].dropna().iloc[0]):g}")
    if swept != "omega_s" and len(rows):
        parts.append(rf"$\omega_s$ = {float(rows['omega_s'].iloc[0]):g}")
    return ", ".join(parts)


def fig_scaling(table: pd.DataFrame) -> Figure:
    """Cost per impact against omega_s, total time and memory against the number of impacts,
    and the cost per impact of each effect; each panel names its motor."""
    fig = Figure(figsize=(17.0, 4.4), layout="constrained")
    a1, a2, a3, a4 = fig.subplots(1, 4)
    w = table[table["study"] == "omega"]
    a1.semilogx(w["omega_s"], 1e9 * w["s_per_impact"], "o-")
    a1.set_xlabel(r"stator frequency $\omega_s$")
    a1.set_ylabel("time per impact [ns]")
    a1.set_ylim(bottom=0)
    a1.set_title(f"cost per impact against $\\omega_s$ ({_scene_of(w, 'omega_s')})", fontsize=9)
    n = table[table["study"] == "impacts"]
    a2.loglog(n["n_impacts"], n["seconds"], "o-", label="measured")
    if len(n):
        x = n["n_impacts"].values
        a2.loglog(x, n["seconds"].values[-1] * x / x[-1], "--", color="k", lw=0.8, label="linear")
    a2.set_xlabel("impacts")
    a2.set_ylabel("wall time [s]")
    a2.legend(fontsize=8)
    a2.set_title(f"time against run length ({_scene_of(n)})", fontsize=9)
    m = table[table["study"] == "memory"]
    # a narrow range (the imports dominate): a linear axis, not a log one with a single decade
    a3.semilogx(m["n_impacts"], m["peak_mb"], "o-")
    a3.set_xlabel("impacts (events only, streamed to netCDF)")
    a3.set_ylabel("peak memory of the process [MB]")
    a3.set_title(f"memory against run length ({_scene_of(m)})", fontsize=9)
    f = table[table["study"] == "effects"]
    if "effect" in f and len(f):
        ns = 1e9 * f["s_per_impact"].values
        y = np.arange(len(f))
        a4.semilogx(ns, y, "o", color="C0")
        for yi, v, label in zip(y, ns, f["effect"].astype(str), strict=True):
            a4.annotate(
                f"{label}: {v:,.0f} ns",
                (v, yi),
                xytext=(0, 6),
                textcoords="offset points",
                ha="center",
                fontsize=7,
            )
        a4.set_yticks([])
        a4.set_ylim(len(f) - 0.4, -0.6)
        a4.set_xlim(ns.min() / 4, ns.max() * 12)
        a4.xaxis.set_minor_formatter(NullFormatter())
        a4.set_xlabel("time per impact [ns] (log scale)")
        a4.set_title(f"cost of each effect ({_scene_of(f)})", fontsize=9)
    else:  # a table without the effects' rows
        a4.remove()
    fig.suptitle(
        "Cost of the exact engine on one core: impacts and contact, torsion only where said",
        fontsize=10,
    )
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
    ax.loglog(
        x,
        ref["half_width"] * np.sqrt(ref["cpu_s"] / x),
        "k--",
        lw=0.8,
        label=r"$\propto 1/\sqrt{\mathrm{CPU}}$",
    )
    sd = float(singles["mean_omega"].std(ddof=1))
    ax.axhspan(
        sd * 0.98, sd * 1.02, color="0.5", alpha=0.5, label=f"scatter of single runs (sd {sd:.2f})"
    )
    ax.xaxis.set_minor_formatter(NullFormatter())
    # under one decade: ticks at 1, 2, 5 of each decade, not a single label
    ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("CPU time of the ensemble [s] (one core)")
    ax.set_ylabel(r"95% half-width of the mean rotor speed $\bar\Omega$")
    ax.legend(fontsize=7, loc="lower left")
    ax.set_title("cost of a confidence interval", fontsize=10)
    best = table.loc[table["member_time"].idxmax()]
    ax2.axhspan(
        best["ci_low"],
        best["ci_high"],
        color=COLORS["fit"],
        alpha=0.3,
        label=f"ensemble: {int(best['members'])} members × {best['duration']:g}, 95%",
    )
    ax2.axhline(best["mean_omega"], color=COLORS["fit"], lw=1)
    ax2.plot(
        singles["de"] * 1e9,
        singles["mean_omega"],
        "o",
        color=COLORS["rotor"],
        label="single runs (no noise)",
    )
    ax2.set_xlabel(r"change of $e$ [$10^{-9}$]")
    ax2.set_ylabel(r"time-averaged rotor speed $\bar\Omega$")
    ax2.set_title("single runs jump; the ensemble statistic does not", fontsize=10)
    ax2.legend(fontsize=7)
    return fig
