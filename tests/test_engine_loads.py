"""One axial trajectory carrying several loads (bouncedisk.engine.loads) equals one run per load.

The invariant behind it (docs/model.md "Events", "The motor under load"): the axial motion and the
restitution noise never depend on ``Ω``, so runs that differ only in the load torque share every
impact. ``omega_integrals`` must therefore give, bit for bit, what :func:`iterate` gives load by
load, whatever the regime: flights only, chattering and sticking contact, stick–slip under load,
a rotor driven backwards past stall, static friction above kinetic, a finite stator inertia.
The same holds for runs that differ in ``R_φ`` and ``ψ`` too (the rotation's parameters):
``row_trajectories`` gives each run's samples as :func:`simulate_arrays` gives them alone.
"""

import dataclasses
import math

import numpy as np
import pytest

from bouncedisk.engine import EngineConfig, EngineError, InitialState, iterate, simulate_arrays
from bouncedisk.engine import kernel as K
from bouncedisk.engine.loads import omega_integrals, row_trajectories


def _one_run(cfg: EngineConfig, load: float, init: InitialState) -> tuple[int, float]:
    gen = iterate(dataclasses.replace(cfg, load_torque=load), init)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            status, final = stop.value
            return status, final["omega_integral"]


LOADS = np.array([0.0, 0.05, 0.2, 0.45, 0.7, 0.95, 1.3, -0.1])

CASES = {
    # (e, ω_s, R_φ, ψ), extra engine settings, initial state
    "periodic, at rest in contact": ((0.55, 1.7, 0.002, 0.4), {}, InitialState(t=0.0, omega=0.0)),
    "chaotic with noise": (
        (0.3, 3.0, 0.01, -0.5),
        {"e_sigma": 0.05, "seed": 7, "member": 3},
        InitialState(t=0.0, omega=0.0),
    ),
    "chattering, from flight": (
        (0.8, 2.2, 0.0005, 1.0),
        {"e_sigma": 0.03, "seed": 2},
        InitialState(t=0.3, u=1.5, v=0.2, omega=40.0),
    ),
    "static friction, stator inertia": (
        (0.45, 1.3, 0.02, 2.0),
        {"mu_ratio": 1.4, "inertia_ratio": 3.0},
        InitialState(t=0.0, omega=0.0),
    ),
    "no impulse cap": ((0.6, 4.5, 0.005, 0.0), {"impulse_cap": False}, InitialState(omega=5.0)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_one_trajectory_for_all_loads_is_one_run_per_load(case):
    (e, w, r, psi), extra, init = CASES[case]
    cfg = EngineConfig(e=e, omega_s=w, r_phi=r, psi=psi, contact=True, torsion=True,
                       t_end=900.0, stats_from=300.0, max_events=10**7, **extra)  # fmt: skip
    got = omega_integrals(cfg, LOADS, init)
    want = np.array([_one_run(cfg, x, init)[1] for x in LOADS])
    np.testing.assert_array_equal(got, want)
    # the loads do act: the speed falls with the load, and past the friction torque it reverses
    mean = got / 600.0
    assert mean[0] > mean[3] > mean[6]
    assert mean[6] < 0.0


def test_the_event_budget_ends_every_load_at_the_same_impact():
    """A run stopped by ``max_events`` stops every load at the same event, as one run each."""
    cfg = EngineConfig(e=0.3, omega_s=3.0, r_phi=0.01, psi=-0.5, torsion=True, t_end=1e6,
                       stats_from=0.0, max_events=777, e_sigma=0.05, seed=1)  # fmt: skip
    init = InitialState(t=0.0, omega=0.0)
    got = omega_integrals(cfg, LOADS, init)
    runs = [_one_run(cfg, x, init) for x in LOADS]
    assert {status for status, _ in runs} == {K.ST_EVENTS}
    np.testing.assert_array_equal(got, [v for _, v in runs])


def test_settings_it_cannot_honour_are_refused():
    """Samples, the clipped model and an open window are refused before any work; a run whose
    dynamics need the contact the configuration left out fails as :func:`iterate` does."""
    base = EngineConfig(e=0.5, omega_s=2.0, torsion=True, t_end=100.0, stats_from=10.0)
    for bad in ({"traj_dt": 0.1}, {"stroboscopic": True}, {"clipped": True},
                {"stats_from": math.inf}, {"t_end": math.inf}):  # fmt: skip
        with pytest.raises(ValueError, match="omega_integrals"):
            omega_integrals(dataclasses.replace(base, **bad), LOADS)
    no_contact = dataclasses.replace(base, contact=False, e=0.2)
    with pytest.raises(EngineError) as err:
        omega_integrals(no_contact, LOADS, InitialState(t=0.0, u=1.2, v=0.0))
    assert err.value.code == K.ST_NEED_CONTACT


#: Rows of one axial run: ``(R_φ, ψ, τ_L)``, the rotation's parameters only.
ROWS = [
    (0.002, 0.4, 0.0),
    (0.01, 0.4, 0.0),
    (0.002, -2.5, 0.0),
    (0.0004, 3.0, 0.3),
    (0.05, 1.0, 0.9),
]


@pytest.mark.parametrize("case", list(CASES))
def test_one_trajectory_for_rotations_is_one_run_each(case):
    """Samples of runs differing in ``R_φ``, ``ψ`` and ``τ_L``, from one axial run, equal each
    run alone bit for bit (the fit evaluates its ``(ψ, R_φ)`` points this way)."""
    (e, w, _, _), extra, init = CASES[case]
    cfgs = [EngineConfig(e=e, omega_s=w, r_phi=r, psi=psi, load_torque=load, contact=True,
                         torsion=True, t_end=600.0, traj_dt=0.7, traj_t0=init.t, traj_t1=590.0,
                         max_events=10**7, **extra) for r, psi, load in ROWS]  # fmt: skip
    got = row_trajectories(cfgs, init)
    for cfg, rows in zip(cfgs, got, strict=True):
        want = simulate_arrays(cfg, init).traj
        assert rows.shape == want.shape and len(rows) > 800
        np.testing.assert_array_equal(rows, want)
    # the rows do differ: other rotations of one axial motion (its samples equal to rounding:
    # in contact each row's segments end at its own stick–slip transitions)
    assert not np.array_equal(got[0][:, K.TR_OMEGA], got[2][:, K.TR_OMEGA])
    np.testing.assert_allclose(got[0][:, K.TR_U], got[2][:, K.TR_U], rtol=0, atol=1e-11)


def test_rows_that_part_in_their_axial_motion_are_refused():
    """Rows that differ in what the axial motion uses, or without a finite sample grid, are
    refused before any work."""
    base = EngineConfig(e=0.5, omega_s=2.0, torsion=True, t_end=100.0, traj_dt=0.5)
    for other in ({"e": 0.51}, {"omega_s": 2.1}, {"member": 1}, {"e_sigma": 0.01}):
        with pytest.raises(ValueError, match="differ only in load_torque, r_phi, psi"):
            row_trajectories([base, dataclasses.replace(base, **other)])
    for bad in ({"traj_dt": 0.0}, {"t_end": math.inf}, {"stroboscopic": True}):
        with pytest.raises(ValueError, match="row_trajectories"):
            row_trajectories([dataclasses.replace(base, **bad)] * 2)
    # a run that fails alone fails the same way among rows
    no_contact = dataclasses.replace(base, contact=False, e=0.2)
    rows = [no_contact, dataclasses.replace(no_contact, psi=1.0)]
    with pytest.raises(EngineError) as err:
        row_trajectories(rows, InitialState(t=0.0, u=1.2, v=0.0))
    assert err.value.code == K.ST_NEED_CONTACT
