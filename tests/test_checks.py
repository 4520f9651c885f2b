"""Reproduction checks that can fail (bouncedisk.studies.reproduction, ``bouncedisk check``).

The stall check asserts the momentum bound on a sweep that reaches it; the identifiability check
asks every joint interval to hold the generating value of synthetic data and takes a NaN interval
for not identified; a built file without one field the checks read is one line naming the file
and the field, exit 2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from load_scenes import small_load_scene

from bouncedisk.cli import main
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.errors import InputError
from bouncedisk.studies import reproduction as checks
from bouncedisk.studies.torque_speed import to_dataset, torque_speed


def _curve(stall: float, lo: float, hi: float, state: str = "found", window: float = 0.0106):
    return {
        "loads": np.linspace(0.0, 1.02, 18),
        "stall": stall,
        "stall_ci95": [lo, hi],
        "state": state,
        "e": 0.3,
        "window": window,
    }


@pytest.mark.parametrize(
    ("name", "curve", "passes"),
    [
        # fig. 3's motor: at the bound, within the window's resolution
        ("load_fig3", _curve(1.0106, 1.0, 1.0125), True),
        ("load_fig3", _curve(math.nan, math.nan, math.nan, "beyond_largest_load"), False),
        ("load_fig3", _curve(0.60, 0.55, 0.65), False),  # the design map's interpolated 0.60
        ("load_fig3", _curve(1.3, 1.0, 1.3), False),  # a root far past the window's resolution
        # fig. 4's motor: below the bound
        ("load_fig4", _curve(0.615, 0.613, 0.617), True),
        ("load_fig4", _curve(math.nan, math.nan, math.nan, "beyond_largest_load"), False),
        ("load_fig4", _curve(1.2, 1.15, 1.25), False),
    ],
)
def test_the_stall_check_fails_unless_the_momentum_bound_holds_on_a_sweep_that_reaches_it(
    name, curve, passes
):
    r = checks._stall_check(name, curve, "test")
    assert r.passed is passes, r
    assert "docs/model.md" in r.claim
    if not math.isfinite(curve["stall"]):
        assert "not found" in r.measured


#: The synthetic motor's generating values in search coordinates (data/prototype sidecars).
GENERATING = (0.55, math.log10(0.002), 0.4, 1.7)


def _fit(lo, hi, gen=GENERATING, identified=1):
    names = ["e", "log10_r_phi", "psi", "omega_s"]
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    sets = ["runup", "load", "both"]
    rows = lambda v: np.vstack([v, v, v])  # noqa: E731
    return xr.Dataset(
        {
            "load_speed_measured": ("reading", np.array([20.0, 10.0, 0.0])),
            "load_speed_band_low": ("reading", np.array([19.0, 9.0, -1.0])),
            "load_speed_band_high": ("reading", np.array([21.0, 11.0, 1.0])),
            "interval_low": (("data_set", "parameter"), rows(lo)),
            "interval_high": (("data_set", "parameter"), rows(hi)),
            "interval_identified": (("data_set", "parameter"), np.full((3, 4), identified)),
            "search_low": ("parameter", np.array([0.05, -4.0, -math.pi, 1.05])),
            "search_high": ("parameter", np.array([0.95, -1.0, math.pi, 4.0])),
            "generating_value": ("parameter", np.asarray(gen, float)),
        },
        coords={"data_set": sets, "parameter": names},
        attrs={"chi2": 17.7, "n_statistics": 16, "chi2_p_value": 0.34, "fit_adequate": 1},
    )


def test_identifiability_needs_every_interval_to_hold_the_generating_value():
    holds = _fit([0.53, -2.75, 0.1, 1.6], [0.58, -2.65, 0.45, 1.75])
    assert checks._identifiability_check(holds, 2, "f").passed
    # `fit --scan 8 --zoom 0`: narrow intervals that exclude every generating value
    wrong = _fit([0.60, -2.2, 1.0, 2.2], [0.62, -2.1, 1.1, 2.3])
    r = checks._identifiability_check(wrong, 2, "f")
    assert not r.passed and "excludes its generating value" in r.measured
    # one parameter excluded is enough
    one = _fit([0.53, -2.75, 0.1, 1.72], [0.58, -2.65, 0.45, 1.75])
    assert not checks._identifiability_check(one, 2, "f").passed
    # an inadequate fit writes NaN intervals: not identified, not a pass
    nan = _fit([np.nan] * 4, [np.nan] * 4)
    r = checks._identifiability_check(nan, 2, "f")
    assert not r.passed and "not identified" in r.measured
    # real data (no generating values): inside the search range is what can be asked
    real = _fit([0.60, -2.2, 1.0, 2.2], [0.62, -2.1, 1.1, 2.3], gen=[np.nan] * 4)
    assert checks._identifiability_check(real, 2, "f").passed
    assert "docs/" in r.claim


# ----------------------------------------------------------------------------- missing fields
def _results(tmp_path):
    """A results folder whose load curve, band, stats and fit files the checks can read."""
    res = tmp_path / "results"
    for sub in ("load", "bands", "stats", "fit"):
        (res / sub).mkdir(parents=True)
    scene = small_load_scene(0.3)
    write_dataset(to_dataset(scene, torque_speed(scene, [0.0, 1.1]), 0.0), res / "load" / "a.nc")
    band = xr.Dataset(
        {"trend_steady": ("member", [90.0, 91.0]), "omega_mean": ("time", [0.0, 1.0])},
        attrs={"mean_trend_r2": 0.9},
    )
    write_dataset(band, res / "bands" / "fig5.nc")
    stats = xr.Dataset(
        {"mean_omega": ("member", [1.0, 2.0]), "regime": ("member", [1, 1])},
        attrs={k: 1.0 for k in checks.STATS_ATTRS},
    )
    write_dataset(stats, res / "stats" / "s.nc")
    fit = _fit([0.53, -2.75, 0.1, 1.6], [0.58, -2.65, 0.45, 1.75])
    fit["omega_measured"] = ("time", [0.0, 1.0])
    write_dataset(fit, res / "fit" / "prototype.nc")
    return res


def _drop(path, name):
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    if name in ds.attrs:
        del ds.attrs[name]
    else:
        ds = ds.drop_vars(name)
    path.unlink()
    write_dataset(ds, path)


@pytest.mark.parametrize(
    ("file", "field"),
    [
        ("stats/s.nc", "stats_mean_omega_ci95"),
        ("load/a.nc", "branch"),
        ("load/a.nc", "e"),
        ("fit/prototype.nc", "chi2"),
        ("fit/prototype.nc", "load_speed_band_low"),
        ("bands/fig5.nc", "mean_trend_r2"),
    ],
)
def test_a_built_file_without_a_field_the_checks_read_is_refused_naming_both(tmp_path, file, field):
    res = _results(tmp_path)
    src = checks._Source(res)
    read = {
        "stats": lambda: src.stats("s"),
        "load": lambda: checks._load_curve(src, "a"),
        "fit": lambda: checks._fit_checks(src),
        "bands": lambda: src.band("fig5"),
    }[file.split("/")[0]]
    read()  # complete: read without complaint
    src.cache.clear()
    _drop(res / file, field)
    with pytest.raises(InputError) as err:
        read()
    assert str(res / file) in str(err.value) and field in str(err.value)


def test_check_results_with_a_file_missing_a_field_is_one_line_and_exit_2(
    tmp_path, monkeypatch, capsys
):
    res = _results(tmp_path)
    _drop(res / "fit" / "prototype.nc", "chi2")
    monkeypatch.setattr(checks, "check_results_folder", lambda p: res)
    monkeypatch.setattr(checks, "CHECKS", [checks._fit_checks])
    assert main(["check", "--results", str(res)]) == 2
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bouncedisk: error: ")
    assert "prototype.nc" in lines[0] and "chi2" in lines[0] and "Traceback" not in out.err


def test_the_speed_may_not_rise_with_the_load_below_the_bound_only():
    c = {
        "loads": np.array([0.0, 0.5, 0.9, 1.01, 1.02]),
        "low": np.array([90.0, 80.0, 85.0, -400.0, -70.0]),
        "high": np.array([91.0, 81.0, 86.0, -390.0, -60.0]),
    }
    # 0.9 rises above 0.5's interval; 1.02 above 1.01's, but past the bound it may
    assert checks._rises(c) == [0.9]
