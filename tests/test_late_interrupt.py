"""An interrupt as a finished command exits: either the command counts as done (exit 0, its
output kept) or as interrupted (exit 130, a message, no output), never both (issue 37 item 14)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import bouncedisk

ENV = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).resolve().parents[1])}
SCENE = """
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0, e_sigma: 1.0e-9}
effects: [impacts, contact, torsion, restitution_noise]
stop: {time: 40.0}
ensemble: {members: 2, seed: 1}
stats: {discard: 10.0}
"""


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
    if p.returncode == 0:
        assert out.exists() and err == ""
    else:
        assert p.returncode == 130, (p.returncode, err)
        assert "interrupted" in err and not out.exists()
