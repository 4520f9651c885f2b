"""A closed standard output (``>&-``) is a one-line error, exit 2, no output file; a command
that prints nothing there still succeeds (docs/formats.md "Package and commands")."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from cli_helpers import SMALL_MOTOR

import bouncedisk
from bouncedisk.cli import main

ENV = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).resolve().parents[1])}
SCENE = SMALL_MOTOR.replace("time: 200.0", "time: 40.0").replace("discard: 50.0", "discard: 10.0")


def _closed(args: list[str]) -> subprocess.CompletedProcess:
    cmd = " ".join(shlex.quote(a) for a in [sys.executable, "-m", "bouncedisk.cli", *args])
    return subprocess.run(
        ["sh", "-c", cmd + " >&-"], capture_output=False, stderr=subprocess.PIPE,
        text=True, env=ENV, timeout=120,
    )  # fmt: skip


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("closed")
    (d / "s.yaml").write_text(SCENE)
    assert main(["simulate", str(d / "s.yaml"), "-o", str(d / "sim.nc"), "-q",
                 "--set", "ensemble.members=1"]) == 0  # fmt: skip
    return d


@pytest.mark.parametrize(
    "command",
    [
        ["info", "{d}/sim.nc"],
        ["stats", "{d}/s.yaml", "-o", "{d}/out.nc"],
        pytest.param(
            ["torque-speed", "{d}/s.yaml", "--loads", "0,0.5", "-o", "{d}/out.nc"],
            marks=pytest.mark.slow,
        ),
        pytest.param(
            ["simulate", "{d}/s.yaml", "-o", "{d}/out.nc", "--set", "ensemble.members=1"],
            marks=pytest.mark.slow,
        ),
    ],
)
def test_closed_stdout_is_one_line_and_no_output(files, command):
    """Before: AttributeError ('NoneType' object has no attribute 'write'), exit 1."""
    r = _closed([a.format(d=files) for a in command])
    # the short scene's window resolves no regime: its warning may come first
    lines = [x for x in r.stderr.strip().splitlines() if not x.startswith("bouncedisk: warning: ")]
    assert r.returncode == 2, r.stderr
    assert lines == ["bouncedisk: error: <stdout>: standard output is closed"]
    assert not (files / "out.nc").exists()


def test_a_quiet_command_needs_no_stdout(files):
    out = files / "quiet.nc"
    r = _closed(
        ["simulate", f"{files}/s.yaml", "-q", "-o", str(out), "--set", "ensemble.members=1"]
    )
    assert r.returncode == 0, r.stderr
    assert out.exists()
