"""Fit the model to a curve: data preparation, search, profiles, the fitted ensemble.

The steps: bound the work (:func:`prepare_curve`), reduce the data to its statistics
(:mod:`~bouncedisk.fitting.summary_stats`), search the synthetic likelihood (:mod:`.search`), profile every parameter
(:mod:`.uncertainty`), and run the fitted model's ensemble for the band of Fig. 5.
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..analysis.observables import first_order_trend
from ..io.load_curves import LoadCurveData
from ..io.runup_curves import MotorCurve
from ..model import limits
from ..model.errors import InputError
from .joint import LoadFit, joint_consistent, load_part, load_result
from .likelihood_basins import Basin, list_basins
from .members import (
    MODEL_E_SIGMA,
    EnsembleSpec,
    member_records,
    param_names,
    physical,
    uniform_grid,
)
from .objective import Objective
from .runs import check_runs, mean_curve
from .search import SearchSettings, confirm_points, search, waterfall
from .summary_stats import (
    STATS,
    Layout,
    member_band,
    provisional_sd,
    records_stats,
    stat_floor,
    trend_stride,
)
from .uncertainty import (
    ADEQUATE_P,
    THRESHOLD,
    Profile,
    adequate,
    all_profiles,
    birge,
    chi2_level,
    combinations,
    consistent_points,
    fit_limit,
    scan_acceptable,
)

#: At most this many samples are fitted (every k-th sample is kept beyond it).
MAX_SAMPLES = 12_000
#: At most this many drive periods are fitted (the record is cropped beyond it).
MAX_PERIODS = 20_000
#: Members per evaluation for one run-up, and for several fitted together (:meth:`FitSettings.for_runs`).
MEMBERS_ONE, MEMBERS_RUNS = 12, 32
#: Members per scan point when several run-ups are fitted together.
SCAN_MEMBERS_RUNS = 4
#: Fewest samples (after the work bound) the statistics are taken on: the block bootstrap's
#: blocks are at least 20 samples, and the data must hold at least 10 of them.
MIN_FIT_SAMPLES = limits.MIN_RUNUP_SAMPLES
#: Fewest drive periods a record must span (the run-up is many impacts long).
MIN_PERIODS = 50
#: Fewest bootstrap resamples: a 95 % percentile interval needs a 2.5 % tail of at least one.
MIN_BOOTSTRAP = limits.BOOTSTRAP_RANGE.low


@dataclass(frozen=True)
class FitSettings:
    """Knobs of the fit; the defaults fit the shipped curve within the pipeline's budget."""

    seed: int = SearchSettings.seed
    bootstrap: int = 40  # block-bootstrap resamples of the data (provisional scales, trend CI)
    members: int | None = None  # members per evaluation in the local search and the profiles
    pilot_members: int = SearchSettings.pilot_members  # members measuring the model's covariance
    band_members: int = 128  # noise-free members of the fitted model's band and trend
    global_members: int | None = None  # members per scan point (None: 1, or 4 for several runs)
    scan: int = SearchSettings.scan
    zoom: int = (
        SearchSettings.zoom
    )  # scan points around each of the best zoom_centres (search module)
    zoom_centres: int = SearchSettings.zoom_centres
    local_nfev: int = SearchSettings.local_nfev
    joint_zoom: int = SearchSettings.joint_zoom  # points around each joint candidate (search)
    # restitution noise of the members (docs/model.md): None (the default) fits it (search
    # coordinate ``e_sigma`` over [0, 0.1], the scan at MODEL_E_SIGMA); a number states it
    # (``bouncedisk fit --e-sigma S``)
    e_sigma: float | None = None
    cores: int = 1
    profile: tuple[str, ...] | None = None  # coordinates to profile (None: all)

    def __post_init__(self) -> None:
        limits.BOOTSTRAP_RANGE.check("FitSettings", "bootstrap", self.bootstrap)
        if self.e_sigma is not None:
            limits.E_SIGMA.check("FitSettings", "e_sigma", self.e_sigma)

    def for_runs(self, runs: int) -> FitSettings:
        """The settings with the ensemble sizes left open (``None``) set for ``runs`` run-ups.

        One run-up: 12 members per evaluation, one per scan point. The mean of several run-ups
        is known ``√runs`` times better than one member's statistics, so the model's Monte-Carlo
        error ``C/K`` must shrink with it: :data:`MEMBERS_RUNS` and :data:`SCAN_MEMBERS_RUNS`.
        """
        one = runs == 1
        return dataclasses.replace(
            self,
            members=self.members or (MEMBERS_ONE if one else MEMBERS_RUNS),
            global_members=self.global_members or (1 if one else SCAN_MEMBERS_RUNS),
        )

    def search_settings(self) -> SearchSettings:
        """The search's share of the settings (sizes resolved by :meth:`for_runs`)."""
        return SearchSettings(
            seed=self.seed,
            scan=self.scan,
            zoom=self.zoom,
            zoom_centres=self.zoom_centres,
            global_members=self.global_members,
            members=self.members,
            pilot_members=self.pilot_members,
            local_nfev=self.local_nfev,
            joint_zoom=self.joint_zoom,
        )


def prepare_curve(curve: MotorCurve) -> tuple[MotorCurve, str]:
    """Bound the work: crop to :data:`MAX_PERIODS` drive periods, keep every k-th sample.

    Subsampling (not averaging) keeps the curve a sample of the same process, so the model is
    sampled the same way. Returns the curve to fit and a note (empty when nothing changed).
    """
    notes = []
    t, om = _relative_time(curve), curve.omega
    if curve.time[0] != 0.0:
        notes.append(f"times counted from the first sample (t0 = {curve.time[0]:.17g} s)")
    t_max = t[0] + MAX_PERIODS / curve.drive_frequency_hz
    if t[-1] > t_max:
        keep = t <= t_max
        notes.append(f"cropped to the first {MAX_PERIODS} drive periods ({t_max - t[0]:.6g} s)")
        t, om = t[keep], om[keep]
    k = int(math.ceil(len(t) / MAX_SAMPLES))
    if k > 1:
        notes.append(f"every {k}th of {len(t)} samples kept ({len(t[::k])} samples)")
        t, om = t[::k], om[::k]
    return dataclasses.replace(curve, time=t, omega=om), "; ".join(notes)


def _relative_time(curve: MotorCurve) -> np.ndarray:
    """Times from the first sample; ``k·dt`` when every sample is within 1 % of ``dt`` of it.

    The statistics then do not depend on the time origin: stamps of 1e9 s (epoch-like) carry
    their steps only to 1.2e-7 s, and are put back on the uniform grid they were taken on.
    """
    t = curve.time - curve.time[0]
    dt = curve.dt
    grid = dt * np.arange(len(t))
    return grid if np.max(np.abs(t - grid)) <= 0.01 * dt else t


def check_fittable(curve: MotorCurve) -> None:
    """Refuse a curve too short or too coarse for the fit's statistics (before any work).

    The record must span :data:`MIN_PERIODS` drive periods and hold :data:`MIN_FIT_SAMPLES`
    samples within the first :data:`MAX_PERIODS` of them (the work bound, :func:`prepare_curve`).
    """
    side = curve.sidecar_path or curve.path
    f, span, n = curve.drive_frequency_hz, float(curve.time[-1] - curve.time[0]), len(curve.time)
    if n < MIN_FIT_SAMPLES:
        raise InputError(
            curve.path,
            "time_s",
            f"has {n} samples; the fit's statistics need at "
            f"least {MIN_FIT_SAMPLES} (trend, ripple and a block bootstrap)",
        )
    if not span * f >= MIN_PERIODS:
        raise InputError(
            side,
            "motor.drive_frequency_hz",
            f"{f:g} Hz: the record ({span:.6g} s) "
            f"spans {span * f:.3g} drive periods; the fit needs at least {MIN_PERIODS}",
        )
    per_sample = curve.dt * f
    kept = min(n, int(MAX_PERIODS / per_sample) + 1)
    if kept < MIN_FIT_SAMPLES:
        raise InputError(
            side,
            "motor.drive_frequency_hz",
            f"{f:g} Hz: one sampling interval "
            f"spans {per_sample:.3g} drive periods, so the first {MAX_PERIODS} "
            f"periods hold {kept} samples; the fit needs at least {MIN_FIT_SAMPLES}",
        )


def data_layout(curves: Sequence[MotorCurve]) -> tuple[Layout, np.ndarray, np.ndarray]:
    """The layout of the statistics, the runs on the uniform grid ``(runs, n)``, and the runs'
    mean statistics (the layout's time constant is the mean curve's)."""
    grid = uniform_grid(curves[0])
    records = np.array([np.interp(grid, c.time, c.omega) for c in curves])
    step = trend_stride(len(grid))
    tau = first_order_trend(grid[::step], records.mean(axis=0)[::step]).tau
    tau = float(np.clip(tau, 2.0 * curves[0].dt, grid[-1] - grid[0]))
    layout = Layout(grid, tau, curves[0].drive_frequency_hz)
    return layout, records, np.mean(records_stats(records, layout), axis=0)


def bootstrap_stats(layout: Layout, records: np.ndarray, n: int, seed: int) -> np.ndarray:
    """Mean statistics of the runs over ``n`` moving-block resamples of each run's residual
    about its trend."""
    rng = np.random.default_rng([seed, 77])
    t = layout.t
    step = trend_stride(len(t))
    b = max(20, len(t) // 40)
    out = np.zeros((n, len(STATS)))
    for data in np.atleast_2d(records):
        base = first_order_trend(t[::step], data[::step])(t)
        resid = data - base
        samples = []
        for _ in range(n):
            starts = rng.integers(0, len(t) - b + 1, size=len(t) // b + 1)
            samples.append(base + np.concatenate([resid[s : s + b] for s in starts])[: len(t)])
        out += records_stats(np.array(samples), layout)
    return out / len(np.atleast_2d(records))


def provisional_cov(target: np.ndarray, boot: np.ndarray) -> np.ndarray:
    """Diagonal scales of the global search: the data's bootstrap spread, at least a few %."""
    wide = provisional_sd(target)
    sd = np.maximum(np.maximum(boot.std(axis=0, ddof=1), 10 * stat_floor(target)), wide)
    return np.diag(sd**2)


@dataclass
class FitResult:
    """Estimate, profiles and diagnostics of a fit (search coordinates unless said otherwise)."""

    names: list[str]
    x: np.ndarray
    chi2: float
    profiles: list[Profile]
    correlation: np.ndarray
    local_sd: np.ndarray
    comb_sd: np.ndarray
    comb_vectors: np.ndarray
    target: np.ndarray
    fitted_stats: np.ndarray
    fitted_sd: np.ndarray
    layout: Layout
    band: dict[str, np.ndarray]
    trend_data: tuple[float, float]
    trend_model: tuple[float, float]
    trend_ci: tuple[tuple[float, float], tuple[float, float]]
    physical: dict[str, float]
    basins: list[Basin]  # acceptable basins, best first; the estimate is basins[0]'s point
    curve: MotorCurve  # the runs' mean (one run: the curve), as fitted
    note: str
    evaluations: int
    wall_time_s: float
    settings: FitSettings
    runs: tuple[MotorCurve, ...]  # every run-up, as fitted (one run: the curve)
    load: LoadFit | None = None  # the load curves' part (joint fit), None for run-ups only
    chi2_level: float = math.nan  # chi2 at the search's best on fresh members (chi2_level)
    #: each local-search start's end chi2 under the final covariance, best first (the waterfall)
    start_chi2: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    #: each start's end point (search coordinates), in the order of start_chi2
    start_x: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    #: the intervals' Δχ² threshold (birge of the search's best chi2), measured from the level
    interval_threshold: float = THRESHOLD

    @property
    def n_statistics(self) -> int:
        """Statistics the fit's ``χ²`` is on: the run-ups' and every load reading (joint fit)."""
        return len(self.target) + (self.load.n if self.load is not None else 0)

    @property
    def theta(self) -> dict[str, float]:
        """The estimate as a dictionary of search coordinates."""
        return dict(zip(self.names, (float(v) for v in self.x), strict=True))


def fitted_band(
    theta: dict[str, float], curve: MotorCurve, layout: Layout, members: int, spec: EnsembleSpec
) -> dict[str, np.ndarray]:
    """The fitted model's noise-free members: ensemble mean, its 95 % interval, member band."""
    runs = np.array(
        member_records(theta, dataclasses.replace(curve, sigma=0.0), range(members), spec)
    )
    return {**member_band(runs), "member0": runs[0]}


def prepare_runs(
    curve: MotorCurve | Sequence[MotorCurve],
) -> tuple[list[MotorCurve], MotorCurve, str]:
    """Check the run-ups (:func:`.runs.check_runs`), bound each (:func:`prepare_curve`).

    Returns the runs as fitted, their mean curve and the note on the work bound.
    """
    runs = _checked_runs(curve)
    prepared = [prepare_curve(c) for c in runs]
    fitted = [c for c, _ in prepared]
    return fitted, mean_curve(fitted), prepared[0][1]


def check_fit_inputs(
    curve: MotorCurve | Sequence[MotorCurve], load: Sequence[LoadCurveData] = ()
) -> None:
    """Refuse what :func:`pose_fit` would refuse of the run-ups and load curves, with no curve
    bounded, statistic or simulation computed: the checks of :func:`prepare_runs` and of the
    load curves' part (:func:`.joint.load_part`: windows, ``Φ0``, amplitudes, rotors), so that a
    command can say a defect before its first progress line."""
    runs = _checked_runs(curve)
    load_part(list(load), runs[0], EnsembleSpec())  # reads the sidecar's constants only


def _checked_runs(curve: MotorCurve | Sequence[MotorCurve]) -> list[MotorCurve]:
    """The run-ups as a list, each fittable (:func:`check_fittable`) and all of one set-up
    (:func:`.runs.check_runs`)."""
    runs = [curve] if isinstance(curve, MotorCurve) else list(curve)
    for c in runs:
        check_fittable(c)
    check_runs(runs)
    return runs


def fit_basins(obj: Objective, members: int, thr: float) -> list[Basin]:
    """Every basin of evaluated points (``members`` members, current metric) within ``thr`` of
    the best ``χ²`` (:func:`.likelihood_basins.list_basins`), the reported one first."""
    pts = {tuple(ev.x): ev.x for ev in obj.log if ev.members == members}
    xs = np.array(list(pts.values()))
    chis = np.array([obj.chi2_now(x, members) for x in xs])
    return list_basins(xs, chis, obj.span, thr)


@dataclass(frozen=True)
class PosedFit:
    """The problem a fit searches (:func:`pose_fit`): its objective and what it was made from."""

    #: The joint (or run-ups') objective: provisional covariance, nothing evaluated.
    obj: Objective
    #: The settings with the ensemble sizes resolved for the runs (:meth:`FitSettings.for_runs`).
    settings: FitSettings
    #: Every run-up, as fitted.
    runs: list[MotorCurve]
    #: The work bound applied (empty: none).
    note: str
    #: The run-ups on the fit's grid ``(runs, samples)``.
    records: np.ndarray
    #: Block-bootstrap statistics of the data ``(resamples, statistics)``.
    boot: np.ndarray


def pose_fit(
    curve: MotorCurve | Sequence[MotorCurve],
    settings: FitSettings | None = None,
    progress: Callable[[str], None] | None = None,
    load: Sequence[LoadCurveData] | None = None,
) -> PosedFit:
    """The objective :func:`fit_curve` searches for ``curve`` (and ``load``), before any search.

    The run-ups are checked and bounded (:func:`prepare_runs`), reduced to their statistics with
    a provisional covariance from the block bootstrap (:func:`provisional_cov`), and joined to the
    load curves' part (:func:`.joint.load_part`); ``settings.e_sigma = None`` adds ``e_sigma``
    to the search coordinates (docs/fitting_method.md).
    """
    runs, fitted, note = prepare_runs(curve)
    s = (settings or FitSettings()).for_runs(len(runs))
    if note and progress:
        progress(f"work bounded: {note}")
    layout, records, target = data_layout(runs)
    boot = bootstrap_stats(layout, records, s.bootstrap, s.seed)
    stated = MODEL_E_SIGMA if s.e_sigma is None else s.e_sigma
    spec = EnsembleSpec(e_sigma=stated, seed=s.seed, cores=max(1, s.cores))
    part = load_part(list(load or []), fitted, spec, progress)
    names = param_names(fitted, fit_e_sigma=s.e_sigma is None)
    obj = Objective(
        fitted,
        names,
        layout,
        target,
        spec,
        s.members,
        initial_cov=provisional_cov(target, boot),
        runs=len(runs),
        load=part,
        parts="both" if part is not None else "runup",
    )
    return PosedFit(obj, s, runs, note, records, boot)


def scan_candidates(
    obj: Objective, s: FitSettings, best_chi2: float, progress: Callable[[str], None] | None
) -> np.ndarray:
    """The scan's points that reproduce the data's statistics within its bootstrap scales and,
    with a load curve, the joint candidates that reproduce the run-ups and the load curve
    together (first): the points the intervals are also judged on."""
    extra = scan_acceptable(obj, s.global_members)
    if progress is not None:
        progress(
            f"scan: {len(extra)} points reproduce the data's statistics within its bootstrap scales"
        )
    if obj.load is not None:
        joint = joint_consistent(obj, s.global_members, best_chi2)
        if progress is not None:
            progress(
                f"scan: {len(joint)} of the joint candidates reproduce the run-ups and the "
                "load curve together (chi2 below its 95 % point)"
            )
        # with the run-ups' own candidates: their intervals alone are judged on them too
        extra = np.concatenate([joint, extra])
    return extra


def fit_curve(
    curve: MotorCurve | Sequence[MotorCurve],
    settings: FitSettings | None = None,
    progress: Callable[[str], None] | None = None,
    load: Sequence[LoadCurveData] | None = None,
) -> FitResult:
    """Fit the model to ``curve``, or jointly to several run-ups of one motor (module docstring,
    :mod:`~bouncedisk.fitting.runs`) and, with ``load``, to its load curves too (:mod:`.loadpart`). Deterministic
    for a given seed."""
    start = _time.perf_counter()
    posed = pose_fit(curve, settings, progress, load)
    obj, s, part = posed.obj, posed.settings, posed.obj.load
    runs, fitted, note, layout, spec = posed.runs, obj.curve, posed.note, obj.layout, obj.spec
    records, target, boot = posed.records, obj.target, posed.boot
    found = search(obj, s.search_settings(), progress)
    best = found.best
    thr = birge(best.chi2, obj.n_stats, len(obj.names))
    if progress is not None and thr > THRESHOLD:
        progress(
            f"chi2 {best.chi2:.4g} on {obj.n_stats} statistics: intervals widened "
            f"(delta chi2 {thr:.4g} instead of {THRESHOLD:.3f})"
        )
    extra = scan_candidates(obj, s, best.chi2, progress)
    level = chi2_level(obj, best.x, s.members)
    # polished within three thresholds of the level (held metric) or three times the 95 % point
    # of chi2(n) (own covariance): a polish of four steps moves chi2 that far, not further
    gof = fit_limit(best.chi2, obj.n_stats, len(obj.names))
    reread = confirm_points(obj, extra, s.members, near=level + 3.0 * thr, near_own=3.0 * gof)
    consistent = consistent_points(obj, reread, s.members, best.chi2)
    if progress is not None:
        progress(
            f"chi2 {best.chi2:.4g} at the best point, {level:.4g} on fresh members; "
            f"{len(reread)} points read on {s.members} members for the scan's candidates "
            f"(refinements included), {len(consistent)} within their own spread"
        )
    profiles, jac, corr, sd = all_profiles(
        obj, best.x, s.members, s.profile and list(s.profile), progress, thr, consistent, level
    )
    final = obj.best(s.members)  # a profile may have found a better point
    basins = fit_basins(obj, s.members, thr)
    if progress is not None and len(basins) > 1:
        progress(
            f"{len(basins)} basins within delta chi2 {thr:.3g} of the best: the data do not "
            "single one out; the estimate is the lowest chi2 (likelihood_basins.list_basins)"
        )
    if not adequate(final.chi2, obj.n_stats):
        # the best point found does not reproduce the data: nothing is identified by it
        profiles = [dataclasses.replace(p, identified=False) for p in profiles]
        if progress is not None:
            progress(
                f"chi2 {final.chi2:.4g} on {obj.n_stats} statistics (p < {ADEQUATE_P:g}): "
                "the fit does not reproduce the data; no parameter reported identified"
            )
    falls = waterfall(obj, found.ends, s.members)  # under the final covariance
    comb_sd, comb_vec = combinations(jac, obj.span)
    ens = obj.ensemble(final.x, s.pilot_members)
    theta = obj.theta(final.x)
    band = fitted_band(theta, fitted, layout, s.band_members, spec)
    step = trend_stride(len(layout.t))
    tm = first_order_trend(layout.t[::step], band["mean"][::step])
    td = first_order_trend(layout.t[::step], records.mean(axis=0)[::step])
    load_fit = None
    if part is not None:
        load_fit = load_result(obj, final.x, s, profiles, reread, progress)
    return FitResult(
        names=obj.names,
        x=final.x,
        chi2=final.chi2,
        profiles=profiles,
        correlation=corr,
        local_sd=sd,
        comb_sd=comb_sd,
        comb_vectors=comb_vec,
        target=target,
        fitted_stats=ens.mean,
        fitted_sd=np.sqrt(np.diag(ens.cov)),
        layout=layout,
        band=band,
        trend_data=(td.steady, td.tau),
        trend_model=(tm.steady, tm.tau),
        trend_ci=(
            tuple(np.percentile(boot[:, 0], [2.5, 97.5])),
            tuple(np.exp(np.percentile(boot[:, 1], [2.5, 97.5]))),
        ),
        physical=physical(theta, fitted),
        basins=basins,
        curve=fitted,
        note=note,
        evaluations=len(obj.read),
        wall_time_s=_time.perf_counter() - start,
        settings=s,
        runs=tuple(runs),
        load=load_fit,
        chi2_level=level,
        start_chi2=falls[0],
        start_x=falls[1],
        interval_threshold=thr,
    )
