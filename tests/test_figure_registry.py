"""The light figure registry: what the Snakefile imports, and how plotting resolves it."""

import inspect
import os
import subprocess
import sys
from pathlib import Path

import pytest

import bouncedisk
from bouncedisk.figures import drawing
from bouncedisk.figures import registry as figure_registry

#: one worker runs every Snakemake in the project root (pytest-xdist ``--dist loadgroup``)
pytestmark = pytest.mark.xdist_group("snakemake-root")

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "config_small.yaml"
HEAVY = ("matplotlib", "xarray", "pandas", "numba", "scipy")


def test_the_registry_imports_no_plotting_or_numerical_stack():
    # a fresh interpreter importing this checkout's package, as the Snakefile does at parse time
    code = (
        "import sys, bouncedisk.figures.registry; "
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r}))"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).parents[1])}
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "[]"


def test_plotting_figures_are_the_registry_resolved():
    assert figure_registry.DRAWING_MODULE == drawing.__name__
    assert list(drawing.FIGURES) == list(figure_registry.FIGURES)
    for name, decl in figure_registry.FIGURES.items():
        spec = drawing.FIGURES[name]
        assert spec.draw is getattr(drawing, decl.draw), name
        assert list(spec.inputs) == list(decl.inputs), name
        for key, opener in decl.inputs.items():
            assert spec.inputs[key] is drawing.OPENERS[opener], (name, key)
        assert spec.params == decl.params, name


def test_every_drawing_function_takes_the_declared_inputs_and_params():
    for name, decl in figure_registry.FIGURES.items():
        draw = getattr(drawing, decl.draw)
        assert callable(draw), name
        # the opened inputs positionally, in the declared order, then the parameters by name
        inspect.signature(draw).bind(*decl.inputs, **dict.fromkeys(decl.params))


def test_every_opener_opens_some_figure_input():
    used = {o for decl in figure_registry.FIGURES.values() for o in decl.inputs.values()}
    assert used == set(drawing.OPENERS)
