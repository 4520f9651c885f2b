"""A load curve's stall torque and maximum power, found (bouncedisk.studies.load_summary).

Closed forms on made-up curves, the states where there is no root or no maximum, no interval
from one member, the refinement converging on a known root, properties over random curves and
random small scenes, and the stall torque at the fig. 3 point from a design map's coarse loads
and from a torque–speed curve's fine ones.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from load_scenes import small_load_scene

from bouncedisk.studies.load_summary import (
    ONE_MEMBER,
    derived,
    first_zero,
    merged,
    peak,
    peak_bracket,
    refine,
    refinement_loads,
    stall_bracket,
)
from bouncedisk.studies.torque_speed import refined_torque_speed, torque_speed


# ----------------------------------------------------------------------------- closed forms
def test_the_stall_torque_is_the_bracketed_root_and_its_state_says_where_it_is():
    loads = np.linspace(0.0, 1.0, 11)
    assert first_zero(loads, 2.0 - 3.0 * loads) == pytest.approx(2.0 / 3.0)
    assert stall_bracket(loads, 2.0 - 3.0 * loads) == ("found", 7)
    assert stall_bracket(loads, 1.0 + loads) == ("beyond_largest_load", -1)
    assert stall_bracket(loads, -1.0 - loads) == ("backwards_at_no_load", -1)
    assert stall_bracket(loads + 1.5, -1.0 - loads) == ("below_smallest_load", -1)
    assert stall_bracket(loads, np.full(11, np.nan)) == ("none", -1)


def test_a_speed_negative_at_the_first_load_is_not_a_root_at_that_load():
    # before: `--loads 1.5,2` with the speed already -79.6 at 1.5 gave "stall torque 1.5
    # [1.5, 1.5]"
    loads = np.array([1.5, 2.0])
    speed = np.array([[-79.6, -180.0], [-79.0, -181.0], [-80.1, -179.0]])
    d = derived(loads, speed, speed * loads)
    assert d["stall_torque"] is None and d["stall_torque_state"] == "below_smallest_load"
    assert d["stall_torque_ci95"] == [None, None]
    assert math.isnan(first_zero(loads, speed.mean(axis=0)))


def test_one_member_gives_no_interval_and_says_why():
    # before: one member gave stall_torque_ci95 [0.7394, 0.7394]
    loads = np.linspace(0.0, 1.0, 6)
    speed = (90.0 - 120.0 * loads)[None, :]
    d = derived(loads, speed, speed * loads)
    assert d["stall_torque"] == pytest.approx(0.75)
    for k in ("no_load_speed", "stall_torque", "max_power", "max_power_load"):
        assert d[f"{k}_ci95"] == [None, None], k
    assert d["interval_note"] == ONE_MEMBER
    two = derived(loads, np.vstack([speed, speed + 1.0]), np.vstack([speed, speed + 1.0]) * loads)
    lo, hi = two["stall_torque_ci95"]
    assert hi > lo and "interval_note" not in two


def test_the_maximum_power_is_a_maximum_only_between_smaller_powers():
    loads = np.linspace(0.0, 1.0, 11)
    p, at = peak(loads, 5.0 - 20.0 * (loads - 0.4) ** 2)
    assert (p, at) == (pytest.approx(5.0), pytest.approx(0.4))
    assert peak_bracket(loads, 5.0 - 20.0 * (loads - 0.4) ** 2) == ("found", 4)
    assert peak_bracket(loads, loads) == ("beyond_largest_load", 10)
    assert peak_bracket(loads, -loads) == ("at_smallest_load", 0)
    # "max. power at load 0.95" was the sweep's last load: now said to lie beyond it
    speed = np.vstack([1.0 + 0.0 * loads, 1.1 + 0.0 * loads])
    d = derived(loads, speed, speed * loads)
    assert d["max_power_state"] == "beyond_largest_load" and d["max_power_bracket"] == [None, None]


def test_peak_of_no_finite_power_is_nan_without_a_warning():
    # before: `--set initial.omega=1e308 --loads 0,0.5` raised "All-NaN slice" in peak
    loads = np.array([0.0, 0.5])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p, at = peak(loads, np.array([np.nan, np.nan]))
        d = derived(loads, np.full((2, 2), np.nan), np.full((2, 2), np.nan))
    assert math.isnan(p) and math.isnan(at)
    assert d["max_power"] is None and d["max_power_state"] == "none"
    assert d["stall_torque"] is None and d["stall_torque_state"] == "none"


def test_the_interval_holds_the_bracket_even_when_the_members_agree():
    # a periodic attractor: every member the same, a zero-width bootstrap; the root of the mean
    # curve is known only to its bracket
    loads = np.array([0.0, 0.5, 1.0, 1.5])
    speed = np.tile([74.0, 74.0, 74.0, -60.0], (4, 1))
    d = derived(loads, speed, speed * loads)
    assert d["stall_torque_bracket"] == [1.0, 1.5]
    assert d["stall_torque_ci95"] == [1.0, 1.5]


# ----------------------------------------------------------------------------- refinement
class _Curve:
    """A stand-in for LoadCurve: members' speeds ``root - load`` (times a member's factor)."""

    root = 0.61803398875
    factors = np.array([90.0, 100.0, 110.0])

    def __init__(self, loads, branches=None):
        self.loads = np.asarray(loads, float)
        self.branches = branches or {"up": [self._stats(x) for x in self.loads]}
        self.sweeps = 0

    def _stats(self, load):
        return self.factors * (self.root - load)

    def matrix(self, branch, name):
        return np.stack(self.branches[branch], axis=1)

    def power(self, branch):
        return self.matrix(branch, "mean_omega") * self.loads


def test_refinement_narrows_the_bracket_to_the_resolution_around_the_root():
    curve = _Curve(np.linspace(0.0, 1.0, 5))
    calls = []

    def sweep(loads, omega0, branch):
        assert branch == "up"  # the curve has no down branch
        calls.append((loads.copy(), omega0))
        return _Curve(loads)

    out = refine(curve, sweep, resolution=1e-3, rounds=10)
    d = derived(out.loads, out.matrix("up", "mean_omega"), out.power("up"))
    a, b = d["stall_torque_bracket"]
    assert b - a <= 1e-3 and a <= _Curve.root <= b
    assert d["stall_torque"] == pytest.approx(_Curve.root, abs=1e-12)  # linear: exact
    lo, hi = d["stall_torque_ci95"]
    assert lo <= _Curve.root <= hi
    # the power (root - x) x peaks at root / 2
    a, b = d["max_power_bracket"]
    assert a <= _Curve.root / 2 <= b and b - a <= 2e-3
    assert np.all(np.diff(out.loads) > 0)
    # each sweep starts at a load the curve had, at the mean speed there
    for loads, omega0 in calls:
        assert omega0 == pytest.approx(100.0 * (_Curve.root - loads[0]))
    assert refinement_loads(out.loads, d, 1e-3).size == 0


def test_merged_keeps_every_branch_sorted():
    a = _Curve([0.0, 0.5, 1.0])
    b = _Curve([0.6, 0.7])
    m = merged(a, b)
    assert list(m.loads) == [0.0, 0.5, 0.6, 0.7, 1.0]
    np.testing.assert_array_equal(m.matrix("up", "x")[:, 2], _Curve.factors * (_Curve.root - 0.6))


# ----------------------------------------------------------------------------- properties
@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(-1e3, 1e3), min_size=2, max_size=12),
    st.integers(1, 5),
    st.floats(0.0, 2.0),
)
def test_property_the_stall_torque_lies_in_a_sign_change_and_no_interval_is_from_one_member(
    values, members, start
):
    loads = start + np.arange(len(values)) * 0.1
    rng = np.random.default_rng(len(values))
    speed = np.asarray(values)[None, :] + rng.normal(0.0, 1.0, (members, len(values)))
    d = derived(loads, speed, speed * loads)
    mean = speed.mean(axis=0)
    if d["stall_torque"] is None:
        assert d["stall_torque_state"] != "found"
        assert not (mean[0] > 0 and np.any(mean <= 0)) or not np.isfinite(mean).all()
    else:
        a, b = d["stall_torque_bracket"]
        k = int(np.searchsorted(loads, b))
        assert mean[k - 1] > 0 >= mean[k] and np.all(mean[:k] > 0)
        assert a <= d["stall_torque"] <= b
        if members >= 2:
            lo, hi = d["stall_torque_ci95"]
            assert (lo is None or lo <= d["stall_torque"]) and (
                hi is None or hi >= d["stall_torque"]
            )
            assert lo is None or hi is None or hi > lo  # never zero width: the bracket is in it
    if members < 2:
        assert all(d[f"{k}_ci95"] == [None, None] for k in ("stall_torque", "max_power_load"))
    if d["max_power_state"] == "found":
        assert d["max_power"] == pytest.approx(float(np.max(mean * loads)))


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.floats(0.3, 0.8),
    st.integers(1, 3),
    st.lists(st.floats(0.0, 2.0), min_size=2, max_size=4, unique=True),
)
def test_property_small_scenes_never_report_a_root_outside_a_sign_change(e, members, loads):
    loads = np.sort(np.asarray(loads))
    s = torque_speed(small_load_scene(e, members), loads, branches=("up",)).summary()
    mean = np.asarray(s["mean_omega"], float)
    if members < 2:
        assert s["stall_torque_ci95"] == [None, None] and s["interval_note"] == ONE_MEMBER
    if not mean[0] > 0:
        assert s["stall_torque"] is None
        assert s["stall_torque_state"] in ("backwards_at_no_load", "below_smallest_load")
    elif s["stall_torque"] is not None:
        a, b = s["stall_torque_bracket"]
        assert a <= s["stall_torque"] <= b <= max(a, 1.0)  # never past the momentum bound
        k = int(np.searchsorted(loads, b))  # the first load <= 0 or past the bound
        assert mean[list(loads).index(a)] > 0 and (mean[k] <= 0 or loads[k] > 1.0)
    else:
        assert np.all(mean > 0) and np.all(loads <= 1.0)
        assert s["stall_torque_state"] == "beyond_largest_load"


# ----------------------------------------------------------------------------- fig. 3 point
def test_design_map_and_torque_speed_stall_torques_agree_at_the_fig3_point():
    """e = 0.3, psi = 0: a design map's coarse loads (0, 0.2, 0.5, 1.3) gave 0.60 by
    interpolation where the torque–speed curve does not stall below the momentum bound 1.
    Refined, both find the root at the bound and their intervals hold it. Past the bound no
    positive speed is stationary (the rotor decelerates at >= tau_L - 1, docs/model.md): a
    finite run's positive mean there is not a speed, so the bracket ends at the bound (before:
    the root was interpolated to the unsettled readings past it, 1.006 [1, 1.009])."""
    scene = small_load_scene(0.3, 2, time=3000.0, discard=500.0)
    res = 0.005
    # what the design map runs (studies/sensitivity.py, MotorModel._load) and the command
    coarse = refined_torque_speed(scene, [0.0, 0.2, 0.5, 1.3], res, branches=("up",)).summary()
    fine = refined_torque_speed(scene, np.linspace(0.0, 1.05, 8), res).summary()
    for s in (coarse, fine):
        lo, hi = s["stall_torque_ci95"]
        assert s["stall_torque_state"] == "found"
        assert 1.0 - 2 * res <= lo <= s["stall_torque"] <= hi <= 1.0
    assert 1.3 in coarse["unsettled_loads"]  # past the bound the rotor only decelerates
    (lo1, hi1), (lo2, hi2) = coarse["stall_torque_ci95"], fine["stall_torque_ci95"]
    assert lo1 <= hi2 and lo2 <= hi1  # equal within their intervals
    # unrefined, the map's loads only bracket it between 0.5 and the bound
    plain = torque_speed(scene, [0.0, 0.2, 0.5, 1.3], branches=("up",)).summary()
    assert plain["stall_torque_bracket"] == [0.5, 1.0] and plain["stall_torque_ci95"][1] == 1.0


def test_the_design_maps_stall_torque_agrees_with_the_curves_at_the_fig3_point():
    """What the design maps compute (studies/sensitivity.py ``load_figures`` on the map's loads,
    every 0.05 up to 1.1, plus 2) against the refined torque–speed curve at e = 0.3, psi = 0:
    both at the momentum bound, within the map's load step (before: the map's root lay past the
    bound, [1.06, 1.07] against the curve's [1.0, 1.009])."""
    from bouncedisk.studies import sensitivity as sens

    scene = small_load_scene(0.3, 2, time=3000.0, discard=500.0)
    loads = [*(0.05 * np.arange(23)), 2.0]
    fig = sens.load_figures(torque_speed(scene, loads, branches=("up",)), 1.0)["stall_torque"]
    value, low, high, _ = fig
    curve = refined_torque_speed(scene, np.linspace(0.0, 1.05, 8), 0.005).summary()
    lo, hi = curve["stall_torque_ci95"]
    assert 0.95 <= low <= value <= high <= 1.0
    assert low <= hi and lo <= high  # equal within their intervals


def test_refinement_sweeps_the_down_branch_from_the_load_above():
    def both(loads):
        c = _Curve(loads)
        c.branches["down"] = [x + 1.0 for x in c.branches["up"]]
        return c

    calls = []

    def sweep(loads, omega0, branch):
        calls.append((branch, loads.copy(), omega0))
        return both(loads)

    out = refine(both(np.linspace(0.0, 1.0, 5)), sweep, resolution=0.1, rounds=1)
    assert len(out.branches["down"]) == len(out.loads) == len(out.branches["up"])
    for branch, loads, omega0 in calls:
        start = loads[0] if branch == "up" else loads[-1]  # the curve's load below / above
        shift = 0.0 if branch == "up" else 1.0
        assert omega0 == pytest.approx(100.0 * (_Curve.root - start) + shift)
    # every added load holds the sweep's own reading on each branch, not the restart's
    np.testing.assert_allclose(out.matrix("down", "x") - out.matrix("up", "x"), 1.0)
    assert {b for b, _, _ in calls} == {"up", "down"}
