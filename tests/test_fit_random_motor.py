"""The random-motor validation benchmark's pieces (``benchmarks/random_motors.py``): its seeded
Sobol' sample of motors the fit was never tuned on, and its coverage with intervals over motors. The
fits themselves (minutes each) are the benchmark's table, not a test."""

from __future__ import annotations

import math
import runpy
from pathlib import Path
from types import SimpleNamespace

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
