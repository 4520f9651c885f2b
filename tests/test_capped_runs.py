"""Runs stopped by the safety cap ``stop.max_events`` are never averaged as if they finished.

A statistic over a window a run did not reach is an error (one line naming ``stop.max_events``,
exit 2, no output), in ``stats``, ``torque-speed`` and the library calls under them; ``simulate``
writes such a run with its status ``cap: ...``.
"""

from __future__ import annotations

import dataclasses

import netCDF4
import pytest
from cli_helpers import one_line, scene_file
from hypothesis import assume, event, given, settings
from hypothesis import strategies as st

from bouncedisk.analysis.ensembles import CappedRun, run_member
from bouncedisk.analysis.statistics import run_stats
from bouncedisk.cli import main
from bouncedisk.engine import simulate_arrays
from bouncedisk.model.engine_config import engine_config
from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import scene_from_mapping


@pytest.mark.parametrize(
    "command",
    [["stats"], ["torque-speed", "--loads", "0,0.5"]],
)
def test_a_capped_ensemble_is_an_error_not_a_number(tmp_path, capsys, command):
    """Before: exit 0 with the capped members' integrals divided by the whole window."""
    scene = scene_file(tmp_path, time=120.0, discard=20.0)
    out = tmp_path / "out.nc"
    args = [command[0], scene, *command[1:], "--set", "stop.max_events=5", "-o", str(out)]
    assert main([*args, "--json"]) == 2
    line = one_line(capsys)
    assert "stop.max_events (from --set stop.max_events)" in line and "cap of 5 events" in line
    assert not out.exists()


def test_the_same_ensemble_with_room_finishes(tmp_path, capsys):
    """The cap is the only cause: with the default cap the same command gives its numbers."""
    assert main(["stats", scene_file(tmp_path, time=120.0, discard=20.0), "--json"]) == 0
    assert '"mean_omega"' in capsys.readouterr().out


def test_info_of_a_load_curve_file_lists_its_variables_with_their_intervals(tmp_path, capsys):
    """``bouncedisk info`` reads every file the package writes, not only simulations: a load
    curve's file gives its title and its variables, each interval with its variable."""
    out = tmp_path / "load.nc"
    scene = scene_file(tmp_path, time=120.0, discard=20.0)
    assert main(["torque-speed", scene, "--loads", "0,0.5", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    rows = dict(ln.strip().split(": ", 1) for ln in capsys.readouterr().out.splitlines())
    assert rows["title"].startswith("bouncedisk load characteristic of scene")
    assert rows["scene_sha256"] and float(rows["e"]) == 0.6  # the scene's provenance
    with netCDF4.Dataset(out) as nc:  # the study's results, each with its interval
        low, high = nc.getncattr("no_load_speed_ci95")
        expected = f"{nc.getncattr('no_load_speed'):.6g}  95% CI [{low:.6g}, {high:.6g}]"
    assert rows["no_load_speed"] == expected
    assert rows["mean_omega"].startswith("ensemble mean of the time-averaged rotor angular")
    assert rows["mean_omega"].endswith("[1], with its 95 % interval")
    assert not any("_ci" in name for name in rows)  # the ends are named with their variable


def test_run_member_raises_on_the_cap():
    cfg = dataclasses.replace(
        engine_config(scene_from_mapping(_raw(0.6, 1.5, 120.0))), max_events=5
    )
    with pytest.raises(CappedRun) as ex:
        run_member(cfg, scene_from_mapping(_raw(0.6, 1.5, 120.0)).initial, 0, 20.0)
    assert ex.value.max_events == 5 and ex.value.t_reached < cfg.t_end


def test_simulate_flags_a_capped_time_stop(tmp_path, capsys):
    """``simulate`` keeps the run (it is a trajectory, not an average) and says it was capped."""
    out = tmp_path / "sim.nc"
    scene = scene_file(tmp_path, time=120.0, discard=20.0)
    extra = ["--set", "stop.max_events=5", "--set", "ensemble.members=1"]
    assert main(["simulate", scene, "-o", str(out), "-q", *extra]) == 0
    with netCDF4.Dataset(out) as ds:
        assert ds.getncattr("status").startswith("cap: stopped at the safety cap")
        assert ds.getncattr("final_t") < 120.0


def _raw(e: float, omega_s: float, time: float, max_events: int | None = None) -> dict:
    stop = {"time": time} if max_events is None else {"time": time, "max_events": max_events}
    return {
        "name": "prop",
        "parameters": {"e": e, "omega_s": omega_s, "r_phi": 0.01, "e_sigma": 1e-9},
        "effects": ["impacts", "contact", "torsion", "restitution_noise"],
        "stop": stop,
        "ensemble": {"members": 2, "seed": 3},
        "stats": {"discard": 10.0},
    }


@settings(max_examples=20, deadline=None)
@given(
    e=st.floats(0.05, 0.9),
    omega_s=st.floats(1.1, 3.0),
    time=st.floats(25.0, 80.0),
    max_events=st.integers(2, 120),
)
def test_property_capped_or_identical_to_the_uncapped_run(e, omega_s, time, max_events):
    """Over random small scenes: a capped ensemble is an error naming stop.max_events, and an
    ensemble that returns numbers is bit for bit the one with no cap in reach."""
    scene = scene_from_mapping(_raw(e, omega_s, time))
    free = run_stats(scene)
    cfg = engine_config(scene)
    events = [
        len(simulate_arrays(dataclasses.replace(cfg, member=m), scene.initial).events["t"])
        for m in range(2)
    ]
    assume(max(events) != max_events)  # a run that ends on its last allowed event: either way
    try:
        capped = run_stats(scene_from_mapping(_raw(e, omega_s, time, max_events)))
    except InputError as ex:
        assert ex.field == "stop.max_events"
        assert f"safety cap of {max_events} events" in ex.message
        assert max(events) > max_events
        event("capped")
        return
    assert max(events) < max_events
    event("finished")
    assert capped.summary() == free.summary()
