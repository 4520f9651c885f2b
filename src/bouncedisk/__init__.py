"""bouncedisk: exact event-driven simulation of a rotor bouncing on a vibrating, twisting stator.

See docs/model.md for the model; :mod:`bouncedisk.engine` for the simulator kernel. The public API is
importable from here, loaded on first use (``import bouncedisk`` alone imports no numba, xarray,
matplotlib or mlflow)::

    import bouncedisk

    scene = bouncedisk.load_scene("workflow/config/scenes/fig3.yaml")
    bouncedisk.run_scene(scene, "fig3.nc")  # a scene -> one netCDF file
    ds = bouncedisk.open_simulation("fig3.nc")

The package is laid out by layer (docs/internals.md, "Package layout"): ``engine`` · ``model`` ·
``io`` · ``run`` · ``analysis`` · ``studies`` · ``fitting`` / ``figures`` / ``tracking`` · ``cli``,
each importing only the layers before it.
"""

from importlib import import_module
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("bouncedisk")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

#: The public API: name -> the module that defines it (imported when the name is first used;
#: strings, so that importing the package imports none of them).
PUBLIC = {
    # the engine
    "engine": "bouncedisk.engine",
    "EngineConfig": "bouncedisk.engine",
    "InitialState": "bouncedisk.engine",
    "EngineError": "bouncedisk.engine",
    "iterate": "bouncedisk.engine",
    "simulate_arrays": "bouncedisk.engine",
    # the model: scenes and parameters
    "Scene": "bouncedisk.model.scene",
    "load_scene": "bouncedisk.model.scene",
    "scene_from_mapping": "bouncedisk.model.scene",
    "Parameters": "bouncedisk.model.params",
    "PhysicalParameters": "bouncedisk.model.params",
    "InputError": "bouncedisk.model.errors",
    # running a scene
    "run_scene": "bouncedisk.run.runner",
    "run_scene_arrays": "bouncedisk.run.runner",
    "RunSummary": "bouncedisk.run.runner",
    # opening a file
    "open_simulation": "bouncedisk.io.netcdf",
    "open_checked": "bouncedisk.io.netcdf",
    # the studies of a scene
    "run_stats": "bouncedisk.analysis.statistics",
    "poincare_dataset": "bouncedisk.analysis.poincare",
    "torque_speed": "bouncedisk.studies.torque_speed",
    "basins": "bouncedisk.studies.basins",
    "start_grid": "bouncedisk.studies.basins",
}

__all__ = ["__version__", *PUBLIC]


def __getattr__(name: str):
    """Import a public name from its module on first use (PEP 562)."""
    module = PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'bouncedisk' has no attribute {name!r}")
    mod = import_module(module)
    value = getattr(mod, name, mod)  # the module itself where it defines no such name (engine)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *PUBLIC])
