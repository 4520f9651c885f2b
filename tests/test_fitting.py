"""Fitting the model to a velocity–time curve: recovery, determinism, bad input."""

import math

import numpy as np
import pytest
import xarray as xr

from bouncedisk.cli import main
from bouncedisk.curves import MotorCurve, read_curve, write_curve
from bouncedisk.fitting import (
    FitSettings,
    fit_curve,
    fit_dataset,
    simulate_curve,
    synthesize_curve,
    uniform_grid,
)
from bouncedisk.observables import first_order_trend

# generating parameters used nowhere else in the repository
TRUE = {"e": 0.42, "r_phi": 0.0031, "psi": -0.55, "omega_s": 2.05}
F_HZ, PHI0, SPAN, DT, SIGMA, SEED = 15000.0, 3.0e-4, 0.1, 2.5e-5, 0.05, 11


def sidecar(f=F_HZ, phi0=PHI0, **extra):
    return {
        "source": "test",
        "synthetic": True,
        "units": {"time": "s", "omega": "rad/s"},
        "motor": {"drive_frequency_hz": f, "Phi0_rad": phi0},
        **extra,
    }


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    df = synthesize_curve(TRUE, F_HZ, PHI0, SPAN, DT, SIGMA, SEED)
    path = tmp_path_factory.mktemp("curve") / "motor.csv"
    write_curve(df, path, sidecar())
    return path


def true_trend(curve: MotorCurve):
    """Trend of the noise-free generating model, averaged over four initial stator phases."""
    theta = {
        "e": TRUE["e"],
        "log10_r_phi": math.log10(TRUE["r_phi"]),
        "psi": TRUE["psi"],
        "omega_s": TRUE["omega_s"],
    }
    grid = uniform_grid(curve)
    mean = np.mean([simulate_curve(theta, curve, k, 4, noise=False) for k in range(4)], axis=0)
    return first_order_trend(grid, mean)


def test_recovers_trend_and_covers_true_parameters(synthetic):
    curve = read_curve(synthetic)
    fit = fit_curve(curve, FitSettings(seed=3))
    ds = fit_dataset(curve, fit)
    truth = true_trend(curve)
    assert ds.attrs["steady_speed_rad_s"] == pytest.approx(truth.steady, rel=0.02)
    assert ds.attrs["time_constant_s"] == pytest.approx(truth.tau, rel=0.02)
    for name in ("e", "r_phi"):
        a = ds[name].attrs
        assert a["ci_low"] <= TRUE[name] <= a["ci_high"], (name, a)
    # the file has what INTERFACES.md promises
    for name in ("omega_measured", "omega_fitted", "e", "r_phi", "psi"):
        assert name in ds
    assert ds["time"].attrs["units"] == "s" and ds["omega_fitted"].attrs["units"] == "rad/s"
    corr = ds["correlation"].values
    assert corr.shape == (4, 4)
    assert np.allclose(np.diag(corr)[np.isfinite(np.diag(corr))], 1.0)
    assert np.all(np.diff(ds["loss_trace"].values[:-1]) <= 1e-12)  # best-so-far per generation


def test_fit_is_deterministic_for_a_seed(synthetic):
    curve = read_curve(synthetic)
    small = FitSettings(
        seed=5,
        scan=32,
        popsize=4,
        maxiter=2,
        local_nfev=5,
        bootstrap=6,
        realizations=2,
        pilot=3,
        pilot_points=2,
    )
    a = fit_curve(curve, small)
    b = fit_curve(curve, small)
    assert a.theta == b.theta
    np.testing.assert_array_equal(a.boot, b.boot)
    c = fit_curve(curve, FitSettings(**{**small.__dict__, "seed": 6}))
    assert c.theta != a.theta


def test_fit_command_writes_file(synthetic, tmp_path, capsys):
    out = tmp_path / "fit.nc"
    code = main(["fit", str(synthetic), "-o", str(out), "--bootstrap", "4", "--seed", "2", "-q"])
    assert code == 0 and out.exists()
    ds = xr.open_dataset(out)
    assert {"ci_low", "ci_high"} <= set(ds["e"].attrs)
    assert "steady_speed_rad_s" in ds.attrs and "time_constant_s" in ds.attrs


def _write(tmp_path, text, side=None):
    import yaml

    p = tmp_path / "c.csv"
    p.write_text(text)
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(side or sidecar()))
    return p


def _rows(n, bad_row=None, bad="x"):
    lines = ["time_s,omega_rad_s"]
    for i in range(n):
        om = bad if i == bad_row else f"{0.1 * i}"
        lines.append(f"{i * 1e-3},{om}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    "text,side,field",
    [
        ("time,omega\n" + "\n".join(f"{i},{i}" for i in range(30)), None, "time_s"),
        (_rows(30, 5, "fast"), None, "omega_rad_s"),
        (_rows(30, 7, "nan"), None, "omega_rad_s"),
        (_rows(10), None, "rows"),
        (
            "time_s,omega_rad_s\n" + "\n".join(f"{(i % 5) * 1e-3},{i}" for i in range(30)),
            None,
            "time_s",
        ),
        (_rows(30), sidecar() | {"units": {"time": "s", "omega": "rpm"}}, "units.omega"),
        (_rows(30), sidecar() | {"units": {"time": "ms", "omega": "rad/s"}}, "units.time"),
        (_rows(30), {"source": "x", "units": {"time": "s", "omega": "rad/s"}}, "motor"),
    ],
)
def test_bad_curves_exit_2_with_one_line(tmp_path, capsys, text, side, field):
    p = _write(tmp_path, text, side)
    out = tmp_path / "fit.nc"
    assert main(["fit", str(p), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0] and not out.exists()


def test_missing_sidecar(tmp_path, capsys):
    p = tmp_path / "c.csv"
    p.write_text(_rows(30))
    assert main(["fit", str(p), "-o", str(tmp_path / "f.nc"), "-q"]) == 2
    assert "sidecar" in capsys.readouterr().err
