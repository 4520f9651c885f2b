"""The package layout: the import contract, light commands, and the public API at the top level.

The layers and what each may import are declared once, in ``[tool.importlinter]`` of
``pyproject.toml`` (docs/internals.md, "Package layout"); this test runs ``lint-imports`` on them.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import bouncedisk

ROOT = Path(__file__).resolve().parents[1]
SRC = Path(bouncedisk.__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(SRC), os.environ.get("PYTHONPATH")]))}  # fmt: skip

#: Imported only by the commands that need them (``figures``, ``tracking``).
HEAVY = ("matplotlib", "mlflow")

SMALL = """\
name: small
parameters: {e: 0.6, omega_s: 1.5}
effects: [impacts, contact]
stop: {impacts: 200}
outputs: {events: true}
"""


def _python(code: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code], cwd=cwd, env=ENV, capture_output=True, text=True, timeout=600
    )


def test_the_import_contracts_are_kept(tmp_path):
    """Layers (each imports only those below it), no import circle within a folder, and only
    ``figures`` / ``tracking`` touch matplotlib / mlflow (``lint-imports``)."""
    exe = shutil.which("lint-imports")
    cmd = [exe] if exe else [sys.executable, "-c", "import importlinter.cli as c; c.lint_imports_command()"]  # fmt: skip
    r = subprocess.run(
        [*cmd, "--config", str(ROOT / "pyproject.toml"), "--cache-dir", str(tmp_path)],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert "0 broken" in r.stdout


def test_simulate_imports_neither_matplotlib_nor_mlflow(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text(SMALL)
    out = tmp_path / "s.nc"
    code = (
        "import json, sys\n"
        "from bouncedisk.cli import main\n"
        f"code = main(['simulate', {str(scene)!r}, '-o', {str(out)!r}, '-q'])\n"
        f"print(json.dumps([code, sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r})]))"
    )
    r = _python(code, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    code, heavy = json.loads(r.stdout.splitlines()[-1])
    assert code == 0 and out.is_file()
    assert heavy == []


def test_drawing_and_reading_files_import_no_numba(tmp_path):
    """A figure job (figures, netCDF reading and writing, the records' names) loads no numba:
    the record layouts are plain integers (``engine/layout.py``) and the engine's entry points
    load on first use; the engine itself still loads, with its cache, when it is used."""
    code = (
        "import json, sys\n"
        "import bouncedisk.figures.drawing, bouncedisk.figures.common, bouncedisk.io.netcdf\n"
        "from bouncedisk.io.records import EventKind, RunStatus, TrajColumn\n"
        "from bouncedisk.engine import KIND_CHATTER\n"
        "before = sorted(m for m in sys.modules if m.split('.')[0] == 'numba')\n"
        "from bouncedisk.engine import EngineConfig, simulate_arrays\n"
        "res = simulate_arrays(EngineConfig(e=0.3, omega_s=1.5, max_events=5))\n"
        "print(json.dumps([before, 'numba' in sys.modules, len(res.events['t']),"
        " int(EventKind.CHATTER) == KIND_CHATTER, RunStatus(res.status_code).text]))"
    )
    r = _python(code, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    before, loaded, events, same_code, status = json.loads(r.stdout.splitlines()[-1])
    assert before == [] and loaded and events == 5 and same_code and status == "completed"


def test_the_command_s_parser_and_the_package_are_light():
    """``bouncedisk --help`` builds every subcommand's parser without the numerical stack, and
    ``import bouncedisk`` imports none of the public API until it is used."""
    code = (
        "import json, sys, contextlib, io\n"
        "import bouncedisk\n"
        "first = sorted(m for m in sys.modules if m.startswith('bouncedisk.'))\n"
        "from bouncedisk.cli.command import build_parser\n"
        "build_parser()\n"
        "heavy = sorted({m.split('.')[0] for m in sys.modules} & {'matplotlib', 'mlflow', "
        "'xarray', 'numba', 'netCDF4', 'pandas', 'scipy'})\n"
        "print(json.dumps([first, heavy]))"
    )
    r = _python(code)
    assert r.returncode == 0, r.stderr[-2000:]
    first, heavy = json.loads(r.stdout.splitlines()[-1])
    assert first == [] and heavy == []


def test_the_public_api_is_importable_from_the_top_level(tmp_path):
    for name in bouncedisk.__all__:
        assert getattr(bouncedisk, name) is not None, name
    assert bouncedisk.engine.EngineConfig is bouncedisk.EngineConfig
    scene = tmp_path / "s.yaml"
    scene.write_text(SMALL)
    summary = bouncedisk.run_scene(bouncedisk.load_scene(str(scene)), tmp_path / "s.nc")
    ds = bouncedisk.open_simulation(tmp_path / "s.nc")
    assert ds.attrs["run_id"] == summary.run_id and ds.sizes["impact"] == summary.n_events
    ds.close()
