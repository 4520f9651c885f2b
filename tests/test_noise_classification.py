"""Regime, period and Lyapunov exponent of runs with restitution noise (docs/model.md "Regimes").

Each impact's restitution ``e_k`` is the engine's draw from the run's noise stream: the impact
map's Jacobians use it, and a cycle repeats within the noise's scatter
(``observables.cycle_tolerance``). A stable cycle with small noise stays that cycle with the
noise-free exponent; a chaotic motion stays chaotic.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bouncedisk.analysis import observables as ob
from bouncedisk.analysis.ensembles import _Reducer, run_member
from bouncedisk.engine import EngineConfig, InitialState, iterate
from bouncedisk.model import stator

#: period-2 orbit (e = 0.3, w = 1.5), chaotic motion (e = 0.6), locked chattering cycle
PERIOD_2 = dict(e=0.3, omega_s=1.5, torsion=True, r_phi=0.01)
CHAOTIC = dict(e=0.6, omega_s=1.5, torsion=True, r_phi=0.01)
LOCKED = dict(e=0.5, omega_s=1.126, torsion=True, r_phi=0.01)
T_END = 1500.0

noise = st.one_of(st.just(0.0), st.floats(-9.0, math.log10(0.05)).map(lambda x: 10.0**x))
seeds = st.integers(0, 2**31)


def _member(scene: dict, e_sigma: float, seed: int = 1, t_end: float = T_END):
    cfg = EngineConfig(**scene, t_end=t_end, e_sigma=e_sigma, seed=seed, max_events=10**6)
    stats, _final, _tail = run_member(cfg, InitialState(), 0, t_end / 2)
    return stats, ob.REGIMES[stats.regime]


NOISE_FREE_LYAPUNOV = _member(PERIOD_2, 0.0)[0].lyapunov


def test_the_noise_free_period_2_orbit():
    stats, name = _member(PERIOD_2, 0.0)
    assert (name, stats.period_p, stats.period_q) == ("periodic", 2, 2)
    assert -0.40 < stats.lyapunov < -0.36


@pytest.mark.parametrize("e_sigma", [1e-7, 1e-6, 1e-4])
def test_small_noise_keeps_the_period_2_orbit(e_sigma):
    stats, name = _member(PERIOD_2, e_sigma)
    assert (name, stats.period_p, stats.period_q) == ("periodic", 2, 2)
    assert abs(stats.lyapunov - NOISE_FREE_LYAPUNOV) < 2e-3


@settings(max_examples=25, deadline=None)
@given(e_sigma=noise, seed=seeds)
def test_periodic_scene_under_noise(e_sigma, seed):
    stats, name = _member(PERIOD_2, e_sigma, seed)
    if e_sigma <= 5e-4:  # scatter well inside the resolution: the noise-free cycle
        assert (name, stats.period_p, stats.period_q) == ("periodic", 2, 2)
        assert abs(stats.lyapunov - NOISE_FREE_LYAPUNOV) < 0.05
    if name in ("periodic", "unresolved"):  # no cycle without contraction, no chaos without
        assert stats.lyapunov < 0.0
    if name == "chaotic":
        assert stats.lyapunov > 0.0


@settings(max_examples=25, deadline=None)
@given(e_sigma=noise, seed=seeds)
def test_chaotic_scene_stays_chaotic_under_noise(e_sigma, seed):
    stats, name = _member(CHAOTIC, e_sigma, seed)
    assert name in ("chaotic", "chaotic-reinjection")
    assert stats.lyapunov > 0.4


@settings(max_examples=15, deadline=None)
@given(e_sigma=st.floats(-9.0, -3.0).map(lambda x: 10.0**x), seed=seeds)
def test_locked_chatter_cycle_under_noise(e_sigma, seed):
    """A complete chatter resets the state, so the cycle repeats up to the noise of one cycle."""
    stats, name = _member(LOCKED, e_sigma, seed, t_end=3000.0)
    assert (name, stats.period_p) == ("chattering-periodic", 20)
    assert stats.lyapunov == -math.inf


def test_each_flight_lands_with_its_own_restitution():
    """The flights of the event table end where they land with the engine's own ``e_k``
    (``event_restitution``), not with the mean ``e``."""
    cfg = EngineConfig(e=0.3, omega_s=1.5, t_end=400.0, e_sigma=1e-3, seed=7, max_events=10**6)
    cfg = EngineConfig(**{**cfg.__dict__, "member": 3})
    ev = {k: [] for k in ("t", "phase", "v_rel", "kind")}
    for c in iterate(cfg, InitialState()):
        for k in ev:
            ev[k].append(getattr(c, k))
    t, ph, vr, kd = (np.concatenate(ev[k]) for k in ("t", "phase", "v_rel", "kind"))
    assert len(t) > 50 and np.all(kd == ob.KIND_IMPACT)
    w = cfg.omega_s

    def miss(e):
        v_post = stator.velocity(ph[:-1], w) + e[:-1] * vr[:-1]
        dt = np.diff(t)
        land = stator.position(ph[:-1]) + v_post * dt - 0.5 * dt**2
        return np.abs(land - stator.position(ph[1:]))

    e_k = ob.event_restitution(cfg.e, cfg.e_sigma, cfg.seed, cfg.member, 0, len(t))
    assert np.max(miss(e_k)) < 1e-9
    assert np.max(miss(np.full(len(t), cfg.e))) > 1e-5
    assert np.std(e_k) == pytest.approx(1e-3, rel=0.3)


def test_compiled_reduction_with_noise_is_the_numpy_one():
    """The compiled reducer's Lyapunov sum with each impact's ``e_k`` is the numpy
    ``impact_jacobians`` + ``benettin`` one, bit for bit, chunk by chunk (the reference's
    chunk carries the previous chunk's last row in front, as the reducer does)."""
    cfg = EngineConfig(**PERIOD_2, t_end=800.0, e_sigma=1e-4, seed=2, member=5, max_events=10**6)
    t_from = 200.0
    red = _Reducer(cfg.e, cfg.omega_s, t_from, cfg.e_sigma, cfg.seed, cfg.member)
    vec = np.full(2, 1.0 / math.sqrt(2.0))
    total, count, prev, offset, seen, last = 0.0, 0, -2, 0, 0, None
    for c in iterate(cfg, InitialState(), chunk_events=37):
        red.add(c.t, c.phase, c.v_rel, c.kind)
        e_k = ob.event_restitution(cfg.e, cfg.e_sigma, cfg.seed, cfg.member, seen, len(c.t))
        seen += len(c.t)
        keep = c.t >= t_from
        rows = [c.t[keep], c.phase[keep], c.v_rel[keep], c.kind[keep], e_k[keep]]
        if not len(rows[0]):
            continue
        m = 0 if last is None else 1
        if last is not None:
            rows = [np.concatenate([a[-1:], b]) for a, b in zip(last, rows, strict=True)]
        jac, idx = ob.impact_jacobians(*rows[:4], rows[4], cfg.omega_s)
        skip = max(0, 20 - count)
        s, n, prev = ob.benettin(jac, (idx + offset - m).astype(np.int64), vec, prev, skip)
        total, count = total + s, count + n
        offset += int(np.count_nonzero(keep))
        last = rows
    assert count == red.lyap_count > 100
    assert repr(total) == repr(red.lyap_sum)
    assert total / count < -0.3
