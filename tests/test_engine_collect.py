"""simulate_arrays collects exactly what iterate streams (engine/driver.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bouncedisk.engine import EngineConfig, InitialState, iterate, simulate_arrays
from bouncedisk.engine import driver as D

CASES = {
    "events stop": EngineConfig(e=0.6, omega_s=1.5, max_events=40_000),
    "time stop, samples": EngineConfig(
        e=0.6, omega_s=1.5, torsion=True, r_phi=0.01, t_end=900.0, traj_dt=0.01, max_events=10**9
    ),
    "strobe": EngineConfig(e=0.3, omega_s=1.5, stroboscopic=True, max_events=20_000),
    "rest": EngineConfig(e=0.5, omega_s=0.9, max_events=100),
    "nothing": EngineConfig(e=0.3, omega_s=1.5, t_end=0.1, max_events=100),
}


def _streamed(cfg: EngineConfig):
    chunks = []
    gen = iterate(cfg, InitialState(), chunk_events=5000, chunk_samples=7000)
    while True:
        try:
            chunks.append(next(gen))
        except StopIteration as stop:
            return chunks, stop.value


@pytest.mark.parametrize("name", sorted(CASES))
def test_collected_arrays_are_the_streamed_chunks(name, monkeypatch):
    # small kernel buffers and capacities: the collection grows many times
    monkeypatch.setattr(D, "_COLLECT_CHUNK", 1000)
    monkeypatch.setattr(D, "_COLLECT_PREALLOCATE", 3000)
    cfg = CASES[name]
    res = simulate_arrays(cfg)
    chunks, (status, final) = _streamed(cfg)
    assert res.status_code == status and res.final == final
    for key, arr in res.events.items():
        parts = [getattr(c, key) for c in chunks]
        want = np.concatenate(parts) if parts else np.empty(0, arr.dtype)
        assert arr.dtype == want.dtype and arr.flags.c_contiguous and arr.flags.owndata
        assert arr.tobytes() == want.tobytes(), key
    for key, cols in (("traj", D.K.TRAJ_COLS), ("strobe", D.K.STROBE_COLS)):
        parts = [getattr(c, key) for c in chunks]
        want = np.concatenate(parts) if parts else np.empty((0, cols))
        got = getattr(res, key)
        assert got.shape == want.shape and got.tobytes() == want.tobytes(), key
    assert math.isfinite(res.final["t"])


def test_on_chunk_sees_every_chunk():
    seen = []
    res = simulate_arrays(CASES["events stop"], on_chunk=seen.append)
    assert sum(len(c.t) for c in seen) == len(res.events["t"]) == 40_000


def test_returning_keeps_a_generators_return_value_after_the_loop():
    from bouncedisk.engine.driver import Returning

    def gen():
        yield 1
        yield 2
        return "done"

    g = Returning(gen())
    assert g.value is None
    assert list(g) == [1, 2] and g.value == "done"
    early = Returning(gen())
    for _ in early:
        break
    assert early.value is None  # not run to its end: no return value
