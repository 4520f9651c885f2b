"""Scenes, physical parameters and the `bouncedisk` command, including bad input."""

import math
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from bouncedisk.cli import main
from bouncedisk.io.provenance import REQUIRED_ATTRS
from bouncedisk.model.errors import InputError
from bouncedisk.model.params import PhysicalParameters
from bouncedisk.model.scene import load_scene

GOOD = """
name: demo
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact, torsion]
stop: {impacts: 50}
outputs: {events: true, trajectory: {dt: 0.05}, stroboscopic: true}
solver: {method: exact, tol: 1.0e-12}
"""


def test_scene_defaults_and_effects(scene_file):
    s = load_scene(scene_file(GOOD))
    assert s.effects == {"impacts", "contact", "torsion", "impulse_cap"}
    assert s.initial.u is None and s.stop.impacts == 50
    s2 = load_scene(
        scene_file(GOOD),
        [
            "parameters.e=0.6",
            "effects={impacts: true, contact: true, torsion: true, impulse_cap: false}",
        ],
    )
    assert s2.params.e == 0.6 and "impulse_cap" not in s2.effects
    assert s.sha256 != s2.sha256


def test_periods_stop_is_converted_to_time(scene_file):
    s = load_scene(scene_file(GOOD), ["stop={periods: 10}"])
    assert s.stop.time == pytest.approx(10 * 2 * math.pi / 1.5)


def test_physical_parameters_convert_to_nondimensional():
    p = PhysicalParameters(
        m_r=0.01,
        r_g=0.004,
        r_c=0.001,
        mu=0.2,
        e=0.5,
        g=9.81,
        f=40e3,
        U0=1e-6,
        Phi0=1e-3,
        psi=0.1,
        F_preload=0.5,
    )
    sc = p.scales()
    g_eff = 9.81 + 0.5 / 0.01
    assert sc.t_c == pytest.approx(math.sqrt(1e-6 / g_eff))
    nd = p.to_nondimensional()
    assert nd.omega_s == pytest.approx(2 * math.pi * 40e3 * sc.t_c)
    r_eff = 2e-3 / 3
    r_d = r_eff * 1e-3 / 1e-6
    assert nd.r_phi == pytest.approx((r_eff / 0.004) ** 2 * 0.2 / r_d)
    assert sc.omega_scale == pytest.approx(nd.r_phi * 1e-3 / sc.t_c)


def test_physical_scene(scene_file):
    text = """
name: phys
physical: {m_r: 0.01, r_g: 0.004, r_c: 0.001, mu: 0.2, e: 0.5, g: 9.81, f: 1000.0, U0: 1.0e-6,
           Phi0: 1.0e-3, psi: 0.0, F_preload: 0.0}
stop: {impacts: 10}
"""
    s = load_scene(scene_file(text))
    assert s.params.omega_s == pytest.approx(2 * math.pi * 1000 * math.sqrt(1e-6 / 9.81))
    assert s.scales is not None


def test_a_derived_parameter_out_of_range_names_the_fields_it_comes_from(scene_file, capsys):
    """A drive typed in the wrong unit (2e12 Hz) makes omega_s absurd: the one line names
    ``physical.omega_s`` and the SI fields it is computed from, which are what the user wrote."""
    text = """
name: phys
physical: {m_r: 0.01, r_g: 0.004, r_c: 0.001, mu: 0.2, e: 0.5, g: 9.81, f: 2.0e+12, U0: 1.0e-6,
           Phi0: 1.0e-3}
stop: {impacts: 10}
"""
    f = scene_file(text)
    assert main(["simulate", str(f), "-o", str(f.with_suffix(".nc")), "-q"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert f"{f}: physical.omega_s: must be a number in" in err
    assert err.endswith("from physical.f, U0, g, F_preload and m_r)")
    assert not f.with_suffix(".nc").exists()


def test_a_physical_window_in_seconds_is_told_its_unit(scene_file, capsys):
    """A physical scene's times are in t_c, not seconds: a stop of 0.02 "seconds" leaves less
    than a period, and the one line names the field at fault and t_c in seconds."""
    text = """
name: phys
physical: {m_r: 0.01, r_g: 0.004, r_c: 0.001, mu: 0.2, e: 0.5, g: 9.81, f: 1000.0, U0: 1.0e-6,
           Phi0: 1.0e-3}
stop: {time: 0.02}
"""
    f = scene_file(text)
    assert main(["stats", str(f), "-q"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    t_c = math.sqrt(1e-6 / 9.81)
    assert f"{f}: stop.time: leaves 0.02 time units" in err
    assert err.endswith(f"(a scene's times are in units of t_c = {t_c:.4g} s, not seconds)")
    assert main(["stats", str(f), "-q", "--set", "stop.time=10", "--set", "stats.discard=9.9"]) == 2
    assert ": stats.discard (from --set stats.discard): leaves 0.1 time units" in (
        capsys.readouterr().err
    )
    # a transient "in seconds" longer than the run is refused as the scene is read, with t_c too
    assert main(["stats", str(f), "-q", "--set", "stop.time=0.5", "--set", "stats.discard=2"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert ": stats.discard (from --set stats.discard): must be shorter than the run" in err
    assert err.endswith(f"(a scene's times are in units of t_c = {t_c:.4g} s, not seconds)")


@pytest.mark.parametrize(
    "override,field",
    [
        ("parameters.e=-0.1", "parameters.e"),
        ("parameters.e=1.5", "parameters.e"),
        ("parameters.omega_s=0", "parameters.omega_s"),
        ("parameters.e=.nan", "parameters.e"),
        ("parameters.r_phi=.inf", "parameters.r_phi"),
        ("parameters.e=abc", "parameters.e"),
        ("effects=[impacts, warp_drive]", "effects.warp_drive"),
        ("bogus_key=1", "bogus_key"),
        ("parameters.bogus=1", "parameters.bogus"),
        ("stop={impacts: 0}", "stop.impacts"),
        ("stop={impacts: 10, time: 5}", "stop"),
        ("outputs.trajectory.dt=-1", "outputs.trajectory.dt"),
        ("solver.method=euler", "solver.method"),
        ("initial={t: 0, u: -5, v: 0}", "initial.u"),
        ("effects=[impacts, stator_inertia]", "effects.stator_inertia"),
    ],
)
def test_bad_values_exit_2_with_one_line(scene_file, tmp_path, capsys, override, field):
    out = tmp_path / "out.nc"
    code = main(["simulate", str(scene_file(GOOD)), "-o", str(out), "--set", override, "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "scene.yaml" in err[0] and field in err[0]
    # the line also names the option that gave the bad value
    assert f"(from --set {override.partition('=')[0]})" in err[0]
    assert not out.exists() and not list(tmp_path.glob(".out.nc*"))


def test_the_clipped_model_names_what_it_needs(scene_file, tmp_path, capsys):
    """The clipped model's contact never opens: without the contact effect, a time stop or the
    exact solver it is refused before any run, naming the field."""
    out = tmp_path / "out.nc"
    base = ["simulate", str(scene_file(GOOD)), "-o", str(out), "-q", "--set", "model=clipped"]
    for extra, field in (
        (["--set", "stop={time: 50}", "--set", "effects=[impacts, torsion]"], "effects "),
        ([], "stop"),
        (["--set", "stop={time: 50}", "--set", "solver={method: rk45}"], "solver.method"),
    ):
        assert main(base + extra) == 2
        (err,) = capsys.readouterr().err.strip().splitlines()
        assert field in err and "clipped" in err
        assert not out.exists()


def test_a_bad_file_value_does_not_blame_an_unrelated_set_option(scene_file, tmp_path, capsys):
    text = "name: x\nparameters: {e: 'high', omega_s: 1.5}\nstop: {impacts: 3}\n"
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    out = tmp_path / "out.nc"
    assert main(["simulate", str(f), "-o", str(out), "--set", "stop.impacts=5", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "parameters.e: must be a number" in err and "--set" not in err


@pytest.mark.parametrize(
    "text,field",
    [
        ("name: x\nparameters: {e: 0.3, omega_s: [1\n", "line"),
        ("- just\n- a list\n", "mapping"),
        ("", "empty"),
        ("name: x\nparameters: {e: 'high', omega_s: 1.5}\nstop: {impacts: 3}\n", "parameters.e"),
        ("name: x\nparameters: {omega_s: 1.5}\nstop: {impacts: 3}\n", "parameters.e"),
        ("name: x\nparameters: {e: 0.3, omega_s: 1.5}\nstop: {impacts: 3.5}\n", "stop.impacts"),
        ("name: 'bad name!'\nparameters: {e: 0.3, omega_s: 1.5}\nstop: {impacts: 3}\n", "name"),
    ],
)
def test_malformed_scene_files(scene_file, tmp_path, capsys, text, field):
    out = tmp_path / "out.nc"
    code = main(["simulate", str(scene_file(text)), "-o", str(out), "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and field in err[0] and "scene.yaml" in err[0]
    assert not out.exists()


def test_missing_effect_is_named(scene_file, tmp_path, capsys):
    out = tmp_path / "out.nc"
    code = main(
        [
            "simulate",
            str(scene_file(GOOD)),
            "-o",
            str(out),
            "-q",
            "--set",
            "effects=[impacts]",
            "--set",
            "parameters.e=0.0",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "'contact'" in err and "effects" in err and not out.exists()


def test_missing_file_and_bad_set_syntax(tmp_path, capsys, scene_file):
    assert main(["simulate", str(tmp_path / "nope.yaml"), "-o", str(tmp_path / "o.nc")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert (
        main(["simulate", str(scene_file(GOOD)), "-o", str(tmp_path / "o.nc"), "--set", "e"]) == 2
    )
    assert "KEY=VALUE" in capsys.readouterr().err


def test_console_script_prints_no_traceback(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("parameters: {e: 2}\n")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "bouncedisk.cli",
            "simulate",
            str(bad),
            "-o",
            str(tmp_path / "o.nc"),
        ],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_simulate_says_which_member_of_an_ensemble_it_ran(scene_file, tmp_path, capsys):
    """An ensemble scene's simulation file holds one run: the command says it is member 0."""
    overrides = ["--set", "effects=impacts,contact,torsion,restitution_noise"]
    overrides += ["--set", "parameters.e_sigma=1e-9", "--set", "ensemble={members: 4, seed: 1}"]
    out = tmp_path / "e.nc"
    assert main(["simulate", str(scene_file(GOOD)), "-o", str(out), *overrides]) == 0
    assert capsys.readouterr().out.rstrip().endswith(", member 0 of 4 (stats runs them all)")
    assert main(["simulate", str(scene_file(GOOD)), "-o", str(out)]) == 0
    assert "member" not in capsys.readouterr().out


def test_simulate_writes_interfaces_names_and_is_deterministic(scene_file, tmp_path):
    f = scene_file(GOOD)
    a, b = tmp_path / "a.nc", tmp_path / "b.nc"
    assert main(["simulate", str(f), "-o", str(a), "-q"]) == 0
    assert main(["simulate", str(f), "-o", str(b), "-q"]) == 0
    da, db = xr.open_dataset(a), xr.open_dataset(b)
    for name in (
        "t_impact",
        "phase",
        "v_rel",
        "omega_after",
        "kind",
        "u_rotor",
        "u_stator",
        "omega_rotor",
        "strobe_u",
    ):
        assert name in da, name
        assert da[name].attrs["units"] and da[name].attrs["long_name"]
        np.testing.assert_array_equal(da[name].values, db[name].values)
    for att in REQUIRED_ATTRS:
        assert att in da.attrs, att
    assert da.attrs["run_id"] != db.attrs["run_id"]
    assert da.attrs["n_impacts"] == 50 and da.attrs["status"] == "completed"
    assert da["t_impact"].encoding.get("zlib") or da["t_impact"].encoding.get("compression")
    assert np.all((da.phase >= 0) & (da.phase < 2 * np.pi))
    # the stroboscopic section samples the stator at phase 0
    np.testing.assert_allclose(np.sin(1.5 * da.strobe_t.values), 0.0, atol=1e-9)


def test_info_lists_the_provenance_in_one_aligned_column(scene_file, tmp_path, capsys):
    out = tmp_path / "a.nc"
    assert main(["simulate", str(scene_file(GOOD)), "-o", str(out), "-q"]) == 0
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = [ln.partition(": ")[0].strip() for ln in lines]
    assert {"scene_sha256", "bouncedisk_version", "n_impacts", "status", "variables"} <= set(names)
    # every name right-aligned to the same column, the longest (bouncedisk_version) included
    assert len({ln.index(": ") for ln in lines}) == 1, lines


def test_info_rejects_corrupt_netcdf(tmp_path, capsys):
    bad = tmp_path / "bad.nc"
    bad.write_bytes(b"CDF\x01garbage" * 10)
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.nc" in err and "corrupt" in err


def test_info_rejects_foreign_netcdf(tmp_path, capsys):
    other = tmp_path / "other.nc"
    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(other)
    assert main(["info", str(other)]) == 2
    err = capsys.readouterr().err
    assert "other.nc: bouncedisk_version: missing required attribute" in err
    assert "not a bouncedisk netCDF file" in err


def test_python_dash_m_bouncedisk_is_the_command(tmp_path):
    """``python -m bouncedisk`` runs the console script's command: same line, same status."""
    missing = tmp_path / "missing.nc"
    r = subprocess.run(
        [sys.executable, "-m", "bouncedisk", "info", str(missing)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == f"bouncedisk: error: {missing}: file not found\n"


def test_input_error_line_format():
    assert InputError("f.yaml", "parameters.e", "bad").line() == "f.yaml: parameters.e: bad"


def test_history_is_the_command_line_main_was_given(scene_file, tmp_path):
    """``history`` records the words ``main`` parsed (not the interpreter's own argv), quoted."""
    f, out = scene_file(GOOD), tmp_path / "with space.nc"
    stats = tmp_path / "stats.nc"
    assert main(["simulate", str(f), "-o", str(out), "--set", "stop.impacts=5", "-q"]) == 0
    with xr.open_dataset(out) as ds:
        history = ds.attrs["history"]
    assert history.endswith(f"bouncedisk simulate {f} -o '{out}' --set stop.impacts=5 -q")
    sets = ["--set", "stop={time: 50.0}", "--set", "stats.discard=0"]
    assert main(["stats", str(f), "-o", str(stats), *sets, "-q"]) == 0
    with xr.open_dataset(stats) as ds:
        assert ds.attrs["history"] == f"{ds.attrs['created']}: bouncedisk stats {f} -o {stats} " + (
            "--set 'stop={time: 50.0}' --set stats.discard=0 -q"
        )
