"""Poincaré and stroboscopic maps of a run, as a Dataset."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..io.provenance import SCENE_ATTRS, base_attrs
from ..io.records import EventKind
from ..model.errors import InputError
from ..model.params import whole_number


def poincare_dataset(sim: xr.Dataset, transient: int = 1000) -> xr.Dataset:
    """Impact map ``(phase, v_rel)`` and stroboscopic map ``(u, v)`` at phase 0 of a run.

    The first ``transient`` events (and stroboscopic points) are left out; chattering tails are
    not impacts and are left out of the impact map. Each variable keeps the simulation's long
    name and units.

    Raises
    ------
    InputError
        ``sim`` not a simulation's Dataset (:func:`~bouncedisk.io.netcdf.open_simulation`), or
        ``transient`` not a whole number >= 0.
    """
    if not isinstance(sim, xr.Dataset) or "kind" not in sim:
        raise InputError(
            "<arguments>", "sim", "must be a simulation's Dataset: open_simulation(path)"
        )
    transient = whole_number("<arguments>", "transient", transient, minimum=0)
    kind = sim["kind"].values
    keep = np.zeros(len(kind), dtype=bool)
    keep[transient:] = True
    keep &= kind == EventKind.IMPACT
    data = {
        name: ("impact", sim[name].values[keep], sim[name].attrs)
        for name in ("t_impact", "phase", "v_rel")
    }
    if "strobe_u" in sim:
        s = slice(min(transient, sim.sizes["period"]), None)
        data.update(
            {
                name: ("period", sim[name].values[s], sim[name].attrs)
                for name in ("strobe_t", "strobe_u", "strobe_v")
            }
        )
    ds = xr.Dataset(data)
    if "period" in sim and "strobe_u" in sim:
        ds = ds.assign_coords(period=("period", sim["period"].values[s]))
    ds.attrs.update(base_attrs(f"Poincaré maps of run {sim.attrs.get('run_id')}"))
    for k in (*SCENE_ATTRS, "run_id", "status"):
        if k in sim.attrs:
            ds.attrs[k if k != "run_id" else "source_run_id"] = sim.attrs[k]
    ds.attrs["run_id"] = f"{sim.attrs.get('run_id')}-poincare"
    ds.attrs["transient_events"] = transient
    ds.attrs["n_impacts"] = int(keep.sum())
    return ds
