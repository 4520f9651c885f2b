"""Reproduction checks that can fail (bouncedisk.studies.reproduction, ``bouncedisk check``).

The stall check asserts the momentum bound on a sweep that reaches it; the identifiability check
asks every joint interval to hold the generating value of synthetic data and takes a NaN interval
for not identified. Every claim is recomputed from the arrays it is about: each test below
tampers with one built file of a small results folder (written here by the project's own
writers from chosen member values) and the claim that reads it must fail, naming what was
tampered with; a file without a field the checks read, or with a field of the wrong type, is one
line naming the file and the field, exit 2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from load_scenes import small_load_scene

from bouncedisk.analysis import observables as ob
from bouncedisk.analysis.bands import _band_dataset, mean_trend_fit
from bouncedisk.analysis.ensembles import MemberStats
from bouncedisk.analysis.statistics import EnsembleStats
from bouncedisk.analysis.statistics import to_dataset as stats_dataset
from bouncedisk.cli import main
from bouncedisk.fitting.uncertainty import ADEQUATE_P
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.errors import InputError
from bouncedisk.studies import check_inputs as inp
from bouncedisk.studies import reproduction as checks
from bouncedisk.studies.torque_speed import LoadCurve, to_dataset


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
        ("load_fig3", _curve(1.05, 1.0, 1.0125), False),  # outside its own interval
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
GENERATING = (0.55, math.log10(0.002), 0.4, 1.7, 0.03)


def _fit(lo, hi, gen=GENERATING, identified=1):
    names = ["e", "log10_r_phi", "psi", "omega_s", "e_sigma"][: len(lo)]
    gen = gen[: len(lo)]
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    sets = ["runup", "load", "both"]
    rows = lambda v: np.vstack([v, v, v])  # noqa: E731
    gen = np.asarray(gen, float)
    return xr.Dataset(
        {
            "load_speed_measured": ("reading", np.array([20.0, 10.0, 0.0])),
            "load_speed_band_low": ("reading", np.array([19.0, 9.0, -1.0])),
            "load_speed_band_high": ("reading", np.array([21.0, 11.0, 1.0])),
            "interval_low": (("data_set", "parameter"), rows(lo)),
            "interval_high": (("data_set", "parameter"), rows(hi)),
            "interval_identified": (("data_set", "parameter"), np.full((3, len(lo)), identified)),
            "search_low": ("parameter", np.array([0.05, -4.0, -math.pi, 1.05, 0.0])[: len(lo)]),
            "search_high": ("parameter", np.array([0.95, -1.0, math.pi, 4.0, 0.1])[: len(lo)]),
            "generating_value": ("parameter", gen),
        },
        coords={"data_set": sets, "parameter": names},
        attrs={
            "chi2": 17.7,
            "n_statistics": 16,
            "chi2_p_value": 0.34175456894060413,
            "fit_adequate": 1,
            "identified": "yes",
            "load_curve_synthetic": int(np.isfinite(gen).any()),
        },
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
    # synthetic data that state no generating value cannot pass as real data
    unstated = _fit([0.60, -2.2, 1.0, 2.2], [0.62, -2.1, 1.1, 2.3], gen=[np.nan] * 4)
    unstated.attrs["load_curve_synthetic"] = 1
    r = checks._identifiability_check(unstated, 2, "f")
    assert not r.passed and "state no generating value" in r.measured


def test_the_fitted_noise_is_reported_against_its_generating_value_not_required():
    """With the noise fitted (a fifth parameter), a noise interval that misses its generating
    value is named in the check's line but does not fail it; the motor parameters still must
    hold theirs, and the noise's interval must still be identified inside the search range."""
    lo, hi = [0.45, -2.71, 0.14, 1.67, 0.0082], [0.575, -2.49, 0.66, 2.12, 0.02999]
    r = checks._identifiability_check(_fit(lo, hi), 2, "f")
    assert r.passed and "e_sigma excludes its generating value 0.03: reported, not required" in (
        r.measured
    )
    assert (
        checks._identifiability_check(_fit(lo, [*hi[:4], 0.04]), 2, "f").measured.count("excludes")
        == 0
    )
    r = checks._identifiability_check(_fit([*lo[:3], 1.72, lo[4]], hi), 2, "f")
    assert not r.passed and "omega_s excludes" in r.measured
    r = checks._identifiability_check(_fit([*lo[:4], 0.0], hi), 2, "f")
    assert not r.passed and "e_sigma reaches the search range's end" in r.measured


def test_the_checks_adequacy_is_the_fits():
    assert checks.FIT_P_MIN == ADEQUATE_P


# ----------------------------------------------------------------------------- a results folder
def _member(k, omega, regime="periodic", lyapunov=-0.5, period=(2, 2), load=0.0):
    return MemberStats(
        member=k,
        mean_omega=omega,
        mean_slip=0.0,
        impact_rate=1.0,
        chatter_rate=0.0,
        chatter_interval=math.nan,
        lyapunov=lyapunov,
        regime=ob.REGIME_CODES[regime],
        period_p=period[0],
        period_q=period[1],
        n_impacts=100,
        n_chatter=0,
        duration=5000.0,
        power_out=load * omega,
        power_torsion_in=1.0,
        power_axial_in=1.0,
        power_chatter_axial=0.0,
        efficiency_torsion=load * omega,
        audit_residual_axial=1e-12,
        audit_residual_torsion=1e-12,
    )


def _ensemble(omegas, **kw) -> EnsembleStats:
    return EnsembleStats([_member(k, w, **kw) for k, w in enumerate(omegas)], 3000.0, 5000.0)


#: The up branch's member speeds of a curve that holds its speed up to the bound and stalls
#: just past it (Fig. 3's motor), at each load of :data:`LOADS`.
LOADS = np.array([0.0, 0.5, 1.0, 1.02])
SPEEDS = [[100.0, 100.0], [99.0, 99.0], [98.0, 98.0], [-5.0, -4.0]]


def _load_file(path, speeds=SPEEDS):
    branch = [_ensemble(w, load=x) for w, x in zip(speeds, LOADS, strict=True)]
    curve = LoadCurve(LOADS, {"up": branch, "down": branch})
    write_dataset(to_dataset(small_load_scene(0.3), curve, 0.0), path)


def _fig5(res):
    """The real Fig. 5 run, its band (members 2 % apart around it) and the long-run ensemble
    around the band's steady speed."""
    sim = res / "simulations" / "fig5.nc"
    assert main(["simulate", str(checks.scene_file("fig5")), "-o", str(sim), "-q"]) == 0
    with xr.open_dataset(sim) as ds:
        t, om = ds["time"].values, ds["omega_rotor"].values
    band = _band_dataset(t, np.stack([om * (1 + d) for d in (-0.02, -0.01, 0.0, 0.01, 0.02)]))
    band.attrs["mean_trend_r2"] = mean_trend_fit(t, band["omega_mean"].values)[1]
    write_dataset(band, res / "bands" / "fig5.nc")
    return float(np.mean(band["trend_steady"].values))


def _results(tmp_path):
    """A results folder of every file the checks read, each claim but the fit's passing."""
    res = tmp_path / "results"
    for sub in ("simulations", "load", "bands", "stats", "fit"):
        (res / sub).mkdir(parents=True)
    steady = _fig5(res)
    scene = small_load_scene(0.3)
    ensembles = {
        "stats_e03": _ensemble([144.0] * 4),
        "stats_e06": _ensemble(
            steady + np.array([-1.0, 0.0, 0.5, 1.0]), regime="chaotic", lyapunov=0.8, period=(0, 0)
        ),
        "stats_locked": _ensemble([50.0] * 4, regime="chattering-periodic", lyapunov=-math.inf),
    }
    for name, ens in ensembles.items():
        write_dataset(stats_dataset(scene, ens, 0.0), res / "stats" / f"{name}.nc")
    for name in checks.LOAD_CURVES:
        _load_file(res / "load" / f"{name}.nc")
    fit = _fit([0.53, -2.75, 0.1, 1.6], [0.58, -2.65, 0.45, 1.75])
    fit["omega_measured"] = ("time", [0.0, 1.0])
    write_dataset(fit, res / "fit" / "prototype.nc")
    return res


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    return _results(tmp_path_factory.mktemp("checks"))


def _copy(results, tmp_path):
    import shutil

    return shutil.copytree(results, tmp_path / "results")


def _edit(path, change):
    """Rewrite the file at ``path`` with ``change(ds)`` applied."""
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    ds = change(ds) or ds
    path.unlink()
    write_dataset(ds, path)


def _drop(path, name):
    def change(ds):
        if name in ds.attrs:
            del ds.attrs[name]
            return ds
        return ds.drop_vars(name)

    _edit(path, change)


#: The claims each file is read by.
CLAIMS = {
    "stats_e03": lambda src: [checks._period_check(src)],
    "stats_e06": lambda src: [checks._chaos_check(src)],
    "stats_locked": lambda src: [checks._locked_check(src)],
    **{name: (lambda src, n=name: checks._load_checks(src, (n,))) for name in checks.LOAD_CURVES},
    "fig5": lambda src: [checks._rise_check(src)],
    "fit": checks._fit_checks,
}


def _reader(file: str) -> str:
    """The key of :data:`CLAIMS` that reads ``file``."""
    stem = file.split("/")[-1].removesuffix(".nc")
    return {"prototype": "fit"}.get(stem, stem)


def _claims(res, which):
    return CLAIMS[which](checks._Source(res))


def test_every_claim_passes_on_the_untampered_folder(results):
    for which in CLAIMS:
        got = _claims(results, which)
        assert got, which
        for r in got:
            assert r.passed, r


def _set(name, value):
    def change(ds):
        if name in ds.attrs:
            ds.attrs[name] = value
        else:
            ds[name] = ds[name].copy(data=value(ds[name].values))

    return change


@pytest.mark.parametrize(
    ("file", "which", "change", "named"),
    [
        # stats: per-member regime, speed and Lyapunov exponent against the attributes
        (
            "stats/stats_e03.nc",
            "stats_e03",
            _set("regime", lambda v: np.full_like(v, ob.REGIME_CODES["chaotic"])),
            "regime",
        ),
        (
            "stats/stats_e03.nc",
            "stats_e03",
            _set("mean_omega", lambda v: v + 1.0),
            "stats_mean_omega",
        ),
        ("stats/stats_e06.nc", "stats_e06", _set("lyapunov", lambda v: -v), "stats_lyapunov"),
        (
            "stats/stats_e03.nc",
            "stats_e03",
            _set("period_p", lambda v: np.where(np.arange(v.size) < 3, 1, v)),
            "stats_regime_fraction 1 vs",
        ),
        ("stats/stats_e06.nc", "stats_e06", _set("stats_regime", "periodic"), "stats_regime"),
        (
            "stats/stats_locked.nc",
            "stats_locked",
            _set("lyapunov", lambda v: np.full_like(v, 0.3)),
            "stats_lyapunov",
        ),
        # load curves: the stall torque and the per-load means against the members
        ("load/load_fig3.nc", "load_fig3", _set("stall_torque", 2.0), "stall_torque 2 vs"),
        (
            "load/load_fig3.nc",
            "load_fig3",
            _set("stall_torque_ci95", [0.9, 0.95]),
            "stall_torque_ci95",
        ),
        ("load/load_fig4.nc", "load_fig4", _set("mean_omega", lambda v: v + 1000.0), "mean_omega["),
        ("load/load_fig4.nc", "load_fig4", _set("mean_omega", lambda v: -v), "mean_omega["),
        ("load/load_fig4.nc", "load_fig4", _set("mean_omega_member", lambda v: -v), "not found"),
        (
            "load/load_fig4.nc",
            "load_fig4",
            _set(
                "audit_residual_axial", lambda v: np.where(np.arange(v.shape[-1]) == 3, np.nan, v)
            ),
            "residual inf",
        ),
        # fig. 5: the run against its ensemble's band; the band's R^2 against its mean
        ("simulations/fig5.nc", "fig5", _set("omega_rotor", lambda v: 10 * v), "inside"),
        ("simulations/fig5.nc", "fig5", _set("omega_rotor", lambda v: -v), "inside"),
        ("bands/fig5.nc", "fig5", _set("mean_trend_r2", 0.99), "mean_trend_r2"),
        # the fit: an inadequate fit, a tampered p-value, generating values moved
        ("fit/prototype.nc", "fit", _set("identified", "no"), "identified"),
        ("fit/prototype.nc", "fit", _set("chi2", 80.0), "chi2_p_value"),
        (
            "fit/prototype.nc",
            "fit",
            _set("generating_value", lambda v: v + 1.0),
            "excludes its generating value",
        ),
    ],
)
def test_a_tampered_file_fails_its_claim_naming_what_disagrees(
    results, tmp_path, file, which, change, named
):
    res = _copy(results, tmp_path)
    _edit(res / file, change)
    got = _claims(res, which)
    failed = [r for r in got if not r.passed]
    assert failed, got
    assert any(named in r.measured for r in failed), failed


@pytest.mark.parametrize(
    ("file", "field"),
    [
        ("stats/stats_e03.nc", "stats_mean_omega_ci95"),
        ("stats/stats_e03.nc", "period_p"),
        ("load/load_fig3.nc", "branch"),
        ("load/load_fig3.nc", "e"),
        ("load/load_fig3.nc", "mean_omega_member"),
        ("load/load_fig3.nc", "stall_torque"),
        ("fit/prototype.nc", "chi2"),
        ("fit/prototype.nc", "identified"),
        ("fit/prototype.nc", "load_speed_band_low"),
        ("fit/prototype.nc", "generating_value"),
        ("fit/prototype.nc", "load_speed_measured"),
        ("bands/fig5.nc", "mean_trend_r2"),
        ("bands/fig5.nc", "omega_p975"),
    ],
)
def test_a_built_file_without_a_field_the_checks_read_is_refused_naming_both(
    results, tmp_path, file, field
):
    res = _copy(results, tmp_path)
    _drop(res / file, field)
    with pytest.raises(InputError) as err:
        _claims(res, _reader(file))
    assert str(res / file) in str(err.value) and field in str(err.value)


@pytest.mark.parametrize(
    ("file", "field", "value"),
    [
        ("stats/stats_e06.nc", "stats_lyapunov_ci95", 0.5),
        ("stats/stats_e06.nc", "stats_regime", 4),
        ("fit/prototype.nc", "chi2", "abc"),
        ("load/load_fig3.nc", "stall_torque_ci95", "abc"),
        ("load/load_fig3.nc", "e", [0.3, 0.6]),
    ],
)
def test_check_results_with_a_field_of_the_wrong_type_is_one_line_and_exit_2(
    results, tmp_path, monkeypatch, capsys, file, field, value
):
    res = _copy(results, tmp_path)
    _edit(res / file, _set(field, value))
    monkeypatch.setattr(checks, "CHECKS", [CLAIMS[_reader(file)]])
    assert main(["check", "--results", str(res)]) == 2
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bouncedisk: error: "), out.err
    assert file.split("/")[-1] in lines[0] and field in lines[0] and "Traceback" not in out.err
    assert "np." not in lines[0]  # the value as written, not numpy's repr


def test_check_results_with_a_file_missing_a_field_is_one_line_and_exit_2(
    results, tmp_path, monkeypatch, capsys
):
    res = _copy(results, tmp_path)
    _drop(res / "fit" / "prototype.nc", "chi2")
    monkeypatch.setattr(checks, "CHECKS", [checks._fit_checks])
    assert main(["check", "--results", str(res)]) == 2
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bouncedisk: error: ")
    assert "prototype.nc" in lines[0] and "chi2" in lines[0] and "Traceback" not in out.err


#: Everything only a joint fit writes (the small fit file's share of checks.JOINT_MARKERS).
JOINT_ONLY = (
    "load_speed_measured",
    "load_speed_band_low",
    "load_speed_band_high",
    "interval_low",
    "interval_high",
    "interval_identified",
    "generating_value",
    "data_set",
    "load_curve_synthetic",
)


def test_a_run_up_only_fit_fails_the_fit_claims_where_a_joint_fit_was_made(results, tmp_path):
    res = _copy(results, tmp_path)

    def run_up_only(ds):
        ds = ds.drop_vars([v for v in JOINT_ONLY if v in ds.variables])
        ds.attrs = {k: v for k, v in ds.attrs.items() if k not in JOINT_ONLY}
        return ds

    _edit(res / "fit" / "prototype.nc", run_up_only)
    # the pipeline made a joint fit: both claims fail, saying why
    got = checks._fit_checks(checks._Source(res, joint_fit=True))
    assert len(got) == 2 and not any(r.passed for r in got)
    assert all("run-up-only fit" in r.measured for r in got)
    # a run-up-only config (or unknown, and nothing of a joint fit in the file): nothing to check
    assert checks._fit_checks(checks._Source(res, joint_fit=False)) == []
    assert checks._fit_checks(checks._Source(res)) == []


def test_the_speed_may_not_rise_with_the_load_below_the_bound_only():
    c = {
        "loads": np.array([0.0, 0.5, 0.9, 1.01, 1.02]),
        "low": np.array([90.0, 80.0, 85.0, -400.0, -70.0]),
        "high": np.array([91.0, 81.0, 86.0, -390.0, -60.0]),
    }
    # 0.9 rises above 0.5's interval; 1.02 above 1.01's, but past the bound it may
    assert checks._rises(c) == [0.9]


def test_the_stored_summary_is_compared_with_the_members_it_summarises():
    same = inp.disagreements(
        {"a": 1.0, "b": [1.0, math.nan], "c": "x"},
        {"a": 1.0 + 1e-12, "b": [1.0, math.nan], "c": "x"},
    )
    assert same == []
    differ = inp.disagreements({"m": np.array([1.0, 2.0, 3.0])}, {"m": np.array([1.0, 2.5, 3.0])})
    assert differ == ["m[1] 2 vs 2.5 from the arrays"]
