"""The fit's data at the edges: time origin, too-short data and a
too-small bootstrap, extreme sidecar values, data the fit used to accept wrongly."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import yaml

from bouncedisk.cli import main
from bouncedisk.fitting import core
from bouncedisk.fitting.core import data_layout, prepare_runs
from bouncedisk.fitting.members import synthesize_curve
from bouncedisk.fitting.summary_stats import STATS
from bouncedisk.io.runup_curves import read_curve, write_curve
from bouncedisk.model.errors import InputError

F_HZ, PHI0, DT, SIGMA = 15000.0, 3.0e-4, 2.5e-5, 0.05
TRUE = {"e": 0.31, "r_phi": 0.0041, "psi": 0.25, "omega_s": 1.37}


def _sidecar(**extra):
    motor = {"drive_frequency_hz": F_HZ, "Phi0_rad": PHI0, **extra.pop("motor", {})}
    return {"source": "test", "synthetic": True, "units": {"time": "s", "omega": "rad/s"},
            "motor": motor, **extra}  # fmt: skip


@pytest.fixture(scope="module")
def frame():
    """A short synthetic run-up (0.02 s, 801 samples)."""
    return synthesize_curve(TRUE, F_HZ, PHI0, 0.02, DT, SIGMA, 3, member=0)


def _curve(tmp_path, df, side=None, name="c.csv"):
    p = tmp_path / name
    write_curve(df, p, side or _sidecar())
    return p


def _fails(capsys, args, field, path=None):
    assert main(["fit", *args, "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0], err
    assert "Traceback" not in err[0]
    if path is not None:
        assert str(path) in err[0]
    return err[0]


# ---------------------------------------------------------------- the time origin


def test_statistics_do_not_depend_on_the_time_origin(tmp_path, frame):
    """Stamps shifted by 1e9 s (epoch-like; their steps carry only 1.2e-7 s) give the data's
    statistics of the unshifted curve to 1e-5: the sampling interval itself is known only to
    ulp(1e9)/span = 6e-6 from such stamps, and the statistics scale with it at most linearly."""
    bound = np.spacing(1e9) / 0.02
    shifted = frame.assign(time_s=frame["time_s"] + 1e9)
    a = read_curve(_curve(tmp_path, frame, name="a.csv"))
    b = read_curve(_curve(tmp_path, shifted, name="b.csv"))
    assert b.time[0] == 1e9 and abs(b.dt / a.dt - 1) <= bound
    (ra,), _, _ = prepare_runs(a)
    (rb,), _, note = prepare_runs(b)
    assert "t0 = 1000000000 s" in note and rb.time[0] == 0.0
    np.testing.assert_array_equal(ra.omega, rb.omega)
    la, _, sa = data_layout([ra])
    lb, _, sb = data_layout([rb])
    assert len(la.t) == len(lb.t) and abs(lb.tau_ref / la.tau_ref - 1) <= 2 * bound
    np.testing.assert_allclose(sb, sa, rtol=2 * bound, atol=1e-9, err_msg=str(STATS))


# ---------------------------------------------------------------- too short, too small


def test_data_too_short_for_the_statistics(tmp_path, capsys, frame):
    p = _curve(tmp_path, frame.iloc[:20])
    err = _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc")], "time_s", p)
    assert f"at least {core.MIN_FIT_SAMPLES}" in err and not (tmp_path / "f.nc").exists()


@pytest.mark.parametrize("n", ["2", "39"])
def test_bootstrap_too_small_for_a_95_interval(tmp_path, capsys, frame, n):
    p = _curve(tmp_path, frame)
    _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc"), "--bootstrap", n], "--bootstrap")


# ---------------------------------------------------------------- extreme sidecar values


@pytest.mark.parametrize(
    "side,field",
    [
        ({"noise_sigma_rad_s": 1e300}, "noise_sigma_rad_s"),
        ({"motor": {"drive_frequency_hz": 1e300}}, "motor.drive_frequency_hz"),
        ({"motor": {"drive_frequency_hz": 1e-300}}, "motor.drive_frequency_hz"),
        ({"motor": {"drive_frequency_hz": 1e9}}, "motor.drive_frequency_hz"),
        ({"motor": {"Phi0_rad": 1e300}}, "motor.Phi0_rad"),
    ],
)
def test_extreme_sidecar_values_one_line(tmp_path, capsys, frame, side, field):
    df = frame.drop(columns="sigma_rad_s") if "noise_sigma_rad_s" in side else frame
    p = _curve(tmp_path, df, _sidecar(**side))
    _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc")], field, p.with_suffix(".yaml"))


# ---------------------------------------------------------------- wrongly accepted


@pytest.mark.parametrize(
    "side,field",
    [
        ({"noise_sigma_rad_s": -0.5}, "noise_sigma_rad_s"),
        ({"synthetic": "no"}, "synthetic"),
        ({"motor": {"U0_m": "banana"}}, "motor.U0_m"),
    ],
)
def test_bad_sidecar_fields(tmp_path, capsys, frame, side, field):
    p = _curve(tmp_path, frame.drop(columns="sigma_rad_s"), _sidecar(**side))
    _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc")], field, p.with_suffix(".yaml"))


def test_boolean_omega_column(tmp_path, capsys, frame):
    p = tmp_path / "c.csv"
    rows = [f"{t!r},True" for t in frame["time_s"]]
    p.write_text("time_s,omega_rad_s\n" + "\n".join(rows) + "\n")
    p.with_suffix(".yaml").write_text(yaml.safe_dump(_sidecar(noise_sigma_rad_s=0.0)))
    _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc")], "omega_rad_s", p)


def test_repeated_omega_column(tmp_path, capsys, frame):
    p = tmp_path / "c.csv"
    rows = [f"{t!r},{w!r},0.0" for t, w in zip(frame["time_s"], frame["omega_rad_s"], strict=True)]
    p.write_text("time_s,omega_rad_s,omega_rad_s\n" + "\n".join(rows) + "\n")
    p.with_suffix(".yaml").write_text(yaml.safe_dump(_sidecar(noise_sigma_rad_s=SIGMA)))
    err = _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc")], "omega_rad_s", p)
    assert "more than once" in err


def test_the_same_curve_twice(tmp_path, capsys, frame):
    p = _curve(tmp_path, frame)
    same = tmp_path / "." / "c.csv"
    _fails(capsys, [str(p), str(same), "-o", str(tmp_path / "f.nc")], "same file", same)


def test_scene_members_as_text_is_refused():
    from types import SimpleNamespace

    from bouncedisk.model.scene import _ensemble

    noisy = (frozenset({"restitution_noise"}), SimpleNamespace(e=0.5, e_sigma=0.03))
    assert _ensemble("s.yaml", {"members": 3}, *noisy).members == 3
    with pytest.raises(InputError, match="ensemble.members"):
        _ensemble("s.yaml", {"members": "3"}, *noisy)


def test_time_origin_keeps_uniform_curves_on_their_grid(frame):
    """The shipped-style curve (t0 = 0, uniform): relative times are its own grid (to round-off)."""
    from bouncedisk.io.runup_curves import MotorCurve

    c = MotorCurve(frame["time_s"].to_numpy(), frame["omega_rad_s"].to_numpy(), SIGMA, F_HZ,
                   PHI0, "", True, "x.csv")  # fmt: skip
    (r,), _, note = prepare_runs(dataclasses.replace(c))
    assert note == "" and np.max(np.abs(r.time - c.time)) <= 1e-9 * DT


# ---------------------------------------------------------------- run-up values beyond the motor


@pytest.mark.parametrize(
    "column,scale,field",
    [
        ("omega_rad_s", 1e200, "omega_rad_s: row"),
        ("sigma_rad_s", 1e300, "sigma_rad_s: row"),
        ("time_s", 1e20, "time_s: row"),
    ],
)
def test_runup_values_beyond_the_motor_are_refused_when_read(
    tmp_path, capsys, frame, column, scale, field
):
    """Run-up speeds x1e200 stopped the fit on a LinAlgError."""
    p = _curve(tmp_path, frame.assign(**{column: frame[column] * scale}))
    with pytest.raises(InputError, match="check the units"):
        read_curve(p)
    _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc")], field, p)


def test_a_runup_has_the_rows_the_fit_needs(tmp_path, frame):
    """One number for the reader, the fit and the formats page."""
    from pathlib import Path

    from bouncedisk.io.runup_curves import MIN_ROWS
    from bouncedisk.model.limits import MIN_RUNUP_SAMPLES

    assert MIN_ROWS == core.MIN_FIT_SAMPLES == MIN_RUNUP_SAMPLES
    with pytest.raises(InputError, match=f"the fit needs at least {MIN_RUNUP_SAMPLES}"):
        read_curve(_curve(tmp_path, frame.iloc[: MIN_RUNUP_SAMPLES - 1]))
    assert len(read_curve(_curve(tmp_path, frame.iloc[:MIN_RUNUP_SAMPLES])).time) == 200
    page = (Path(__file__).parents[1] / "docs" / "formats.md").read_text()
    section = page.split("## Run-up curves")[1].split("## ")[0]
    assert f"least {MIN_RUNUP_SAMPLES} rows" in " ".join(section.split())


# ---------------------------------------------------------------- several --load


def test_every_load_option_is_fitted(tmp_path, monkeypatch, frame):
    """`--load A --load B` kept only B, silently."""
    from bouncedisk.fitting import command

    given = []

    def run_fit(curves, output, settings, loads, *rest):
        given.extend(loads)
        raise InputError("<test>", "", "stopped before the fit")

    monkeypatch.setattr(command, "run_fit", run_fit)
    p = _curve(tmp_path, frame)
    argv = ["fit", str(p), "--load", "a.csv", "--load", "b.csv", "-o", "f.nc", "-q"]
    assert main(argv) == 2
    assert given == ["a.csv", "b.csv"]


def test_a_run_up_after_a_load_option_is_a_run_up(tmp_path, monkeypatch, frame):
    """`fit --load L.csv RUN.csv`: one curve per `--load`, so RUN.csv is the run-up."""
    from bouncedisk.fitting import command

    seen = {}

    def run_fit(curves, output, settings, loads, *rest):
        seen.update(curves=[str(c) for c in curves], loads=list(loads))
        raise InputError("<test>", "", "stopped before the fit")

    monkeypatch.setattr(command, "run_fit", run_fit)
    p = _curve(tmp_path, frame)
    assert main(["fit", "--load", "a.csv", str(p), "-o", "f.nc", "-q"]) == 2
    assert seen == {"curves": [str(p)], "loads": ["a.csv"]}


def test_a_missing_load_among_several_is_named(tmp_path, capsys, frame):
    p = _curve(tmp_path, frame)
    first, second = tmp_path / "first.csv", tmp_path / "second.csv"
    args = [str(p), "--load", str(first), "--load", str(second), "-o", str(tmp_path / "f.nc")]
    err = _fails(capsys, args, "file not found", first)
    assert str(second) not in err


# ---------------------------------------------------------------- the fit's settings, one rule each


def test_fit_settings_check_e_sigma_and_bootstrap_as_the_command_line(tmp_path, capsys, frame):
    from bouncedisk.model.limits import BOOTSTRAP_RANGE, E_SIGMA

    for kwargs in (
        {"e_sigma": 0.7},
        {"e_sigma": -0.1},
        {"e_sigma": float("nan")},
        {"bootstrap": BOOTSTRAP_RANGE.high + 1},
        {"bootstrap": BOOTSTRAP_RANGE.low - 1},
    ):
        with pytest.raises(InputError) as ex:
            core.FitSettings(**kwargs)
        (name,) = kwargs
        assert ex.value.field == name
    core.FitSettings(e_sigma=E_SIGMA.high, bootstrap=BOOTSTRAP_RANGE.high)
    p = _curve(tmp_path, frame)
    err = _fails(capsys, [str(p), "-o", str(tmp_path / "f.nc"), "--e-sigma", "0.7"], "--e-sigma")
    assert E_SIGMA.text() in err
    err = _fails(
        capsys, [str(p), "-o", str(tmp_path / "f.nc"), "--bootstrap", "10001"], "--bootstrap"
    )
    assert "10000" in err


def test_the_config_schema_states_the_bounds_of_the_command_line():
    from pathlib import Path

    from bouncedisk.model.limits import BOOTSTRAP_RANGE, E_SIGMA

    schema_file = Path(__file__).parents[1] / "workflow" / "schemas" / "config.schema.yaml"
    proto = yaml.safe_load(schema_file.read_text())["properties"]["prototype"]["properties"]
    assert (proto["bootstrap"]["minimum"], proto["bootstrap"]["maximum"]) == (
        BOOTSTRAP_RANGE.low,
        BOOTSTRAP_RANGE.high,
    )
    assert (proto["e_sigma"]["minimum"], proto["e_sigma"]["maximum"]) == (E_SIGMA.low, E_SIGMA.high)


def test_a_synthetic_curve_has_every_sample_its_span_asks_for():
    """``synthesize_curve`` at a step whose median over the stamps rounds the grid one sample
    short (8484.2 Hz sampled at 0.4 drive periods for 0.37 s): one row per ``k dt`` up to the
    span, every speed finite."""
    import math

    import numpy as np

    from bouncedisk.fitting import synthesize_curve

    f, span = 8484.2, 0.37
    dt = 0.4 / f
    true = {"e": 0.91, "r_phi": 1.3e-4, "psi": -2.65, "omega_s": 1.07}
    df = synthesize_curve(true, f, 1.47e-3, span, dt, 0.01, 5007, member=0, e_sigma=0.0)
    assert len(df) == math.floor(span / dt + 1e-9) + 1 == 7848
    assert np.isfinite(df["omega_rad_s"]).all()


def test_run_ups_at_different_stated_amplitudes_are_refused(tmp_path, frame, capsys):
    """The run-ups of one fit are one experiment: a second run-up that states another axial
    amplitude (``motor.U0_m``), or none where the first states one, is one line naming it and
    the field, exit 2 (its amplitude would otherwise be the first's, unread)."""
    a = _curve(tmp_path, frame, _sidecar(motor={"U0_m": 1e-6}), "a.csv")
    same = _curve(tmp_path, frame, _sidecar(motor={"U0_m": 1e-6}), "same.csv")
    other = _curve(tmp_path, frame, _sidecar(motor={"U0_m": 2e-6}), "other.csv")
    unstated = _curve(tmp_path, frame, _sidecar(), "unstated.csv")
    core.check_runs([read_curve(a), read_curve(same)])  # one amplitude: accepted
    for bad in (other, unstated):
        with pytest.raises(InputError, match=r"motor\.U0_m: is .*, but 1e-06 in ") as ex:
            core.check_runs([read_curve(a), read_curve(bad)])
        # a sidecar's field names the sidecar, the other run's too
        assert ex.value.line().startswith(str(bad.with_suffix(".yaml"))), ex.value.line()
        assert f"in {a.with_suffix('.yaml')}:" in ex.value.line() and "\n" not in ex.value.line()
    _fails(capsys, [str(a), str(other), "-o", str(tmp_path / "f.nc")], "motor.U0_m",
           other.with_suffix(".yaml"))  # fmt: skip
    assert not (tmp_path / "f.nc").exists()


def test_run_ups_that_disagree_are_the_only_line_with_progress_on(tmp_path, frame, capsys):
    """Two run-ups of different lengths, without ``-q``: the command's one line is the error,
    before any progress line (the run-ups are checked together before the fit starts)."""
    a = _curve(tmp_path, frame, name="a.csv")
    short = _curve(tmp_path, frame.iloc[:-40], name="short.csv")
    assert main(["fit", str(a), str(short), "-o", str(tmp_path / "f.nc")]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith(f"bouncedisk: error: {short}: time_s: has ") and "samples" in line


def test_two_load_curves_after_one_load_option_are_told_to_repeat_it(tmp_path, frame, capsys):
    """``--load A.csv B.csv`` (one option, two files): one line saying that each load curve takes
    a ``--load`` of its own; the help and the pages say the same."""
    from bouncedisk.cli.command import build_parser

    run = _curve(tmp_path, frame)
    with pytest.raises(SystemExit) as ex:
        main(["fit", str(run), "--load", "a.csv", "b.csv", "-o", str(tmp_path / "f.nc")])
    assert ex.value.code == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "unrecognized arguments: b.csv" in line and line.endswith("(see bouncedisk fit --help)")
    assert "each load curve after a --load of its own" in line
    fit = build_parser()._subparsers._group_actions[0].choices["fit"]
    assert "--load A.csv --load B.csv" in " ".join(fit.format_help().split())
