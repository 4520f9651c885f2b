"""A stopped fit stops promptly, and a long load curve reports its progress (the fit's part of
"long runs print progress and stop on SIGTERM/SIGINT")."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest

from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting.members import thread_map


def test_an_interrupt_cancels_the_members_not_started():
    """``KeyboardInterrupt`` (how the command receives SIGINT and SIGTERM) in the caller's thread
    while members run: the queued members never start and the call returns at once, not after
    every member (40 of 0.2 s on two threads would take 4 s)."""
    started = []
    lock = threading.Lock()

    def member(i):
        with lock:
            started.append(i)
        time.sleep(0.2)
        return i

    def interrupt(k):
        if k == 2:
            raise KeyboardInterrupt

    t = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        thread_map(member, range(40), 2, on_done=interrupt)
    assert time.perf_counter() - t < 1.5
    assert len(started) <= 6, started  # the two running and at most a couple picked up after
    # without an interrupt: every result, in order, and on_done after each
    seen = []
    assert thread_map(lambda i: i * i, range(9), 2, on_done=seen.append) == [
        i * i for i in range(9)
    ]
    assert seen == list(range(1, 10))


def test_a_failing_member_stops_the_rest_too():
    """An error of one member is raised as it is, and the queued members are cancelled."""
    started = []

    def member(i):
        started.append(i)
        if i == 0:
            raise ValueError("member 0 failed")
        time.sleep(0.1)
        return i

    with pytest.raises(ValueError, match="member 0"):
        thread_map(member, range(30), 2)
    assert len(started) < 10


def test_a_long_load_evaluation_reports_its_progress(monkeypatch):
    """Every :data:`loadpart.PROGRESS_S` seconds of an evaluation the load part reports how many
    member curves it has read (here at every one: the interval set to 0)."""
    from bouncedisk.io.load_curves import LoadCurveData

    monkeypatch.setattr(lp, "PROGRESS_S", 0.0)
    data = LoadCurveData(torque=np.array([0.0, 1e-5]), speed=np.array([1.0, 0.5]), speed_sd=None,
                         drive_frequency_hz=15000.0, phi0_rad=3e-4,
                         rotor={"m_r_kg": 0.01, "r_g_m": 0.004, "r_c_m": 0.002}, preload_n=0.77,
                         window_s=(0.005, 0.01), synthetic=True, path="<test>")  # fmt: skip
    lines = []
    for cores in (1, 2):
        lines.clear()
        part = lp.LoadPart([data], 0.03, 1, cores=cores, progress=lines.append)
        theta = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}
        part.values(theta, np.array([0.55, math.log10(0.002), 0.4, 1.7]), 3)
        assert [ln.split(" member")[0] for ln in lines] == [f"load curve: {j}/3" for j in (1, 2, 3)]


@pytest.mark.slow  # a subprocess that imports the package and starts a fit
def test_sigterm_stops_a_running_fit_promptly(tmp_path):
    """``bouncedisk fit`` receiving SIGTERM in its scan: exit 130 within seconds (a fit of the
    shipped curve runs for minutes), one line on stderr, no output file."""
    import os
    import signal
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).parents[1]
    out = tmp_path / "fit.nc"
    proc = subprocess.Popen(
        [sys.executable, "-m", "bouncedisk.cli", "fit", str(root / "data/prototype/synthetic_motor.csv"),
         "-o", str(out), "--cores", "2"],
        stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )  # fmt: skip
    lines = []
    for line in proc.stderr:  # wait until the fit has started its work
        lines.append(line)
        if "samples over" in line:
            break
    time.sleep(3.0)
    sent = time.perf_counter()
    proc.send_signal(signal.SIGTERM)
    rest = proc.stderr.read()
    code = proc.wait(timeout=120)
    waited = time.perf_counter() - sent
    assert code == 130, (code, lines, rest)
    assert waited < 30.0, waited
    assert rest.strip().splitlines()[-1] == "bouncedisk: interrupted; no output written"
    assert not out.exists()


def test_a_burst_of_interrupts_is_one_line(tmp_path):
    """Ctrl-C pressed again while the fit stops (or ``timeout``, which signals the command and
    then its process group): the first SIGINT stops it, the others are ignored, and stderr
    holds the one line after the progress, no traceback; exit 130, no fit file."""
    import signal
    import subprocess
    import sys
    from pathlib import Path

    out = tmp_path / "fit.nc"
    curve = Path(__file__).resolve().parents[1] / "data/prototype/synthetic_motor.csv"
    cmd = [sys.executable, "-m", "bouncedisk.cli", "fit", str(curve),
           "--scan", "8", "--zoom", "0", "--cores", "2", "-o", str(out)]  # fmt: skip
    p = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    lines = []
    while len(lines) < 3:  # in the search (after the two lines that say what was read)
        line = p.stderr.readline()
        assert line, "".join(lines)
        lines.append(line)
    for _ in range(6):
        p.send_signal(signal.SIGINT)
        time.sleep(0.03)
    rest = p.stderr.read()
    assert p.wait(timeout=120) == 130, rest
    assert rest.strip().splitlines()[-1:] == ["bouncedisk: interrupted; no output written"], rest
    assert "Traceback" not in rest and "Exception ignored" not in rest, rest
    assert not out.exists()


def test_a_deferred_interrupt_reaches_the_command_handler_that_ignores_the_next():
    """A signal deferred by a run's block (``deferred_interrupts``: no stop inside a file
    write) is handed, when the block ends, to the handler it replaced: the console script's
    stops the command and ignores a second signal, so the stop's one line stays the only one."""
    import os
    import signal

    from bouncedisk.cli.command import _install_signal_handlers
    from bouncedisk.run.runner import deferred_interrupts

    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        _install_signal_handlers(console=True)
        with pytest.raises(KeyboardInterrupt), deferred_interrupts():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)  # the handler runs in the main thread, at the next bytecode
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    finally:
        for s, h in saved.items():
            signal.signal(s, h)
