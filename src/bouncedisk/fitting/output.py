"""The fit file (docs/formats.md) and its one-screen summary.

Names kept from docs/formats.md: ``omega_measured(time)``, ``omega_fitted(time)`` (rad/s, on the
measured ``time`` in s), one scalar per parameter with ``ci_low``/``ci_high``, and the global
attributes ``steady_speed_rad_s``/``time_constant_s`` (the first-order trend of the data). Added:
the fitted model's band ``omega_fitted_low``/``omega_fitted_high`` (95 % interval of its ensemble
mean), both trends, the profiles (``profile_chi2_<p>`` over ``profile_<p>``), correlations, the
identified combinations, and every statistic measured and fitted (``stat_<name>(source)``, each in
its own units).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.stats import chi2 as chi2_dist

from ..analysis.observables import first_order_trend
from ..io.provenance import base_attrs, new_run_id, sha256_file
from .core import FitResult
from .members import BOUNDS
from .summary_stats import STAT_LONG_NAMES, STAT_UNITS, STATS, trend_stride
from .uncertainty import THRESHOLD, adequate, identified, reference_chi2

#: Public name: (search coordinate, transform, units, long name).
PUBLIC = {
    "e": ("e", lambda v: v, "1", "coefficient of restitution"),
    "r_phi": ("log10_r_phi", lambda v: 10.0**v, "1", "angular amplitude ratio R_phi"),
    "psi": ("psi", lambda v: v, "rad", "phase of the torsional vibration"),
    "omega_s": ("omega_s", lambda v: v, "1", "nondimensional stator frequency"),
    "speed_scale": (
        "log10_speed_scale",
        lambda v: 10.0**v,
        "rad/s",
        "rad/s per unit of nondimensional rotor angular velocity",
    ),
    "e_sigma": (
        "e_sigma",
        lambda v: v,
        "1",
        "restitution noise: standard deviation of an impact's coefficient of restitution about e",
    ),
}


def _curves(fit: FitResult, ds_time: np.ndarray) -> dict:
    """Measured and fitted curves on the measured time (fitted ones interpolated from the grid)."""
    g = fit.layout.t
    b = fit.band

    def on_time(v):
        return np.interp(ds_time, g, v)

    step = trend_stride(len(g))
    tm = first_order_trend(g[::step], b["mean"][::step])
    td = first_order_trend(g[::step], np.interp(g, fit.curve.time, fit.curve.omega)[::step])

    def var(v, long_name):
        return ("time", v, {"units": "rad/s", "long_name": long_name})

    lo, hi = residual_band(b, fit.curve.sigma, len(fit.runs))
    runs = np.array([np.interp(ds_time, r.time, r.omega) for r in fit.runs])
    return {
        "omega_measured_run": (
            ("run", "time"),
            runs,
            {"units": "rad/s", "long_name": "measured rotor angular velocity of each run-up"},
        ),
        "residual_band_low": var(
            on_time(lo),
            "lower end of the 95% band of data minus the "
            "ensemble mean: members' 2.5th percentile and the measurement "
            "noise in quadrature",
        ),
        "residual_band_high": var(
            on_time(hi),
            "upper end of the 95% band of data minus the ensemble mean (see residual_band_low)",
        ),
        "omega_measured": var(
            fit.curve.omega,
            "measured rotor angular velocity (the mean of the run-ups when several are fitted)",
        ),
        "omega_fitted": var(
            on_time(b["mean"]),
            "fitted model: ensemble mean of the rotor angular velocity (noise-free members)",
        ),
        "omega_fitted_low": var(on_time(b["low"]), "lower end of the 95% interval of the mean"),
        "omega_fitted_high": var(on_time(b["high"]), "upper end of the 95% interval of the mean"),
        "omega_fitted_p025": var(on_time(b["p025"]), "2.5th percentile of the fitted members"),
        "omega_fitted_p975": var(on_time(b["p975"]), "97.5th percentile of the fitted members"),
        "omega_fitted_member0": var(on_time(b["member0"]), "one member of the fitted model"),
        "trend_fitted": var(tm(ds_time), "first-order trend of the fitted model's ensemble mean"),
        "trend_measured": var(td(ds_time), "first-order trend of the data"),
    }


def residual_band(band: dict, sigma: float, runs: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """95 % band of the measured curve minus the ensemble mean (Fig. 5's residual panel).

    A measured curve is one member plus measurement noise (docs/model.md "Long-run statistics"), so
    ``data − mean`` should stay within the members' central 95 % about the mean, widened in
    quadrature by the measurement noise ``1.96 σ``. The mean of ``runs`` run-ups spreads
    ``√runs`` times less (both parts divided by ``√runs``).
    """
    mean = band["mean"]
    noise = (1.96 * sigma) ** 2
    lo = -np.sqrt(((mean - band["p025"]) ** 2 + noise) / runs)
    hi = np.sqrt(((band["p975"] - mean) ** 2 + noise) / runs)
    return lo, hi


#: Fig. 5 check: a residual outside its 95 % band at more than this fraction of the samples, or
#: outside for longer than :data:`RESIDUAL_MAX_RUN_TAU` time constants in a row, is a systematic
#: excursion (the model does not reproduce the curve).
RESIDUAL_MAX_OUTSIDE = 0.10
RESIDUAL_MAX_RUN_TAU = 1.0


def residual_check(ds: xr.Dataset) -> dict[str, float]:
    """Where the data leave the fitted model's band: fraction outside and the longest run (s).

    Returns ``outside_fraction`` (raw residual outside the band), ``longest_run_s`` (longest
    stretch over which the residual, smoothed over a tenth of the data's time constant so that
    the measurement noise does not break a run, stays outside the band), ``time_constant_s``
    and ``passed`` (fraction at most :data:`RESIDUAL_MAX_OUTSIDE`, run at most
    :data:`RESIDUAL_MAX_RUN_TAU` data time constants).
    """
    t = ds["time"].values
    r = ds["omega_measured"].values - ds["omega_fitted"].values
    lo, hi = ds["residual_band_low"].values, ds["residual_band_high"].values
    out = (r < lo) | (r > hi)
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    tau = float(ds.attrs["time_constant_s"])
    w = int(max(1, min(len(r), round(0.1 * tau / dt)))) if dt > 0 else 1
    smooth = np.convolve(r, np.ones(w) / w, mode="same")
    longest, run = 0, 0
    for o in (smooth < lo) | (smooth > hi):
        run = run + 1 if o else 0
        longest = max(longest, run)
    frac = float(out.mean())
    passed = frac <= RESIDUAL_MAX_OUTSIDE and longest * dt <= RESIDUAL_MAX_RUN_TAU * tau
    return {
        "outside_fraction": frac,
        "longest_run_s": longest * dt,
        "time_constant_s": tau,
        "passed": bool(passed),
    }


def _parameters(fit: FitResult) -> tuple[dict, list[str]]:
    """Scalar parameter variables with intervals, and the names not identified (an inadequate
    fit, :func:`.uncertainty.identified`: every interval NaN, every parameter not identified)."""
    out, not_identified = {}, []
    prof = {p.name: p for p in fit.profiles}
    ok, reason = identified(fit.chi2, fit.n_statistics)
    for pub, (internal, fn, units, long_name) in PUBLIC.items():
        if internal not in fit.names:
            continue
        j = fit.names.index(internal)
        lo_b, hi_b = BOUNDS[internal]
        attrs = {
            "units": units,
            "long_name": long_name,
            "ci_level": 0.95,
            "search_low": fn(lo_b),
            "search_high": fn(hi_b),
            "search_coordinate": internal,
            "local_sd_search_coordinate": fit.local_sd[j],
        }
        p = prof.get(internal)
        if p is None:
            attrs.update(
                ci_low=fn(lo_b),
                ci_high=fn(hi_b),
                identified=0,
                interval="not profiled: the search range",
            )
        else:
            attrs.update(
                ci_low=fn(p.ci_low),
                ci_high=fn(p.ci_high),
                identified=int(p.identified),
                interval=f"profile likelihood, delta chi2 <= {p.threshold:.4g}"
                + (f" (scaled from {THRESHOLD:.3f} by chi2/dof)" if p.threshold > THRESHOLD else "")
                + (
                    "; widened to every acceptable point found (several basins)"
                    if p.multimodal
                    else ""
                ),
                multimodal=int(p.multimodal),
                delta_chi2=p.threshold,
                open_low=int(p.open_low),
                open_high=int(p.open_high),
            )
            if not p.identified:
                not_identified.append(pub)
        if not ok:
            attrs.update(ci_low=np.nan, ci_high=np.nan, identified=0, interval=reason)
            if pub not in not_identified:
                not_identified.append(pub)
        out[pub] = xr.DataArray(fn(fit.x[j]), attrs=attrs)
    return out, not_identified


def _profiles(fit: FitResult) -> dict:
    out = {}
    for p in fit.profiles:
        pub = next(k for k, v in PUBLIC.items() if v[0] == p.name)
        fn, units = PUBLIC[pub][1], PUBLIC[pub][2]
        dim = f"profile_{pub}"
        out[dim] = (dim, fn(p.values), {"units": units, "long_name": f"profiled value of {pub}"})
        out[f"profile_chi2_{pub}"] = (
            dim,
            p.chi2 - fit.chi2,
            {"units": "1", "long_name": f"profile of chi2 over {pub}, minus the best chi2"},
        )
    return out


def _statistics(fit: FitResult) -> dict:
    out = {}
    for k, name in enumerate(STATS):
        vals = [fit.target[k], fit.fitted_stats[k], fit.fitted_sd[k]]
        out[f"stat_{name}"] = (
            "source",
            np.array(vals),
            {"units": STAT_UNITS[k], "long_name": STAT_LONG_NAMES[k]},
        )
    return out


def _basins(fit: FitResult) -> xr.Dataset:
    """Every acceptable basin (:mod:`.likelihood_basins`): its best point, ``χ²`` and size; the first is the
    estimate's."""
    n = len(fit.basins)
    x = np.array([b.x for b in fit.basins]).reshape(n, len(fit.names))
    return xr.Dataset(
        {
            "basin_x": (
                ("basin", "parameter"),
                x,
                {
                    "units": "1",
                    "long_name": "best point of each "
                    "acceptable basin in search coordinates (basin 0: the estimate)",
                },
            ),
            "basin_chi2": (
                "basin",
                np.array([b.chi2 for b in fit.basins]),
                {"units": "1", "long_name": "chi2 of each basin's best point"},
            ),
            "basin_points": (
                "basin",
                np.array([b.points for b in fit.basins], dtype=np.int64),
                {"units": "1", "long_name": "evaluated points in each basin"},
            ),
        },
        coords={"basin": ("basin", np.arange(n)), "parameter": ("parameter", fit.names)},
    )


def interval_reference(fit: FitResult) -> float:
    """The ``χ²`` the intervals' ``Δχ²`` is measured from: the best, or the level on fresh
    members when that is higher (:func:`.uncertainty.reference_chi2`)."""
    level = fit.chi2_level if np.isfinite(fit.chi2_level) else None
    return reference_chi2(fit.chi2, level)


def starts_accepted(fit: FitResult) -> int:
    """How many local-search starts end where the intervals would accept a point: ``χ²`` at most
    the intervals' threshold above their reference (:func:`interval_reference`)."""
    limit = interval_reference(fit) + fit.interval_threshold
    return int(np.sum(np.asarray(fit.start_chi2) <= limit))


def _waterfall(fit: FitResult) -> xr.Dataset:
    """Every local-search start's end ``χ²`` and point, best first (the waterfall)."""
    n = len(fit.start_chi2)
    return xr.Dataset(
        {
            "start_chi2": (
                "start",
                np.asarray(fit.start_chi2, float),
                {
                    "units": "1",
                    "long_name": "chi2 each local-search start ended at, under the final "
                    "covariance, best first (the waterfall)",
                },
            ),
            "start_x": (
                ("start", "parameter"),
                np.asarray(fit.start_x, float).reshape(n, len(fit.names)),
                {"units": "1", "long_name": "where each start ended, in search coordinates"},
            ),
        },
        coords={"start": ("start", np.arange(n)), "parameter": ("parameter", fit.names)},
    )


def fit_dataset(fit: FitResult) -> xr.Dataset:
    """The fit file (module docstring)."""
    curve = fit.curve
    paths = [r.path for r in fit.runs]
    path = ", ".join(paths)
    ds = xr.Dataset(
        {**_curves(fit, curve.time), **_statistics(fit), **_profiles(fit)},
        coords={
            "time": ("time", curve.time, {"units": "s", "long_name": "time", "axis": "T"}),
            "run": ("run", np.arange(len(fit.runs))),
            "source": ("source", ["measured", "fitted_mean", "fitted_member_sd"]),
            "parameter": ("parameter", fit.names),
            "parameter2": ("parameter2", fit.names),
            "combination": ("combination", np.arange(len(fit.names))),
        },
    )
    ds["correlation"] = (
        ("parameter", "parameter2"),
        fit.correlation,
        {
            "units": "1",
            "long_name": "correlation of the search coordinates (inverse of J^T J at the estimate)",
        },
    )
    ds["combination_sd"] = (
        "combination",
        fit.comb_sd,
        {
            "units": "1",
            "long_name": "standard deviation of each eigen-combination, as a fraction of "
            "the search ranges (< 1: identified by the curve)",
        },
    )
    ds = ds.merge(_basins(fit)).merge(_waterfall(fit))
    ds["combination_vector"] = (
        ("combination", "parameter"),
        fit.comb_vectors,
        {
            "units": "1",
            "long_name": "eigen-combination of the search coordinates scaled to their ranges",
        },
    )
    params, not_identified = _parameters(fit)
    for k, v in params.items():
        ds[k] = v
    ds["t_c"] = xr.DataArray(fit.physical["t_c"], attrs={"units": "s", "long_name": "t_c"})
    if "speed_scale" not in ds:
        ds["speed_scale"] = xr.DataArray(
            fit.physical["speed_scale"],
            attrs={"units": "rad/s", "long_name": "R_phi Phi0 / t_c (from the known Phi0)"},
        )
    ds.attrs.update(base_attrs(f"bouncedisk fit to {path}", kind="fit"))
    ds.attrs.update(_global_attrs(fit, paths, not_identified))
    if fit.load is not None:
        from .load_output import load_dataset

        ds = ds.merge(load_dataset(fit), combine_attrs="no_conflicts")
    check = residual_check(ds)
    ds.attrs.update(
        residual_outside_fraction=check["outside_fraction"],
        residual_longest_run_s=check["longest_run_s"],
        residual_within_band=int(check["passed"]),
    )
    return ds


def _global_attrs(fit: FitResult, paths: list[str], not_identified: list[str]) -> dict:
    th = fit.physical
    sha = ", ".join(sha256_file(p) for p in paths)
    n_stats = fit.n_statistics
    ok, reason = identified(fit.chi2, fit.n_statistics)
    return {
        "identified": "yes" if ok else "no",
        "identified_reason": reason,
        "run_id": new_run_id("fit", sha),
        "scene_name": "fit",
        "status": "completed",
        "e": th["e"],
        "omega_s": th["omega_s"],
        "r_phi": th["r_phi"],
        "psi": th["psi"],
        "effects": "contact,impacts,impulse_cap,restitution_noise,torsion",
        "solver": "exact",
        "steady_speed_rad_s": fit.trend_data[0],
        "time_constant_s": fit.trend_data[1],
        "steady_speed_ci_rad_s": np.asarray(fit.trend_ci[0]),
        "time_constant_ci_s": np.asarray(fit.trend_ci[1]),
        "model_steady_speed_rad_s": fit.trend_model[0],
        "model_time_constant_s": fit.trend_model[1],
        "trend_comment": "steady_speed_rad_s, time_constant_s: first-order trend of the data "
        "(95% intervals: block bootstrap); model_*: trend of the fitted model's ensemble mean",
        "not_identified": ",".join(not_identified) or "none",
        "basins": len(fit.basins),
        "chi2_reference": interval_reference(fit),
        "delta_chi2": fit.interval_threshold,
        "starts": len(fit.start_chi2),
        "starts_accepted": starts_accepted(fit),
        "basin_rule": "basins: evaluated points within the interval threshold of the best chi2, "
        "grouped within 5% of every search range; the estimate is the basin with the lowest chi2 "
        "(10 significant digits, ties to the smaller point); more than one basin: the data do not "
        "single one out",
        "chi2": fit.chi2,
        "n_statistics": n_stats,
        "chi2_p_value": float(chi2_dist.sf(fit.chi2, n_stats)),
        "chi2_fresh_members": fit.chi2_level,
        "fit_adequate": int(adequate(fit.chi2, n_stats)),
        "evaluations": fit.evaluations,
        "ensemble_members": fit.settings.members,
        "band_members": fit.settings.band_members,
        "e_sigma": fit.theta.get("e_sigma", fit.settings.e_sigma),
        "e_sigma_fitted": int("e_sigma" in fit.names),
        "seed": fit.settings.seed,
        "n_bootstrap": fit.settings.bootstrap,
        "scan_points": fit.settings.scan,
        "zoom_points": fit.settings.zoom,
        "joint_zoom_points": fit.settings.joint_zoom,
        "work_note": fit.note or "none",
        "curve_file": ", ".join(paths),
        "curve_sha256": sha,
        "runs": len(paths),
        "curve_source": fit.curve.source,
        "curve_synthetic": int(fit.curve.synthetic),
        "drive_frequency_hz": fit.curve.drive_frequency_hz,
        "Phi0_rad": fit.curve.phi0_rad if fit.curve.phi0_rad is not None else "unknown",
        "noise_sigma_rad_s": fit.curve.sigma,
        "wall_time_s": round(fit.wall_time_s, 3),
        "method": "synthetic likelihood of ensemble statistics; Sobol scan of (e, omega_s) with "
        "psi from a grid and r_phi matched to the trend, then multi-start least squares; profile "
        "likelihoods widened to every acceptable point found",
    }


def summary_text(ds: xr.Dataset) -> str:
    """A human-readable summary of a fit file."""
    a = ds.attrs
    lines = [
        f"fit of {a.get('curve_file')} (seed {a.get('seed')}, {a.get('wall_time_s')} s, "
        f"chi2 {a.get('chi2', float('nan')):.4g} on {a.get('n_statistics')} statistics)"
    ]
    if a.get("identified", "yes") == "no":
        lines.append(f"  NOT IDENTIFIED: {a.get('identified_reason', 'inadequate fit')}")
    for name in PUBLIC:
        if name in ds and "ci_low" in ds[name].attrs:
            v = ds[name].attrs
            flag = "" if v["identified"] else "   <- not identified"
            unit = "" if v["units"] == "1" else f" {v['units']}"  # "1": dimensionless (CF)
            ci = (
                f"95% [{v['ci_low']:.5g}, {v['ci_high']:.5g}]{unit}"
                if np.isfinite(v["ci_low"])
                else "no interval (inadequate fit)"
            )
            lines.append(f"  {name:>12} = {float(ds[name]):.5g}{unit}   {ci}{flag}")
    if not a.get("e_sigma_fitted", 1):
        lines.append(f"  {'e_sigma':>12} = {a['e_sigma']:.5g}   stated, not fitted")
    s_ci, t_ci = a["steady_speed_ci_rad_s"], a["time_constant_ci_s"]
    lines.append(
        f"  trend of the data: steady speed {a['steady_speed_rad_s']:.5g} rad/s "
        f"[{s_ci[0]:.5g}, {s_ci[1]:.5g}], time constant {a['time_constant_s']:.4g} s "
        f"[{t_ci[0]:.4g}, {t_ci[1]:.4g}]"
    )
    lines.append(
        f"  trend of the fitted model: {a['model_steady_speed_rad_s']:.5g} rad/s, "
        f"{a['model_time_constant_s']:.4g} s; not identified: {a['not_identified']}"
    )
    if a.get("starts", 0):
        lines.append(
            f"  local search: {a['starts_accepted']} of {a['starts']} starts end within the "
            f"intervals' acceptance, chi2 <= {a['chi2_reference'] + a['delta_chi2']:.4g} "
            "(start_chi2, start_x: the waterfall)"
        )
    if not a.get("fit_adequate", 1):
        lines.append(
            f"  WARNING: chi2 {a['chi2']:.4g} on {a['n_statistics']} statistics "
            f"(p = {a['chi2_p_value']:.2g}): the best point found does not reproduce "
            "the data's statistics; the intervals are not trustworthy"
        )
    if "combination_sd" in ds:
        names = [str(n) for n in ds["parameter"].values]
        for k in range(min(2, ds.sizes["combination"])):
            v = ds["combination_vector"].values[k]
            terms = " ".join(
                f"{c:+.2f}·{n}" for c, n in zip(v, names, strict=True) if abs(c) >= 0.1
            )
            lines.append(
                f"  combination {k + 1} (coordinates scaled to their ranges): {terms}, "
                f"sd {float(ds['combination_sd'].values[k]):.3g} of the ranges"
            )
    if "residual_outside_fraction" in a:
        lines.append(
            f"  residual outside the 95% band: {100 * a['residual_outside_fraction']:.1f} % "
            f"of the samples, longest run {a['residual_longest_run_s']:.3g} s"
            + ("" if a.get("residual_within_band", 1) else "  <- systematic excursion")
        )
    if "interval_low" in ds:
        from .load_output import identifiability_lines

        lines.extend(identifiability_lines(ds))
    if a.get("work_note", "none") != "none":
        lines.append(f"  note: {a['work_note']}")
    return "\n".join(lines)
