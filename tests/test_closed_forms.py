"""The engine against closed forms and classic bouncing-ball results (docs/model.md)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from bouncedisk.analysis import observables as ob
from bouncedisk.engine import KIND_CHATTER, EngineConfig, InitialState, simulate_arrays
from bouncedisk.studies import thresholds

W_REST = 1e-9  # a stator that is practically at rest over the test's time span


def test_flight_on_resting_stator_takes_2v():
    for v0 in (0.3, 1.0, 7.5):
        res = simulate_arrays(
            EngineConfig(e=0.5, omega_s=W_REST, max_events=1), InitialState(t=0.0, u=0.0, v=v0)
        )
        assert res.events["t"][0] == pytest.approx(2 * v0, abs=1e-7)
        assert res.events["v_rel"][0] == pytest.approx(v0, abs=1e-7)


def test_chattering_on_resting_stator_accumulates_at_t0_plus_2v_over_1_minus_e():
    for e, v0, t0 in ((0.5, 1.0, 0.0), (0.3, 0.4, 2.0), (0.8, 2.0, 0.0)):
        res = simulate_arrays(
            EngineConfig(e=e, omega_s=W_REST, max_events=10_000), InitialState(t=t0, u=0.0, v=v0)
        )
        kind = res.events["kind"]
        assert kind[-1] == KIND_CHATTER and np.sum(kind == KIND_CHATTER) == 1
        assert res.events["t"][-1] == pytest.approx(t0 + 2 * v0 / (1 - e), abs=1e-6)
        # it jumps to the accumulation point instead of resolving the bounces
        assert len(kind) < 200
        assert res.status.startswith("rest")  # omega_s < 1: it stays in contact afterwards


def test_chattering_on_a_slow_stator_follows_the_bounce_sequence():
    e, v0 = 0.5, 0.5
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=1e-3, max_events=10_000), InitialState(t=0.0, u=0.0, v=v0)
    )
    t = res.events["t"]
    # each flight is e times the previous one (to first order in the slow stator motion)
    ratios = np.diff(t[:-1])[1:] / np.diff(t[:-1])[:-1]
    assert np.allclose(ratios[:5], e, rtol=1e-3)
    assert t[-1] == pytest.approx(2 * v0 / (1 - e), rel=1e-2)


def test_first_impact_from_default_initial_condition_matches_brute_force():
    """Default start: in contact at t = 0; separation at asin(1/w²)/w, first root of the gap."""
    w = 1.5
    res = simulate_arrays(EngineConfig(e=0.3, omega_s=w, max_events=1))
    t_sep = math.asin(1 / w**2) / w
    u0, v0 = 1 / w**2, w * math.cos(w * t_sep)

    def gap(t):
        return u0 + v0 * (t - t_sep) - 0.5 * (t - t_sep) ** 2 - np.sin(w * t)

    grid = np.linspace(t_sep + 0.05, 8.0, 400_001)
    i = int(np.argmax(gap(grid) < 0))
    ref = brentq(gap, grid[i - 1], grid[i], xtol=1e-15)
    assert res.events["t"][0] == pytest.approx(ref, abs=1e-11)
    assert res.events["t"][0] == pytest.approx(3.6734012, abs=1e-6)


@pytest.mark.parametrize("n", [1, 2])
def test_period_n_fixed_point_is_reproduced_exactly(n):
    e, w = 0.3, math.sqrt(ob.period_n_threshold(n, 0.3) * 1.1)
    phi, vp = ob.period_n_fixed_point(n, e, w)
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=30), InitialState(t=phi / w, u=math.sin(phi), v=vp)
    )
    assert np.allclose(res.events["phase"], phi, atol=1e-9)
    assert np.allclose(np.diff(res.events["t"]), 2 * math.pi * n / w, atol=1e-9)


def test_impact_map_jacobian_at_period_1_fixed_point():
    e, w = 0.3, math.sqrt(2.0)
    phi, vp = ob.period_n_fixed_point(1, e, w)
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=20), InitialState(t=phi / w, u=math.sin(phi), v=vp)
    )
    ev = res.events
    jac, _ = ob.impact_jacobians(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], e, w)
    assert np.linalg.det(jac[-1]) == pytest.approx(e * e, abs=1e-9)
    expected = 1 + e * e - (1 + e) ** 2 * w * w * math.sin(phi)
    assert np.trace(jac[-1]) == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("n", [1, 2])
def test_period_n_existence_threshold_within_1e_3(n):
    """Bisect Γ on 'a run started at the orbit's phase settles on it' (docs/model.md Γ_n), with the
    reproduction check's own bisection (bouncedisk.studies.thresholds)."""
    e = 0.3
    g_n = ob.period_n_threshold(n, e)
    # the bracket the bisection starts from is a real bracket: below, no orbit; above, stable
    assert not thresholds.settles_on_period(e, 0.9 * g_n, n, 0.0, 4000)
    assert thresholds.settles_on_period(e, 1.1 * g_n, n, math.acos(1 / 1.1), 4000)
    assert abs(thresholds.engine_existence_threshold(n, e) - g_n) < 1e-3


def test_period_doubling_threshold_within_1e_3():
    """Bisect Γ on 'the period-1 orbit is stable' using the engine's long-run behaviour."""
    e = 0.3
    g_pd = ob.period_doubling_threshold(1, e)
    assert thresholds.period_one_is_stable(e, g_pd - 0.05)
    assert not thresholds.period_one_is_stable(e, g_pd + 0.05)
    assert abs(thresholds.engine_doubling_threshold(e) - g_pd) < 1e-3


def test_seed_claim_e03_is_period_2():
    w = 1.5
    res = simulate_arrays(EngineConfig(e=0.3, omega_s=w, max_events=3000))
    ev = res.events
    per = ob.find_period(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], w, max_period=16)
    assert per is not None and per.p == 2 and per.q == 2
    assert abs(per.phases[1] - per.phases[0]) > 0.5  # two distinct impact phases
    # it is the period-doubled period-1 orbit: past the doubling threshold 2.13 < Γ = 2.25
    assert ob.period_doubling_threshold(1, 0.3) == pytest.approx(2.127, abs=1e-3)


def test_seed_claim_e06_has_no_period_up_to_16_and_positive_lyapunov():
    w = 1.5
    res = simulate_arrays(EngineConfig(e=0.6, omega_s=w, max_events=20_000))
    ev = res.events
    per = ob.find_period(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], w, max_period=16, tail=2000)
    assert per is None
    lam, lam_t = ob.lyapunov_exponent(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], 0.6, w)
    assert lam > 0.1 and lam_t > 0.0
