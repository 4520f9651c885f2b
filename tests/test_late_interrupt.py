"""An interrupt as a finished command exits: either the command counts as done (exit 0, its
output kept) or as interrupted (exit 130, a message, no output), never both."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

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
    if p.returncode == 0:
        assert out.exists() and err == ""
    else:
        assert p.returncode == 130, (p.returncode, err)
        assert "interrupted" in err and not out.exists()
