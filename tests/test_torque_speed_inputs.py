"""``bouncedisk torque-speed``: the scene the user gave, honest intervals at the edges, loads in
the scene's units, and no traceback from any load (docs/user_guide/load.md)."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import netCDF4
import numpy as np
import pytest
from cli_helpers import SMALL_MOTOR, one_line, scene_file
from hypothesis import given, settings
from hypothesis import strategies as st

from bouncedisk.cli import main
from bouncedisk.cli.torque_speed import format_curve
from bouncedisk.model.scene import load_scene, scene_from_mapping
from bouncedisk.studies.torque_speed import (
    DEFAULT_LOADS,
    derived,
    parse_loads,
    scene_loads,
    torque_speed,
    with_load,
)

SMALL = SMALL_MOTOR
PHYSICAL = """
name: phys
physical: {m_r: 0.01, r_g: 0.004, r_c: 0.001, mu: 0.2, e: 0.5, g: 9.81, f: 2.0e+2, U0: 1.0e-4,
  Phi0: 1.0e-3, e_sigma: 1.0e-9}
effects: [impacts, contact, torsion, restitution_noise]
stop: {time: 60.0}
ensemble: {members: 2, seed: 1}
stats: {discard: 10.0}
"""


def _file(folder: Path, text: str = SMALL, name: str = "small.yaml") -> str:
    return scene_file(folder, text, name)


def _json(capsys) -> dict:
    def refuse(name):
        raise AssertionError(f"not JSON: {name}")

    return json.loads(capsys.readouterr().out, parse_constant=refuse)


# ------------------------------------------------ the user's effects, in every form
def test_set_effects_reach_the_curve(tmp_path, capsys):
    """Before: the file's own effects were appended after the user's --set, so kinetic_static
    and mu_ratio were lost."""
    out = tmp_path / "c.nc"
    args = ["torque-speed", _file(tmp_path), "--loads", "0,0.5", "-q", "-o", str(out)]
    args += ["--set", "effects=impacts,contact,torsion,restitution_noise,kinetic_static"]
    args += ["--set", "parameters.mu_ratio=1.5", "--set", "stop.time=60"]
    assert main(args) == 0
    with netCDF4.Dataset(out) as ds:
        assert "kinetic_static" in ds.getncattr("effects").split(",")
        assert ds.getncattr("mu_ratio") == 1.5


def test_removing_torsion_by_set_is_honoured(tmp_path, capsys):
    """Before: the file's torsion came back; a curve without torsion is refused."""
    args = ["torque-speed", _file(tmp_path), "--loads", "0,0.5"]
    assert main([*args, "--set", "effects=impacts,contact,restitution_noise"]) == 2
    assert "effects (from --set effects): a load curve needs the 'torsion'" in one_line(capsys)


@pytest.mark.parametrize(
    "effects",
    [
        "{impacts: true, contact: true, torsion: true, restitution_noise: true}",
        "'impacts, contact, torsion, restitution_noise'",
    ],
)
def test_documented_effects_forms_run(tmp_path, capsys, effects):
    """Before: "needs the 'load' effect (from --set parameters.load_torque)" with no --set."""
    text = SMALL.replace(
        "effects: [impacts, contact, torsion, restitution_noise]", f"effects: {effects}"
    )
    text = text.replace("time: 200.0", "time: 60.0").replace("discard: 50.0", "discard: 10.0")
    assert main(["torque-speed", _file(tmp_path, text), "--loads", "0,0.5", "--json"]) == 0
    assert len(_json(capsys)["mean_omega"]) == 2


OPTIONAL = {
    "kinetic_static": "parameters.mu_ratio=1.7",
    "stator_inertia": "parameters.inertia_ratio=30",
}


@settings(max_examples=12, deadline=None)
@given(
    chosen=st.sets(st.sampled_from(sorted(OPTIONAL))),
    cap=st.booleans(),
    form=st.sampled_from(["list", "string", "mapping"]),
)
def test_property_the_curve_runs_the_users_effects(chosen, cap, form):
    """Over random effect sets in every documented form: the curve's scene has exactly the
    user's effects plus ``load``, and the numbers are those of that scene."""
    effects = ["impacts", "contact", "torsion", "restitution_noise", *sorted(chosen)]
    if form == "list":
        value = "[" + ",".join(effects) + "]"
    elif form == "string":
        value = ",".join(effects)
    else:
        value = "{" + ", ".join(f"{k}: true" for k in effects) + ", impulse_cap: " + str(cap) + "}"
    sets = [f"effects={value}", "stop.time=40", "stats.discard=10"]
    sets += [OPTIONAL[k] for k in sorted(chosen)]
    with tempfile.TemporaryDirectory() as d:
        scene = with_load(load_scene(_file(d), sets))
    want = set(effects) | {"load"}
    if form != "mapping" or cap:
        want.add("impulse_cap")
    assert set(scene.effects) == want
    assert scene.raw["parameters"]["load_torque"] == 0.0
    assert scene_from_mapping(scene.raw, scene.source).effects == scene.effects
    curve = torque_speed(scene, [0.0, 0.5], branches=("up",))
    assert np.isfinite(curve.matrix("up", "mean_omega")).all()


# ------------------------------------------------------- honest intervals at the edges
def test_one_member_has_no_intervals(tmp_path, capsys):
    """Before: stall_torque_ci95 [0.7394, 0.7394] from 2,000 resamples of one member."""
    args = ["torque-speed", _file(tmp_path), "--set", "ensemble.members=1", "--loads", "0:1:6"]
    assert main([*args, "--json"]) == 0
    s = _json(capsys)
    assert s["stall_torque"] is not None
    for name in ("no_load_speed", "stall_torque", "max_power", "max_power_load"):
        assert s[f"{name}_ci95"] == [None, None], name


def test_stall_below_the_smallest_load_is_unknown(tmp_path, capsys):
    """Before: `--loads 1.5,2` (speed already -79.6 at 1.5) reported stall_torque 1.5 [1.5, 1.5]."""
    assert main(["torque-speed", _file(tmp_path), "--loads", "1.5,2", "--json"]) == 0
    s = _json(capsys)
    assert s["mean_omega"][0] < 0
    assert s["stall_torque"] is None and s["stall_torque_ci95"] == [None, None]


def test_table_says_why_a_derived_value_is_missing():
    s = {
        "loads": [1.5, 2.0],
        "mean_omega": [-79.6, -255.0],
        "mean_omega_ci95": [[-135.0, -23.0], [None, None]],
        "power_out": [-119.0, None],
        "efficiency_torsion": [None, -9.2],
    }
    for k in ("no_load_speed", "stall_torque", "max_power", "max_power_load"):
        s[k], s[f"{k}_ci95"] = None, [None, None]
    s["stall_torque_state"], s["max_power_state"] = "below_smallest_load", "at_smallest_load"
    table = format_curve(s)
    assert "no_load_speed: n/a (the loads do not include 0)" in table
    assert "stall_torque: n/a (below_smallest_load: the mean speed is <= 0 already" in table
    assert "max_power: n/a (at_smallest_load: the power is largest at the smallest load" in table
    assert "speed stays positive" not in table
    assert table.splitlines()[0].endswith("eff. drive")  # W_L / W_t, a nondimensional scene's


@settings(max_examples=20, deadline=None)
@given(
    members=st.integers(1, 5),
    steps=st.lists(st.floats(0.05, 1.0), min_size=2, max_size=6),
    start=st.sampled_from([0.0, 0.3]),
    data=st.data(),
)
def test_property_derived_quantities_are_honest(members, steps, start, data):
    """Over random curves: one member gives no interval; the stall torque is a zero crossing
    between two loads of the grid, never the first load of a grid that starts past the stall
    (nor 0 for a motor that turns backwards with no load); no interval is reversed."""
    loads = start + np.cumsum([0.0, *steps[1:]])
    n = len(loads)
    values = st.floats(-50.0, 50.0, allow_nan=False)
    speed = np.array(data.draw(st.lists(st.lists(values, min_size=n, max_size=n),
                                        min_size=members, max_size=members)))  # fmt: skip
    power = speed * loads
    out = derived(loads, speed, power)
    mean = speed.mean(axis=0)
    if members == 1:
        assert all(out[f"{k}_ci95"] == [None, None] for k in ("stall_torque", "max_power"))
        assert out["max_power_load_ci95"] == [None, None]
    st_ = out["stall_torque"]
    if mean[0] <= 0:  # no stall torque: the motor turns backwards, or stalls below the loads
        assert st_ is None
        want = "backwards_at_no_load" if loads[0] == 0.0 else "below_smallest_load"
        assert out["stall_torque_state"] == want
    elif st_ is not None:
        k = int(np.argmax(mean <= 0))
        assert mean[k] <= 0 < mean[k - 1]
        assert loads[k - 1] <= st_ <= loads[k]
    else:
        assert (mean > 0).all()
    for k in ("stall_torque", "max_power", "max_power_load"):
        lo, hi = out[f"{k}_ci95"]
        if lo is not None and hi is not None and out[k] is not None and members > 1:
            assert lo <= hi


# ----------------------------------------------------- loads in the scene's units
@pytest.mark.parametrize(
    "loads,extra",
    [
        ("1e300,0", []),
        ("0:1e300:3", []),
        ("0,0.5", ["--set", "initial.omega=1e308"]),
        ("", []),
    ],
)
def test_hostile_loads_are_one_line(tmp_path, capsys, loads, extra):
    """Before: TypeError in format_curve, "All-NaN slice" in peak, and `--loads ""` ran the
    default loads."""
    out = tmp_path / "c.nc"
    args = ["torque-speed", _file(tmp_path), "--loads", loads, "-o", str(out), *extra]
    assert main(args) == 2
    line = one_line(capsys)
    assert ("--loads" in line) or ("initial.omega" in line)
    assert not out.exists()
    assert main([*args, "--json"]) == 2


def test_physical_overflowing_load_is_one_line(tmp_path, capsys):
    """Before: the table crashed and --json printed Infinity with exit 0."""
    args = ["torque-speed", _file(tmp_path, PHYSICAL, "p.yaml"), "--loads", "0,1e305", "--json"]
    assert main(args) == 2
    assert "the largest load is 1e+305 N m; loads must be at most 0.001308 N m" in one_line(capsys)


def test_physical_default_loads_are_nondimensional(tmp_path, capsys):
    """Before: the default 0:1:11 was read as N·m (tau_L up to 25,484 here, no power)."""
    scene = with_load(load_scene(_file(tmp_path, PHYSICAL, "p.yaml")))
    torque = scene.physical.scales().torque
    assert np.array_equal(scene_loads(scene, None), parse_loads(DEFAULT_LOADS))
    assert np.allclose(scene_loads(scene, f"0,{0.5 * torque!r}"), [0.0, 0.5])
    args = [
        "torque-speed",
        _file(tmp_path, PHYSICAL, "p.yaml"),
        "--set",
        "ensemble.members=2",
        "--resolution",
        "0",
    ]  # the default loads as given, unrefined
    assert main(args) == 0
    table = capsys.readouterr().out
    assert table.splitlines()[0].split()[:3] == ["load", "(N", "m)"]
    assert table.splitlines()[0].endswith("eff. motor")  # P_out / (P_ax + P_t), not W_L / W_t
    last = [line for line in table.splitlines() if line.strip()][11]
    assert float(last.split()[0]) == pytest.approx(torque, rel=1e-3)


def test_a_physical_curve_names_its_unsettled_loads_in_newton_metres(tmp_path, capsys):
    """The table is in N·m: so is its "not settled" line (it gave nondimensional tau_L)."""
    scene = _file(tmp_path, PHYSICAL, "p.yaml")
    torque = with_load(load_scene(scene)).physical.scales().torque
    args = ["torque-speed", scene, "--set", "stop.time=30", "--set", "stats.discard=5"]
    assert main([*args, "--set", "ensemble.members=2", "--loads", "0", "--resolution", "0"]) == 0
    (line,) = [x for x in capsys.readouterr().out.splitlines() if "not settled" in x]
    assert line == "        not settled: 0 N m (a finite window's mean, not a speed)"
    assert main([*args, "--loads", f"0,{0.5 * torque!r}", "--json"]) == 0
    s = _json(capsys)
    assert s["unsettled_loads_Nm"] == pytest.approx([torque * x for x in s["unsettled_loads"]])


def test_pipeline_script_reads_loads_as_the_command():
    """The pipeline's torque_speed script converts its loads with the command's function."""
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "torque_speed.py"
    assert "scene_loads(" in script.read_text()


@settings(max_examples=8, deadline=None)
@given(e=st.floats(0.1, 0.9), omega_s=st.floats(1.2, 2.5), top=st.floats(0.3, 2.0))
def test_property_one_member_scene_has_no_intervals(e, omega_s, top):
    """Over random small scenes of one member: no derived interval, and a stall torque (if any)
    between two loads of the grid, the first where the speed is <= 0 or that lies past the
    momentum bound 1 (clipped to it), and the one before."""
    raw = {
        "parameters": {"e": e, "omega_s": omega_s, "r_phi": 0.01, "e_sigma": 1e-9},
        "effects": ["impacts", "contact", "torsion", "restitution_noise"],
        "stop": {"time": 40.0},
        "stats": {"discard": 10.0},
    }
    loads = np.linspace(0.0, top, 4)
    s = torque_speed(with_load(scene_from_mapping(raw)), loads, branches=("up",)).summary()
    for k in ("no_load_speed", "stall_torque", "max_power", "max_power_load"):
        assert s[f"{k}_ci95"] == [None, None], k
    speed = s["mean_omega"]
    if s["stall_torque"] is not None and s["stall_torque"] > 0:
        k = next(i for i, v in enumerate(speed) if v <= 0 or loads[i] > 1.0)
        top = min(loads[k], max(loads[k - 1], 1.0))
        assert loads[k - 1] <= s["stall_torque"] <= top and speed[k - 1] > 0


@pytest.mark.parametrize(
    "text,said",
    [
        ("0,0.9,0.9000000000000001,1", "repeats a load"),  # one load twice, by round-off
        ("1,,2", "has an empty item"),
        ("1,2,", "has an empty item"),
    ],
)
def test_a_load_list_with_a_near_duplicate_or_an_empty_item_is_refused(text, said):
    from bouncedisk.model.errors import InputError
    from bouncedisk.studies.torque_speed import parse_loads

    with pytest.raises(InputError) as ex:
        parse_loads(text)
    assert said in ex.value.line()
