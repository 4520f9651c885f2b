"""A small random-motor case of ``benchmarks/random_motors.py`` (the test of record is the
benchmark's table): a motor of the seeded Sobol' sample the fit was never tuned on, its run-up and
load curve made by the model with independent reading noise, fitted with the restitution noise
free. Either the fit is adequate and every joint interval holds the generating value, or it says
it identified nothing (NaN intervals)."""

from __future__ import annotations

import dataclasses
import math
import runpy
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _bench() -> SimpleNamespace:
    """``benchmarks/random_motors.py``'s names (the benchmark is a script, not a module)."""
    return SimpleNamespace(**runpy.run_path(str(ROOT / "benchmarks" / "random_motors.py")))


def test_the_sample_is_seeded_spans_the_box_and_has_deterministic_motors():
    """16 motors: the same every time, inside the search box, every fourth at ``e_sigma = 0``."""
    from bouncedisk.fitting.members import BOUNDS

    rm = _bench()
    a, b = rm.motors(16), rm.motors(16)
    assert a == b and len(a) == 16
    assert [m["e_sigma"] for m in a[3::4]] == [0.0] * 4
    assert sum(m["e_sigma"] > 0 for m in a) == 12
    for m in a:
        assert BOUNDS["e"][0] <= m["e"] <= BOUNDS["e"][1]
        assert BOUNDS["omega_s"][0] <= m["omega_s"] <= BOUNDS["omega_s"][1]
        assert BOUNDS["log10_r_phi"][0] <= math.log10(m["r_phi"]) <= BOUNDS["log10_r_phi"][1]
        assert 0.0 <= m["e_sigma"] <= 0.1
    # a Sobol' sample fills the box: each coordinate's 16 values spread over its range
    es = sorted(m["e"] for m in a)
    assert es[0] < 0.15 and es[-1] > 0.85


def test_the_coverage_carries_its_interval_over_motors_and_the_targets_own_chance():
    """The pooled coverage of the table: the bootstrap over whole motors is wider than the
    binomial interval of independent intervals when misses cluster in motors (and equal to the
    observed rate when every motor holds the same number), Clopper–Pearson's is exact (the
    binomial tail at each end is 2.5 %), and the chance that exact 95 % intervals hold on 15 or
    16 of 16 motors is the binomial sum."""
    from scipy.stats import binom

    rm = _bench()
    clustered = [5] * 12 + [0, 3, 3, 2]  # 68 of 80, the misses in four motors
    c = rm.coverage(clustered, 5)
    assert (c["held"], c["intervals"], c["rate"]) == (68, 80, 0.85)
    lo, hi = c["ci95_if_independent"]
    assert binom.sf(67, 80, lo) == pytest.approx(0.025, abs=2e-3)  # P(X >= 68 | lo)
    assert binom.cdf(68, 80, hi) == pytest.approx(0.025, abs=2e-3)  # P(X <= 68 | hi)
    assert c["ci95_motors"][0] < lo - 0.03 and c["ci95_motors"][1] > hi + 0.03
    assert rm.coverage([4] * 16, 5)["ci95_motors"] == [0.8, 0.8]
    assert c["exact_intervals_meet_one_target"] == round(0.95**16 + 16 * 0.05 * 0.95**15, 3)
    row = {"adequate": True, "holds": {"e": True, "psi": False}, "r_phi_factor": 1.5}
    assert rm.rates([row])["coverage"]["held"] == 1


@pytest.mark.slow  # one small joint fit with five coordinates
@pytest.mark.xfail(
    strict=True,
    reason="a known defect: at these tiny search sizes motor 0 is fitted adequately but its "
    "psi interval [-0.390, 1.559] misses the generating -0.671 (before the scan candidates were "
    "re-read on the fit's members: e_sigma [0.030, 0.064] missed 0.0665); at the default sizes "
    "every interval of motor 0 holds (benchmarks/random_motors.py)",
)
def test_a_random_motor_is_identified_or_says_it_is_not(tmp_path):
    from bouncedisk.fitting import fit_curve, fit_dataset
    from bouncedisk.io.load_curves import read_load_curve
    from bouncedisk.io.runup_curves import read_curve

    rm = _bench()
    k = 0
    true = rm.motors(16)[k]
    run, load = rm.make_motor_data(tmp_path, true, k, loads=10, repeats=5, reading_noise=0.05)
    df = pd.read_csv(load)
    assert len(df) == 10 and df["torque_Nm"].iloc[0] == 0.0
    assert df["speed_rad_s"].iloc[-1] < 0.5 * df["speed_rad_s"].iloc[0]  # past stall
    assert np.all(df["speed_sd_rad_s"] >= 0.05)  # the reading noise is in the spread
    settings = dataclasses.replace(
        rm.FitSettings(seed=1, scan=16, zoom=4, zoom_centres=2, members=4, pilot_members=8,
                       band_members=8, local_nfev=4, cores=2, joint_zoom=8), e_sigma=None,
    )  # fmt: skip
    ds = fit_dataset(fit_curve(read_curve(run), settings, load=[read_load_curve(load)]))
    lo, hi = ds["interval_low"].values[2], ds["interval_high"].values[2]
    if ds.attrs["identified"] == "yes":
        for j, name in enumerate(str(n) for n in ds["parameter"].values):
            t = math.log10(true["r_phi"]) if name == "log10_r_phi" else true[name]
            assert lo[j] <= t <= hi[j], (name, lo[j], t, hi[j])
    else:
        assert np.isnan(lo).all() and np.isnan(hi).all()
