"""The joint fit of run-ups and load curves: the load part of the likelihood, the
command's checks, the fit file and its figures, and recovery at three parameter sets."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from bouncedisk.analysis.ensembles import run_member
from bouncedisk.cli import main
from bouncedisk.engine import EngineConfig, InitialState
from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset, summary_text, synthesize_curve
from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting.members import BOUNDS, MODEL_E_SIGMA
from bouncedisk.fitting.synthetic import synthetic_load_curve
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import read_curve, write_curve

F_HZ, PHI0, SPAN, DT, SIGMA = 15000.0, 3.0e-4, 0.06, 2.5e-5, 0.05
ROTOR = {"m_r_kg": 0.01, "r_g_m": 0.004, "r_c_m": 0.002}
PRELOAD = 0.77
#: The recovery cases of tests/test_fitting.py, with the load range (fractions of the torque
#: scale mu m_r g_eff r_eff) from no load to past stall: measured with 2 members, window
#: [0.03, 0.06] s, the periodic and near-boundary rotors ride the stator up to ~0.95, the chaotic
#: one stalls near 0.45 (its curve runs on to 2.2 times that: past stall the curves of different
#: basins part, as for the shipped motor).
CASES = {
    "periodic": ({"e": 0.31, "r_phi": 0.0041, "psi": 0.25, "omega_s": 1.37}, 1.05),
    "chaotic_reinjection": ({"e": 0.62, "r_phi": 0.0027, "psi": -0.35, "omega_s": 1.48}, 1.0),
    "near_boundary": ({"e": 0.33, "r_phi": 0.0052, "psi": 0.7, "omega_s": 1.40}, 1.05),
}
NAMES = ("e", "r_phi", "psi", "omega_s")


def torque_scale(true: dict) -> float:
    """``μ m_r g_eff r_eff`` of the test motor at ``true`` (N·m)."""
    theta = {"e": true["e"], "log10_r_phi": math.log10(true["r_phi"]), "psi": true["psi"],
             "omega_s": true["omega_s"]}  # fmt: skip
    data = _fake_load_data()
    return lp.motor_scales(theta, data)[2]


def _fake_load_data(window=(0.03, 0.06), torques=(0.0, 1e-4, 2e-4)):
    from bouncedisk.io.load_curves import LoadCurveData

    n = len(torques)
    return LoadCurveData(torque=np.array(torques), speed=np.zeros(n), speed_sd=None,
                         drive_frequency_hz=F_HZ, phi0_rad=PHI0, rotor=ROTOR, preload_n=PRELOAD,
                         window_s=window, synthetic=True, path="<test>")  # fmt: skip


def make_data(
    folder: Path, true: dict, top: float, loads: int = 10, seed: int = 3, repeats: int = 5
):
    """A synthetic run-up (one member plus noise) and load curve of the test motor."""
    run = folder / "run.csv"
    df = synthesize_curve(true, F_HZ, PHI0, SPAN, DT, SIGMA, seed, member=0)
    write_curve(df, run, {"source": "test", "synthetic": True, "units": {"time": "s", "omega": "rad/s"},
                          "motor": {"drive_frequency_hz": F_HZ, "Phi0_rad": PHI0}})  # fmt: skip
    spec = {
        "parameters": dict(true), "e_sigma": 0.03, "drive_frequency_hz": F_HZ, "Phi0_rad": PHI0,
        "rotor": ROTOR, "preload_N": PRELOAD,
        "load_curve": {"loads_Nm": list(np.linspace(0.0, top, loads) * torque_scale(true)),
                       "repeats": repeats, "window_s": [0.03, 0.06], "seed": seed + 40},
    }  # fmt: skip
    ldf, side = synthetic_load_curve(spec)
    load = folder / "load.csv"
    write_curve(ldf, load, side)
    return run, load


# ------------------------------------------------------------------ the load part, exactly


def test_torque_scale_is_the_closed_form():
    """``μ m_r g_eff r_eff = R_φ m_r r_g² Φ0 / t_c²`` (docs/model.md eqs. 2, 15: g_eff cancels), the
    speed scale ``R_φ Φ0 / t_c``, ``t_c = ω_s / 2πf``."""
    theta = {"e": 0.4, "log10_r_phi": -2.3, "psi": 0.1, "omega_s": 1.9}
    t_c, speed, torque = lp.motor_scales(theta, _fake_load_data())
    r = 10**-2.3
    assert t_c == pytest.approx(1.9 / (2 * math.pi * F_HZ), rel=1e-14)
    assert speed == pytest.approx(r * PHI0 / t_c, rel=1e-14)
    assert torque == pytest.approx(
        r * ROTOR["m_r_kg"] * ROTOR["r_g_m"] ** 2 * PHI0 / t_c**2, rel=1e-12
    )


def test_a_curve_at_another_drive_frequency_is_read_at_its_condition():
    """A load curve at twice the run-ups' drive frequency is read at ``ω_s`` twice the point's
    (``ω_s = 2π f t_c`` with ``t_c`` held; the other parameters shared), and its stated
    generating ``ω_s`` is brought back to the run-ups' drive frequency."""
    import dataclasses

    from bouncedisk.fitting.joint import stated_truth
    from bouncedisk.fitting.loadpart import Setup

    theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}
    base = _fake_load_data((0.01, 0.02))
    fast = dataclasses.replace(base, drive_frequency_hz=2 * F_HZ, window_s=(0.005, 0.01))
    part = lp.LoadPart([base, fast], 0.03, 5, drive_hz=F_HZ)
    got = part.values(part.condition(theta, base), np.zeros(4), 2)  # members 0 and 1
    n = len(base.torque)
    at = part.condition(theta, fast)
    assert at["omega_s"] == pytest.approx(3.4, rel=1e-12)
    assert at["log10_r_phi"] == pytest.approx(theta["log10_r_phi"], abs=1e-12)
    for m in range(2):
        np.testing.assert_array_equal(got[m, :n], lp.curve_readings(theta, base, m, 0.03, 5))
        np.testing.assert_array_equal(got[m, n:], lp.curve_readings(at, fast, m, 0.03, 5))
    assert not np.array_equal(got[0, n:], lp.curve_readings(theta, fast, 0, 0.03, 5))
    side = {"generating_parameters": {**theta, "r_phi": 0.002, "omega_s": 3.4}}
    stated = dataclasses.replace(fast, sidecar=side)
    truth = stated_truth([stated], Setup(F_HZ, PHI0, ROTOR, PRELOAD))
    assert truth["omega_s"] == pytest.approx(1.7) and truth["r_phi"] == pytest.approx(0.002)
    assert stated_truth([stated])["omega_s"] == pytest.approx(3.4)


def test_a_curve_at_another_stated_amplitude_is_read_at_its_condition():
    """Where the curves state different axial amplitudes (``motor.U0_m``), a curve's ``U0`` is
    the reference's times the ratio (``ω_s ∝ √U0``, ``R_φ ∝ U0``: four times the amplitude is
    twice ``ω_s`` and four times ``R_φ``); where they state one amplitude or none, ``U0`` is
    held; where some state one and some do not, a curve that states none is one line naming it."""
    import dataclasses
    from types import SimpleNamespace

    from bouncedisk.fitting.joint import reference_u0
    from bouncedisk.model.errors import InputError

    theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}
    base = dataclasses.replace(_fake_load_data(), sidecar={"motor": {"U0_m": 1e-6}})
    big = dataclasses.replace(base, sidecar={"motor": {"U0_m": 4e-6}}, path="big.csv")
    part = lp.LoadPart([base, big], 0.03, 5, drive_hz=F_HZ, phi0_rad=PHI0, u0=1e-6)
    at = part.condition(theta, big)
    assert at["omega_s"] == pytest.approx(3.4, rel=1e-12)
    assert at["log10_r_phi"] == pytest.approx(math.log10(0.008), abs=1e-12)
    assert part.condition(theta, base) == pytest.approx(theta, rel=1e-12)
    held = lp.LoadPart([base, big], 0.03, 5, drive_hz=F_HZ, phi0_rad=PHI0)  # no u0: held
    assert held.condition(theta, big) == pytest.approx(theta, rel=1e-12)
    # which: amplitudes that differ are conditions; one for all, or none, is held; a gap is one
    # line, also where the one amplitude stated would be held (it is stated for one curve only)
    silent = dataclasses.replace(base, sidecar={})
    assert lp.amplitudes([base, big], 1e-6, "run.yaml") is True
    assert lp.amplitudes([base, base], 1e-6, "run.yaml") is False
    assert lp.amplitudes([silent, silent], None, "run.yaml") is False
    for curves in ([base, big], [base, base], [silent, base]):
        with pytest.raises(InputError, match=r"^run.yaml: motor.U0_m: is required") as ex:
            lp.amplitudes(curves, None, "run.yaml")
        assert "\n" not in ex.value.line()
    with pytest.raises(InputError, match=r"^gap.yaml: motor.U0_m: is required"):
        lp.amplitudes([big, dataclasses.replace(base, sidecar={}, path="gap.csv")], 1e-6, "r.yaml")
    # the run-ups' stated amplitude is the reference's only where the amplitudes are conditions
    runups = SimpleNamespace(sidecar={"motor": {"U0_m": 1e-6}}, sidecar_path="run.yaml", path="")
    assert reference_u0([base, big], runups) == 1e-6
    assert reference_u0([base, base], runups) is None


@pytest.mark.cost(8)
def test_the_generating_point_reproduces_a_curve_at_four_times_the_amplitude(tmp_path):
    """A load curve of the test motor run at four times the stator's amplitude (made at ``ω_s``
    doubled and ``R_φ`` four times), read by the load part at the run-ups' point: with the
    amplitudes stated its readings are within their spread (``χ²`` of 5 readings near 5); read
    as if the amplitude were held, they are not."""
    true, top = CASES["periodic"]
    spec = {
        "parameters": {**true, "omega_s": 2 * true["omega_s"], "r_phi": 4 * true["r_phi"]},
        "e_sigma": 0.03, "drive_frequency_hz": F_HZ, "Phi0_rad": PHI0, "rotor": ROTOR,
        "preload_N": PRELOAD,
        "load_curve": {"loads_Nm": list(np.linspace(0.0, 0.8, 5) * torque_scale(true)),
                       "repeats": 5, "window_s": [0.03, 0.06], "seed": 72},
    }  # fmt: skip
    ldf, side = synthetic_load_curve(spec)
    side["motor"]["U0_m"] = 4e-6
    write_curve(ldf, tmp_path / "big.csv", side)
    big = read_load_curve(tmp_path / "big.csv")
    x = {"e": true["e"], "log10_r_phi": math.log10(true["r_phi"]), "psi": true["psi"],
         "omega_s": true["omega_s"]}  # fmt: skip
    key = np.array([*x.values(), 0.03])

    def chi2(u0):
        part = lp.LoadPart([big], 0.03, 5, drive_hz=F_HZ, phi0_rad=PHI0, u0=u0)
        part.set_cov(part.values(x, key, lp.LOAD_PILOT))
        r = part.residuals(x, key, lp.LOAD_MEMBERS)
        return float(r @ r)

    stated, held = chi2(1e-6), chi2(None)
    assert stated < 20.0 and 10 * stated < held, (stated, held)


def test_a_reading_is_the_members_window_mean():
    """:func:`loadpart.curve_readings` is, at every load, the ensemble reducer's mean speed over
    the window of the same member run under that load alone, in rad/s (two routes through the
    engine: one axial trajectory for all loads, and one run per load)."""
    theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}
    t_c, speed, torque = lp.motor_scales(theta, _fake_load_data())
    data = _fake_load_data((0.01, 0.02), torques=(0.0, 1.2e-4, 3.0 * torque))
    got = lp.curve_readings(theta, data, 3, 0.03, 17)
    for load, reading in zip(data.torque, got, strict=True):
        cfg = EngineConfig(e=0.55, omega_s=1.7, r_phi=0.002, psi=0.4, contact=True, torsion=True,
                           t_end=0.02 / t_c, max_events=10**8, e_sigma=0.03, seed=17,
                           load_torque=load / torque)  # fmt: skip
        stats, _, _ = run_member(
            cfg, InitialState(t=0.0, omega=0.0), lp.LOAD_STREAM + 3, 0.01 / t_c
        )
        assert reading == pytest.approx(stats.mean_omega * speed, rel=1e-12)
    # under a load past stall the rotor is driven backwards
    assert got[0] > got[1] > 0 > got[2]


def test_load_residuals_are_the_whitened_difference(tmp_path):
    """``L⁻¹(μ − y)`` with ``L Lᵀ = D + C_L/K`` (module docstring), against numpy's Cholesky; ``D``
    uses the data's spread over sqrt(repeats), never below the members' spread."""
    true, top = CASES["chaotic_reinjection"]
    _, load = make_data(tmp_path, true, top, loads=4, repeats=5)
    data = read_load_curve(load)
    part = lp.LoadPart([data], 0.03, 5)
    theta = {"e": true["e"], "log10_r_phi": math.log10(true["r_phi"]), "psi": true["psi"],
             "omega_s": true["omega_s"]}  # fmt: skip
    x = np.array([theta["e"], theta["log10_r_phi"], theta["psi"], theta["omega_s"]])
    part.set_cov(part.values(theta, x, 8))
    c = part.cov_model
    d = np.maximum(np.maximum(data.speed_sd**2, np.diag(c)), part.floor**2) / 5
    np.testing.assert_allclose(part.data_var(), d, rtol=1e-14)
    sigma = np.diag(d) + c / 4
    want = np.linalg.solve(np.linalg.cholesky(sigma), part.mean(theta, x, 4) - data.speed)
    np.testing.assert_allclose(part.residuals(theta, x, 4), want, rtol=1e-10, atol=1e-12)
    # the first k members of a larger cached set are the same streams
    np.testing.assert_array_equal(part.values(theta, x, 3), part.values(theta, x, 8)[:3])


# ------------------------------------------------------------------ the command's checks


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("joint")
    true, top = CASES["chaotic_reinjection"]
    make_data(folder, true, top, loads=6)
    return folder


def _copy_load(src: Path, dst: Path, edit=None) -> Path:
    import yaml

    side = yaml.safe_load(src.with_suffix(".yaml").read_text())
    if edit:
        edit(side)
    dst.write_text(src.read_text())
    dst.with_suffix(".yaml").write_text(yaml.safe_dump(side))
    return dst


# another drive frequency or Phi0 is no disagreement: it is another condition of the motor
# (test_a_second_drive_frequency_is_a_condition_of_the_same_motor)
@pytest.mark.parametrize(
    "edit,field",
    [
        (lambda s: s.update(repeats=0), "repeats"),
        (lambda s: s.update(repeats="five"), "repeats"),
        (lambda s: s["rotor"].pop("r_g_m"), "rotor.r_g_m"),
    ],
)
def test_a_load_curve_that_disagrees_is_one_line_and_no_file(
    data_dir, tmp_path, capsys, edit, field
):
    bad = _copy_load(data_dir / "load.csv", tmp_path / "bad.csv", edit)
    out = tmp_path / "fit.nc"
    code = main(
        ["fit", str(data_dir / "run.csv"), "--load", str(bad), "-o", str(out), "--scan", "8"]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err[-1].startswith("bouncedisk: error: ") and field in err[-1], err
    assert not out.exists()


def test_load_curve_errors_before_work(data_dir, tmp_path, capsys):
    out = tmp_path / "fit.nc"
    cases = [
        (["--load", str(tmp_path / "none.csv")], "file not found"),
        (["--load", str(data_dir / "load.csv"), "--load", str(data_dir / "load.csv")], "same file"),
        (["--load", str(data_dir / "run.csv")], "same file"),
    ]
    for extra, text in cases:
        code = main(["fit", str(data_dir / "run.csv"), *extra, "-o", str(out)])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and text in err[-1], (extra, err)
        assert not out.exists()
    # the output may not overwrite a load curve (nor its sidecar)
    target = _copy_load(data_dir / "load.csv", tmp_path / "l.csv")
    for o in (target, target.with_suffix(".yaml")):
        code = main(["fit", str(data_dir / "run.csv"), "--load", str(target), "-o", str(o)])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and "input file" in err[-1], err


def test_run_ups_without_phi0_cannot_take_a_load_curve(data_dir, tmp_path, capsys):
    import yaml

    side = yaml.safe_load((data_dir / "run.yaml").read_text())
    side["motor"].pop("Phi0_rad")
    run = tmp_path / "run.csv"
    run.write_text((data_dir / "run.csv").read_text())
    run.with_suffix(".yaml").write_text(yaml.safe_dump(side))
    code = main(["fit", str(run), "--load", str(data_dir / "load.csv"), "-o", str(tmp_path / "f.nc"),
                 "--scan", "8", "--zoom", "0", "-q"])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and "Phi0_rad" in err[-1] and not (tmp_path / "f.nc").exists()


# ------------------------------------------------------------------ a small joint fit, whole

TINY = FitSettings(seed=5, scan=16, zoom=4, zoom_centres=2, members=4, pilot_members=8,
                   band_members=8, local_nfev=4, bootstrap=40, cores=2, joint_zoom=8,
                   e_sigma=MODEL_E_SIGMA)  # fmt: skip


@pytest.fixture(scope="module")
def tiny_fit(data_dir):
    curve = read_curve(data_dir / "run.csv")
    load = read_load_curve(data_dir / "load.csv")
    return fit_curve(curve, TINY, load=[load])


@pytest.mark.slow
@pytest.mark.cost(30)
def test_a_second_drive_frequency_is_a_condition_of_the_same_motor(data_dir, tmp_path):
    """The run-up and load curve of the test motor, and a load curve of the same motor at twice
    the drive frequency (its model made at ``ω_s`` doubled), fitted together: the file records
    each reading's drive frequency, the generating point is the run-ups' (``ω_s`` not doubled)
    and reads the second curve's readings as well as the first's, and the load figure draws one
    series per drive frequency."""
    from bouncedisk.figures.drawing import FIGURES

    true, top = CASES["chaotic_reinjection"]
    spec = {
        "parameters": {**true, "omega_s": 2 * true["omega_s"]}, "e_sigma": 0.03,
        "drive_frequency_hz": 2 * F_HZ, "Phi0_rad": PHI0, "rotor": ROTOR, "preload_N": PRELOAD,
        "load_curve": {"loads_Nm": list(np.linspace(0.0, 0.8, 5) * torque_scale(true)),
                       "repeats": 5, "window_s": [0.03, 0.06], "seed": 71},
    }  # fmt: skip
    ldf, side = synthetic_load_curve(spec)
    write_curve(ldf, tmp_path / "fast.csv", side)
    loads = [read_load_curve(data_dir / "load.csv"), read_load_curve(tmp_path / "fast.csv")]
    # what is tested is the file and the conditions, not the search: its smallest settings
    smallest = dataclasses.replace(TINY, scan=8, zoom=0, joint_zoom=4, local_nfev=2)
    ds = fit_dataset(fit_curve(read_curve(data_dir / "run.csv"), smallest, load=loads))
    drive = ds["load_drive_frequency_hz"].values
    assert sorted(set(drive)) == [F_HZ, 2 * F_HZ] and int((drive == 2 * F_HZ).sum()) == 5
    assert ds.attrs["generating_omega_s"] == pytest.approx(true["omega_s"])
    # at the generating point each curve's readings are within their own spread: chi2 of the
    # 11 readings near their count, far from what a wrong condition (omega_s not doubled) gives
    assert ds.attrs["chi2_generating_load"] < 40.0, ds.attrs["chi2_generating_load"]
    labels = FIGURES["fit_load"].draw(ds).axes[0].get_legend_handles_labels()[1]
    assert any("(curve 1, 15 kHz)" in lab for lab in labels)
    assert any("(curve 2, 30 kHz)" in lab for lab in labels)


@pytest.mark.xdist_group("tiny_joint_fit")  # one worker fits, not both
@pytest.mark.cost(10)  # the tiny joint fit
def test_the_fit_file_holds_the_load_curves_and_the_identifiability_table(tiny_fit, tmp_path):
    from bouncedisk.io.netcdf import write_dataset

    ds = fit_dataset(tiny_fit)
    path = tmp_path / "fit.nc"
    write_dataset(ds, path)
    back = xr.open_dataset(path)
    n = back.sizes["reading"]
    assert n == 6 and back.attrs["n_load_readings"] == 6
    assert back.attrs["n_statistics"] == 11 + 6  # the run-up's statistics and the readings
    assert back.attrs["joint_zoom_points"] == 8  # TINY's joint zoom, recorded
    assert list(back["data_set"].values) == ["run-ups", "load curve", "both"]
    assert back["interval_low"].shape == (3, 4)
    np.testing.assert_array_less(back["load_speed_fitted_low"].values,
                                 back["load_speed_fitted_high"].values)  # fmt: skip
    lo, hi = back["interval_low"].values, back["interval_high"].values
    assert np.all(lo <= hi)
    # the joint intervals are the parameters' own (ci_low/ci_high), in search coordinates
    for j, name in enumerate(back["parameter"].values):
        pub = "r_phi" if name == "log10_r_phi" else str(name)
        f = (lambda v: 10**v) if name == "log10_r_phi" else (lambda v: v)
        assert f(lo[2, j]) == pytest.approx(back[pub].attrs["ci_low"], rel=1e-12)
        assert f(hi[2, j]) == pytest.approx(back[pub].attrs["ci_high"], rel=1e-12)
        assert BOUNDS[str(name)][0] <= lo[2, j] and hi[2, j] <= BOUNDS[str(name)][1]
    # the generating parameters of the synthetic load curve are stated for the figure, in
    # search coordinates beside the search range
    true = CASES["chaotic_reinjection"][0]
    assert back.attrs["generating_e"] == true["e"]
    gen = dict(zip(back["parameter"].values, back["generating_value"].values, strict=True))
    assert gen["log10_r_phi"] == pytest.approx(math.log10(true["r_phi"]), rel=1e-15)
    assert gen["omega_s"] == true["omega_s"] and gen["psi"] == true["psi"]
    assert [back["search_low"].values[j] for j in range(4)] == [
        BOUNDS[str(n)][0] for n in back["parameter"].values
    ]
    text = summary_text(back)
    assert "load curve: chi2" in text and "95% intervals by data set" in text
    # a unit follows its value and its interval; a stated noise is shown as stated
    assert re.search(r"\n +psi = \S+ rad   95% \[\S+, \S+\] rad\n", text), text
    assert f"e_sigma = {MODEL_E_SIGMA:.5g}   stated, not fitted" in text
    # the chi2 at the generating point, under the fit's final metric: the parts add up; the
    # summary says whether the generating point is more likely, by each point's own likelihood
    at = {k: back.attrs[f"chi2_generating_{k}"] for k in ("runup", "load", "both")}
    assert at["both"] == pytest.approx(at["runup"] + at["load"], rel=1e-12) and at["load"] > 0
    assert f"at the generating point: chi2 {at['both']:.4g}" in text
    from bouncedisk.fitting.joint import generating_point_better

    own = {k: back.attrs[f"loglik_own_{k}"] for k in ("generating", "estimate")}
    verdict = (
        "not the likelihood's maximum"
        if generating_point_better(own)
        else "not more than 3.84 below"
    )
    assert f"-2 log L {own['generating']:.4g} at the generating point" in text
    assert verdict in text and f"{own['estimate']:.4g} at the estimate" in text


@pytest.mark.xdist_group("tiny_joint_fit")  # one worker fits, not both
def test_joint_chi2_is_the_sum_of_the_parts(tiny_fit):
    """Independent experiments: the joint ``χ²`` at the estimate is the run-ups' plus the load
    curve's, and the load part's ``χ²`` is reported."""
    lf = tiny_fit.load
    assert lf.chi2 > 0 and lf.n == 6
    assert tiny_fit.chi2 >= lf.chi2


@pytest.mark.xdist_group("tiny_joint_fit")  # one worker fits, not both
def test_joint_figures_draw(tiny_fit, tmp_path):
    from bouncedisk.figures.drawing import FIGURES

    ds = fit_dataset(tiny_fit)
    for name in ("fit_load", "fit_identifiability"):
        fig = FIGURES[name].draw(ds)
        assert len(fig.axes) >= 2
        fig.savefig(tmp_path / f"{name}.png", dpi=50)
        assert (tmp_path / f"{name}.png").stat().st_size > 5000


@pytest.mark.xdist_group("tiny_joint_fit")  # one worker fits, not both
def test_joint_figures_refuse_a_run_up_fit(tiny_fit):
    from bouncedisk.figures.drawing import FIGURES

    ds = fit_dataset(tiny_fit).drop_vars(["load_speed_measured"])
    with pytest.raises(ValueError, match="no load curve"):
        FIGURES["fit_load"].draw(ds)


def test_the_joint_zoom_samples_around_distinct_candidates(monkeypatch):
    """:func:`search.joint_zoom`: :data:`JOINT_ZOOM_POINTS` points around each of the best
    :data:`JOINT_ZOOM_CENTRES` candidates distinct in ``(e, omega_s)``, within
    ``± JOINT_ZOOM_HALF`` of the range there and inside the search box, keeping the centre's
    ``(ψ, R_φ)`` before the load match (replaced here by the identity)."""
    from types import SimpleNamespace

    from bouncedisk.fitting import search as se
    from bouncedisk.fitting.search import SearchSettings

    names = ["e", "log10_r_phi", "psi", "omega_s"]
    lo = np.array([BOUNDS[n][0] for n in names])
    hi = np.array([BOUNDS[n][1] for n in names])
    obj = SimpleNamespace(names=names, lo=lo, hi=hi, span=hi - lo,
                          map=lambda f, xs: [f(x) for x in xs])  # fmt: skip
    monkeypatch.setattr(se, "load_matched", lambda obj, x: x)
    # six candidates, best first; the second is a near-copy of the first (not distinct), the
    # last sits on the box's corner
    ranked = [np.array(v) for v in ([0.5, -2.5, 0.3, 2.0], [0.501, -2.4, 0.1, 2.001],
              [0.3, -2.2, -1.0, 1.5], [0.8, -3.0, 2.0, 3.0], [0.2, -2.0, 0.0, 3.5],
              [hi[0], -2.6, 0.5, lo[3]])]  # fmt: skip
    pts = se.joint_zoom(obj, ranked, SearchSettings())
    assert len(pts) == se.JOINT_ZOOM_CENTRES * se.JOINT_ZOOM_POINTS
    centres = [ranked[i] for i in (0, 2, 3, 4)]  # the near-copy is skipped
    ax = [0, 3]
    for k, c in enumerate(centres):
        block = np.array(pts[k * se.JOINT_ZOOM_POINTS : (k + 1) * se.JOINT_ZOOM_POINTS])
        off = np.abs(block[:, ax] - c[ax]) / obj.span[ax]
        assert np.all(off <= se.JOINT_ZOOM_HALF + 1e-8)
        assert np.all(block[:, [1, 2]] == c[[1, 2]])
        assert len({tuple(p) for p in block}) == se.JOINT_ZOOM_POINTS
        assert np.all((block >= lo - 1e-12) & (block <= hi + 1e-12))


# ------------------------------------------------------------------ the joint valley near a bifurcation

#: The ``near_boundary`` case's scan points (``benchmarks/joint_recovery.py``, scan 256, seed 1):
#: the best of the run-ups (next to the joint valley, with ``ψ`` 0.19 off it) and one from the
#: valley of the run-ups elsewhere, whose joint ``χ²`` on the scan's members is lower, so the
#: joint zoom centres there.
NEAR_SCAN = (
    [0.37879925, -2.28179542, 0.89033742, 1.36337288],
    [0.0882715, -2.17422374, -0.06388694, 1.61867096],
)


@pytest.mark.slow
@pytest.mark.cost(45)
def test_the_joint_stage_finds_the_valley_near_the_period_doubling(tmp_path):
    """Near the period doubling the joint valley is a thin tube in ``(e, ψ, omega_s)`` between
    the scan's points: from these scan points the joint candidates
    (:func:`search.joint_candidates`) must reach it — the best of them, on the fit's 12 members,
    reproduces both data sets (``χ²`` adequate) near the generating point. Without the joint
    refinement the best candidate's ``χ²`` was in the hundreds."""
    from bouncedisk.fitting import core
    from bouncedisk.fitting import search as se
    from bouncedisk.fitting.joint import load_part
    from bouncedisk.fitting.members import EnsembleSpec, param_names
    from bouncedisk.fitting.objective import Objective
    from bouncedisk.fitting.uncertainty import adequate

    true, top = CASES["near_boundary"]
    run, load = make_data(tmp_path, true, top, loads=10, seed=3)
    s = FitSettings(seed=1, scan=256, zoom=8, zoom_centres=4, cores=1, e_sigma=MODEL_E_SIGMA)
    s = s.for_runs(1)
    runs, fitted, _ = core.prepare_runs(read_curve(run))
    layout, records, target = core.data_layout(runs)
    boot = core.bootstrap_stats(layout, records, s.bootstrap, s.seed)
    spec = EnsembleSpec(e_sigma=s.e_sigma, seed=s.seed, cores=1)
    part = load_part([read_load_curve(load)], fitted, spec)
    obj = Objective(fitted, param_names(fitted), layout, target, spec, s.members,
                    initial_cov=core.provisional_cov(target, boot), load=part,
                    parts="both")  # fmt: skip
    # the scan, as the search leaves it: the run-ups' chi2 of its points, on one member
    scan = [np.array(x) for x in NEAR_SCAN]
    for x in scan:
        obj.seeing("runup").chi2(x, 1)
    ranked = sorted((ev for ev in obj.log), key=lambda ev: ev.chi2)
    obj.set_cov(se.measure_cov(obj, ranked[0].x, s.pilot_members))
    cands = se.joint_candidates(obj, ranked, s.search_settings())
    chis = se.rerank(obj, cands, s.search_settings())  # as the search does next
    best = cands[int(np.argmin(chis))]
    assert adequate(min(chis), obj.n_stats), min(chis)
    gen = np.array([true["e"], math.log10(true["r_phi"]), true["psi"], true["omega_s"]])
    # within a few hundredths of the ranges of the generating point (the valley runs on in e)
    assert np.all(np.abs(best - gen) / obj.span <= [0.05, 0.02, 0.03, 0.01]), best


@pytest.mark.xdist_group("tiny_joint_fit")  # one worker fits, not both
def test_an_inadequate_fit_reports_no_interval(tiny_fit, tmp_path):
    """The same fit with a ``χ²`` the data reject (p < 0.001): every interval of the file is NaN,
    ``identified = "no"`` with the reason, and the summary and figures say so; the fit as it
    came (its own ``χ²``) keeps its intervals under ``identified = "yes"`` exactly when adequate."""
    import dataclasses

    from scipy.stats import chi2 as chi2_dist

    from bouncedisk.figures.drawing import FIGURES

    n = 11 + tiny_fit.load.n
    ok = chi2_dist.sf(tiny_fit.chi2, n) > 1e-3
    as_is = fit_dataset(tiny_fit)
    assert as_is.attrs["identified"] == ("yes" if ok else "no")
    bad = dataclasses.replace(tiny_fit, chi2=float(chi2_dist.isf(1e-4, n)))
    ds = fit_dataset(bad)
    assert ds.attrs["identified"] == "no" and "p = 0.0001 < 0.001" in ds.attrs["identified_reason"]
    for name in NAMES:
        assert math.isnan(ds[name].attrs["ci_low"]) and math.isnan(ds[name].attrs["ci_high"])
        assert ds[name].attrs["identified"] == 0 and np.isfinite(float(ds[name]))
    assert np.isnan(ds["interval_low"].values).all() and np.isnan(ds["interval_high"].values).all()
    assert not ds["interval_identified"].values.any()
    assert ds.attrs["not_identified"] == ",".join(NAMES)
    text = summary_text(ds)
    assert "NOT IDENTIFIED: inadequate fit" in text and "95% [" not in text
    assert "95% intervals by data set: none (inadequate fit)" in text
    for name in ("fit_profiles", "fit_identifiability", "fit_load"):
        fig = FIGURES[name].draw(ds)
        fig.savefig(tmp_path / f"{name}.png", dpi=40)
    *profiles, falls = FIGURES["fit_profiles"].draw(ds).axes
    titles = [ax.get_title() for ax in profiles]
    assert all("no interval: inadequate fit" in t for t in titles), titles
    assert falls.get_title().startswith("waterfall: ")
    assert "NO INTERVALS" in FIGURES["fit_identifiability"].draw(ds).axes[0].get_title()
    assert "FIT INADEQUATE" in FIGURES["fit_load"].draw(ds).axes[0].get_title()


@pytest.mark.xdist_group("tiny_joint_fit")  # one worker fits, not both
def test_the_figures_say_synthetic_and_zoom_on_the_intervals(tiny_fit):
    """Synthetic data are labelled "synthetic", never "measured"; each profile panel spans its
    interval plus half its width on either side (within the search range); the
    identifiability legend names the three data sets, the estimate and the generating value."""
    from bouncedisk.figures.drawing import FIGURES

    ds = fit_dataset(tiny_fit)
    assert ds.attrs["load_curve_synthetic"] == 1
    ax = FIGURES["fit_load"].draw(ds).axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert any(lab.startswith("synthetic") for lab in labels)
    assert not any("measured" in lab for lab in labels), labels
    import pandas as pd

    from bouncedisk.figures.motor import fig5_motor

    curve = pd.DataFrame({"time_s": ds["time"].values, "omega_rad_s": ds["omega_measured"].values})
    labels = fig5_motor(curve, fitted=ds).axes[0].get_legend_handles_labels()[1]
    assert ds.attrs["curve_synthetic"] == 1 and "synthetic (prototype curve)" in labels
    assert not any("measured" in lab for lab in labels), labels
    fig = FIGURES["fit_identifiability"].draw(ds)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    for want in ("95% interval: run-ups", "95% interval: load curve", "95% interval: both",
                 "estimate", "generating value"):  # fmt: skip
        assert want in legend, legend
    if ds.attrs["identified"] == "yes":
        from bouncedisk.figures.motor import PARAM_LABELS

        names = {label: name for name, label in PARAM_LABELS.items()}
        for ax in FIGURES["fit_profiles"].draw(ds).axes[:-1]:  # the last: the waterfall
            label = ax.get_xlabel().rsplit(" [", 1)[0]
            name = names.get(label, label)
            a = ds[name].attrs
            lo, hi = ax.get_xlim()
            if name in ("r_phi", "speed_scale"):
                lo, hi, c0, c1 = (math.log10(v) for v in (lo, hi, a["ci_low"], a["ci_high"]))
                s0, s1 = math.log10(a["search_low"]), math.log10(a["search_high"])
            else:
                c0, c1, s0, s1 = a["ci_low"], a["ci_high"], a["search_low"], a["search_high"]
            pad = 0.5 * (c1 - c0)
            assert lo == pytest.approx(max(s0, c0 - pad)) and hi == pytest.approx(min(s1, c1 + pad))
            # the dashed line is where the file's interval accepts a point, not a fixed 3.84:
            # delta_chi2 above the reference (the level on fresh members when higher)
            (line,) = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
            offset = ds.attrs["chi2_reference"] - ds.attrs["chi2"]
            assert line.get_ydata()[0] == pytest.approx(offset + a["delta_chi2"])
            assert ("widened: several basins" in ax.get_title()) == bool(a["multimodal"])


@pytest.mark.parametrize("threshold, multimodal", [(3.841, 0), (5.06, 1)])
def test_the_profile_figure_draws_the_threshold_its_interval_used(threshold, multimodal):
    """The dashed line of a profile panel is the parameter's ``delta_chi2`` (Birge-scaled when
    the fit is poor), and an interval widened to other basins says so in the panel's title."""
    from bouncedisk.figures.motor import fig_fit_profiles

    values = np.linspace(0.4, 0.6, 9)
    attrs = {"ci_low": 0.45, "ci_high": 0.55, "search_low": 0.0, "search_high": 0.9, "units": "1",
             "identified": 1, "multimodal": multimodal, "delta_chi2": threshold}  # fmt: skip
    ds = xr.Dataset(
        {"e": ((), 0.5, attrs), "profile_chi2_e": ("profile_e", 400.0 * (values - 0.5) ** 2)},
        coords={"profile_e": values},
    )
    (ax,) = fig_fit_profiles(ds).axes
    (line,) = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert line.get_ydata()[0] == pytest.approx(threshold)
    assert f"Δχ² = {threshold:.3g}" in line.get_label()
    assert ("widened: several basins" in ax.get_title()) == bool(multimodal)


def test_the_waterfall_panel_draws_each_start_above_the_best_and_counts_those_that_reach_it():
    """The last panel of the profile figure: each start's end chi2 above the best, best first;
    the dashed line, in it and in the profile panels, where the intervals accept a point
    (delta_chi2 above the reference, here the level 3 above the best); the title counting the
    starts under it."""
    from bouncedisk.figures.motor import fig_fit_profiles

    values = np.linspace(0.4, 0.6, 9)
    attrs = {"ci_low": 0.45, "ci_high": 0.55, "search_low": 0.0, "search_high": 0.9, "units": "1",
             "identified": 1, "multimodal": 0, "delta_chi2": 5.0}  # fmt: skip
    ds = xr.Dataset(
        {
            "e": ((), 0.5, attrs),
            "profile_chi2_e": ("profile_e", 400.0 * (values - 0.5) ** 2),
            "start_chi2": ("start", [12.0, 14.0, 30.0, 112.0]),
        },
        coords={"profile_e": values},
        attrs={
            "chi2": 10.0,
            "chi2_reference": 13.0,
            "delta_chi2": 5.0,
            "starts": 4,
            "starts_accepted": 3,
        },  # fmt: skip
    )
    profile, falls = fig_fit_profiles(ds).axes
    (line,) = [ln for ln in profile.get_lines() if ln.get_linestyle() == "--"]
    assert line.get_ydata()[0] == 8.0 and "level on fresh members (+3)" in line.get_label()
    (points,) = [ln for ln in falls.get_lines() if ln.get_marker() == "s"]
    assert list(points.get_xdata()) == [1, 2, 3, 4]
    assert list(points.get_ydata()) == [2.0, 4.0, 20.0, 102.0]
    (line,) = [ln for ln in falls.get_lines() if ln.get_linestyle() == "--"]
    assert line.get_ydata()[0] == 8.0
    assert falls.get_title() == "waterfall: 3 of 4 starts end\nwhere the intervals accept"
    assert falls.get_ylim()[1] >= 102.0


def test_a_window_the_run_did_not_reach_is_an_error_never_a_number(tmp_path, capsys, monkeypatch):
    """A member stopped by the event budget before the window's end reads NaN (not the part it
    reached divided by the whole window: 0.445 rad/s instead of about 20.5 for the shipped
    curve over [0.06, 1e5] s), and a window beyond the budget is refused before any work."""
    theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}
    data = _fake_load_data((0.01, 0.02))
    assert np.isfinite(lp.curve_readings(theta, data, 0, 0.03, 17)).all()
    monkeypatch.setattr(lp, "MAX_EVENTS", 50)  # the run stops at 50 impacts, before t0
    assert np.isnan(lp.curve_readings(theta, data, 0, 0.03, 17)).all()
    monkeypatch.undo()
    import yaml

    shipped = Path(__file__).parents[1] / "data" / "prototype"
    load = _copy_load(shipped / "synthetic_motor_load.csv", tmp_path / "load.csv",
                      lambda s: s.update(window_s=[0.06, 1e5]))  # fmt: skip
    assert yaml.safe_load(load.with_suffix(".yaml").read_text())["window_s"] == [0.06, 1e5]
    out = tmp_path / "fit.nc"
    code = main(["fit", str(shipped / "synthetic_motor.csv"), "--load", str(load), "-o", str(out),
                 "--scan", "8", "--zoom", "0", "-q"])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    # the load-curve file's own bound (20,000 drive periods) refuses it before the fit's budget
    assert err[0].startswith(f"bouncedisk: error: {load.with_suffix('.yaml')}: window_s")
    assert not out.exists()


# ------------------------------------------------------------------ the restitution noise, fitted


def test_a_fitted_restitution_noise_is_the_points_own_and_zero_is_deterministic():
    """With ``e_sigma`` a search coordinate the members use the point's own value, not the stated
    one; at 0 (the deterministic limit) every member runs the same orbit, so the members differ
    only by their measurement noise and the load readings of all members coincide."""
    from bouncedisk.fitting.members import (
        EnsembleSpec,
        member_records,
        param_names,
        restitution_noise,
    )

    curve = read_curve_like()
    assert param_names(curve) == ["e", "log10_r_phi", "psi", "omega_s"]
    assert param_names(curve, fit_e_sigma=True)[-1] == "e_sigma"
    assert BOUNDS["e_sigma"] == (0.0, 0.1)
    theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}
    assert restitution_noise(theta, 0.03) == 0.03
    assert restitution_noise({**theta, "e_sigma": 0.0}, 0.03) == 0.0
    spec = EnsembleSpec(e_sigma=0.03, seed=4)
    quiet = dataclass_replace(curve, sigma=0.0)
    det = member_records({**theta, "e_sigma": 0.0}, quiet, range(2), spec)
    np.testing.assert_array_equal(det[0], det[1])
    noisy = member_records(theta, quiet, range(2), spec)
    assert np.max(np.abs(noisy[0] - noisy[1])) > 0.1  # the stated 3 % parts the members
    np.testing.assert_array_equal(member_records({**theta, "e_sigma": 0.03}, quiet, range(2), spec)[1],
                                  noisy[1])  # fmt: skip
    data = _fake_load_data((0.01, 0.02))
    r0, r1 = (lp.curve_readings({**theta, "e_sigma": 0.0}, data, m, 0.03, 17) for m in (0, 1))
    np.testing.assert_array_equal(r0, r1)
    assert not np.array_equal(*(lp.curve_readings(theta, data, m, 0.03, 17) for m in (0, 1)))


def test_a_fitted_noise_reads_each_candidate_at_every_level_and_a_stated_one_at_none():
    """:func:`search.at_noise_levels`: with ``e_sigma`` fitted, each run-up candidate again at
    every level of :data:`search.CANDIDATE_NOISE`, the other coordinates as they were (a basin
    whose own noise is far from the scan's is otherwise never a joint candidate); with the noise
    stated, no copy."""
    from types import SimpleNamespace

    from bouncedisk.fitting import search as se

    assert se.CANDIDATE_NOISE == (0.01, 0.06, 0.09)
    names = ["e", "log10_r_phi", "psi", "omega_s", "e_sigma"]
    xs = [np.array([0.5, -2.0, 0.3, 1.7, 0.03]), np.array([0.2, -2.5, -1.0, 2.4, 0.03])]
    out = se.at_noise_levels(SimpleNamespace(names=names), xs)
    assert len(out) == len(xs) * len(se.CANDIDATE_NOISE)
    for k, y in enumerate(out):
        x = xs[k // len(se.CANDIDATE_NOISE)]
        np.testing.assert_array_equal(y[:4], x[:4])
        assert y[4] == se.CANDIDATE_NOISE[k % len(se.CANDIDATE_NOISE)]
    assert xs[0][4] == 0.03  # the candidates themselves unchanged
    assert se.at_noise_levels(SimpleNamespace(names=names[:4]), [x[:4] for x in xs]) == []


def test_the_metric_is_measured_where_a_chaotic_motors_members_part():
    """:func:`search.metric_point`: a fitted ``e_sigma`` of 0 is raised to
    :data:`search.METRIC_E_SIGMA`, which the objective's lattice keeps (8 decimals), any other
    point is left as it is; there the members of a chaotic point part (at 0 they coincide, so
    a covariance measured there would hold the reading noise only)."""
    from types import SimpleNamespace

    from bouncedisk.fitting import search as se
    from bouncedisk.fitting.members import EnsembleSpec, member_records
    from bouncedisk.fitting.objective import snap

    names = ["e", "log10_r_phi", "psi", "omega_s", "e_sigma"]
    obj = SimpleNamespace(names=names)
    x = np.array([0.55, math.log10(0.002), 0.4, 1.7, 0.0])
    y = se.metric_point(obj, x)
    np.testing.assert_array_equal(y[:4], x[:4])
    assert y[4] == se.METRIC_E_SIGMA == snap(y)[4] > 0.0 and x[4] == 0.0
    noisy = np.array([0.55, -2.7, 0.4, 1.7, 0.05])
    np.testing.assert_array_equal(se.metric_point(obj, noisy), noisy)
    np.testing.assert_array_equal(se.metric_point(SimpleNamespace(names=names[:4]), x[:4]), x[:4])
    theta = dict(zip(names[:4], x[:4], strict=True))
    quiet = dataclass_replace(read_curve_like(), sigma=0.0)
    spec = EnsembleSpec(e_sigma=0.03, seed=4)
    at = {s: member_records({**theta, "e_sigma": s}, quiet, range(2), spec) for s in (0.0, y[4])}
    np.testing.assert_array_equal(*at[0.0])
    assert np.max(np.abs(at[y[4]][0] - at[y[4]][1])) > 1e-3


def read_curve_like():
    """A 0.02 s curve of the test motor (for the grid and scales only)."""
    from bouncedisk.io.runup_curves import MotorCurve

    t = DT * np.arange(int(0.02 / DT) + 1)
    return MotorCurve(time=t, omega=np.zeros(len(t)), sigma=SIGMA, drive_frequency_hz=F_HZ,
                      phi0_rad=PHI0, source="", synthetic=True, path="")  # fmt: skip


def dataclass_replace(obj, **kw):
    import dataclasses

    return dataclasses.replace(obj, **kw)


@pytest.mark.slow  # a tiny joint fit with five coordinates
def test_a_fitted_restitution_noise_is_a_variable_with_its_interval_and_table_row(data_dir):
    """``FitSettings(e_sigma=None)`` (``--e-sigma fit``): ``e_sigma`` is a fifth search coordinate
    over [0, 0.1]; the file carries it as a variable with ``ci_low``/``ci_high`` like ``e``, a
    fifth row of the identifiability table, and the generating value the sidecar states."""
    import dataclasses

    fit = fit_curve(read_curve(data_dir / "run.csv"), dataclasses.replace(TINY, e_sigma=None),
                    load=[read_load_curve(data_dir / "load.csv")])  # fmt: skip
    ds = fit_dataset(fit)
    assert list(ds["parameter"].values)[-1] == "e_sigma" and ds["interval_low"].shape == (3, 5)
    a = ds["e_sigma"].attrs
    assert {"ci_low", "ci_high", "identified", "search_low", "search_high"} <= set(a)
    assert (a["search_low"], a["search_high"]) == (0.0, 0.1)
    assert 0.0 <= float(ds["e_sigma"]) <= 0.1 and ds.attrs["e_sigma_fitted"] == 1
    assert ds.attrs["e_sigma"] == float(ds["e_sigma"])
    assert float(ds["generating_value"].values[-1]) == 0.03
    if ds.attrs["identified"] == "yes":
        assert a["ci_low"] <= float(ds["e_sigma"]) <= a["ci_high"]
        assert ds["interval_low"].values[2, -1] == a["ci_low"]
    assert "e_sigma" in summary_text(ds)


@pytest.mark.slow  # two tiny fits
def test_an_uninformative_load_curve_does_not_narrow_the_intervals(data_dir, tmp_path):
    """Data without information must not change an interval: the load curve of ``data_dir`` with
    ``speed_sd_rad_s`` 1000 (its readings say nothing at this spread) leaves every joint interval
    at least as wide as the run-up alone's fit, and its own row of the table is the search range.
    Before: the joint intervals were the joint candidates' only, and e.g. ``e`` shrank from
    [0.058, 0.863] to [0.058, 0.406] and ``R_phi`` from [0.00215, 0.0131] to [0.00495, 0.0101]."""
    import pandas as pd

    flat = _copy_load(data_dir / "load.csv", tmp_path / "flat.csv")
    df = pd.read_csv(flat)
    df["speed_sd_rad_s"] = 1000.0
    df.to_csv(flat, index=False)
    curve = read_curve(data_dir / "run.csv")
    alone = fit_dataset(fit_curve(curve, TINY))
    joint = fit_dataset(fit_curve(curve, TINY, load=[read_load_curve(flat)]))
    assert joint.attrs["chi2_load"] < 0.01  # the readings carry no weight
    for j, name in enumerate(joint["parameter"].values):
        pub = "r_phi" if name == "log10_r_phi" else str(name)
        f = math.log10 if name == "log10_r_phi" else (lambda v: v)
        lo, hi = joint["interval_low"].values[:, j], joint["interval_high"].values[:, j]
        assert lo[2] <= f(alone[pub].attrs["ci_low"]) + 1e-12, name
        assert hi[2] >= f(alone[pub].attrs["ci_high"]) - 1e-12, name
        assert (lo[1], hi[1]) == BOUNDS[str(name)], name  # the load curve alone: nothing


def test_a_view_of_one_part_shares_the_evaluations(tmp_path):
    """:meth:`Objective.seeing`: the view's ``parts`` is its own (the objective's is unchanged),
    its evaluations land in the shared log and cache, a covariance set on either is the other's
    too, and an unknown part is refused."""
    from bouncedisk.fitting.objective import Objective

    curve = read_curve_like()
    obj = Objective(curve, ["e", "log10_r_phi", "psi", "omega_s"], None, np.zeros(3),
                    None, 4, initial_cov=np.eye(3), parts="both")  # fmt: skip
    view = obj.seeing("runup")
    assert view.parts == "runup" and obj.parts == "both"
    assert view.log is obj.log and view.cache is obj.cache and view.load is obj.load
    view.log.append("x")
    assert obj.log == ["x"]
    obj.set_cov(np.diag([4.0, 1.0, 1.0]))  # a view made before sees the new metric
    assert view.covariance[0, 0] == 4.0 and view._metric.white[0, 0] == pytest.approx(0.5)
    view.set_cov(np.diag([9.0, 1.0, 1.0]))  # and the objective sees the view's
    assert obj.covariance[0, 0] == 9.0 and obj._metric.white[0, 0] == pytest.approx(1 / 3)
    with pytest.raises(ValueError, match="parts must be one of"):
        obj.seeing("all")


def _small_objective(data_dir, joint: bool = True):
    """The joint objective of ``data_dir``'s data as :func:`~bouncedisk.fitting.fit_curve` poses
    it (:func:`~bouncedisk.fitting.pose_fit`: the provisional metric, nothing evaluated), 4
    members, one thread; ``joint=False``: the run-up's alone."""
    from bouncedisk.fitting import pose_fit

    load = [read_load_curve(data_dir / "load.csv")] if joint else None
    settings = dataclass_replace(TINY, e_sigma=0.03, cores=1)
    obj = pose_fit(read_curve(data_dir / "run.csv"), settings, load=load).obj
    assert not obj.cache and not obj.log and obj.members == 4  # posed, not searched
    return obj


def test_fresh_members_are_other_members_and_the_level_is_their_mean(data_dir):
    """:meth:`Objective.fresh_chi2`: block 0 is the very ``χ²`` the search reads (the same
    members of the run-ups and of the load part, each data set alone too), a later block is
    other members (another value); :func:`chi2_level` is the mean of blocks 1-3, never below
    the point's own ``χ²``."""
    from bouncedisk.fitting.uncertainty import LEVEL_BLOCKS, chi2_level

    obj = _small_objective(data_dir)
    x = np.array([0.6, math.log10(0.0027), -0.3, 1.5])
    own = obj.chi2(x, 4)
    assert obj.fresh_chi2(x, 4, 0) == pytest.approx(own, rel=1e-12)
    for part in ("runup", "load"):
        view = obj.seeing(part)
        assert view.fresh_chi2(x, 4, 0) == pytest.approx(view.chi2_now(x, 4), rel=1e-12), part
    blocks = [obj.fresh_chi2(x, 4, b) for b in range(1, LEVEL_BLOCKS + 1)]
    assert len(set(blocks + [own])) == LEVEL_BLOCKS + 1  # four different member sets
    assert chi2_level(obj, x, 4) == pytest.approx(max(float(np.mean(blocks)), own), rel=1e-12)
    # the load part's first members are unchanged by reading later ones (one growing cache)
    theta = obj.theta(x)
    first = obj.load.values(theta, x, 8).copy()
    obj.load.residuals(theta, x, 8, first=16)
    np.testing.assert_array_equal(obj.load.values(theta, x, 8), first)


def test_candidates_are_re_read_on_the_fit_members_with_their_nuisance_refined(data_dir):
    """:func:`.search.confirm_points`: every candidate (at most the cap, the best read so far) is
    logged on the fit's members, then its ``(ψ, R_φ)`` refined at the same ``(e, omega_s)`` to a
    ``χ²`` no worse; a second objective re-reads the same ones."""
    from bouncedisk.fitting import search as se
    from bouncedisk.fitting.objective import snap

    pts = snap(np.array([[0.3 + 0.01 * k, -2.5, 0.1 * k, 1.2 + 0.02 * k] for k in range(6)]))
    obj = _small_objective(data_dir, joint=False)  # the run-up's members: the cheap part
    monkey = pytest.MonkeyPatch()
    monkey.setattr(se, "CONFIRM_CAP", 4)
    try:
        # once each (duplicates too), each with its polish on the held metric (none on its own)
        assert len(se.confirm_points(obj, np.vstack([pts, pts]), 4, near_own=-1.0)) == 2 * 4
        again = _small_objective(data_dir, joint=False)
        se.confirm_points(again, pts, 4, near_own=-1.0)
    finally:
        monkey.undo()
    read = {tuple(ev.x[[0, 3]]) for ev in obj.log if ev.members == 4}
    assert len(read) == 4 and read <= {tuple(p[[0, 3]]) for p in pts}
    assert read == {tuple(ev.x[[0, 3]]) for ev in again.log if ev.members == 4}
    for ex in read:  # logged: the candidate, then its polish (a trust region never ends worse)
        start, end = [ev.chi2 for ev in obj.log if tuple(ev.x[[0, 3]]) == ex]
        assert end <= start * (1 + 1e-12), (ex, start, end)


def test_own_covariance_chi2_is_the_held_one_where_the_covariance_was_measured(data_dir):
    """:meth:`Objective.own_chi2` measures the run-ups' covariance at the point itself: where the
    held covariance was measured (:func:`.search.measure_cov`, same members) it is the held
    ``χ²``; elsewhere it differs, and :func:`consistent_points` keeps exactly the points whose
    own ``χ²`` is below the 95 % point of ``χ²(n)``."""
    from scipy.stats import chi2 as chi2_dist

    from bouncedisk.fitting.search import measure_cov
    from bouncedisk.fitting.uncertainty import consistent_points

    obj = _small_objective(data_dir, joint=False)
    x = np.array([0.6, math.log10(0.0027), -0.3, 1.5])
    y = np.array([0.3, math.log10(0.004), 0.5, 2.5])  # another regime
    obj.set_cov(measure_cov(obj, x, 4))
    assert obj.own_chi2(x, 4) == pytest.approx(obj.chi2_now(x, 4), rel=1e-9)
    assert obj.own_chi2(y, 4) != pytest.approx(obj.chi2_now(y, 4), rel=1e-3)
    limit = float(chi2_dist.ppf(0.95, obj.n_stats))
    kept = consistent_points(obj, np.array([x, y]), 4, 0.0)  # a best chi2 below n: no scaling
    want = [p for p in (x, y) if obj.own_chi2(p, 4) <= limit]
    np.testing.assert_array_equal(kept, np.array(want).reshape(-1, 4))


def test_points_evaluated_together_are_the_points_evaluated_alone(data_dir):
    """:meth:`Objective.prefetch`: points sharing ``(e, omega_s)`` from one axial run per member
    (other ψ and R_φ; a point at another ``(e, omega_s)`` on its own) have, bit for bit, the
    statistics :meth:`Objective.ensemble` gives each on a fresh objective, are not run again, and
    count as evaluations only once read."""
    base = np.array([0.6, math.log10(0.0027), -0.3, 1.5])
    pts = [base + [0.0, dl, dp, 0.0] for dl, dp in ((0, 0), (0.2, 0), (0, 1.1), (-0.4, -2.0))]
    pts.append(base + [0.1, 0.0, 0.0, 0.2])
    together = _small_objective(data_dir, joint=False)
    together.prefetch(pts, 4)
    assert len(together.cache) == len(pts) and not together.read  # run ahead, not yet read
    counted = []
    together.on_eval = counted.append
    for x in pts:
        alone = _small_objective(data_dir, joint=False).ensemble(x, 4)
        got = together.ensemble(x, 4)
        np.testing.assert_array_equal(got.mean, alone.mean)
        np.testing.assert_array_equal(got.cov, alone.cov)
    # read from the cache, each counted as an evaluation once it is read (the fit's count)
    assert counted == list(range(1, len(pts) + 1)) and len(together.read) == len(pts)
    # they differ from each other: the rows are other rotations, not one point repeated
    assert len({together.ensemble(x, 4).mean[0] for x in pts}) == len(pts)


def test_the_jacobians_points_are_predicted_and_read_together():
    """:func:`search.difference_points` names the points where scipy's forward-difference
    Jacobian reads (inside the box, at its faces, at zero), so that :func:`search.polish`
    evaluates them with the step's point: every point the Jacobian asks for was predicted."""
    from scipy.optimize import least_squares

    from bouncedisk.fitting.search import DIFF_STEP, difference_points

    rng = np.random.default_rng(1)
    asked, predicted = [], set()

    def step(u):
        predicted.update(tuple(v) for v in difference_points(u, DIFF_STEP))
        return a @ (u * u) - b

    def differences(f, us):
        us = list(us)
        asked.extend(tuple(u) for u in us)
        return [a @ (u * u) - b for u in us]

    for start in ([0.0, 0.3], [1.0, 0.7], [0.9995, 0.2], [0.5, 1e-12]):
        a, b = rng.normal(size=(5, 2)), rng.normal(size=5)
        least_squares(step, np.array(start), bounds=(0.0, 1.0), diff_step=DIFF_STEP, max_nfev=6,
                      workers=differences)  # fmt: skip
    assert len(asked) >= 16 and set(asked) <= predicted


def test_the_chi2_at_the_generating_point_changes_no_cache_and_no_count(data_dir):
    """:func:`~bouncedisk.fitting.joint.chi2_at_truth` reads the generating point after the fit:
    the objective's cache and its points read (the fit's count of evaluations) are as before."""
    from bouncedisk.fitting.joint import (
        chi2_at_truth,
        generating_point_better,
        generating_x,
        loglik_at_truth,
    )

    obj = _small_objective(data_dir)
    obj.chi2(np.array([0.6, math.log10(0.0027), -0.3, 1.5]), 4)
    cache, read = set(obj.cache), set(obj.read)
    at = chi2_at_truth(obj, 4)
    assert at is not None and at["both"] == pytest.approx(at["runup"] + at["load"], rel=1e-12)
    assert set(obj.cache) == cache and set(obj.read) == read and len(read) == 1
    log = list(obj.log)
    estimate = np.array([0.6, math.log10(0.0027), -0.3, 1.5])
    own = loglik_at_truth(obj, estimate, 4, 6)
    assert set(obj.cache) == cache and set(obj.read) == read and obj.log == log
    # each point read on the same members: the constant dropped is the same for both
    assert own == {
        "generating": obj.own_loglik(generating_x(obj), 4, 6),
        "estimate": obj.own_loglik(estimate, 4, 6),
    }
    assert own["generating"] != own["estimate"]
    # the verdict: below by more than the 95 % point of chi2(1), not merely below
    assert generating_point_better({"generating": 0.0, "estimate": 3.9})
    assert not generating_point_better({"generating": 0.0, "estimate": 3.8})


def test_own_loglik_is_woods_gaussian_log_likelihood(data_dir):
    """:meth:`~bouncedisk.fitting.objective.Objective.own_loglik` is ``−2 log`` of the Gaussian
    density of the data under the point's own members (Wood's synthetic likelihood), up to the
    constant ``n log 2π``, for the run-ups' statistics and the load curve's readings alike
    (checked against scipy's multivariate normal), and no held metric moves it."""
    from scipy.stats import multivariate_normal

    from bouncedisk.fitting.loadpart import members_for
    from bouncedisk.fitting.summary_stats import regularized_cov, stat_floor

    obj = _small_objective(data_dir)
    x = np.array([0.6, math.log10(0.0027), -0.3, 1.5])
    k = 6
    ens = obj.ensemble(x, k)
    sigma = regularized_cov(ens.cov, stat_floor(obj.target)) * (1.0 / obj.runs + 1.0 / k)
    density = multivariate_normal(ens.mean, sigma).logpdf(obj.target)
    runup = -2.0 * density - len(obj.target) * math.log(2.0 * math.pi)
    part, kl, theta = obj.load, members_for(k), obj.theta(x)
    values = part.values(theta, x, kl)
    cov = part.members_cov(values)
    sigma_l = np.diag(part.data_var(cov)) + cov / kl
    density_l = multivariate_normal(values.mean(axis=0), sigma_l).logpdf(part.y)
    load = -2.0 * density_l - part.n * math.log(2.0 * math.pi)
    assert obj.seeing("runup").own_loglik(x, k) == pytest.approx(runup, rel=1e-9, abs=1e-9)
    # scipy's eigendecomposition of the readings' ill-conditioned covariance: to 1e-4
    assert obj.seeing("load").own_loglik(x, k) == pytest.approx(load, rel=1e-9, abs=1e-4)
    both = obj.own_loglik(x, k)
    assert both == pytest.approx(runup + load, rel=1e-9, abs=1e-4)
    # the held metrics, measured elsewhere, do not move it (they move chi2)
    chi2 = obj.chi2_now(x, k)
    other = np.array([0.3, math.log10(0.01), 1.0, 2.5])
    obj.set_cov(4.0 * obj.covariance)
    part.set_cov(part.values(obj.theta(other), other, kl))
    assert obj.own_loglik(x, k) == both and obj.chi2_now(x, k) != chi2
