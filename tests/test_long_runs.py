"""Long runs within bounds: streamed segments, the output's size refused before running or
while streaming, the pipeline's peak memory; the final state of a run ending in contact,
chattering as the drive tends to ``omega_s = 1``, and exact event times over long runs.
"""

import math
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr
from cli_checks import FIG3, SMALL, no_files, one_line

from bouncedisk.cli import main
from bouncedisk.engine import EngineConfig, InitialState, iterate, simulate_arrays
from bouncedisk.io.records import EventKind


# -------------------------------------------------------------------------- bounded memory/disk
def test_segment_longer_than_the_buffer_is_streamed():
    """One flight of ~2000 time units at dt = 0.007 (~300,000 samples) in 1,000-row chunks."""
    cfg = EngineConfig(e=0.3, omega_s=1.5, max_events=3, traj_dt=0.007, stroboscopic=True)
    init = InitialState(t=0.0, u=2.0, v=1000.0)
    chunks = list(iterate(cfg, init, chunk_samples=1000))
    assert max(len(c.traj) for c in chunks) <= 1000
    assert max(len(c.strobe) for c in chunks) <= 1000
    whole = simulate_arrays(cfg, init)
    traj = np.concatenate([c.traj for c in chunks])
    strobe = np.concatenate([c.strobe for c in chunks])
    assert len(traj) > 250_000
    assert np.array_equal(traj, whole.traj) and np.array_equal(strobe, whole.strobe)
    assert np.array_equal(np.concatenate([c.t for c in chunks]), whole.events["t"])


@pytest.mark.parametrize(
    "sets",
    [
        ["outputs.trajectory.dt=1.0e-9"],  # 24 GB RSS before the output was streamed
        ["outputs.trajectory.dt=1.0e-8", "stop={time: 4.0}"],  # 12.5 GiB allocation
        ["initial={t: 0.0, u: 2.0, v: 1.0e+10}"],  # 72.8 TiB allocation
        ["initial={t: 0.0, u: 2.0, v: 1.0e+10}", "outputs={trajectory: false, stroboscopic: true}"],
    ],
)
def test_output_over_the_disk_limit_is_refused_before_running(tmp_path, capsys, sets):
    out = tmp_path / "out.nc"
    argv = ["simulate", FIG3, "-o", str(out), "-q"]
    for s in sets:
        argv += ["--set", s]
    start = time.process_time()
    assert main(argv) == 2
    assert time.process_time() - start < 10.0  # CPU seconds, not wall-clock
    line = one_line(capsys)
    assert "over the limit" in line and "--max-output" in line
    no_files(tmp_path)


def test_limit_is_configurable_and_enforced_while_streaming(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out.nc"
    scene = tmp_path / "s.yaml"
    scene.write_text(SMALL)
    # a normal run fits the default limit
    assert main(["simulate", str(scene), "-o", str(out), "-q"]) == 0
    out.unlink()
    assert main(["simulate", str(scene), "-o", str(out), "-q", "--max-output", "2K"]) == 2
    assert "over the limit of 2 KiB" in one_line(capsys)
    no_files(tmp_path)
    # a time stop's event count is unknown in advance: the writer stops the run
    monkeypatch.setenv("BOUNCEDISK_MAX_OUTPUT", "100K")
    argv = ["simulate", str(scene), "-o", str(out), "-q", "--set", "stop={time: 1.0e+5}"]
    argv += ["--set", "outputs={events: true}"]
    assert main(argv) == 2
    assert "over the limit" in one_line(capsys)
    no_files(tmp_path)
    assert main(["simulate", str(scene), "-o", str(out), "--max-output", "lots"]) == 2
    assert "--max-output" in one_line(capsys)


# -------------------------------------------------------------------------------- pipeline peak
def test_scaling_trajectory_case_runs_in_bounded_memory():
    """The '+ trajectory' case of the scaling study at 30,000 impacts (12.7 million samples):
    collected in memory it peaked above 1 GB; streamed, it stays near the engine's baseline."""
    code = (
        "from bouncedisk.studies.scaling import _rate\n"
        "from bouncedisk.engine import EngineConfig\n"
        "_rate(EngineConfig(e=0.6, omega_s=1.5, max_events=30000, torsion=True, r_phi=0.01,"
        " traj_dt=0.01), repeat=1)\n"
        "print([l for l in open('/proc/self/status') if l.startswith('VmHWM')][0].split()[1])\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    peak_mb = int(proc.stdout.strip().splitlines()[-1]) / 1024
    assert peak_mb < 500, peak_mb


# ---------------------------------------------------------------------------------- final state
def test_final_in_contact(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text(SMALL)
    rest = tmp_path / "rest.nc"
    args = ["simulate", str(scene), "-o", str(rest), "-q", "--set", "parameters.omega_s=0.8"]
    assert main(args) == 0
    with xr.open_dataset(rest) as ds:
        assert ds.attrs["status"].startswith("rest")
        assert ds.attrs["final_in_contact"] == 1
    flying = tmp_path / "fly.nc"
    args = ["simulate", str(scene), "-o", str(flying), "-q"]
    args += ["--set", "initial={t: 0.0, u: 3.0, v: 0.0}", "--set", "stop={time: 0.5}"]
    assert main(args) == 0
    with xr.open_dataset(flying) as ds:
        assert ds.attrs["final_in_contact"] == 0
    # in contact at the end of a time stop
    res = simulate_arrays(EngineConfig(e=0.0, omega_s=0.9, t_end=3.0))
    assert res.final["in_contact"] == 1.0


# -------------------------------------------------------------------------------- omega_s -> 1+
@pytest.mark.parametrize("w", [1.0000001, 1.000001, 1.00001, 1.0001])
@pytest.mark.parametrize("e", [0.3, 0.6])
def test_chattering_near_omega_one_is_accumulated(w, e):
    """Every cycle near w = 1+ is separate, land, accumulate (one chatter event), ride."""
    res = simulate_arrays(EngineConfig(e=e, omega_s=w, max_events=300))
    kind = res.events["kind"]
    assert res.ok and np.count_nonzero(kind == EventKind.CHATTER) >= 10
    imp = kind == EventKind.IMPACT
    assert res.events["v_rel"][imp][5:].min() > 1e-12  # no bounce resolved below rounding
    assert np.diff(res.events["t"]).min() > 1e-7


def test_below_the_grazing_limit_the_rotor_rests():
    res = simulate_arrays(EngineConfig(e=0.3, omega_s=1.00000001, max_events=300))
    assert res.status.startswith("rest") and len(res.events["t"]) == 0


# ---------------------------------------------------------------------------- exact event times
def test_period_index_and_phase_keep_long_runs_exact(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text(
        "name: long\nparameters: {e: 0.3, omega_s: 1000.0}\ninitial: {t: 5.0e+8}\n"
        "stop: {impacts: 20000}\n"
    )
    out = tmp_path / "out.nc"
    assert main(["simulate", str(scene), "-o", str(out), "-q"]) == 0
    with xr.open_dataset(out) as ds:
        n = ds["period_index"].values
        ph = ds["phase"].values
        t = ds["t_impact"].values
        assert n.dtype == np.int64
    # t_impact alone resolves ~6e-8 at t ~ 5e8; the phase resolves ~1e-16 of a period
    assert np.spacing(t).max() > 5e-8
    order = np.lexsort((ph, n))
    assert np.array_equal(order, np.arange(len(n)))  # (period, phase) strictly ordered
    assert np.all((np.diff(n) > 0) | (np.diff(ph) > 0))
    assert np.allclose((2 * math.pi * n + ph) / 1000.0, t, rtol=0, atol=1e-6)
