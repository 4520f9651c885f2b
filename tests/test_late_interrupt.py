"""An interrupt as a finished command exits: either the command counts as done (exit 0, its
output kept) or as interrupted (exit 130, a message, no output), never both."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import SMALL_MOTOR

import bouncedisk

ENV = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).resolve().parents[1])}
SCENE = SMALL_MOTOR.replace("time: 200.0", "time: 40.0").replace("discard: 50.0", "discard: 10.0")


@pytest.mark.parametrize("delay", [0.1])
def test_sigint_after_the_output_is_written(tmp_path, delay):
    """Before: killed by SIGINT (status -2, 130 in a shell), no message, the file kept."""
    (tmp_path / "s.yaml").write_text(SCENE)
    out = tmp_path / "s.nc"
    cmd = [sys.executable, "-m", "bouncedisk.cli", "stats", str(tmp_path / "s.yaml"), "-o",
           str(out), "-q", "--no-track"]  # fmt: skip
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    deadline = time.monotonic() + 120
    while not out.exists() and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.002)
    time.sleep(delay)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    # the short scene's window resolves no regime: its warning is not an error
    errors = [x for x in err.splitlines() if not x.startswith("bouncedisk: warning: ")]
    if p.returncode == 0:
        assert out.exists() and errors == []
    else:
        assert p.returncode == 130, (p.returncode, err)
        assert "interrupted" in err and not out.exists()


# ------------------------------------------------------- runs that go on without any event
#: The clipped model has no events: a run is contact to its time stop (about 20 min here).
CLIPPED = """
name: clipped
model: clipped
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01}
effects: [impacts, contact, torsion]
stop: {time: 1.0e9}
"""


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_run_without_events_stops_on_a_signal(tmp_path, sig):
    """Before: the whole run was one kernel call, so the signal waited for its end (about 20
    minutes; no progress line either, the loop never got control back)."""
    import select

    (tmp_path / "c.yaml").write_text(CLIPPED)
    out = tmp_path / "c.nc"
    cmd = [sys.executable, "-m", "bouncedisk.cli", "simulate", str(tmp_path / "c.yaml"), "-o",
           str(out), "--no-track"]  # fmt: skip
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    try:
        # the progress line (after 2 s) shows the run is under way, between two kernel calls
        ready, _, _ = select.select([p.stderr], [], [], 60)
        assert ready, "no progress line within 60 s"
        assert "clipped:" in p.stderr.readline()
        p.send_signal(sig)
        _, err = p.communicate(timeout=20)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, (p.returncode, err)
    assert "interrupted; no output written" in err and not out.exists()


@pytest.mark.parametrize(
    "kw",
    [
        {"omega_s": 0.5, "torsion": True},  # contact never ends (w <= 1)
        {"omega_s": 1.5, "torsion": True, "clipped": True},
        {"omega_s": 1.00000001, "torsion": True, "mu_ratio": 1.3},  # a window too shallow
    ],
)
def test_a_run_without_events_hands_back_control_every_few_periods(kw):
    """Before: no chunk at all until the end (the kernel returns after events or samples)."""
    from bouncedisk.engine import EngineConfig, InitialState, driver, iterate

    cfg = EngineConfig(e=0.3, t_end=3000.0, **kw)
    init = InitialState(omega=2.0)
    chunks = [c.t_now for c in iterate(cfg, init)]
    periods = 3000.0 * cfg.omega_s / (2 * math.pi)
    assert len(chunks) >= int(periods / driver._SLICE_PERIODS)
    assert all(np.diff(chunks) > 0)


@pytest.mark.parametrize(
    "kw",
    [
        {"omega_s": 0.5, "torsion": True, "load_torque": 0.2},
        {"omega_s": 1.5, "torsion": True, "clipped": True},
    ],
)
def test_slices_change_no_result(monkeypatch, kw):
    """A run cut every 7 periods gives the same bits as one uncut call."""
    from bouncedisk.engine import EngineConfig, InitialState, driver, simulate_arrays

    cfg = EngineConfig(e=0.3, t_end=400.0, traj_dt=0.37, stats_from=50.0, **kw)
    init = InitialState(t=0.3, omega=3.0, u=1.5, v=0.2)
    monkeypatch.setattr(driver, "_SLICE_PERIODS", 7)
    cut = simulate_arrays(cfg, init)
    monkeypatch.setattr(driver, "_may_run_without_events", lambda cfg: False)
    whole = simulate_arrays(cfg, init)
    assert len(cut.traj) > 100 and len(cut.strobe) == 0
    assert np.array_equal(cut.traj, whole.traj)
    for k, v in whole.events.items():
        assert np.array_equal(cut.events[k], v)
    assert cut.final == whole.final and cut.status == whole.status
