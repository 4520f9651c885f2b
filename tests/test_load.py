"""The motor under load (docs/model.md "The motor under load"): closed forms, the energy audit,
the momentum bound, the torque–speed curve and bad input."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad, solve_ivp

from bouncedisk.cli import main
from bouncedisk.engine import EngineConfig, simulate_arrays
from bouncedisk.engine import laws as L
from bouncedisk.engine.driver import audit_balances
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.netcdf import open_checked
from bouncedisk.model.params import PhysicalParameters
from bouncedisk.model.scene import scene_from_mapping
from bouncedisk.studies.torque_speed import first_zero, parse_loads, peak, torque_speed

W, R, PSI = 1.5, 0.01, 0.7

# --- closed forms against quadrature of the ODE with the load ----------------------------------


def _n(ph):
    return 1.0 - W * W * math.sin(ph)


@pytest.mark.parametrize("sigma", [1.0, -1.0])
@pytest.mark.parametrize("load", [0.0, 0.35])
def test_slip_omega_with_load_solves_the_ode(sigma, load):
    """Eq. 23 with the load: Ω' = −σN − τ_L, integrated numerically from the same start."""
    th0, om0, tau = 0.4, 37.0, 1.9
    sol = solve_ivp(
        lambda t, y: [-sigma * _n(th0 + W * t) - load],
        (0.0, tau),
        [om0],
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
    )
    for t in np.linspace(0.0, tau, 7):
        assert L.slip_omega(om0, sigma, W, th0, t, load) == pytest.approx(sol.sol(t)[0], abs=1e-9)
        ref = quad(lambda x: L.slip_omega(om0, sigma, W, th0, x, load), 0.0, t)[0]
        assert L.slip_omega_integral(om0, sigma, W, th0, t, load) == pytest.approx(ref, abs=1e-10)


def test_flight_omega_with_load_is_linear():
    """Flight: Ω' = −τ_L, and its integral Ω0 τ − τ_L τ²/2."""
    assert L.loaded_omega(5.0, 0.25, 2.0) == 4.5
    assert L.loaded_omega_integral(5.0, 0.25, 2.0) == pytest.approx(10.0 - 0.5)
    assert L.loaded_omega(5.0, 0.0, 2.0) == 5.0


@pytest.mark.parametrize("sigma", [1.0, -1.0])
@pytest.mark.parametrize("load", [0.0, 0.35])
def test_audit_integrals_of_a_slip_segment_match_quadrature(sigma, load):
    """W_t = ∫ −σN Ω_s/R dt and ∫ N Ω dt in closed form, against quadrature."""
    th0, om0, tau = 2.2, -12.0, 3.1
    w_t = quad(lambda t: -sigma * _n(th0 + W * t) * W * math.cos(th0 + W * t + PSI) / R, 0, tau)
    assert L.slip_twist_work(sigma, W, R, PSI, th0, tau) == pytest.approx(w_t[0], rel=1e-11)
    n_om = quad(lambda t: _n(th0 + W * t) * L.slip_omega(om0, sigma, W, th0, t, load), 0, tau)
    got = L.slip_load_omega_integral(om0, sigma, W, th0, tau, load)
    assert got == pytest.approx(n_om[0], rel=1e-11, abs=1e-11)


@pytest.mark.parametrize("load", [0.0, 0.35])
def test_stick_and_contact_work_match_quadrature(load):
    """Sticking, f = α_s/R + τ_L: W_t = ∫ f Ω_s/R dt; riding: W_ax = ∫ N v_s dt."""
    th0, tau = 5.0, 2.3

    def stick_power(t):
        ph = th0 + W * t + PSI
        return (-W * W * math.sin(ph) / R + load) * W * math.cos(ph) / R

    ref = quad(stick_power, 0.0, tau)[0]
    assert L.stick_twist_work(W, R, PSI, load, th0, tau) == pytest.approx(ref, rel=1e-11)
    ref_ax = quad(lambda t: _n(th0 + W * t) * W * math.cos(th0 + W * t), 0.0, tau)[0]
    assert L.contact_axial_work(W, th0, tau) == pytest.approx(ref_ax, rel=1e-11, abs=1e-13)


def _cfg(**kw):
    base = dict(e=0.0, omega_s=W, r_phi=R, psi=PSI, torsion=True, max_events=10**9)
    base.update(kw)
    return EngineConfig(**base)


def test_stick_ends_where_the_loaded_stick_condition_fails():
    """While sticking (RΩ = Ω_s), |α_s + Rτ_L| <= RN; between, the slip obeys Ω' = −σN − τ_L.

    Checked on the dense trajectory of an e = 0 stick–slip run under load.
    """
    load, r = 0.4, 2.0  # a large R: the rotor sticks for long stretches
    res = simulate_arrays(_cfg(t_end=60.0, traj_dt=1e-3, load_torque=load, r_phi=r))
    t, om = res.traj[:, 0], res.traj[:, 4]
    ph = W * t
    n_load = 1.0 - W * W * np.sin(ph)
    alpha = -W * W * np.sin(ph + PSI)
    s = r * om - W * np.cos(ph + PSI)
    contact = np.abs(res.traj[:, 1] - res.traj[:, 3]) < 1e-12
    sticking = contact & (np.abs(s) < 1e-12)
    assert sticking.sum() > 1000 and (contact & ~sticking).sum() > 1000
    margin = np.abs(alpha + r * load) - r * n_load
    assert margin[sticking].max() <= 1e-9
    # slipping samples: the finite-difference acceleration is −σN − τ_L
    slipping = contact & ~sticking
    k = np.flatnonzero(slipping[1:-1] & slipping[:-2] & slipping[2:]) + 1
    k = k[np.sign(s[k - 1]) == np.sign(s[k + 1])]
    acc = (om[k + 1] - om[k - 1]) / (t[k + 1] - t[k - 1])
    assert np.allclose(acc, -np.sign(s[k]) * n_load[k] - load, atol=1e-4)


def test_flight_under_load_decelerates_linearly():
    """In flight Ω' = −τ_L exactly (no friction in the air)."""
    res = simulate_arrays(_cfg(e=0.6, t_end=40.0, traj_dt=1e-2, load_torque=0.3))
    t, u, us, om = res.traj[:, 0], res.traj[:, 1], res.traj[:, 3], res.traj[:, 4]
    fly = u - us > 1e-6
    k = np.flatnonzero(fly[:-1] & fly[1:])
    # consecutive flight samples with no impact between them
    imp = res.events["t"]
    between = np.searchsorted(imp, t[k]) == np.searchsorted(imp, t[k + 1])
    k = k[between]
    assert len(k) > 500
    slope = (om[k + 1] - om[k]) / (t[k + 1] - t[k])
    assert np.allclose(slope, -0.3, atol=1e-9)


def test_zero_load_gives_the_same_numbers_as_no_load():
    """Effect ``load`` with τ_L = 0 is bit-identical to the same scene without it."""
    a = simulate_arrays(_cfg(e=0.6, t_end=3000.0, traj_dt=0.5, stats_from=0.0))
    b = simulate_arrays(_cfg(e=0.6, t_end=3000.0, traj_dt=0.5, stats_from=0.0, load_torque=0.0))
    for key in a.events:
        assert a.events[key].tobytes() == b.events[key].tobytes(), key
    assert a.traj.tobytes() == b.traj.tobytes()
    assert a.final == b.final


def test_scene_with_load_zero_equals_scene_without(tmp_path):
    raw = {
        "parameters": {"e": 0.3, "omega_s": 1.5, "r_phi": 0.01, "psi": 0.0},
        "effects": ["impacts", "contact", "torsion"],
        "stop": {"impacts": 500},
    }
    outs = []
    for with_load in (False, True):
        r = json.loads(json.dumps(raw))
        if with_load:
            r["effects"].append("load")
            r["parameters"]["load_torque"] = 0.0
        path = tmp_path / f"s{int(with_load)}.yaml"
        import yaml

        path.write_text(yaml.safe_dump(r))
        out = tmp_path / f"o{int(with_load)}.nc"
        assert main(["simulate", str(path), "-o", str(out), "-q"]) == 0
        outs.append(xr.open_dataset(out))
    for name in ("t_impact", "phase", "v_rel", "omega_after"):
        assert outs[0][name].values.tobytes() == outs[1][name].values.tobytes()


# --- the energy audit closes to round-off in every regime -------------------------------------

REGIMES = {
    # name: engine settings; 10^6 events, or a time stop where the rotor never leaves
    "periodic e=0.3": dict(e=0.3, psi=0.0, max_events=10**6),
    "chaotic with chatter e=0.6": dict(e=0.6, psi=0.0, max_events=10**6),
    "e=0 stick-slip": dict(e=0.0, max_events=10**6),
    "w<=1 permanent contact": dict(e=0.5, omega_s=0.9, t_end=2.0e5),
    "e=1": dict(e=1.0, max_events=10**6),
    "kinetic-static, finite stator inertia": dict(
        e=0.4, mu_ratio=1.3, inertia_ratio=5.0, max_events=3 * 10**5
    ),
}


@pytest.mark.slow
@pytest.mark.parametrize("load", [0.0, 0.3])
@pytest.mark.parametrize("regime", sorted(REGIMES))
def test_energy_audit_closes_to_round_off(regime, load):
    """docs/model.md "Power and energy audit": both balances close to ≤ 1e-9 relative over 10⁶
    events (flights, slips, sticks, impacts, chattering tails)."""
    res = simulate_arrays(_cfg(stats_from=0.0, load_torque=load, **REGIMES[regime]))
    assert res.ok
    terms = res.final["audit"]
    ax, tor = audit_balances(terms)
    assert ax <= 1e-9 and tor <= 1e-9, (ax, tor, terms)
    assert terms["work_torsion"] != 0.0
    if load:
        assert terms["work_load"] != 0.0
    if REGIMES[regime].get("omega_s", W) > 1.0 and REGIMES[regime]["e"] < 1.0:
        assert terms["loss_axial"] > 0.0  # impacts dissipate


def test_audit_catches_a_wrong_term():
    """The residual is not zero by construction: a 1e-6 error in one term shows."""
    res = simulate_arrays(_cfg(e=0.6, psi=0.0, max_events=20000, stats_from=0.0, load_torque=0.2))
    terms = dict(res.final["audit"])
    terms["loss_friction"] *= 1.0 + 1e-6
    terms["loss_axial"] *= 1.0 + 1e-6
    ax, tor = audit_balances(terms)
    assert ax > 1e-8 and tor > 1e-8


def test_a_window_of_free_flight_audits_to_round_off_not_to_one():
    """omega_s = 1000 launches the rotor on a flight of about 2000 time units: the window
    300-1500 holds no impact, no work and no loss, and its energy change is the round-off of
    two energies near 5e5. Measured against the largest term alone (that round-off), the
    residual read 1; against the energies too, round-off. A planted error of 1e-6 in the change
    still shows."""
    res = simulate_arrays(_cfg(e=0.6, omega_s=1000.0, t_end=1500.0, stats_from=300.0))
    assert res.ok and not res.final["in_contact"] and len(res.events["t"]) <= 1  # in flight
    terms = dict(res.final["audit"])
    assert terms["work_axial"] == terms["loss_axial"] == 0.0
    assert terms["energy_axial_level"] == pytest.approx(0.5 * 1000.0**2 * 1.0, rel=0.5)
    ax, tor = audit_balances(terms)
    assert ax <= 1e-12 and tor == 0.0, (ax, terms)
    terms["energy_axial_change"] += 1e-6 * terms["energy_axial_level"]
    assert audit_balances(terms)[0] == pytest.approx(1e-6, rel=1e-3)


def test_audit_window_starts_inside_a_segment():
    """An audit from t = 1234.5 (inside some flight or contact) closes as well as from 0."""
    res = simulate_arrays(_cfg(e=0.6, psi=0.0, t_end=20000.0, stats_from=1234.5, load_torque=0.2))
    ax, tor = audit_balances(res.final["audit"])
    assert ax <= 1e-9 and tor <= 1e-9


# --- the momentum bound: the mean friction torque is at most 1 --------------------------------


@pytest.mark.parametrize("load", [1.2, 1.5])
def test_a_load_above_one_runs_away_backwards(load):
    """Mean N = 1 (momentum balance), so |mean friction torque| <= 1: with τ_L > 1 the rotor
    decelerates at least at τ_L − 1 on average and runs away backwards."""
    t_end = 20000.0
    res = simulate_arrays(_cfg(e=0.6, psi=0.0, t_end=t_end, load_torque=load))
    mean_friction = (res.final["omega"] - 0.0) / t_end + load
    assert abs(mean_friction) <= 1.0 + 1e-3
    assert res.final["omega"] < -(load - 1.0) * t_end * 0.9


# --- torque–speed curves ---------------------------------------------------------------------


def test_first_zero_and_peak_closed_forms():
    loads = np.linspace(0.0, 1.0, 11)
    assert first_zero(loads, 2.0 - 3.0 * loads) == pytest.approx(2.0 / 3.0)
    assert math.isnan(first_zero(loads, 1.0 + loads))
    # running backwards at no load has no stall torque (not "stall torque 0")
    assert math.isnan(first_zero(loads, -1.0 - loads))
    p, at = peak(loads, 5.0 - 20.0 * (loads - 0.4) ** 2)
    assert p == pytest.approx(5.0) and at == pytest.approx(0.4)
    # a collapse past the peak: no parabola overshooting the samples
    p, at = peak(np.array([0.0, 0.4, 0.8, 1.2]), np.array([0.0, 17.8, 34.4, -387.5]))
    assert (p, at) == (34.4, 0.8)


def _stats_scene(**over):
    raw = {
        "name": "loadcurve",
        "parameters": {"e": 0.6, "omega_s": 1.5, "r_phi": 0.01, "psi": 0.0, "e_sigma": 1e-9},
        "effects": ["impacts", "contact", "torsion", "restitution_noise", "load"],
        "stop": {"time": 3000.0},
        "stats": {"discard": 500.0},
        "ensemble": {"members": 6, "seed": 3},
    }
    raw["parameters"]["load_torque"] = 0.0
    raw.update(over)
    return scene_from_mapping(raw, "<test>")


def test_torque_speed_curve_falls_with_load_and_does_not_depend_on_cores():
    scene = _stats_scene()
    loads = [0.0, 0.2, 0.4, 0.6, 0.8]
    one = torque_speed(scene, loads, cores=1).summary()
    two = torque_speed(scene, loads, cores=2).summary()
    assert json.dumps(one) == json.dumps(two)
    speed = one["mean_omega"]
    assert all(a > b for a, b in zip(speed, speed[1:], strict=False))
    assert 0.0 < one["stall_torque"] < 1.0  # the momentum bound
    lo, hi = one["stall_torque_ci95"]
    assert lo <= one["stall_torque"] <= hi
    # the maximum power is the largest sampled mean power, at its load (no interpolation)
    k = int(np.argmax(one["power_out"]))
    assert one["max_power"] == pytest.approx(one["power_out"][k], rel=1e-14)
    assert one["max_power_load"] == loads[k] and 0.0 < loads[k] < loads[-1]
    assert max(one["audit_residual_torsion"]) <= 1e-9
    assert max(one["audit_residual_axial"]) <= 1e-9
    # output power is τ_L Ω̄ exactly, per load
    for load, p, om in zip(loads, one["power_out"], speed, strict=True):
        assert p == pytest.approx(load * om, rel=1e-12, abs=1e-12)
    assert one["down"]["mean_omega"][0] == pytest.approx(speed[0], rel=0.1)


def test_physical_load_torque_is_scaled_by_the_friction_torque():
    phys = PhysicalParameters(
        m_r=0.01,
        r_g=0.004,
        r_c=0.002,
        mu=0.3,
        e=0.5,
        g=9.81,
        f=15e3,
        U0=1e-6,
        Phi0=1e-4,
        F_preload=0.5,
        load_torque=2e-5,
    )
    g_eff = 9.81 + 0.5 / 0.01
    scale = 0.3 * 0.01 * g_eff * (2.0 * 0.002 / 3.0)
    assert phys.scales().torque == pytest.approx(scale, rel=1e-14)
    assert phys.to_nondimensional().load_torque == pytest.approx(2e-5 / scale, rel=1e-14)
    sc = phys.scales()
    assert sc.torsion_power == pytest.approx(sc.torque * sc.omega_scale)


def test_parse_loads():
    assert np.allclose(parse_loads("0:1:5"), [0, 0.25, 0.5, 0.75, 1.0])
    assert np.allclose(parse_loads("0.5, 0.1,0"), [0.0, 0.1, 0.5])


# --- bad input: one line, exit 2, nothing written ---------------------------------------------

SCENE = """\
parameters: {{e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0, e_sigma: 1.0e-9{extra}}}
effects: [{effects}]
stop: {{time: 1000.0}}
ensemble: {{members: 2, seed: 1}}
"""
FULL = "impacts, contact, torsion, restitution_noise, load"


@pytest.mark.parametrize(
    "extra, effects, field",
    [
        (", load_torque: -0.2", FULL, "parameters.load_torque"),
        (", load_torque: .nan", FULL, "parameters.load_torque"),
        (", load_torque: heavy", FULL, "parameters.load_torque"),
        # past the bound torque-speed's loads keep (a hundred times tau_L = 1): overflow, not data
        (", load_torque: 1.0e+6", FULL, "parameters.load_torque: must be in [0, 100] friction"),
        ("", FULL, "parameters.load_torque"),
        (", load_torque: 0.2", "impacts, contact, torsion, restitution_noise", "load_torque"),
        (", load_torque: 0.2", "impacts, contact, restitution_noise, load", "effects.load"),
    ],
)
def test_bad_load_input_is_one_line_exit_2_and_no_output(
    extra, effects, field, scene_file, tmp_path, capsys
):
    f = scene_file(SCENE.format(extra=extra, effects=effects))
    for cmd in (["simulate", str(f), "-o"], ["stats", str(f), "-o"]):
        out = tmp_path / "out.nc"
        assert main([*cmd, str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and field in err[0] and str(f) in err[0], err
        assert not out.exists()


@pytest.mark.parametrize("loads", ["1:0:3", "a,b", "0:1:1", "0,0.1,0.1", "nan,1", "=-1,2", "0:1"])
def test_bad_loads_option(loads, scene_file, tmp_path, capsys):
    f = scene_file(SCENE.format(extra=", load_torque: 0.0", effects=FULL))
    out = tmp_path / "c.nc"
    opt = ["--loads" + loads] if loads.startswith("=") else ["--loads", loads]
    assert main(["torque-speed", str(f), *opt, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--loads" in err[0]
    assert not out.exists()


def test_torque_speed_command_writes_a_curve_file(scene_file, tmp_path, capsys):
    """The command adds the load effect itself, writes the file and prints JSON: the members in
    the file are those of the curve run directly on the scene with the load effect, the file's
    means and intervals are the members' Student statistics, and power is ``τ_L Ω̄``."""
    from scipy import stats as sps

    from bouncedisk.model.scene import load_scene

    f = scene_file(SCENE.format(extra="", effects="impacts, contact, torsion, restitution_noise"))
    out = tmp_path / "c.nc"
    loads = [0.0, 0.3, 0.9]
    args = [
        "torque-speed",
        str(f),
        "--loads",
        "0,0.3,0.9",
        "-o",
        str(out),
        "--json",
        "-q",
        "--resolution",
        "0",
    ]  # the loads as given: the curve below, unrefined
    assert main(args) == 0
    summary = json.loads(capsys.readouterr().out)
    on = [
        "effects=[impacts, contact, torsion, restitution_noise, load]",
        "parameters.load_torque=0",
    ]
    direct = torque_speed(load_scene(f, on), loads, cores=1)
    assert summary == json.loads(json.dumps(direct.summary()))
    ds = open_checked(out)  # the labels "branch" are a CF label on "branch_index" in the file
    assert list(ds.branch.values) == ["up", "down"] and list(ds.load_torque.values) == loads
    for branch in ("up", "down"):
        om = direct.matrix(branch, "mean_omega")  # (member, load)
        assert om.shape == (2, 3) and np.ptp(om[:, 0]) > 0  # two members that differ
        got = ds.sel(branch=branch)
        assert np.array_equal(got.mean_omega_member.values, om.T)
        power = got.power_out_member.values
        assert np.allclose(power, np.array(loads)[:, None] * om.T, rtol=1e-12, atol=1e-15)
        half = sps.t.ppf(0.975, 1) * om.std(axis=0, ddof=1) / np.sqrt(2)
        mean = om.mean(axis=0)
        assert np.allclose(got.mean_omega.values, mean, rtol=1e-15, atol=0)
        assert np.allclose(got.mean_omega_ci95_low.values, mean - half, rtol=1e-13, atol=0)
        assert np.allclose(got.mean_omega_ci95_high.values, mean + half, rtol=1e-13, atol=0)
    assert ds.attrs["no_load_speed"] == summary["no_load_speed"]
    assert list(ds.attrs["no_load_speed_ci95"]) == summary["no_load_speed_ci95"]
    for name in ds.variables:
        assert "units" in ds[name].attrs or name == "branch"


def test_clipped_model_takes_the_load():
    """The clipped spring-contact model takes the load too: where N is clipped to 0 the rotor
    decelerates at −τ_L, and the torsional balance closes (no axial balance there)."""
    cfg = _cfg(e=0.6, psi=0.0, clipped=True, t_end=400.0, stats_from=0.0, load_torque=0.3)
    res = simulate_arrays(dataclasses.replace(cfg, traj_dt=0.01))
    ax, tor = audit_balances(res.final["audit"])
    assert math.isnan(ax) and tor <= 1e-9
    t, om = res.traj[:, 0], res.traj[:, 4]
    ph = np.mod(W * t, 2 * math.pi)
    th_sep = math.asin(1.0 / (W * W))
    free = (ph > th_sep + 0.01) & (ph < math.pi - th_sep - 0.01)
    k = np.flatnonzero(free[:-1] & free[1:])
    slope = (om[k + 1] - om[k]) / (t[k + 1] - t[k])
    assert len(k) > 100 and np.allclose(slope, -0.3, atol=1e-9)


# --- measured load curves (docs/formats.md): the shipped synthetic one and bad files ------------


def test_shipped_synthetic_load_curve_is_regenerated_byte_for_byte(tmp_path):
    import yaml

    from bouncedisk.fitting.synthetic import synthetic_load_curve
    from bouncedisk.io.runup_curves import write_curve

    root = Path(__file__).resolve().parents[1]
    spec = yaml.safe_load((root / "workflow/config/synthetic_motor.yaml").read_text())
    df, sidecar = synthetic_load_curve(spec)
    write_curve(df, tmp_path / "synthetic_motor_load.csv", sidecar)
    for name in ("synthetic_motor_load.csv", "synthetic_motor_load.yaml"):
        shipped = (root / "data/prototype" / name).read_bytes()
        assert (tmp_path / name).read_bytes() == shipped, name
    data = read_load_curve(root / "data/prototype/synthetic_motor_load.csv")
    assert data.synthetic and data.window_s == (0.06, 0.12)
    # from no load to past stall: the speed changes sign once
    assert data.speed[0] > 0 > data.speed[-1]


LOAD_CSV = "torque_Nm,speed_rad_s,speed_sd_rad_s\n0,20,0.3\n1e-4,14,0.5\n2e-4,0.6,0.5\n"
LOAD_YAML = """\
units: {torque: N m, speed: rad/s}
motor: {drive_frequency_hz: 20000.0, Phi0_rad: 2.0e-4}
rotor: {m_r_kg: 0.01, r_g_m: 0.004, r_c_m: 0.002}
window_s: [0.06, 0.12]
"""


@pytest.mark.parametrize(
    "csv, yaml_text, field",
    [
        (LOAD_CSV.replace("1e-4,14", "1e-4,fast"), LOAD_YAML, "speed_rad_s: row 3"),
        (LOAD_CSV.replace("1e-4,14", "1e-4,nan"), LOAD_YAML, "speed_rad_s: row 3"),
        (LOAD_CSV.replace("1e-4,14", "-1e-4,14"), LOAD_YAML, "torque_Nm: row 3"),
        (LOAD_CSV.replace("2e-4,0.6", "1e-4,0.6"), LOAD_YAML, "torque_Nm: row 4"),
        (LOAD_CSV.replace("speed_rad_s,", "omega,"), LOAD_YAML, "speed_rad_s"),
        (LOAD_CSV, LOAD_YAML.replace(" r_c_m: 0.002", " r_x: 0.002"), "rotor.r_x"),
        (LOAD_CSV, LOAD_YAML.replace(", r_c_m: 0.002", ""), "rotor.r_c_m"),
        (LOAD_CSV, LOAD_YAML.replace("[0.06, 0.12]", "[0.12, 0.06]"), "window_s"),
        (LOAD_CSV, LOAD_YAML.replace("rotor:", "rotr:"), "rotr"),
        (LOAD_CSV.replace("0,20,0.3", "0,20,-0.3"), LOAD_YAML, "speed_sd_rad_s: row 2"),
        # a row is the file's line: comment and blank lines above it counted
        (
            "# brake run\n" + LOAD_CSV.replace("1e-4,14", "1e-4,nan"),
            LOAD_YAML,
            "speed_rad_s: row 4",
        ),
        (LOAD_CSV.replace("\n1e-4,14", "\n\n# x\n-1e-4,14"), LOAD_YAML, "torque_Nm: row 5"),
        (LOAD_CSV.replace("\n2e-4", "\n# x\n1e-4"), LOAD_YAML, "torque_Nm: row 5"),
        (
            "\ufeff# rig\n" + LOAD_CSV.replace("1e-4,14", "1e-4,nan"),
            LOAD_YAML,
            "speed_rad_s: row 4",
        ),
        # an indented comment is a row of pandas' own, with no numbers: the line to mend
        (LOAD_CSV.replace("\n1e-4,14", "\n  # x\n1e-4,14"), LOAD_YAML, "torque_Nm: row 3: missing"),
    ],
)
def test_bad_load_curve_names_file_row_and_column(csv, yaml_text, field, tmp_path):
    from bouncedisk.model.errors import InputError

    (tmp_path / "load.csv").write_text(csv)
    (tmp_path / "load.yaml").write_text(yaml_text)
    with pytest.raises(InputError) as ex:
        read_load_curve(tmp_path / "load.csv")
    line = ex.value.line()
    assert field in line and "load." in line and "\n" not in line


def test_a_condition_converts_the_point_by_the_physical_scales():
    """:func:`loadpart.convert` (docs/model.md "Physical conversion", U0, mu, e, psi held):
    omega_s = 2 pi f t_c with t_c = sqrt(U0 / g_eff), g_eff = g + F / m_r, and
    R_phi = mu U0 r_eff / (r_g^2 Phi0) with r_eff = 2 r_c / 3; there and back is the identity."""
    import math

    from bouncedisk.fitting.loadpart import Setup, convert

    rotor = {"m_r_kg": 0.01, "r_g_m": 0.004, "r_c_m": 0.002}
    a = Setup(20000.0, 2e-4, rotor, 0.77)
    theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}

    def moved(**change):
        b = a._replace(**{k: v for k, v in change.items() if k != "rotor"})
        b = b._replace(rotor={**rotor, **change.get("rotor", {})})
        out = convert(theta, a, b)
        back = convert(out, b, a)
        assert back["omega_s"] == pytest.approx(1.7, rel=1e-12)
        assert back["log10_r_phi"] == pytest.approx(theta["log10_r_phi"], abs=1e-12)
        assert (out["e"], out["psi"]) == (0.55, 0.4)
        return out["omega_s"] / 1.7, 10 ** (out["log10_r_phi"] - theta["log10_r_phi"])

    assert convert(theta, a, a) is theta
    assert moved(f=30000.0) == pytest.approx((1.5, 1.0))
    assert moved(phi0=4e-4) == pytest.approx((1.0, 0.5))
    assert moved(rotor={"r_g_m": 0.008}) == pytest.approx((1.0, 0.25))
    assert moved(rotor={"r_c_m": 0.003}) == pytest.approx((1.0, 1.5))
    g = 9.81
    ratio = math.sqrt((g + 0.77 / 0.01) / (g + 2.0 / 0.01))  # t_c shrinks as g_eff grows
    assert moved(preload=2.0) == pytest.approx((ratio, 1.0))
    assert moved(rotor={"m_r_kg": 0.02}) == pytest.approx(
        (math.sqrt((g + 0.77 / 0.01) / (g + 0.77 / 0.02)), 1.0)
    )


def test_the_reference_condition_does_not_hang_on_the_order_of_the_curves(tmp_path):
    """The reference rotor and preload are those of the load curves at the run-ups' drive and
    Phi0, whatever the order; two such curves that disagree are one line naming the field."""
    import dataclasses

    from bouncedisk.fitting.loadpart import reference_setup
    from bouncedisk.model.errors import InputError

    (tmp_path / "load.csv").write_text(LOAD_CSV)
    (tmp_path / "load.yaml").write_text(LOAD_YAML)
    base = read_load_curve(tmp_path / "load.csv")
    heavy = {**base.rotor, "r_g_m": 0.006}
    other = dataclasses.replace(base, drive_frequency_hz=14000.0, rotor=heavy, preload_n=2.0)
    for curves in ([base, other], [other, base]):
        ref = reference_setup(curves, 20000.0, 2e-4)
        assert ref == (20000.0, 2e-4, base.rotor, base.preload_n, None)  # no amplitude stated
    # no curve at the run-ups' drive: every curve's, which must agree
    assert reference_setup([other], 20000.0, 2e-4).rotor == heavy
    clash = dataclasses.replace(base, rotor=heavy, path=str(tmp_path / "clash.csv"))
    with pytest.raises(InputError, match="clash.yaml: rotor: differs from") as ex:
        reference_setup([base, clash], 20000.0, 2e-4)
    assert "\n" not in ex.value.line()


def test_simulation_files_carry_the_energy_audit(scene_file, tmp_path):
    """Every simulated run records its audit (per run, docs/model.md): residuals and terms."""
    f = scene_file(
        "parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0, load_torque: 0.2}\n"
        "effects: [impacts, contact, torsion, load]\nstop: {impacts: 3000}\n"
    )
    out = tmp_path / "s.nc"
    assert main(["simulate", str(f), "-o", str(out), "-q"]) == 0
    a = xr.open_dataset(out).attrs
    assert a["audit_residual_axial"] <= 1e-9 and a["audit_residual_torsion"] <= 1e-9
    assert a["audit_work_load"] > 0.0 and a["load_torque"] == 0.2


def test_physical_scene_reports_watts_and_the_motor_efficiency():
    """A physical scene's stats add the speed in rad/s, the powers in W and
    η = P_out / (P_ax + P_t), each with its interval."""
    from bouncedisk.analysis.statistics import run_stats
    from bouncedisk.model.params import Parameters

    phys = PhysicalParameters.from_nondimensional(
        Parameters(e=0.55, omega_s=1.7, r_phi=0.002, psi=0.4),
        20000.0, 2e-4, 0.01, 0.004, 0.002, F_preload=0.77, load_torque=5e-5,
    )  # fmt: skip
    raw = {
        "physical": {**phys.as_dict(), "e_sigma": 0.03},
        "effects": ["impacts", "contact", "torsion", "restitution_noise", "load"],
        "stop": {"time": 4000.0},
        "stats": {"discard": 1000.0},
        "ensemble": {"members": 4, "seed": 1},
    }
    scene = scene_from_mapping(raw, "<physical>")
    s = run_stats(scene).summary()
    sc = phys.scales()
    assert s["mean_omega_rad_s"] == pytest.approx(s["mean_omega"] * sc.omega_scale)
    low, high = s["mean_omega_rad_s_ci95"]  # the interval in rad/s too, around its mean
    assert low < s["mean_omega_rad_s"] < high
    assert low == pytest.approx(s["mean_omega_ci95"][0] * sc.omega_scale)
    assert s["power_out_W"] == pytest.approx(s["power_out"] * sc.torque * sc.omega_scale)
    assert s["power_axial_in_W"] == pytest.approx(s["power_axial_in"] * sc.axial_power)
    eta = s["power_out_W"] / (s["power_out_W"] / s["efficiency_torsion"] + s["power_axial_in_W"])
    assert s["efficiency"] == pytest.approx(eta, rel=0.05)  # mean of ratios vs ratio of means
    assert 0.0 < s["efficiency"] < s["efficiency_torsion"] < 1.0


@settings(max_examples=40)
@given(
    e=st.floats(0.0, 1.0),
    w=st.floats(0.5, 6.0),
    log_r=st.floats(-3.0, 0.5),
    psi=st.floats(-math.pi, math.pi),
    load=st.floats(0.0, 2.0),
    rho=st.floats(1.0, 1.5),
)
def test_audit_closes_for_any_parameters(e, w, log_r, psi, load, rho):
    """Property: both balances close to round-off for any (e, ω_s, R_φ, ψ, τ_L, μ_s/μ_k)."""
    cfg = EngineConfig(
        e=e, omega_s=w, r_phi=10.0**log_r, psi=psi, torsion=True, mu_ratio=rho,
        max_events=3000, t_end=3000.0, stats_from=0.0, load_torque=load,
    )  # fmt: skip
    res = simulate_arrays(cfg)
    ax, tor = audit_balances(res.final["audit"])
    assert ax <= 1e-9 and tor <= 1e-9, (ax, tor)


def test_a_curve_of_the_other_kind_is_told_how_to_give_it(tmp_path, capsys):
    """A load curve given as a run-up, or a run-up's sidecar key in a load curve's: the one line
    names the key, says which kind of curve it belongs to and how ``fit`` takes that kind."""
    from bouncedisk.model.errors import InputError

    (tmp_path / "load.csv").write_text(LOAD_CSV)
    (tmp_path / "load.yaml").write_text(LOAD_YAML)
    assert main(["fit", str(tmp_path / "load.csv"), "-o", str(tmp_path / "f.nc"), "-q"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "load.yaml: rotor: unknown key" in line
    assert line.endswith("it is a load curve's key: give that curve after a --load")
    (tmp_path / "load.yaml").write_text(LOAD_YAML + "noise_sigma_rad_s: 0.1\n")
    with pytest.raises(InputError, match="it is a run-up's key: give that curve before the op"):
        read_load_curve(tmp_path / "load.csv")
    # a key neither kind knows: no hint
    (tmp_path / "load.yaml").write_text(LOAD_YAML + "rotr: 1\n")
    with pytest.raises(InputError, match=r"rotr: unknown key \(known: [^)]*\)$"):
        read_load_curve(tmp_path / "load.csv")
