"""Poincaré and stroboscopic maps of a run, as a Dataset."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..io.provenance import SCENE_ATTRS, base_attrs
from ..io.records import EventKind


def poincare_dataset(sim: xr.Dataset, transient: int = 1000) -> xr.Dataset:
    """Impact map ``(phase, v_rel)`` and stroboscopic map ``(u, v)`` at phase 0 of a run.

    The first ``transient`` events (and stroboscopic points) are left out; chattering tails are
    not impacts and are left out of the impact map.
    """
    kind = sim["kind"].values
    keep = np.zeros(len(kind), dtype=bool)
    keep[transient:] = True
    keep &= kind == EventKind.IMPACT
    data = {
        "t_impact": ("impact", sim["t_impact"].values[keep]),
        "phase": ("impact", sim["phase"].values[keep]),
        "v_rel": ("impact", sim["v_rel"].values[keep]),
    }
    if "strobe_u" in sim:
        s = slice(min(transient, sim.sizes["period"]), None)
        data.update(
            {
                "strobe_t": ("period", sim["strobe_t"].values[s]),
                "strobe_u": ("period", sim["strobe_u"].values[s]),
                "strobe_v": ("period", sim["strobe_v"].values[s]),
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
