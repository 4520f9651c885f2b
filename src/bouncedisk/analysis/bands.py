"""Ensemble bands of the rotor speed ``Ω(t)``: the spread behind a single trajectory.

A single run of a chaotic scene is one realization; the band shows where the others lie. The
members are the scene's runs with restitution noise (docs/model.md "Long-run statistics of chaotic
motion"), sampled on the scene's trajectory grid. Per time: the ensemble mean with its 95 %
Student-t interval, and the central 95 % of the members. Per member: the first-order trend of
its rise (steady speed, time constant, ripple; :func:`.observables.first_order_trend`).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import xarray as xr

from ..engine import simulate_arrays
from ..io.provenance import base_attrs, new_run_id
from ..io.records import TrajColumn
from ..model.engine_config import engine_config
from ..model.errors import InputError
from ..model.params import NATURAL_E_SIGMA
from ..model.scene import Scene
from ..run.cores import map_on_threads
from ..run.runner import scene_attrs
from . import observables as ob
from .statistics import LEVEL, t_half_width


def _member_omega(scene: Scene, member: int, e_sigma: float, seed: int) -> np.ndarray:
    """``(t, Ω)`` samples of one member on the scene's trajectory grid."""
    cfg = engine_config(scene)
    sigma = cfg.e_sigma if cfg.e_sigma > 0 else e_sigma
    cfg = dataclasses.replace(cfg, e_sigma=sigma, seed=seed, member=member, stroboscopic=False)
    res = simulate_arrays(cfg, scene.initial)
    return res.traj[:, [TrajColumn.T, TrajColumn.OMEGA]]


def member_speeds(
    scene: Scene, members: int, seed: int, e_sigma: float = NATURAL_E_SIGMA, cores: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """``Ω(t)`` of members ``0 … members−1`` on the scene's trajectory grid.

    Returns ``(t, om)``: the times every member reached and the speeds, shape (member, time).
    Members use the scene's restitution noise, or ``e_sigma`` when it has none.
    """
    runs = map_on_threads(lambda m: _member_omega(scene, m, e_sigma, seed), range(members), cores)
    n = min(len(r) for r in runs)
    return runs[0][:n, 0], np.stack([r[:n, 1] for r in runs])


def _band_dataset(t: np.ndarray, om: np.ndarray) -> xr.Dataset:
    """Band variables of member speeds ``om`` (member, time): mean with a Student-t 95 %
    interval, 2.5/97.5 percentiles, and each member's first-order trend."""
    members = len(om)
    mean = om.mean(axis=0)
    half = t_half_width(om, LEVEL, axis=0)
    lo, hi = np.percentile(om, [2.5, 97.5], axis=0)
    trends = [ob.first_order_trend(t, row) for row in om]

    def var(values, long_name):
        return ("time", values, {"long_name": long_name, "units": "1"})

    def per_member(values, long_name):
        return ("member", np.asarray(values, float), {"long_name": long_name, "units": "1"})

    return xr.Dataset(
        {
            "omega_member0": var(om[0], "rotor angular velocity of member 0"),
            "omega_mean": var(mean, "ensemble mean of the rotor angular velocity"),
            "omega_ci_low": var(mean - half, "lower end of the 95% interval of the mean"),
            "omega_ci_high": var(mean + half, "upper end of the 95% interval of the mean"),
            "omega_p025": var(lo, "2.5th percentile of the members"),
            "omega_p975": var(hi, "97.5th percentile of the members"),
            "trend_steady": per_member(
                [x.steady for x in trends], "steady speed of the first-order trend"
            ),
            "trend_tau": per_member(
                [x.tau for x in trends], "time constant of the first-order trend"
            ),
            "ripple_rms": per_member(
                [x.ripple_rms for x in trends], "RMS of the ripple about the trend"
            ),
        },
        coords={
            "time": ("time", t, {"long_name": "time", "units": "1"}),
            "member": ("member", np.arange(members), {"long_name": "ensemble member"}),
        },
    )


def mean_trend_fit(t: np.ndarray, mean: np.ndarray) -> tuple[ob.FirstOrderTrend, float]:
    """The first-order trend of the ensemble mean ``Ω̄(t)`` and its ``R²``, the share of the
    mean's variance it explains (``nan`` for a constant mean)."""
    trend = ob.first_order_trend(t, mean)
    resid = mean - trend(t)
    r2 = 1.0 - float(np.var(resid) / np.var(mean)) if np.var(mean) > 0 else float("nan")
    return trend, r2


def omega_band(
    scene: Scene,
    members: int,
    seed: int = 0,
    e_sigma: float = NATURAL_E_SIGMA,
    cores: int = 1,
) -> xr.Dataset:
    """The ensemble band of ``Ω(t)`` for ``scene`` (which must sample a trajectory, with torsion).

    Members end at different times when the scene stops on impacts: the band covers the times
    every member reached.

    Raises
    ------
    InputError
        When the scene has no trajectory output or no torsion, or ``members < 2``.
    """
    if scene.outputs.trajectory is None or not scene.has("torsion"):
        raise InputError(
            scene.source, "outputs.trajectory", "a band needs a trajectory of Ω (torsion)"
        )
    if members < 2:
        raise InputError(scene.source, "members", f"a band needs at least 2 members, got {members}")
    start = time.perf_counter()
    t, om = member_speeds(scene, members, seed, e_sigma, cores)
    ds = _band_dataset(t, om)
    mean_trend, r2 = mean_trend_fit(t, ds["omega_mean"].values)
    ds.attrs.update(
        base_attrs(f"bouncedisk ensemble band of the rotor speed, scene '{scene.name}'")
    )
    ds.attrs.update(scene_attrs(scene))
    ds.attrs.update(
        {
            "ensemble_members": members,
            "ensemble_seed": seed,
            "band_e_sigma": engine_config(scene).e_sigma or e_sigma,
            "mean_trend_steady": mean_trend.steady,
            "mean_trend_tau": mean_trend.tau,
            "mean_trend_r2": r2,
            "run_id": new_run_id(f"{scene.name}-band", scene.sha256),
            "wall_time_s": round(time.perf_counter() - start, 6),
            "status": "completed",
        }
    )
    return ds
