"""The named engine records (status, event kinds, columns) and the numpy stator kinematics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays
from bouncedisk.io.records import EventKind, RunStatus, StrobeColumn, TrajColumn
from bouncedisk.model import stator


def test_a_run_at_rest_reports_the_rest_status_by_name():
    # omega_s < 1: the load never turns negative, the rotor rides the stator for ever
    res = simulate_arrays(EngineConfig(e=0.5, omega_s=0.9, max_events=10))
    assert res.status_code == RunStatus.REST
    assert res.status == RunStatus(res.status_code).text
    assert RunStatus.REST.ok and not RunStatus.NEED_CONTACT.ok


def test_completed_runs_name_their_status_and_event_kinds():
    res = simulate_arrays(EngineConfig(e=0.6, omega_s=1.5, max_events=3000))
    assert res.status_code == RunStatus.EVENTS and res.status == "completed"
    kinds = set(np.unique(res.events["kind"]).tolist())
    assert kinds <= {EventKind.IMPACT, EventKind.CHATTER} and EventKind.IMPACT in kinds


def test_trajectory_columns_hold_what_their_names_say():
    w = 1.5
    cfg = EngineConfig(e=0.3, omega_s=w, torsion=True, max_events=40, traj_dt=0.01)
    res = simulate_arrays(cfg, InitialState(t=0.0, omega=2.0))
    tr = res.traj
    assert tr.shape[1] == len(TrajColumn)
    np.testing.assert_allclose(
        tr[:, TrajColumn.U_STATOR], np.sin(w * tr[:, TrajColumn.T]), atol=1e-9
    )
    # the rotor is never below the stator, and its speed starts where the scene put it
    assert (tr[:, TrajColumn.U] - tr[:, TrajColumn.U_STATOR]).min() >= -1e-9
    assert tr[0, TrajColumn.OMEGA] == pytest.approx(2.0, abs=0.05)


def test_stroboscopic_columns_sit_at_phase_zero():
    w = 1.5
    res = simulate_arrays(EngineConfig(e=0.3, omega_s=w, max_events=200, stroboscopic=True))
    sb = res.strobe
    assert sb.shape[1] == len(StrobeColumn) and len(sb) > 10
    periods = sb[:, StrobeColumn.PERIOD]
    np.testing.assert_allclose(sb[:, StrobeColumn.T], periods * 2 * math.pi / w, rtol=1e-12)


@pytest.mark.parametrize("theta", [0.0, 0.3, 2.0, -7.5, 1e4])
def test_stator_scalars_and_arrays_agree_bit_for_bit(theta):
    w, psi = 1.7, 0.4
    arr = np.array([theta])
    for f, args in (
        (stator.position, ()),
        (stator.velocity, (w,)),
        (stator.acceleration, (w,)),
        (stator.normal_load, (w,)),
        (stator.twist, (psi,)),
        (stator.twist_rate, (w, psi)),
    ):
        scalar, vector = f(theta, *args), f(arr, *args)
        assert isinstance(scalar, float) and isinstance(vector, np.ndarray)
        assert np.float64(scalar).tobytes() == vector[0].tobytes(), f.__name__


def test_stator_derivatives_and_load_follow_eq_1():
    w, psi, h = 2.3, 0.7, 1e-6
    t = np.linspace(0.0, 5.0, 41)
    d = lambda f, *a: (f(w * (t + h), *a) - f(w * (t - h), *a)) / (2 * h)  # noqa: E731
    np.testing.assert_allclose(d(stator.position), stator.velocity(w * t, w), atol=1e-7)
    np.testing.assert_allclose(d(stator.velocity, w), stator.acceleration(w * t, w), atol=1e-6)
    np.testing.assert_allclose(d(stator.twist, psi), stator.twist_rate(w * t, w, psi), atol=1e-7)
    np.testing.assert_array_equal(
        stator.normal_load(w * t, w), 1.0 - w * w * np.sin(w * t)
    )  # N = 1 + a_s (eq. 17)


def test_stator_functions_take_any_array_like_phase():
    # ArrayLike as documented: a list or tuple of phases is read as a float array, as before
    w, psi, theta = 1.7, 0.4, [0.0, 0.3, 2.0]
    arr = np.array(theta)
    for f, args in (
        (stator.position, ()),
        (stator.velocity, (w,)),
        (stator.normal_load, (w,)),
        (stator.twist, (psi,)),
        (stator.twist_rate, (w, psi)),
    ):
        np.testing.assert_array_equal(f(theta, *args), f(arr, *args), err_msg=f.__name__)
        np.testing.assert_array_equal(f(tuple(theta), *args), f(arr, *args), err_msg=f.__name__)
