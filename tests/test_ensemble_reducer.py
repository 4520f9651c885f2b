"""The compiled reduction of ensemble members gives the numpy reduction's numbers, bit for bit.

``analysis/ensembles.py`` reduces each chunk in compiled code that releases the GIL (members
on two cores run nearly twice as fast as on one); the reference here is the reduction as it was
written in numpy (``observables.impact_jacobians`` then ``observables.benettin``, the tail
concatenated), fed the same chunks.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bouncedisk.analysis import observables as ob
from bouncedisk.analysis.ensembles import LYAPUNOV_SKIP, TAIL_EVENTS, _Reducer
from bouncedisk.engine import EngineConfig, InitialState, iterate


class _NumpyReducer:
    """The reduction of ``_Reducer.add`` in numpy (before it was compiled)."""

    def __init__(self, e: float, omega_s: float, t_from: float):
        self.e, self.w, self.t_from = e, omega_s, t_from
        self.n_impacts = self.n_chatter = 0
        self.chatter_first = self.chatter_last = math.nan
        self.lyap_sum, self.lyap_count = 0.0, 0
        self.vec = np.full(2, 1.0 / math.sqrt(2.0))
        self.prev_pair, self.offset = -2, 0
        self.tail = {k: np.empty(0) for k in ("t", "phase", "v_rel")}
        self.tail["kind"] = np.empty(0, dtype=np.int8)

    def add(self, t, phase, v_rel, kind) -> None:
        keep = t >= self.t_from
        if not np.any(keep):
            return
        t, phase, v_rel, kind = t[keep], phase[keep], v_rel[keep], kind[keep]
        self.n_impacts += int(np.count_nonzero(kind == ob.KIND_IMPACT))
        chat = t[kind == ob.KIND_CHATTER]
        if len(chat):
            if self.n_chatter == 0:
                self.chatter_first = float(chat[0])
            self.chatter_last = float(chat[-1])
            self.n_chatter += len(chat)
        tl = self.tail
        m = 1 if len(tl["t"]) else 0
        cat = {
            k: np.concatenate([tl[k][len(tl[k]) - m :], v])
            for k, v in (("t", t), ("phase", phase), ("v_rel", v_rel), ("kind", kind))
        }
        jac, idx = ob.impact_jacobians(
            cat["t"], cat["phase"], cat["v_rel"], cat["kind"], self.e, self.w
        )
        skip = max(0, LYAPUNOV_SKIP - self.lyap_count)
        total, count, self.prev_pair = ob.benettin(
            jac, (idx + self.offset - m).astype(np.int64), self.vec, self.prev_pair, skip
        )
        self.lyap_sum += total
        self.lyap_count += count
        self.offset += len(t)
        for k in tl:
            tl[k] = cat[k][-TAIL_EVENTS:]


SCENES = {
    "chaotic, chatters": (EngineConfig(e=0.6, omega_s=1.5, torsion=True, t_end=9000.0), 300.0),
    "periodic": (EngineConfig(e=0.3, omega_s=1.5, t_end=4000.0, e_sigma=1e-9), 100.0),
    "locked chatter cycle": (EngineConfig(e=0.5, omega_s=1.126, t_end=3000.0), 50.0),
    "noisy, loaded": (
        EngineConfig(e=0.5, omega_s=2.2, torsion=True, load_torque=0.2, t_end=6000.0, e_sigma=1e-3),
        2000.0,
    ),
}


@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("chunk", [97, 1500, 1 << 16])
def test_compiled_reduction_is_the_numpy_one(name, chunk):
    cfg, t_from = SCENES[name]
    cfg = EngineConfig(**{**cfg.__dict__, "max_events": 10**9})
    new, old = _Reducer(cfg.e, cfg.omega_s, t_from), _NumpyReducer(cfg.e, cfg.omega_s, t_from)
    for c in iterate(cfg, InitialState(), chunk_events=chunk):
        new.add(c.t, c.phase, c.v_rel, c.kind)
        old.add(c.t, c.phase, c.v_rel, c.kind)
    for attr in ("n_impacts", "n_chatter", "lyap_count", "prev_pair", "offset"):
        assert getattr(new, attr) == getattr(old, attr), attr
    for attr in ("chatter_first", "chatter_last", "lyap_sum"):
        assert repr(getattr(new, attr)) == repr(getattr(old, attr)), attr
    assert new.vec.tobytes() == old.vec.tobytes()
    assert old.n_impacts > 0 and old.lyap_count > 0
    for k, v in old.tail.items():
        assert new.tail[k].dtype == v.dtype and new.tail[k].tobytes() == v.tobytes(), k


def test_compiled_period_search_is_the_numpy_one():
    rng = np.random.default_rng(5)
    for trial in range(300):
        p_true = int(rng.integers(1, 9))
        n = int(rng.integers(4, 200))
        cyc = rng.uniform(0, 2 * np.pi, p_true)
        ph = np.resize(cyc, n) + rng.normal(0, 10 ** rng.uniform(-9, -5), n)
        ph = np.mod(ph, 2 * np.pi)
        vr = np.resize(rng.uniform(0, 3, p_true), n) * (1 + rng.normal(0, 1e-7, n))
        kd = (rng.uniform(size=n) < (0.02 if trial % 3 else 0.0)).astype(np.int8)
        for maxp in (4, 16, 32):
            got = ob._first_period(ph, vr, kd, maxp, 1e-6)
            assert got == ob._first_period_numpy(ph, vr, kd, maxp, 1e-6)
            t = np.arange(n) * 4.0
            per = ob.find_period(t, ph, vr, kd, 1.5, max_period=maxp, tail=n)
            per32 = ob.find_period(t, ph.astype(np.float32), vr, kd, 1.5, max_period=maxp, tail=n)
            assert (per is None) == (got == 0)
            assert per32 is None or per32.p >= 1


def _numpy_chatter_cycle(t, phase, v_rel, kind, omega_s, tol=1e-6):
    """``observables.chatter_cycle`` as it was written in numpy."""
    where = np.nonzero(kind == ob.KIND_CHATTER)[0]
    if len(where) < 3:
        return None
    a, b, c = where[-3], where[-2], where[-1]
    if c - b != b - a:
        return None
    m = c - b
    dph = ob.circular_distance(phase[b + 1 : c + 1], phase[a + 1 : b + 1])
    dv = np.abs(v_rel[b + 1 : c + 1] - v_rel[a + 1 : b + 1])
    if np.any(kind[b + 1 : c + 1] != kind[a + 1 : b + 1]) or np.any(dph > tol) or np.any(dv > tol):
        return None
    q = int(round((t[c] - t[b]) * omega_s / ob.TWO_PI))
    return int(m - 1), q


def test_compiled_chatter_cycle_is_the_numpy_one():
    rng = np.random.default_rng(11)
    for trial in range(500):
        m = int(rng.integers(1, 12))
        cycles = int(rng.integers(1, 6))
        base_ph = rng.uniform(0, 2 * np.pi, m)
        base_vr = rng.uniform(0, 2, m)
        kinds = np.zeros(m, np.int8)
        kinds[-1] = ob.KIND_CHATTER
        ph = np.tile(base_ph, cycles) + rng.normal(0, 10 ** rng.uniform(-9, -5), m * cycles)
        vr = np.tile(base_vr, cycles) + rng.normal(0, 10 ** rng.uniform(-9, -5), m * cycles)
        kd = np.tile(kinds, cycles)
        if trial % 4 == 0 and len(kd) > 2:  # an extra chatter somewhere
            kd[int(rng.integers(0, len(kd)))] = ob.KIND_CHATTER
        if trial % 7 == 0:
            ph[int(rng.integers(0, len(ph)))] = np.nan
        ph = np.mod(ph, 2 * np.pi)
        t = np.cumsum(rng.uniform(3, 5, len(kd)))
        got = ob.chatter_cycle(t, ph, vr, kd, 1.5)
        assert got == _numpy_chatter_cycle(t, ph, vr, kd, 1.5)
