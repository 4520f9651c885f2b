"""``bouncedisk info FILE``: what a file written by bouncedisk holds.

A simulation file lists its provenance (scene, parameters, run); a fit file prints the fit's
summary, as ``bouncedisk fit`` does; any other file (statistics, sweeps, load curves, basins,
sensitivity) its title, provenance and variables. The file is opened lazily: only its header
is read, so memory stays flat whatever its size.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the parser stays light: xarray is imported when the command runs
    import xarray as xr

#: Variables listed by name before the rest are counted.
LISTED_VARIABLES = 24
#: Suffixes of the variables that hold another's interval ends (listed with it, not apart).
INTERVAL_SUFFIXES = ("_ci_low", "_ci_high", "_ci95_low", "_ci95_high")


def _cmd_info(args: argparse.Namespace) -> int:
    from ..io.netcdf import REQUIRED_SIMULATION, open_checked, open_simulation

    ds = open_checked(
        args.file, required_attrs=("bouncedisk_version",), what="bouncedisk netCDF", lazy=True
    )
    try:
        if all(name in ds.variables for name in REQUIRED_SIMULATION):
            ds.close()
            ds = open_simulation(args.file, lazy=True)
            print(_aligned(_simulation_rows(ds)))
        elif _is_fit(ds):
            from ..fitting.output import summary_text

            print(summary_text(ds))
        else:
            print(_aligned(_product_rows(ds)))
    finally:
        ds.close()
    return 0


def _is_fit(ds: xr.Dataset) -> bool:
    """A fit file (``bouncedisk fit``): its processing level is the fit's."""
    from ..io.provenance import PROCESSING

    return ds.attrs.get("processing_level") == PROCESSING["fit"][0]


def _simulation_rows(ds: xr.Dataset) -> list[tuple[str, object]]:
    """A simulation's scene, parameters, run and variables."""
    from ..io.provenance import RUN_ATTRS, SCENE_ATTRS

    keys = dict.fromkeys(("scene_name", "run_id", *SCENE_ATTRS, *RUN_ATTRS, "n_chatter"))
    rows = [(k, ds.attrs[k]) for k in keys if k in ds.attrs]
    rows.append(("variables", ", ".join(sorted(ds.data_vars))))
    return rows


def _product_rows(ds: xr.Dataset) -> list[tuple[str, object]]:
    """Any other file's title, provenance, dimensions and variables (with their units)."""
    from ..io.provenance import SCENE_ATTRS

    a = ds.attrs
    keys = ("title", "id", *SCENE_ATTRS, "bouncedisk_version", "git_commit", "date_created")
    rows: list[tuple[str, object]] = [(k, a[k]) for k in dict.fromkeys(keys) if k in a]
    for k in (k for k in a if f"{k}_ci95" in a):  # the study's results, with their intervals
        low, high = np.ravel(a[f"{k}_ci95"])[:2]
        rows.append((k, f"{a[k]:.6g}  95% CI [{low:.6g}, {high:.6g}]"))
    rows.append(("dimensions", ", ".join(f"{d} {n}" for d, n in ds.sizes.items())))
    ends = {
        n for n in ds.data_vars for s in INTERVAL_SUFFIXES if n.endswith(s) and n[: -len(s)] in ds
    }
    names = sorted(n for n in ds.data_vars if n not in ends)
    for name in names[:LISTED_VARIABLES]:
        a = ds[name].attrs
        units = f" [{a['units']}]" if "units" in a else ""
        band = any(f"{name}{s}" in ends for s in INTERVAL_SUFFIXES)
        band = ", with its 95 % interval" if band else ""
        rows.append((name, f"{a.get('long_name', '-')}{units}{band}"))
    if len(names) > LISTED_VARIABLES:
        rows.append(("...", f"{len(names) - LISTED_VARIABLES} more variables"))
    return rows


def _aligned(rows: list[tuple[str, object]]) -> str:
    """One column of right-aligned names, however long the longest."""
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:>{width}}: {v}" for k, v in rows)


def _add_info(sub) -> None:
    """``bouncedisk info FILE``."""
    p = sub.add_parser(
        "info",
        help="summarise a netCDF file written by bouncedisk (a simulation, a fit, a study)",
    )
    p.add_argument("file")
    p.set_defaults(func=_cmd_info)
