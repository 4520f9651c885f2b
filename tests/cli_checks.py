"""What the command-line tests share: the scenes they run and the checks of a one-line error and
of outputs left behind (``test_command_line_errors.py``, ``test_output_safety.py``, ...)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import bouncedisk

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "workflow" / "config" / "scenes"
FIG3 = str(SCENES / "fig3.yaml")
S6 = str(SCENES / "stats_e06.yaml")
#: Subprocesses run the package these tests import.
ENV = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).resolve().parents[1])}

SMALL = """
name: small
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01}
effects: [impacts, contact, torsion]
stop: {impacts: 50}
outputs: {events: true, trajectory: {dt: 0.05}}
"""
#: A short chaotic ensemble (seconds).
QUICK_STATS = ["--set", "stop.time=300", "--set", "stats.discard=50", "--set", "ensemble.members=4"]


def one_line(capsys) -> str:
    """The one line a command wrote on stderr (no traceback)."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    return err[0]


def no_files(folder: Path, stem: str = "out.nc") -> None:
    """Neither the output nor a temporary of it is in ``folder``."""
    assert not (folder / stem).exists()
    assert not [p for p in folder.iterdir() if p.name.startswith(f".{stem}.")]


def leftovers(folder: Path, stem: str) -> list[Path]:
    """The output ``stem`` and its temporaries found in ``folder``."""
    return [p for p in folder.iterdir() if p.name == stem or p.name.startswith(f".{stem}.")]


def write_scene(tmp_path: Path, text: str = SMALL) -> str:
    """A scene file with ``text`` in ``tmp_path``."""
    f = tmp_path / "s.yaml"
    f.write_text(text)
    return str(f)


def read_only_folder(tmp_path: Path) -> Path:
    """A folder where no file can be created (a chmod-ed one, or /sys when running as root)."""
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    for cand in (ro, Path("/sys")):
        try:
            (cand / ".probe").touch()
        except OSError:
            return cand
        (cand / ".probe").unlink()
    pytest.skip("no read-only folder available")
