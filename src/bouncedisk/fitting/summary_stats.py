"""Summary statistics of a speed record, and of an ensemble of model records.

The model is chaotic, so a measured curve is one realization; what the model predicts is the
distribution of a realization's statistics (docs/model.md "Long-run statistics of chaotic motion").
A record ``y(t)`` (rad/s on a uniform grid) is reduced to:

* the trend: steady speed ``S`` and ``log τ`` of its first-order fit
  (:func:`~bouncedisk.analysis.observables.first_order_trend`), and the rise curve as the mean speed over
  three fixed windows ``[0, τ_ref/2]``, ``[τ_ref/2, τ_ref]``, ``[τ_ref, 2τ_ref]`` (``τ_ref`` the
  data's time constant, fixed once per fit, so these are linear in the record);
* the ripple, the residual about the trend once the rise is over (``t ≥ 3τ_ref``, or the last
  half): ``log`` RMS, the power-weighted mean frequency as a fraction of the drive frequency, and
  the fractions of its power in the low (``< f_N/8``) and middle (``f_N/8 … f_N/2``) bands of the
  sampled spectrum (``f_N`` the Nyquist frequency);
* the kicks: ``log`` of the variance of the sample-to-sample increments over the ripple part.
  Each impact changes ``x = R_φ Ω`` by ``R_φ H`` (docs/model.md "Events", ``H ≤ F``), so in rad/s the
  kicks scale with ``R_φ`` at a fixed steady speed, while the measurement noise adds ``2σ²``.
  Unlike the time constant, which one run-up realizes once (its spread across the members of a
  chaotic ensemble is tens of percent), this averages over every sample of the steady part: it
  is what carries ``R_φ`` in a chaotic curve;
* the mean speed over the ripple part: linear in the record like the rise windows, so the
  ensemble mean of it is the ensemble-mean curve's (the first-order steady speed of one chaotic
  run-up is not: its members' mean differs from the mean curve's by percent).

With the drive frequency and Φ0 known, docs/model.md's scaling (``x = R_φ Ω`` evolves at a rate
``∝ R_φ`` while the axial motion does not depend on ``R_φ``) makes ``S`` fix one combination of
``(e, omega_s, ψ)`` and ``τ`` mainly ``R_φ``; the rise shape and the ripple carry the rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..analysis.observables import first_order_trend


@dataclass(frozen=True)
class Statistic:
    """One statistic of a record: its name, units and the scales the fit gives it.

    ``floor`` is the smallest standard deviation the fit allows it (its own resolution) and
    ``provisional`` its standard deviation in the global search's provisional metric; both are
    fractions of the steady speed for statistics in rad/s (``per_speed``), absolute otherwise.
    """

    name: str
    units: str
    long_name: str
    floor: float
    provisional: float

    @property
    def per_speed(self) -> bool:
        """Whether the scales are fractions of the steady speed (a statistic in rad/s)."""
        return self.units == "rad/s"


#: The statistics, in vector order (:func:`record_stats`).
STATISTICS: tuple[Statistic, ...] = (
    Statistic("steady_speed", "rad/s", "steady speed S of the first-order trend", 1e-3, 0.02),
    Statistic(
        "log_time_constant",
        "1",
        "natural log of the time constant of the first-order trend (tau in s)",
        2e-3,
        0.05,
    ),
    Statistic("rise_mean_1", "rad/s", "mean speed over [0, tau_ref/2]", 1e-3, 0.02),
    Statistic("rise_mean_2", "rad/s", "mean speed over [tau_ref/2, tau_ref]", 1e-3, 0.02),
    Statistic("rise_mean_3", "rad/s", "mean speed over [tau_ref, 2 tau_ref]", 1e-3, 0.02),
    Statistic(
        "log_ripple_rms",
        "1",
        "natural log of the RMS ripple about the trend (rms in rad/s)",
        5e-3,
        0.05,
    ),
    Statistic(
        "ripple_frequency",
        "1",
        "power-weighted mean ripple frequency over the drive frequency",
        2e-3,
        0.03,
    ),
    Statistic(
        "ripple_low_band",
        "1",
        "fraction of the ripple power below 1/8 of the Nyquist frequency",
        2e-3,
        0.03,
    ),
    Statistic(
        "ripple_mid_band",
        "1",
        "fraction of the ripple power between 1/8 and 1/2 of the Nyquist frequency",
        2e-3,
        0.03,
    ),
    Statistic(
        "log_increment_var",
        "1",
        "natural log of the variance of sample-to-sample increments after the rise (in (rad/s)^2)",
        5e-3,
        0.05,
    ),
    Statistic("steady_mean", "rad/s", "mean speed after the rise (the ripple part)", 1e-3, 0.02),
)
STATS: tuple[str, ...] = tuple(st.name for st in STATISTICS)
STAT_UNITS: tuple[str, ...] = tuple(st.units for st in STATISTICS)
STAT_LONG_NAMES: tuple[str, ...] = tuple(st.long_name for st in STATISTICS)
#: Trend points used by the first-order fit (the record is subsampled evenly to about this).
TREND_POINTS = 300


def trend_stride(n: int) -> int:
    """The stride that thins ``n`` samples to about :data:`TREND_POINTS` for a first-order
    trend fit."""
    return max(1, n // TREND_POINTS)


@dataclass(frozen=True)
class Layout:
    """Where the statistics are taken on a record: fixed once per fit from the data.

    Parameters
    ----------
    t : ndarray
        Uniform time grid (s), starting at the record's first sample.
    tau_ref : float
        The data's time constant (s): sets the rise windows and the start of the ripple part.
    drive_frequency_hz : float
        Drive frequency ``f`` (the ripple frequency is reported as a fraction of it).
    """

    t: np.ndarray
    tau_ref: float
    drive_frequency_hz: float

    def windows(self) -> list[np.ndarray]:
        """Boolean masks of the three rise windows (each at least two samples)."""
        t0 = self.t[0]
        edges = [0.0, 0.5, 1.0, 2.0]
        out = []
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            m = (self.t >= t0 + a * self.tau_ref) & (self.t < t0 + b * self.tau_ref)
            if m.sum() < 2:
                k = int(np.searchsorted(self.t, t0 + a * self.tau_ref))
                m = np.zeros(len(self.t), bool)
                m[min(k, len(self.t) - 2) : min(k, len(self.t) - 2) + 2] = True
            out.append(m)
        return out

    def steady(self) -> np.ndarray:
        """Mask of the ripple part: after three time constants, or the last half if too short."""
        m = self.t >= self.t[0] + 3.0 * self.tau_ref
        if m.sum() < max(32, len(self.t) // 4):
            m = self.t >= self.t[len(self.t) // 2]
        return m


def record_stats(y: np.ndarray, layout: Layout) -> np.ndarray:
    """The statistics (order of :data:`STATS`) of one record ``y`` (rad/s) on ``layout.t``."""
    return records_stats(np.asarray(y, float)[None, :], layout)[0]


def records_stats(ys: np.ndarray, layout: Layout) -> np.ndarray:
    """The statistics (order of :data:`STATS`) of every row of ``ys`` (records in rad/s on
    ``layout.t``), shape ``(rows, len(STATS))``.

    The rows' ripple spectra come from one :func:`ripple_psd` call on the stacked residuals: a
    row's spectrum is the same, bit for bit, as from a call of its own
    (``tests/test_fit_statistics.py``), and the segments' transforms of all the rows run
    together instead of one short call each.
    """
    ys = np.atleast_2d(np.asarray(ys, float))
    t = layout.t
    step = trend_stride(len(t))
    steady = layout.steady()
    windows = layout.windows()
    head, ripples = [], []
    for y in ys:
        trend = first_order_trend(t[::step], y[::step])
        rise = [float(np.mean(y[m])) for m in windows]
        r = (y - trend(t))[steady]
        ripples.append(r - r.mean())
        head.append([trend.steady, np.log(trend.tau), *rise])
    r = np.array(ripples)
    dt = float(t[1] - t[0])
    f, pxx = ripple_psd(r, dt)
    out = []
    for y, h, ri, p in zip(ys, head, r, pxx, strict=True):
        spectral = _ripple_spectrum(f[1:], p[1:], dt, layout.drive_frequency_hz)
        rms = max(float(np.std(ri)), 1e-300)
        kicks = max(float(np.var(np.diff(y[steady]))), 1e-300)
        out.append([*h, np.log(rms), *spectral, np.log(kicks), float(np.mean(y[steady]))])
    return np.array(out, dtype=float)


#: Samples per segment of the ripple's Welch spectrum (fewer when the ripple part is shorter).
PSD_SEGMENT = 256


@lru_cache(maxsize=8)
def _hann(n: int) -> tuple[np.ndarray, float]:
    """The periodic Hann window of ``n`` samples and the sum of its squares."""
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n) if n > 1 else np.ones(n)
    w.flags.writeable = False  # shared by every call (cached)
    return w, float(np.add.reduce(w * w))


def ripple_psd(r: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Welch's one-sided power spectral density of each row of ``r`` (sampled every ``dt``).

    Segments of :data:`PSD_SEGMENT` samples (the row's length if shorter) overlapping by half,
    each with its mean removed and a periodic Hann window, ``|FFT|² dt / Σw²``, doubled except at
    0 and (even segments) the Nyquist frequency, averaged over the segments: the estimate of
    ``scipy.signal.welch`` with its defaults, to round-off (``tests/test_fit_statistics.py``),
    at a fraction of its per-call cost. Rows are independent: a row's spectrum is the same, bit
    for bit, alone or stacked.

    Returns
    -------
    f : ndarray
        Frequencies (Hz).
    pxx : ndarray
        Densities, shape ``(rows, len(f))`` (``(len(f),)`` for one row given as 1-D).
    """
    r = np.asarray(r, float)
    rows = np.atleast_2d(r)
    n = min(PSD_SEGMENT, rows.shape[1])
    if n == 0:  # no samples: no frequencies
        return np.zeros(0), np.zeros(rows.shape[:-1] + (0,)) if r.ndim > 1 else np.zeros(0)
    hop = n - n // 2
    starts = np.arange(0, rows.shape[1] - n + 1, hop)
    seg = np.lib.stride_tricks.sliding_window_view(rows, n, axis=1)[:, starts, :]
    seg = seg - seg.mean(axis=-1, keepdims=True)
    w, ww = _hann(n)
    spec = np.fft.rfft(seg * w, axis=-1)
    p = (spec.real**2 + spec.imag**2) * (dt / ww)
    p[..., 1 : -1 if n % 2 == 0 else None] *= 2
    pxx = p.mean(axis=1)
    return np.fft.rfftfreq(n, dt), pxx if r.ndim > 1 else pxx[0]


def _ripple_spectrum(
    f: np.ndarray, pxx: np.ndarray, dt: float, drive_frequency_hz: float
) -> tuple[float, float, float]:
    """The ripple's power-weighted mean frequency (a fraction of the drive frequency) and the
    fractions of its power below ``f_N/8`` and in ``f_N/8 … f_N/2`` (module docstring)."""
    total = float(np.sum(pxx))
    if not total > 0:  # no ripple (or not a number): no spectrum
        return 0.0, 0.0, 0.0
    nyq = 0.5 / dt
    freq = float(np.sum(f * pxx) / total) / drive_frequency_hz
    low = float(np.sum(pxx[f < nyq / 8]) / total)
    mid = float(np.sum(pxx[(f >= nyq / 8) & (f < nyq / 2)]) / total)
    return freq, low, mid


def dominant_frequency(y: np.ndarray, layout: Layout) -> float:
    """Frequency of the largest peak of the ripple spectrum, as a fraction of the drive frequency.

    Reported, not fitted: it jumps between spectral lines as the parameters move.
    """
    t = layout.t
    step = trend_stride(len(t))
    trend = first_order_trend(t[::step], y[::step])
    r = (y - trend(t))[layout.steady()]
    f, pxx = ripple_psd(r - r.mean(), float(t[1] - t[0]))
    return float(f[1 + int(np.argmax(pxx[1:]))]) / layout.drive_frequency_hz


@dataclass(frozen=True)
class EnsembleStats:
    """Statistics of ``members`` model records: their mean and their covariance across members."""

    mean: np.ndarray
    cov: np.ndarray
    members: int
    values: np.ndarray  # (members, n_stats)

    @classmethod
    def from_values(cls, values: np.ndarray) -> EnsembleStats:
        """Summarise per-member statistics ``values`` of shape ``(members, n_stats)``."""
        v = np.asarray(values, float)
        # fixed-order sums over the members (no BLAS: the same bits under every kernel)
        mean = np.add.reduce(v, axis=0) / len(v)
        c = v - mean
        if len(v) > 1:
            cov = np.add.reduce(c[:, :, None] * c[:, None, :], axis=0) / (len(v) - 1)
        else:
            cov = np.zeros((v.shape[1],) * 2)
        return cls(mean=mean, cov=np.atleast_2d(cov), members=len(v), values=v)


def regularized_cov(cov: np.ndarray, floor: np.ndarray, shrink: float = 0.2) -> np.ndarray:
    """Shrink a sample covariance toward its diagonal and floor its variances.

    ``(1 − shrink)·C + shrink·diag(C)``, then every variance raised to at least ``floor²``
    (periodic members are identical: without measurement noise their spread is zero).
    """
    d = np.diag(cov).copy()
    out = (1.0 - shrink) * cov + shrink * np.diag(d)
    sd = np.sqrt(np.maximum(np.diag(out), 0.0))
    new_sd = np.maximum(sd, floor)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = out / np.outer(np.where(sd > 0, sd, 1.0), np.where(sd > 0, sd, 1.0))
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, 1.0)
    return corr * np.outer(new_sd, new_sd)


def _scaled(measured: np.ndarray, field: str) -> np.ndarray:
    speed = max(abs(float(measured[0])), 1e-12)
    return np.array([getattr(st, field) * (speed if st.per_speed else 1.0) for st in STATISTICS])


def stat_floor(measured: np.ndarray) -> np.ndarray:
    """Smallest standard deviation allowed per statistic (resolution of the statistic itself)."""
    return _scaled(measured, "floor")


def provisional_sd(measured: np.ndarray) -> np.ndarray:
    """Standard deviations of the global search's provisional metric: a few % of each statistic."""
    return _scaled(measured, "provisional")


def member_band(values: np.ndarray) -> dict[str, np.ndarray]:
    """Ensemble mean of ``values`` ``(members, n)``, the 95 % interval of that mean (Student) and
    the members' 2.5–97.5 % band: the fitted model's band of a run-up and of a load curve. The
    interval of the mean is the project's one Student-t helper
    (:func:`bouncedisk.analysis.statistics.confidence_interval`), column by column."""
    from ..analysis.statistics import confidence_interval

    ci = np.array([confidence_interval(values[:, j]) for j in range(values.shape[1])]).reshape(
        -1, 3
    )
    lo, hi = np.percentile(values, [2.5, 97.5], axis=0)
    return {"mean": ci[:, 0], "low": ci[:, 1], "high": ci[:, 2], "p025": lo, "p975": hi}
