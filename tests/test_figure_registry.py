"""The light figure registry: what the Snakefile imports, and how plotting resolves it."""

import inspect
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import bouncedisk
from bouncedisk import figure_registry, plotting

#: one worker runs every Snakemake in the project root (pytest-xdist ``--dist loadgroup``)
pytestmark = pytest.mark.xdist_group("snakemake-root")

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "config_small.yaml"
HEAVY = ("matplotlib", "xarray", "pandas", "numba", "scipy")


def test_the_registry_imports_no_plotting_or_numerical_stack():
    # a fresh interpreter importing this checkout's package, as the Snakefile does at parse time
    code = (
        "import sys, bouncedisk.figure_registry; "
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r}))"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).parents[1])}
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "[]"


def test_plotting_figures_are_the_registry_resolved():
    assert figure_registry.DRAWING_MODULE == plotting.__name__
    assert list(plotting.FIGURES) == list(figure_registry.FIGURES)
    for name, decl in figure_registry.FIGURES.items():
        spec = plotting.FIGURES[name]
        assert spec.draw is getattr(plotting, decl.draw), name
        assert list(spec.inputs) == list(decl.inputs), name
        for key, opener in decl.inputs.items():
            assert spec.inputs[key] is plotting.OPENERS[opener], (name, key)
        assert spec.params == decl.params, name


def test_every_drawing_function_takes_the_declared_inputs_and_params():
    for name, decl in figure_registry.FIGURES.items():
        draw = getattr(plotting, decl.draw)
        assert callable(draw), name
        # the opened inputs positionally, in the declared order, then the parameters by name
        inspect.signature(draw).bind(*decl.inputs, **dict.fromkeys(decl.params))


def test_every_opener_opens_some_figure_input():
    used = {o for decl in figure_registry.FIGURES.values() for o in decl.inputs.values()}
    assert used == set(plotting.OPENERS)


def _dry_run(cwd: Path, res: Path) -> subprocess.CompletedProcess:
    cmd = ["snakemake", "--cores", "1", "--configfile", str(SMALL), "--config", f"results={res}"]
    return subprocess.run([*cmd, "-n"], cwd=cwd, capture_output=True, text=True)


@pytest.mark.skipif(shutil.which("snakemake") is None, reason="snakemake not found")
def test_the_figure_table_is_checked_against_the_registry(tmp_path):
    # a scratch copy of the pipeline, whose figure table disagrees with the registry one way at a
    # time: the Snakefile fails before any job, naming the table and the entry
    copy = tmp_path / "copy"
    shutil.copytree(ROOT / "workflow", copy / "workflow")
    shutil.copytree(ROOT / "data", copy / "data")
    shutil.copy(ROOT / "Snakefile", copy / "Snakefile")
    table = copy / "workflow" / "config" / "figures.yaml"
    good = table.read_text()
    entry = "  plot: regime_map\n  inputs: {sweep:"
    assert entry in good
    known = ", ".join(sorted(figure_registry.FIGURES))
    for broken, message in (
        (
            good.replace(entry, "  plot: nope\n  inputs: {sweep:"),
            f"regime_map.plot: unknown figure 'nope' (bouncedisk.plotting.FIGURES: {known})",
        ),
        (
            good.replace(entry, "  plot: regime_map\n  inputs: {swep:"),
            "regime_map.inputs: 'regime_map' takes ['sweep'], the table gives ['swep']",
        ),
        (
            good.replace("  params: {labels: poincare}\n", ""),
            "poincare_maps.params: 'poincare' takes ['labels'], the table gives []",
        ),
    ):
        table.write_text(broken)
        p = _dry_run(copy, tmp_path / "r")
        out = p.stdout + p.stderr
        assert p.returncode != 0 and f"figures.yaml: {message}" in out, out[-2000:]
    assert not (tmp_path / "r").exists()
