"""The fit's statistics (bouncedisk.fitting.summary_stats): closed forms, linearity, R_φ scaling."""

import math

import numpy as np
import pytest

from bouncedisk.fitting.members import EnsembleSpec, member_records
from bouncedisk.fitting.summary_stats import (
    STAT_LONG_NAMES,
    STAT_UNITS,
    STATISTICS,
    STATS,
    Layout,
    provisional_sd,
    record_stats,
    records_stats,
    stat_floor,
)
from bouncedisk.io.runup_curves import MotorCurve

F_HZ, PHI0, DT = 15000.0, 3.0e-4, 2.5e-5
KICKS, STEADY, LOG_TAU = (STATS.index(n) for n in ("log_increment_var", "steady_mean",
                                                   "log_time_constant"))  # fmt: skip
#: a chaotic point with chatter reinjection (the chaotic case of ``benchmarks/fit_recovery.py``)
CHAOTIC = {"e": 0.62, "psi": -0.35, "omega_s": 1.48}


def _members(r_phi: float, n: int = 2401, members: int = 16) -> tuple[np.ndarray, Layout]:
    t = DT * np.arange(n)
    curve = MotorCurve(time=t, omega=np.zeros(n), sigma=0.0, drive_frequency_hz=F_HZ,
                       phi0_rad=PHI0, source="", synthetic=True, path="")  # fmt: skip
    layout = Layout(t, 0.008, F_HZ)
    theta = {**CHAOTIC, "log10_r_phi": math.log10(r_phi)}
    vals = member_records(theta, curve, range(members), EnsembleSpec(seed=4, cores=2),
                          lambda y: record_stats(y, layout))  # fmt: skip
    return np.array(vals), layout


def test_one_table_names_every_statistic():
    assert len(STATS) == len(STAT_UNITS) == len(STAT_LONG_NAMES) == len(STATISTICS)
    assert len(set(STATS)) == len(STATS)
    measured = np.arange(len(STATS), dtype=float) + 10.0
    floor, wide = stat_floor(measured), provisional_sd(measured)
    for k, st in enumerate(STATISTICS):  # speeds scale with the steady speed, others do not
        scale = measured[0] if st.units == "rad/s" else 1.0
        assert floor[k] == pytest.approx(st.floor * scale)
        assert wide[k] == pytest.approx(st.provisional * scale)


def test_increment_variance_of_white_noise_is_two_sigma_squared():
    """Closed form: a constant speed plus white noise σ has increments of variance 2σ²."""
    rng = np.random.default_rng(1)
    sigma = 0.2
    y = 5.0 + rng.normal(0.0, sigma, 20_000)
    t = 1e-4 * np.arange(len(y))
    value = math.exp(record_stats(y, Layout(t, 0.01, F_HZ))[KICKS])
    assert value == pytest.approx(2.0 * sigma**2, rel=0.03)  # sampling error ~1 %


def test_linear_statistics_of_the_mean_are_the_mean_of_the_statistics():
    """The rise windows and the steady mean are linear in the record: the ensemble mean of the
    statistic is the statistic of the ensemble-mean curve (what the recovery criteria compare)."""
    rng = np.random.default_rng(2)
    t = DT * np.arange(3000)
    layout = Layout(t, 0.01, F_HZ)
    recs = [20.0 * (1 - np.exp(-t / 0.01)) + rng.normal(0, 1.0, len(t)) for _ in range(5)]
    each = np.array([record_stats(r, layout) for r in recs])
    of_mean = record_stats(np.mean(recs, axis=0), layout)
    linear = [STATS.index(n) for n in ("rise_mean_1", "rise_mean_2", "rise_mean_3", "steady_mean")]
    np.testing.assert_allclose(of_mean[linear], each[:, linear].mean(axis=0), rtol=1e-12)


def test_the_statistics_of_many_records_are_each_records_own_bit_for_bit():
    """records_stats (one ripple_psd call for all rows, what a fit's ensembles use) gives every row
    the statistics record_stats gives it alone, to the bit: batching changes no fit. Rows of
    other noise levels and a flat record (no ripple: its spectral statistics are 0) included."""
    rng = np.random.default_rng(7)
    t = DT * np.arange(2777)
    layout = Layout(t, 0.006, F_HZ)
    rise = 20.0 * (1 - np.exp(-t / 0.006))
    recs = [rise + rng.normal(0.0, s, len(t)) * np.sin(t * rng.uniform(1e3, 4e4)) ** 2
            for s in (1e-3, 0.1, 1.0, 30.0)] + [np.full(len(t), 3.0)]  # fmt: skip
    many = records_stats(np.array(recs), layout)
    assert many.shape == (len(recs), len(STATS))
    for row, rec in zip(many, recs, strict=True):
        assert row.tobytes() == record_stats(rec, layout).tobytes()
    assert np.all(np.isfinite(many[:-1])) and many[-1, STATS.index("ripple_frequency")] == 0.0


@pytest.mark.slow
def test_kicks_carry_r_phi_where_the_time_constant_scatters():
    """docs/model.md: an impact changes ``x = R_φ Ω`` by ``R_φ H``; noise-free members' increment
    variance goes like ``R_φ²`` at an unchanged steady speed, and spreads by a few percent across
    the members of a chaotic ensemble while their time constants spread by tens of percent."""
    base, _ = _members(0.0027)
    double, _ = _members(0.0054)
    shift = double[:, KICKS].mean() - base[:, KICKS].mean()
    assert shift == pytest.approx(2.0 * math.log(2.0), abs=0.06)  # measured 1.374 vs 1.386
    assert double[:, STEADY].mean() == pytest.approx(base[:, STEADY].mean(), rel=0.03)
    tau = np.exp(base[:, LOG_TAU])
    assert tau.std(ddof=1) / tau.mean() > 0.2  # measured 0.53
    assert base[:, KICKS].std(ddof=1) < 0.05  # measured 0.024 (2.4 % in the variance)


@pytest.mark.parametrize("length", [3, 100, 255, 256, 257, 1001])
def test_the_ripple_spectrum_is_welchs_estimate(length):
    """ripple_psd is scipy's Welch estimate with its defaults (periodic Hann, half overlap,
    constant detrend, density, one-sided), to round-off, for segments odd and even, whole and
    shorter than the record."""
    from scipy.signal import welch

    from bouncedisk.fitting.summary_stats import PSD_SEGMENT, ripple_psd

    rng = np.random.default_rng(length)
    r = rng.normal(size=(3, length)) + 5.0 * np.sin(0.3 * np.arange(length))
    f, p = ripple_psd(r, DT)
    f0, p0 = welch(r, fs=1.0 / DT, nperseg=min(PSD_SEGMENT, length))
    np.testing.assert_allclose(f, f0, rtol=1e-14)
    np.testing.assert_allclose(p, p0, rtol=1e-10, atol=1e-13 * p0.max())
    assert ripple_psd(r[1], DT)[1].tobytes() == p[1].tobytes()


def test_one_birge_factor_scales_every_threshold_of_the_intervals():
    """The Δχ² threshold and the goodness-of-fit limit are scaled by the same factor, χ²/dof with
    dof = n − p when that exceeds 1 (docs/fitting_method.md "The intervals")."""
    from scipy.stats import chi2

    from bouncedisk.fitting.uncertainty import THRESHOLD, birge, birge_scale, fit_limit

    assert THRESHOLD == pytest.approx(3.841458820694124)
    assert birge_scale(20.0, 27, 5) == 1.0  # 20 below 22 degrees of freedom: no scaling
    assert birge_scale(44.0, 27, 5) == pytest.approx(2.0)  # 44 / (27 - 5)
    assert birge(44.0, 27, 5) == pytest.approx(2.0 * THRESHOLD)
    assert fit_limit(44.0, 27, 5) == pytest.approx(2.0 * chi2.ppf(0.95, 27))
    assert fit_limit(20.0, 27, 5) == pytest.approx(chi2.ppf(0.95, 27))
    assert birge_scale(10.0, 3, 5) == 10.0  # fewer statistics than coordinates: dof at least 1
