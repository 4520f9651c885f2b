"""Fit the bouncing-disk model to a measured rotor velocity–time curve.

The model is chaotic, so it is not fitted point by point. Both the measured curve and the
simulated one are reduced to summary statistics: the first-order trend
(steady speed ``S``, time constant ``τ``) and the ripple about it (RMS amplitude ``A`` and the
power-weighted mean frequency ``f_r`` of the residual), and the loss compares those
(:func:`curve_stats`). Nondimensional time and speed map to SI units through the scales of
MODEL.md: ``t = t_nd · t_c`` with ``t_c = omega_s / (2π f)`` (``f`` the known drive frequency)
and ``Ω_rad_s = Ω · R_φ Φ0 / t_c`` (``Φ0`` the torsional amplitude; a free speed scale when
unknown).

Search: :func:`scipy.optimize.differential_evolution` (seeded) over ``e``, ``log10 R_φ``, ``ψ``,
``omega_s`` (and ``log10`` speed scale), then :func:`scipy.optimize.least_squares` with a robust
(soft-L1) loss. Uncertainty: a moving-block bootstrap of the residual segments about the
trend, each refitted by the chord method (the Jacobian at the estimate, two steps with exact
residuals); intervals are the union of the bootstrap percentiles and the projection of the
likelihood region (every evaluated point within the χ² 95 % quantile of the best), correlations
those of the refits.
A parameter whose whole search range moves the statistics by less than one standard
deviation (sensitivity matrix) or whose interval covers more than half its range is reported as
not identified by the data, and its interval is widened to the search range.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import xarray as xr
from scipy.optimize import differential_evolution, least_squares
from scipy.signal import welch
from scipy.stats import chi2 as chi2_dist

from .curves import MotorCurve
from .engine import EngineConfig, InitialState, simulate_arrays
from .observables import first_order_trend
from .provenance import base_attrs, new_run_id, sha256_file

STATS = (
    "steady_speed",
    "time_constant",
    "ripple_rms",
    "ripple_frequency",
    "rise_half_tau",
    "rise_two_tau",
    "ripple_lowband",
    "ripple_skewness",
)
STAT_UNITS = ("rad/s", "s", "rad/s", "Hz", "1", "1", "1", "1")
#: statistics compared on a log scale (positive by construction)
LOG_STATS = np.array([False, True, True, True, False, False, False, False])
BOUNDS = {
    "e": (0.05, 0.95),
    "log10_r_phi": (-4.0, -1.0),
    "psi": (-math.pi, math.pi),
    "omega_s": (1.05, 4.0),
    "log10_speed_scale": (-4.0, 3.0),
}


@dataclass(frozen=True)
class FitSettings:
    """Knobs of the fit (defaults sized for a curve of a few thousand samples)."""

    seed: int = 12345
    realizations: int = 4  # jittered model runs averaged per evaluation (local stage)
    global_realizations: int = 2  # the same during the global search (cheaper, noisier)
    jitter: float = 0.02  # parameter jitter of the realizations, as a fraction of each range
    pilot: int = 6  # jittered runs per pilot point that estimate the model's own spread
    pilot_points: int = 4  # best scan points where that spread is measured
    scan: int = 512  # Sobol points scanned to seed the global search's population
    popsize: int = 10
    maxiter: int = 15
    local_nfev: int = 60
    bootstrap: int = 40
    block: int = 0  # bootstrap block length in samples (0: n/40, at least 20)


def param_names(curve: MotorCurve) -> list[str]:
    """Search coordinates: ``e, log10 R_φ, ψ, omega_s`` (+ ``log10`` speed scale if Φ0 is unknown)."""
    names = ["e", "log10_r_phi", "psi", "omega_s"]
    if curve.phi0_rad is None:
        names.append("log10_speed_scale")
    return names


def physical(theta: dict[str, float], curve: MotorCurve) -> dict[str, float]:
    """Nondimensional parameters and SI scales of a parameter vector."""
    w = theta["omega_s"]
    r_phi = 10.0 ** theta["log10_r_phi"]
    t_c = w / (2.0 * math.pi * curve.drive_frequency_hz)
    if curve.phi0_rad is not None:
        scale = r_phi * curve.phi0_rad / t_c
    else:
        scale = 10.0 ** theta["log10_speed_scale"]
    return {
        "e": theta["e"],
        "r_phi": r_phi,
        "psi": theta["psi"],
        "omega_s": w,
        "t_c": t_c,
        "speed_scale": scale,
    }


def uniform_grid(curve: MotorCurve) -> np.ndarray:
    """The uniform time grid (s) the statistics are computed on."""
    dt = curve.dt
    n = int(math.floor((curve.time[-1] - curve.time[0]) / dt + 1e-9)) + 1
    return curve.time[0] + dt * np.arange(n)


def simulate_curve(
    theta: dict[str, float],
    curve: MotorCurve,
    realization: int = 0,
    realizations: int = 1,
    noise: bool = True,
) -> np.ndarray:
    """Model rotor speed (rad/s) on the curve's uniform grid, from rest in contact.

    Realization ``k`` starts at stator phase ``2πk/K``; measurement noise of the curve's sigma is
    added with a fixed seed per realization (common random numbers across evaluations).
    """
    p = physical(theta, curve)
    grid = uniform_grid(curve)
    t_c = p["t_c"]
    w = p["omega_s"]
    t0 = (realization / max(1, realizations)) * 2.0 * math.pi / w
    dt_nd = curve.dt / t_c
    span_nd = (grid[-1] - grid[0]) / t_c
    cfg = EngineConfig(
        e=p["e"],
        omega_s=w,
        r_phi=p["r_phi"],
        psi=p["psi"],
        contact=True,
        torsion=True,
        t_end=t0 + span_nd + 0.5 * dt_nd,
        max_events=50_000_000,
        traj_dt=dt_nd,
        traj_t0=t0,
        traj_t1=t0 + span_nd + 0.5 * dt_nd,
    )
    res = simulate_arrays(cfg, InitialState(t=t0, omega=0.0))
    om = res.traj[: len(grid), 4] * p["speed_scale"]
    if len(om) < len(grid):
        om = np.concatenate([om, np.full(len(grid) - len(om), om[-1] if len(om) else 0.0)])
    if noise and curve.sigma > 0:
        rng = np.random.default_rng(1_000_003 + realization)
        om = om + rng.normal(0.0, curve.sigma, len(om))
    return om


def curve_stats(t: np.ndarray, om: np.ndarray) -> np.ndarray:
    """Summary statistics of a speed record on a uniform grid (order of :data:`STATS`).

    Trend: steady speed ``S`` and time constant ``τ`` of the first-order fit
    (:func:`~bouncedisk.observables.first_order_trend`, on at most 400 evenly spaced points).
    Rise shape: the speed smoothed over 2 % of the record at ``τ/2`` and ``2τ``, over ``S``
    (0.39 and 0.86 for an exact exponential). Ripple, the residual after three time constants (or
    over the last half): RMS, power-weighted mean frequency (Welch), fraction of its power below
    1/8 of the Nyquist frequency, and skewness.
    """
    step = max(1, len(t) // 400)
    trend = first_order_trend(t[::step], om[::step])
    resid = om - trend(t)
    steady = t >= t[0] + 3.0 * trend.tau
    if steady.sum() < max(16, len(t) // 4):
        steady = t >= t[len(t) // 2]
    r = resid[steady]
    dt = float(t[1] - t[0])
    f, pxx = welch(r - r.mean(), fs=1.0 / dt, nperseg=min(256, len(r)))
    pxx = pxx[1:]
    f = f[1:]
    total = float(np.sum(pxx))
    freq = float(np.sum(f * pxx) / total) if total > 0 else 0.0
    low = float(np.sum(pxx[f < f[-1] / 8]) / total) if total > 0 else 0.0
    sd = float(np.std(r))
    skew = float(np.mean((r - r.mean()) ** 3) / sd**3) if sd > 0 else 0.0
    width = max(1, int(0.02 * len(t)))
    smooth = np.convolve(om, np.ones(width) / width, mode="same")
    scale = trend.steady if trend.steady != 0 else 1.0
    rise = [float(np.interp(t[0] + k * trend.tau, t, smooth)) / scale for k in (0.5, 2.0)]
    return np.array([trend.steady, trend.tau, sd, freq, rise[0], rise[1], low, skew])


def _transform(stats: np.ndarray) -> np.ndarray:
    """The positive scale statistics on a log scale, the others as they are."""
    out = stats.astype(float).copy()
    out[LOG_STATS] = np.log(np.maximum(stats[LOG_STATS], 1e-300))
    return out


def block_bootstrap_stats(
    t: np.ndarray, om: np.ndarray, n_boot: int, rng: np.random.Generator, block: int = 0
) -> np.ndarray:
    """Statistics of ``n_boot`` moving-block resamples of the residual about the trend."""
    step = max(1, len(t) // 400)
    trend = first_order_trend(t[::step], om[::step])
    base = trend(t)
    resid = om - base
    n = len(t)
    b = block or max(20, n // 40)
    out = np.empty((n_boot, len(STATS)))
    for i in range(n_boot):
        starts = rng.integers(0, n - b + 1, size=n // b + 1)
        res = np.concatenate([resid[s : s + b] for s in starts])[:n]
        out[i] = curve_stats(t, base + res)
    return out


@dataclass
class FitResult:
    """Estimates (search coordinates), intervals, identifiability and diagnostics of a fit."""

    names: list[str]
    theta: dict[str, float]
    ci_low: dict[str, float]
    ci_high: dict[str, float]
    identified: dict[str, bool]
    boot: np.ndarray  # (n_boot, n_params)
    correlation: np.ndarray
    stats_measured: np.ndarray
    stats_fitted: np.ndarray
    stats_sigma: np.ndarray
    loss_trace: list[float]
    loss: float
    sensitivity: np.ndarray  # (n_stats, n_params): change of the scaled residual over the range
    trend_ci: tuple  # 95 % bootstrap intervals of the data's steady speed and time constant
    physical: dict[str, float]
    wall_time_s: float
    settings: FitSettings = field(default_factory=FitSettings)
    objective: object = field(default=None, repr=False)  # the loss, for diagnostics


def fitted_realization(
    theta: dict[str, float], curve: MotorCurve, obj: _Objective, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free jittered realization ``k`` of the fitted model and its statistics."""
    x = np.array([theta[n] for n in obj.names])
    xj = np.clip(x + obj.jitter[k % len(obj.jitter)], obj.lo, obj.hi)
    om = simulate_curve(dict(zip(obj.names, xj, strict=True)), curve, k, 8, noise=False)
    return om, curve_stats(obj.grid, om)


class _Objective:
    """Scaled residuals of the summary statistics for a parameter vector."""

    def __init__(
        self,
        curve: MotorCurve,
        names: list[str],
        target: np.ndarray,
        sigma: np.ndarray,
        settings: FitSettings,
    ):
        self.curve = curve
        self.names = names
        self.target = _transform(target)
        self.sigma = sigma
        self.settings = settings
        self.grid = uniform_grid(curve)
        self.realizations = settings.realizations
        self.cache: dict[tuple, np.ndarray] = {}
        bounds = np.array([BOUNDS[n] for n in names])
        self.lo, self.hi = bounds[:, 0], bounds[:, 1]
        # fixed, seeded parameter offsets of the realizations (the first one unjittered)
        rng = np.random.default_rng(settings.seed + 7)
        self.jitter = rng.normal(0.0, settings.jitter, (16, len(names))) * (self.hi - self.lo)
        self.jitter[0] = 0.0

    def realization_stats(self, x: np.ndarray, k: int) -> np.ndarray:
        """Transformed statistics of jittered realization ``k`` at ``x``."""
        xj = np.clip(x + self.jitter[k % len(self.jitter)], self.lo, self.hi)
        theta = dict(zip(self.names, xj, strict=True))
        return _transform(curve_stats(self.grid, simulate_curve(theta, self.curve, k, 8)))

    def model_stats(self, x: np.ndarray) -> np.ndarray:
        key = (self.realizations,) + tuple(np.round(x, 12))
        if key not in self.cache:
            k = self.realizations
            self.cache[key] = np.mean([self.realization_stats(x, i) for i in range(k)], axis=0)
        return self.cache[key]

    def residuals(self, x: np.ndarray, target: np.ndarray | None = None) -> np.ndarray:
        tgt = self.target if target is None else target
        return (self.model_stats(x) - tgt) / self.sigma

    def loss(self, x: np.ndarray) -> float:
        r = self.residuals(x)
        return float(np.sum(np.log1p(r * r)))  # Cauchy-like robust loss for the global search


def fit_curve(curve: MotorCurve, settings: FitSettings | None = None, progress=None) -> FitResult:
    """Fit the model to ``curve`` (module docstring). Deterministic for a given seed."""
    s = settings or FitSettings()
    start = _time.perf_counter()
    rng = np.random.default_rng(s.seed)
    names = param_names(curve)
    bounds = [BOUNDS[n] for n in names]
    grid = uniform_grid(curve)
    data = np.interp(grid, curve.time, curve.omega)
    measured = curve_stats(grid, data)
    boot_stats = block_bootstrap_stats(grid, data, max(s.bootstrap, 20), rng, s.block)
    tb = np.array([_transform(b) for b in boot_stats])
    sd = tb.std(axis=0, ddof=1)
    # centred bootstrap: replicate deviations applied to the data's own statistics
    boot_targets = _transform(measured) + (tb - tb.mean(axis=0))
    floor = np.array([0.005 * abs(measured[0]) + 1e-12, 0.01, 0.02, 0.02, 0.01, 0.01, 0.01, 0.05])
    sigma_data = np.maximum(sd, floor)
    obj = _Objective(curve, names, measured, sigma_data, s)

    trace: list[float] = []

    def callback(xk, convergence=None):
        trace.append(obj.loss(xk))
        if progress:
            progress(f"global search: generation {len(trace)}, loss {trace[-1]:.4g}")

    obj.realizations = s.global_realizations
    # seed the population with the best points of a Sobol scan of the whole search box
    from scipy.stats import qmc

    lo_b = np.array([b[0] for b in bounds])
    hi_b = np.array([b[1] for b in bounds])
    scan = qmc.scale(qmc.Sobol(len(names), seed=s.seed).random(s.scan), lo_b, hi_b)
    scan_loss = np.array([obj.loss(x) for x in scan])
    # the model's own spread: the statistics are fractal in the parameters (windows of periodic
    # and chaotic motion), so jittered realizations at the best scan point set a noise floor
    spreads = []
    for i in np.argsort(scan_loss)[: s.pilot_points]:
        pilot = np.array([obj.realization_stats(scan[i], k) for k in range(s.pilot)])
        spreads.append(pilot.std(axis=0, ddof=1))
    sigma_model = np.sqrt(np.mean(np.square(spreads), axis=0))
    sigma = np.sqrt(sigma_data**2 + sigma_model**2 / s.global_realizations)
    obj.sigma = sigma
    scan_loss = np.array([obj.loss(x) for x in scan])  # cached statistics, new sigma
    if progress:
        progress(f"scan: {s.scan} points, best loss {scan_loss.min():.4g}")
    init = scan[np.argsort(scan_loss)[: s.popsize * len(names)]]
    de = differential_evolution(
        obj.loss,
        bounds,
        seed=s.seed,
        maxiter=s.maxiter,
        tol=0.0,
        atol=0.0,
        polish=False,
        init=init,
        updating="deferred",
        workers=1,
        callback=callback,
    )
    # the global stage's cheaper evaluations are kept for the likelihood region; the local stage
    # averages more realizations
    global_cache = obj.cache
    obj.cache = {}
    obj.realizations = s.realizations
    sigma = np.sqrt(sigma_data**2 + sigma_model**2 / s.realizations)
    obj.sigma = sigma
    lo = np.array([b[0] for b in bounds])
    hi = np.array([b[1] for b in bounds])
    span = hi - lo
    diff_step = 0.02 * span / np.maximum(np.abs(de.x), 1e-3)
    ls = least_squares(
        obj.residuals,
        de.x,
        bounds=(lo, hi),
        loss="soft_l1",
        diff_step=diff_step,
        max_nfev=s.local_nfev,
        x_scale=span,
    )
    x_best = ls.x if obj.loss(ls.x) <= obj.loss(de.x) else de.x
    trace.append(obj.loss(x_best))
    if progress:
        progress(f"local refinement: loss {trace[-1]:.4g}")

    # sensitivity: change of each scaled residual when a parameter sweeps 20 % of its range
    jac = np.empty((len(STATS), len(names)))
    for j in range(len(names)):
        h = 0.1 * span[j]
        xp = x_best.copy()
        xm = x_best.copy()
        xp[j] = min(hi[j], x_best[j] + h)
        xm[j] = max(lo[j], x_best[j] - h)
        jac[:, j] = (obj.model_stats(xp) - obj.model_stats(xm)) / sigma / (xp[j] - xm[j])
    sens = jac * span  # per whole search range
    _u, sv, vt = np.linalg.svd(sens, full_matrices=True)
    sv_full = np.zeros(len(names))
    sv_full[: len(sv)] = sv
    weak = [k for k in range(len(names)) if sv_full[k] < 1.0]
    # truncated pseudo-inverse: directions the statistics do not constrain are left alone
    pinv = np.linalg.pinv(sens, rcond=1.0 / max(sv_full[0], 1.0)) * span[:, None]

    # bootstrap refits over residual-segment resamples (chord method: fixed Jacobian, exact
    # residuals, two steps from the estimate)
    boot = np.empty((s.bootstrap, len(names)))
    for b in range(s.bootstrap):
        tgt = boot_targets[b % len(boot_targets)]
        x = x_best.copy()
        for _ in range(2):
            x = np.clip(x - pinv @ obj.residuals(x, tgt), lo, hi)
        boot[b] = x
        if progress and (b + 1) % 10 == 0:
            progress(f"bootstrap: {b + 1} / {s.bootstrap} refits")

    theta = dict(zip(names, x_best, strict=True))
    ci_lo = dict(zip(names, np.percentile(boot, 2.5, axis=0), strict=True))
    ci_hi = dict(zip(names, np.percentile(boot, 97.5, axis=0), strict=True))
    # likelihood region: every evaluated point within the chi-square 95 % quantile of the best
    # (a sampled profile likelihood): a valley of equally good fits widens the interval
    evaluated = {**global_cache, **obj.cache}
    pts = np.array([k[1:] for k in evaluated])
    chi2 = np.array([float(np.sum(((v - obj.target) / sigma) ** 2)) for v in evaluated.values()])
    region = pts[chi2 <= chi2.min() + chi2_dist.ppf(0.95, len(names))]
    for j, n in enumerate(names):
        ci_lo[n] = float(min(ci_lo[n], region[:, j].min(), x_best[j]))
        ci_hi[n] = float(max(ci_hi[n], region[:, j].max(), x_best[j]))
    identified = {}
    for j, n in enumerate(names):
        wide = (ci_hi[n] - ci_lo[n]) > 0.5 * span[j]
        flat = any(abs(vt[k, j]) > 0.5 for k in weak)
        identified[n] = not (wide or flat)
        if not identified[n]:
            ci_lo[n], ci_hi[n] = float(lo[j]), float(hi[j])
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.corrcoef(boot.T) if s.bootstrap > 2 else np.full((len(names),) * 2, np.nan)
    fitted_stats = np.mean(
        [fitted_realization(theta, curve, obj, k)[1] for k in range(s.realizations)], axis=0
    )
    return FitResult(
        names=names,
        theta=theta,
        ci_low=ci_lo,
        ci_high=ci_hi,
        identified=identified,
        boot=boot,
        correlation=np.atleast_2d(corr),
        stats_measured=measured,
        stats_fitted=fitted_stats,
        stats_sigma=sigma,
        loss_trace=trace,
        loss=trace[-1],
        sensitivity=sens,
        trend_ci=(
            tuple(np.percentile(boot_targets[:, 0], [2.5, 97.5])),
            tuple(np.exp(np.percentile(boot_targets[:, 1], [2.5, 97.5]))),
        ),
        physical=physical(theta, curve),
        wall_time_s=_time.perf_counter() - start,
        settings=s,
        objective=obj,
    )


PUBLIC = {  # name in the file, from internal name, transform, units, long name
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
}


def fit_dataset(curve: MotorCurve, fit: FitResult) -> xr.Dataset:
    """The fit file (INTERFACES.md): measured and fitted curves, estimates with intervals."""
    theta = fit.theta
    grid = uniform_grid(curve)
    sims = [
        fitted_realization(theta, curve, fit.objective, k)[0]
        for k in range(fit.settings.realizations)
    ]
    model = np.interp(curve.time, grid, sims[0])
    step = max(1, len(grid) // 400)
    trend = first_order_trend(grid[::step], np.mean(sims, axis=0)[::step])
    ds = xr.Dataset(
        {
            "omega_measured": (
                "time",
                curve.omega,
                {"units": "rad/s", "long_name": "measured rotor angular velocity"},
            ),
            "omega_fitted": (
                "time",
                model,
                {
                    "units": "rad/s",
                    "long_name": "fitted model rotor angular velocity"
                    " (one realization, noise-free)",
                },
            ),
            "omega_fitted_mean": (
                "time",
                np.interp(curve.time, grid, np.mean(sims, axis=0)),
                {
                    "units": "rad/s",
                    "long_name": "fitted model rotor angular "
                    "velocity, mean of the jittered realizations",
                },
            ),
            "trend_fitted": (
                "time",
                trend(curve.time),
                {"units": "rad/s", "long_name": "first-order trend of the fitted model"},
            ),
            "trend_measured": (
                "time",
                _data_trend(curve)(curve.time),
                {"units": "rad/s", "long_name": "first-order trend of the data"},
            ),
            "stats_measured": ("stat", fit.stats_measured, {"long_name": "statistics of the data"}),
            "stats_fitted": (
                "stat",
                fit.stats_fitted,
                {"long_name": "statistics of the fitted model (noise-free)"},
            ),
            "stats_sigma": (
                "stat",
                fit.stats_sigma,
                {
                    "long_name": "standard deviation used in the loss (steady speed in "
                    "rad/s, the others on a log scale)"
                },
            ),
            "loss_trace": (
                "iteration",
                np.asarray(fit.loss_trace),
                {"long_name": "robust loss: best per generation, then refined"},
            ),
            "bootstrap_estimates": (
                ("bootstrap", "parameter"),
                fit.boot,
                {"long_name": "refitted parameters (search coordinates)"},
            ),
            "correlation": (
                ("parameter", "parameter2"),
                fit.correlation,
                {"long_name": "correlation of the bootstrap estimates"},
            ),
            "sensitivity": (
                ("stat", "parameter"),
                fit.sensitivity,
                {"long_name": "change of the scaled statistic over each search range"},
            ),
        },
        coords={
            "time": ("time", curve.time, {"units": "s", "long_name": "time", "axis": "T"}),
            "stat": (
                "stat",
                list(STATS),
                {"long_name": "summary statistic", "units_of_values": " ".join(STAT_UNITS)},
            ),
            "parameter": ("parameter", fit.names),
            "parameter2": ("parameter2", fit.names),
        },
    )
    not_identified = []
    for pub, (internal, fn, units, long_name) in PUBLIC.items():
        if internal not in theta:
            continue
        j = fit.names.index(internal)
        lo, hi = fn(fit.ci_low[internal]), fn(fit.ci_high[internal])
        b_lo, b_hi = BOUNDS[internal]
        ds[pub] = xr.DataArray(
            fn(theta[internal]),
            attrs={
                "units": units,
                "long_name": long_name,
                "ci_low": min(lo, hi),
                "ci_high": max(lo, hi),
                "ci_level": 0.95,
                "identified": int(fit.identified[internal]),
                "search_low": fn(b_lo),
                "search_high": fn(b_hi),
                "search_coordinate": internal,
                "bootstrap_sd": float(np.std(fit.boot[:, j], ddof=1)) if len(fit.boot) > 1 else 0.0,
            },
        )
        if not fit.identified[internal]:
            not_identified.append(pub)
    ds["t_c"] = xr.DataArray(
        fit.physical["t_c"], attrs={"units": "s", "long_name": "time scale sqrt(U0/g_eff)"}
    )
    if "speed_scale" not in ds:
        ds["speed_scale"] = xr.DataArray(
            fit.physical["speed_scale"],
            attrs={"units": "rad/s", "long_name": "R_phi Phi0 / t_c (from the known Phi0)"},
        )
    ds.attrs.update(base_attrs(f"bouncedisk fit to {curve.path}"))
    run_id = new_run_id("fit", sha256_file(curve.path))
    ds.attrs.update(
        {
            "run_id": run_id,
            "scene_name": "fit",
            "status": "completed",
            "e": float(theta["e"]),
            "omega_s": float(theta["omega_s"]),
            "r_phi": float(10.0 ** theta["log10_r_phi"]),
            "psi": float(theta["psi"]),
            "effects": "contact,impacts,impulse_cap,torsion",
            "solver": "exact",
            "steady_speed_rad_s": float(fit.stats_measured[0]),
            "time_constant_s": float(fit.stats_measured[1]),
            "steady_speed_ci_rad_s": np.asarray(fit.trend_ci[0]),
            "time_constant_ci_s": np.asarray(fit.trend_ci[1]),
            "trend_comment": "steady_speed_rad_s and time_constant_s: first-order trend fitted to the "
            "measured curve (95% intervals from the centred block bootstrap); "
            "model_*: trend of the fitted bouncing-disk model",
            "model_steady_speed_rad_s": float(trend.steady),
            "model_time_constant_s": float(trend.tau),
            "not_identified": ",".join(not_identified) or "none",
            "curve_file": curve.path,
            "curve_sha256": sha256_file(curve.path),
            "curve_source": curve.source,
            "curve_synthetic": int(curve.synthetic),
            "drive_frequency_hz": curve.drive_frequency_hz,
            "Phi0_rad": curve.phi0_rad if curve.phi0_rad is not None else "unknown",
            "noise_sigma_rad_s": curve.sigma,
            "seed": fit.settings.seed,
            "n_bootstrap": fit.settings.bootstrap,
            "loss": fit.loss,
            "wall_time_s": round(fit.wall_time_s, 3),
            "method": "differential_evolution (seeded) + least_squares (soft_l1) on summary "
            "statistics; moving-block bootstrap of residual segments",
        }
    )
    return ds


def _data_trend(curve: MotorCurve):
    grid = uniform_grid(curve)
    step = max(1, len(grid) // 400)
    return first_order_trend(grid[::step], np.interp(grid, curve.time, curve.omega)[::step])


def synthesize_curve(
    true: dict[str, float],
    drive_frequency_hz: float,
    phi0_rad: float,
    span_s: float,
    dt_s: float,
    sigma: float,
    seed: int,
) -> pd.DataFrame:
    """A synthetic measured curve: the model at ``true`` plus Gaussian noise ``sigma`` (rad/s).

    ``true`` holds ``e, r_phi, psi, omega_s``.
    """
    n = int(math.floor(span_s / dt_s + 1e-9)) + 1
    t = dt_s * np.arange(n)
    dummy = MotorCurve(
        time=t,
        omega=np.zeros(n),
        sigma=0.0,
        drive_frequency_hz=drive_frequency_hz,
        phi0_rad=phi0_rad,
        source="",
        synthetic=True,
        path="",
    )
    theta = {
        "e": true["e"],
        "log10_r_phi": math.log10(true["r_phi"]),
        "psi": true["psi"],
        "omega_s": true["omega_s"],
    }
    om = simulate_curve(theta, dummy, 0, 1, noise=False)
    rng = np.random.default_rng(seed)
    om_noisy = om + rng.normal(0.0, sigma, n)
    return pd.DataFrame({"time_s": t, "omega_rad_s": om_noisy, "sigma_rad_s": np.full(n, sigma)})


def fit_command(args) -> None:
    """``bouncedisk fit CURVE.csv -o FIT.nc`` (see :mod:`bouncedisk.cli`)."""
    import sys

    from .curves import read_curve
    from .datasets import write_dataset

    curve = read_curve(args.curve, args.sidecar)
    settings = FitSettings(seed=args.seed, bootstrap=args.bootstrap)

    def progress(msg: str) -> None:
        if not args.quiet:
            print(f"fit: {msg}", file=sys.stderr, flush=True)

    fit = fit_curve(curve, settings, progress)
    ds = fit_dataset(curve, fit)
    write_dataset(ds, args.output)
    if not args.quiet:
        print(summary_text(ds))


def summary_text(ds: xr.Dataset) -> str:
    """A human-readable summary of a fit file."""
    lines = [
        f"fit of {ds.attrs.get('curve_file')} (seed {ds.attrs.get('seed')}, "
        f"{ds.attrs.get('wall_time_s')} s)"
    ]
    for name in PUBLIC:
        if name in ds and "ci_low" in ds[name].attrs:
            a = ds[name].attrs
            flag = "" if a["identified"] else "   <- not identified by the data"
            lines.append(
                f"  {name:>12} = {float(ds[name]):.5g}   95% [{a['ci_low']:.5g}, "
                f"{a['ci_high']:.5g}] {a['units']}{flag}"
            )
    a = ds.attrs
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
    return "\n".join(lines)
