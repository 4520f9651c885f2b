"""The motor's figures in one place (load_summary.derived): distinct refined loads, a located
maximum at a stall that collapses at the momentum bound, no interval where there is no estimate,
unsettled runs reported, and the command's refinement and scenes."""

from __future__ import annotations

import numpy as np
import pytest
from cli_helpers import scene_file

from bouncedisk.cli import main
from bouncedisk.studies.load_summary import derived, distinct_new, refine, settled_loads


class _Collapse:
    """A stand-in load curve: the speed holds near 74 up to the momentum bound 1 and collapses
    past it (a finite window's mean past the bound falls with the load, as on the Fig. 3 motor)."""

    def __init__(self, loads, branches=None):
        self.loads = np.asarray(loads, float)
        if branches is not None:
            self.branches = branches
            return
        x = self.loads
        speed = np.where(x <= 1.0, 77.8 - 3.6 * x, 12.0 - 2000.0 * (x - 1.0))
        self.branches = {"up": [speed * f for f in (0.999, 1.0, 1.001)]}
        self.branches["up"] = list(np.stack(self.branches["up"]).T)

    def matrix(self, branch, name):
        return np.stack(self.branches[branch], axis=1)

    def power(self, branch):
        return self.matrix(branch, "mean_omega") * self.loads


def test_near_duplicate_loads_are_one_load():
    # 0.8999999999999999 (from linspace(0.75, 1.05, 5)) beside the grid's 0.9
    got = distinct_new(np.linspace(0.0, 1.05, 8), np.linspace(0.75, 1.05, 5)[1:-1])
    assert got == pytest.approx([0.825, 0.975], abs=1e-12)


def test_refined_maximum_is_located_on_distinct_loads_up_to_the_bound():
    """Loads 0:1.05:8 refined at 0.01 must not keep near-duplicates (0.975 beside
    0.9750000000000001), on which a bracket would collapse to a zero-width interval short of the
    maximum at the bound."""
    sweeps = lambda loads, omega0, branch: _Collapse(loads)  # noqa: E731
    out = refine(_Collapse(np.linspace(0.0, 1.05, 8)), sweeps, resolution=0.01)
    assert np.all(np.diff(out.loads) > 1e-9)
    d = derived(out.loads, out.matrix("up", "x"), out.power("up"), 1.0)
    assert d["max_power_state"] == "found"
    assert 73.5 <= d["max_power"] <= 74.2 + 1e-9  # the direct loads: 73.5 at 0.99, 74.2 at 1
    lo, hi = d["max_power_load_ci95"]
    assert 0.98 <= lo < hi <= 1.0 and hi - lo > 0
    # the stall: at the bound, never past it (before: interpolated to the collapsing readings)
    assert 0.98 <= d["stall_torque"] <= 1.0 and d["stall_torque_bracket"][1] == 1.0


@pytest.mark.parametrize(
    ("loads", "speed", "stall", "peak"),
    [
        (
            np.linspace(0.0, 0.2, 5),
            lambda x: 80.0 - x,
            "beyond_largest_load",
            "beyond_largest_load",
        ),
        (np.linspace(0.0, 1.0, 5), lambda x: -80.0 - x, "backwards_at_no_load", "at_smallest_load"),
        (np.array([1.5, 2.0, 3.0]), lambda x: -80.0 * x, "below_smallest_load", "none"),
    ],
)
def test_no_interval_where_there_is_no_estimate(loads, speed, stall, peak):
    """No zero-width interval where there is no estimate: a maximum beyond the largest load, a
    motor running backwards at no load, loads all past the momentum bound (where no reading is a
    stationary power: no maximum at all)."""
    members = np.stack([speed(loads) * f for f in (0.99, 1.0, 1.01)])
    d = derived(loads, members, members * loads, 1.0)
    assert (d["stall_torque_state"], d["max_power_state"]) == (stall, peak)
    for name in ("stall_torque", "max_power", "max_power_load", "efficiency_at_max_power"):
        assert d[name] is None and d[f"{name}_ci95"] == [None, None], name


def test_a_drifting_run_is_reported_unsettled_and_past_the_bound_nothing_is_settled():
    loads = np.array([0.0, 0.5, 0.9, 1.1])
    speed = np.tile([100.0, 90.0, 80.0, 50.0], (3, 1))
    drift = np.tile([0.1, -5.0, 0.0, -60.0], (3, 1)) + np.array([[0.0], [0.01], [-0.01]])
    assert settled_loads(loads, speed, drift, 1.0).tolist() == [True, False, True, False]
    assert derived(loads, speed, speed * loads, 1.0, drift=drift)["unsettled_loads"] == [0.5, 1.1]


SCENE = """
name: loaded
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.1, psi: 0.0, e_sigma: 1.0e-9}
effects: [impacts, contact, torsion, restitution_noise, load]
stop: {time: 100.0}
ensemble: {members: 2, seed: 1}
stats: {discard: 20.0}
"""


def test_command_takes_a_scene_with_the_load_effect_and_no_load_torque(tmp_path, capsys):
    """`torque-speed` takes a scene listing the `load` effect without `load_torque`."""
    path = scene_file(tmp_path, SCENE, "loaded.yaml")
    assert main(["torque-speed", path, "--loads", "0,0.5", "--resolution", "0", "-q"]) == 0
    assert "load_torque" not in capsys.readouterr().err


def test_command_refines_as_the_pipeline_does(tmp_path, capsys):
    """`bouncedisk torque-speed` printed the unrefined grid ("stall 0.928 [0.9, 1]"): it now adds
    loads until the stall's bracket is within --resolution."""
    import json

    path = scene_file(tmp_path, SCENE, "loaded.yaml")
    assert main(["torque-speed", path, "--loads", "0:1.2:5", "--json", "-q"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert len(s["loads"]) > 5 and s["stall_torque_state"] == "found"
    a, b = s["stall_torque_bracket"]
    assert b - a <= 0.005 + 1e-12 and b <= 1.0
    assert main(["torque-speed", path, "--loads", "0,1", "--resolution", "x"]) == 2
    assert "--resolution" in capsys.readouterr().err
