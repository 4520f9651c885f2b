"""The bouncing model against the clipped-contact one: the same scene run both ways."""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from ..io.provenance import base_attrs
from ..io.records import TrajColumn
from ..model.params import NATURAL_E_SIGMA
from ..model.scene import Scene
from ..run.runner import run_scene_arrays, scene_attrs


def clipped_comparison(
    scene: Scene,
    psis: list[float],
    members: int = 16,
    seed: int = 1,
    e_sigma: float = NATURAL_E_SIGMA,
) -> xr.Dataset:
    """Rotor angular velocity ``omega_rotor(model, psi, time)`` of both contact models.

    The scene must stop on time and ask for a trajectory; both models share its time grid.
    The bouncing model is chaotic, so its ensemble band is added
    (``omega_bouncing_{mean,ci_low,ci_high,p025,p975}(psi, time)``, :func:`bands.omega_band`);
    the clipped model has no impacts and no noise.
    """
    from ..analysis.bands import omega_band

    if scene.stop.time is None or scene.outputs.trajectory is None:
        from ..model.errors import InputError

        raise InputError(scene.source, "stop", "the comparison needs a time stop and a trajectory")
    models = ("bouncing", "clipped")
    series = {}
    time = None
    for model in models:
        for p in psis:
            sc = dataclasses.replace(
                scene, model=model, params=dataclasses.replace(scene.params, psi=p)
            )
            res = run_scene_arrays(sc)
            if time is None:
                time = res.traj[:, TrajColumn.T]
            series[model, p] = np.interp(
                time, res.traj[:, TrajColumn.T], res.traj[:, TrajColumn.OMEGA]
            )
    om = np.array([[series[m, p] for p in psis] for m in models])
    band_vars = {}
    bands = [
        omega_band(
            dataclasses.replace(scene, params=dataclasses.replace(scene.params, psi=p)),
            members,
            seed=seed,
            e_sigma=e_sigma,
        )
        for p in psis
    ]
    for key in ("mean", "ci_low", "ci_high", "p025", "p975"):
        rows = [np.interp(time, b["time"].values, b[f"omega_{key}"].values) for b in bands]
        band_vars[f"omega_bouncing_{key}"] = (
            ("psi", "time"),
            np.array(rows),
            {**bands[0][f"omega_{key}"].attrs, "comment": "bouncing model, ensemble"},
        )
    ds = xr.Dataset(
        {
            "omega_rotor": (
                ("model", "psi", "time"),
                om,
                {"long_name": "rotor angular velocity", "units": "1"},
            ),
            **band_vars,
        },
        coords={
            "model": ("model", list(models), {"long_name": "contact model"}),
            "psi": ("psi", np.asarray(psis, float), {"units": "rad", "long_name": "psi"}),
            "time": ("time", time, {"units": "1", "long_name": "time"}),
        },
    )
    ds.attrs.update(base_attrs("bouncing disk vs clipped spring-contact model"))
    attrs = scene_attrs(scene)
    attrs.pop("psi", None)
    attrs.pop("model", None)
    ds.attrs.update(attrs)
    ds.attrs["run_id"] = f"{scene.name}-{scene.sha256[:8]}-comparison"
    ds.attrs.update({"ensemble_members": members, "ensemble_seed": seed, "band_e_sigma": e_sigma})
    return ds
