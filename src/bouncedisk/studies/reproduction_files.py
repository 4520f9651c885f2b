"""What the reproduction checks read: the shipped scenes and the pipeline's built results.

Standard library only: the Snakefile reads these lists when it is parsed
(``workflow/rules/common.smk``: the pipeline builds what the checks read), and
:mod:`bouncedisk.studies.reproduction` reads the files.
"""

from __future__ import annotations

from importlib import resources
from importlib.resources.abc import Traversable

#: The scene files the package ships (package data; the pipeline's ``workflow/config/scenes``
#: is a link to this folder): the checks simulate the same scenes the pipeline runs.
SCENE_DIR: Traversable = resources.files("bouncedisk") / "scenes"
#: The ensemble statistics the checks read (``results/stats/<name>.nc``).
STATS_SCENES = ("stats_e03", "stats_e06", "stats_locked")
#: The load curves the checks read (``results/load/<name>.nc``).
LOAD_CURVES = ("load_fig3", "load_fig4")
#: The pipeline's joint fit of the prototype (run-up and load curve).
FIT_FILE = "fit/prototype.nc"
#: Every built result the checks read (relative to the results folder).
RESULT_FILES = (
    "simulations/fig5.nc",
    "bands/fig5.nc",
    *(f"stats/{name}.nc" for name in STATS_SCENES),
    *(f"load/{name}.nc" for name in LOAD_CURVES),
    FIT_FILE,
)


def scene_file(name: str) -> Traversable:
    """The shipped scene file ``bouncedisk/scenes/<name>.yaml`` (it may not exist)."""
    return SCENE_DIR / f"{name}.yaml"
