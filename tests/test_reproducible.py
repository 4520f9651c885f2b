"""The same answer on every machine: reductions without kernel-dependent bits, and a
fit whose estimate round-off cannot move (docs/user_guide/reproducible.md)."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bouncedisk.fitting import detlinalg
from bouncedisk.fitting.core import FitSettings, fit_curve
from bouncedisk.fitting.likelihood_basins import CHI2_DIGITS, list_basins, rank_key
from bouncedisk.fitting.members import synthesize_curve
from bouncedisk.fitting.output import fit_dataset
from bouncedisk.io.runup_curves import MotorCurve, read_curve, write_curve

F_HZ, PHI0, DT, SIGMA = 15000.0, 3.0e-4, 2.5e-5, 0.05
TRUE = {"e": 0.31, "r_phi": 0.0041, "psi": 0.25, "omega_s": 1.37}
#: A fit small enough for a test: every stage runs (scan, zoom, re-ranking, local search, one profile).
SMALL = FitSettings(seed=4, scan=8, zoom=2, zoom_centres=1, members=4, pilot_members=6,
                    band_members=4, local_nfev=2, bootstrap=40, profile=("e",), e_sigma=0.03)  # fmt: skip
#: BLAS set-ups: this CPU's default kernels on two threads, and the AVX2 kernels another machine
#: would pick on one thread.
KERNELS = (
    {"OPENBLAS_NUM_THREADS": "2"},
    {"OPENBLAS_CORETYPE": "Haswell", "OPENBLAS_NUM_THREADS": "1"},
)

_PROBE = """
import json, sys
import numpy as np
from bouncedisk.io.runup_curves import read_curve
from bouncedisk.fitting.core import FitSettings, data_layout, fit_curve, prepare_runs
from bouncedisk.fitting.summary_stats import EnsembleStats, record_stats
from bouncedisk.analysis.observables import first_order_trend
c = read_curve(sys.argv[1])
(r,), _, _ = prepare_runs(c)
layout, records, target = data_layout([r])
tr = first_order_trend(layout.t[::3], records[0][::3])
vals = [tr.steady, tr.tau, tr.ripple_rms, *target]
ens = EnsembleStats.from_values(np.array([record_stats(records[0][::-1], layout), target, 2 * target]))
vals += [*ens.cov.ravel()]
out = {"stats": [v.hex() for v in map(float, vals)]}
if sys.argv[2] == "fit":
    out["x"] = fit_curve(c, FitSettings(**json.loads(sys.argv[3]))).x.tolist()
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def curve_csv(tmp_path_factory):
    p = tmp_path_factory.mktemp("repro") / "c.csv"
    df = synthesize_curve(TRUE, F_HZ, PHI0, 0.02, DT, SIGMA, 3, member=0)
    write_curve(df, p, {"source": "test", "synthetic": True,
                        "units": {"time": "s", "omega": "rad/s"},
                        "motor": {"drive_frequency_hz": F_HZ, "Phi0_rad": PHI0}})  # fmt: skip
    return p


def _probe(path: Path, env: dict, fit: bool = False) -> dict:
    settings = {k: v for k, v in dataclasses.asdict(SMALL).items() if k != "profile"}
    settings["profile"] = list(SMALL.profile)
    full = {**os.environ, **env}
    args = [
        sys.executable,
        "-c",
        _PROBE,
        str(path),
        "fit" if fit else "stats",
        json.dumps(settings),
    ]
    done = subprocess.run(args, env=full, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.slow  # two Python subprocesses
def test_statistics_bit_identical_under_blas_kernels(curve_csv):
    """The trend, the data's statistics and an ensemble covariance have the same bits under the
    default OpenBLAS kernels, the AVX2 ones and one or two threads (no BLAS in them)."""
    assert _probe(curve_csv, KERNELS[0])["stats"] == _probe(curve_csv, KERNELS[1])["stats"]


@pytest.mark.slow
@pytest.mark.cost(16)
def test_fit_estimate_equal_under_kernels_threads_and_round_off(curve_csv):
    """A small fit gives the same estimate (to 1e-6 relative) under another BLAS kernel, one or
    two BLAS threads, one or two fit threads, and with the data perturbed by 1e-15 relative
    noise: every evaluated point is on a lattice, every reduction BLAS-free, every ranking a
    total order (:mod:`bouncedisk.fitting.likelihood_basins`)."""
    curve = read_curve(curve_csv)
    ref = fit_curve(curve, SMALL).x
    rng = np.random.default_rng(0)
    noisy = dataclasses.replace(
        curve, omega=curve.omega * (1 + 1e-15 * rng.standard_normal(len(curve.omega)))
    )
    assert not np.array_equal(noisy.omega, curve.omega)
    others = [fit_curve(noisy, SMALL).x, fit_curve(curve, dataclasses.replace(SMALL, cores=2)).x]
    others += [np.array(_probe(curve_csv, env, fit=True)["x"]) for env in KERNELS]
    for x in others:
        np.testing.assert_allclose(x, ref, rtol=1e-6, atol=1e-12)


def test_fit_file_lists_the_basins_and_reports_the_first(curve_csv):
    fit = fit_curve(read_curve(curve_csv), dataclasses.replace(SMALL, scan=8, zoom=0))
    ds = fit_dataset(fit)
    assert ds.attrs["basins"] == ds.sizes["basin"] == len(fit.basins) >= 1
    np.testing.assert_array_equal(ds["basin_x"].values[0], fit.x)
    assert ds["basin_chi2"].values[0] == fit.chi2 == min(ds["basin_chi2"].values)
    assert ds["basin_chi2"].values.max() <= fit.chi2 + fit.profiles[0].threshold
    assert (ds["basin_points"].values >= 1).all()


# ---------------------------------------------------------------- the choice rule


def test_basins_do_not_depend_on_the_order_of_the_points():
    rng = np.random.default_rng(1)
    span = np.array([1.0, 2.0])
    xs = np.vstack([rng.uniform(0, 0.01, (5, 2)), 0.5 + rng.uniform(0, 0.01, (4, 2)), [[0.9, 1.9]]])
    chis = np.concatenate([3 + rng.uniform(0, 1, 5), 2.5 + rng.uniform(0, 1, 4), [50.0]])
    a = list_basins(xs, chis, span, threshold=3.84)
    order = rng.permutation(len(xs))
    b = list_basins(xs[order], chis[order], span, threshold=3.84)
    assert [(tuple(q.x), q.chi2, q.points) for q in a] == [
        (tuple(q.x), q.chi2, q.points) for q in b
    ]
    # two basins (the far point is outside the threshold), best first, all points counted
    assert len(a) == 2 and a[0].chi2 == chis.min() and sum(q.points for q in a) == 9


def test_rank_ties_go_to_the_smaller_point():
    """Equal to CHI2_DIGITS digits is a tie, decided by the coordinates, not by which came first."""
    c = 4.0
    tiny = c * 10.0 ** (-CHI2_DIGITS - 2)
    assert rank_key(c + tiny, [0.1, 0.2]) < rank_key(c, [0.1, 0.3])
    assert rank_key(c, [0.1, 0.2]) < rank_key(c * (1 + 10.0 ** (1 - CHI2_DIGITS)), [0.0, 0.0])
    xs, chis = np.array([[0.1, 0.3], [0.9, 0.9], [0.1, 0.2]]), np.array([c, c, c + tiny])
    basins = list_basins(xs, chis, np.ones(2), 1.0)
    assert tuple(basins[0].x) == (0.1, 0.2)  # the reported basin is the first


# ---------------------------------------------------------------- fixed-order linear algebra


def test_detlinalg_agrees_with_lapack():
    rng = np.random.default_rng(2)
    a = rng.normal(size=(30, 11))
    c = a.T @ a
    low = detlinalg.cholesky(c)
    np.testing.assert_allclose(low @ low.T, c, rtol=1e-12, atol=1e-12)
    assert np.allclose(np.triu(low, 1), 0.0)
    np.testing.assert_allclose(detlinalg.lower_inverse(low) @ low, np.eye(11), atol=1e-12)
    w, v = detlinalg.sym_eig(c)
    np.testing.assert_allclose(w, np.linalg.eigvalsh(c), rtol=1e-12)
    np.testing.assert_allclose(v @ np.diag(w) @ v.T, c, rtol=1e-12, atol=1e-10)
    j = rng.normal(size=(11, 4))
    np.testing.assert_allclose(detlinalg.pinv(j, 1e-8), np.linalg.pinv(j, 1e-8), atol=1e-12)
    np.testing.assert_allclose(detlinalg.pinv_sym(c, 1e-10), np.linalg.inv(c), rtol=1e-9)
    with pytest.raises(np.linalg.LinAlgError):
        detlinalg.cholesky(-c)
    assert detlinalg.dot([1e16, 1.0, -1e16], [1.0, 1.0, 1.0]) == 1.0  # exactly rounded


def test_uniform_curve_dt_is_its_mean_step():
    """Epoch-like stamps (steps quantized to 1.2e-7 s, 0.6 % of a step): the mean step is good
    to ulp(1e9)/span, the median step would be off by the quantum."""
    t = 1e9 + 2e-5 * np.arange(1000)
    c = MotorCurve(t, np.zeros(1000), 0.0, 2e4, None, "", True, "x.csv")
    assert abs(c.dt / 2e-5 - 1) <= np.spacing(1e9) / (t[-1] - t[0])
    assert abs(np.median(np.diff(t)) / 2e-5 - 1) > 1e-3
