"""Property tests (hypothesis): the invariants hold over random parameters and initial states."""

import math

from hypothesis import given
from hypothesis import strategies as st
from invariants import check_events_sane, check_no_skipped_root, check_slip_never_reverses

from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays
from bouncedisk.io.records import TrajColumn as C
from bouncedisk.model import stator


@given(
    e=st.floats(0.0, 1.0),
    w=st.floats(0.3, 40.0),
    r_phi=st.floats(1e-4, 10.0),
    psi=st.floats(-math.pi, math.pi),
    start_in_flight=st.booleans(),
    height=st.floats(0.0, 3.0),
    v0=st.floats(-5.0, 5.0),
    t0=st.floats(0.0, 100.0),
    omega0=st.floats(-50.0, 50.0),
    inertia=st.one_of(st.just(math.inf), st.floats(0.1, 100.0)),
    mu_ratio=st.floats(1.0, 3.0),
)
def test_invariants_over_random_scenes(
    e, w, r_phi, psi, start_in_flight, height, v0, t0, omega0, inertia, mu_ratio
):
    if start_in_flight:
        us = stator.position(w * t0)
        init = InitialState(t=t0, omega=omega0, u=us + height, v=v0)
    else:
        init = InitialState(t=t0, omega=omega0)
    cfg = EngineConfig(
        e=e,
        omega_s=w,
        r_phi=r_phi,
        psi=psi,
        torsion=True,
        inertia_ratio=inertia,
        mu_ratio=mu_ratio,
        max_events=3000,
        t_end=t0 + 5e4,
        traj_dt=0.0,
    )
    res = simulate_arrays(cfg, init)
    assert res.ok, res.status
    check_events_sane(res)
    check_no_skipped_root(res, e, w, n_check=100, samples=200 if w < 10 else 2000)
    check_slip_never_reverses(res, r_phi, w, psi)
    if len(res.events["t"]):
        assert res.events["t"][0] >= t0 - 1e-12 * (1.0 + t0)


@given(
    e=st.floats(0.0, 1.0),
    w=st.floats(0.3, 5.0),
    dt=st.floats(0.003, 0.3),
)
def test_dense_trajectory_never_below_stator(e, w, dt):
    cfg = EngineConfig(
        e=e, omega_s=w, torsion=True, r_phi=0.05, t_end=60.0, traj_dt=dt, max_events=100_000
    )
    res = simulate_arrays(cfg)
    tr = res.traj
    assert len(tr) == int(math.floor(60.0 / dt + 1e-9)) + 1
    assert (tr[:, C.U] - tr[:, C.U_STATOR]).min() >= -1e-9
