"""Parameter sweeps: bifurcation diagrams, regime maps, rotor-speed curves.

A sweep takes a base scene and a grid of parameter values. The first swept parameter is split
into contiguous shards, so every shard is a hypercube block and shards join with
``xarray.combine_by_coords`` / ``open_mfdataset``. Each grid point is one in-memory run of the
engine, reduced to the observables the sweep records.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr

from . import observables as ob
from .engine.kernel import KIND_IMPACT, ST_REST
from .errors import InputError
from .params import Parameters
from .provenance import base_attrs, new_run_id
from .runner import run_scene_arrays, scene_attrs
from .scene import Scene

SWEEPABLE = ("e", "omega_s", "r_phi", "psi")


def grid_values(spec: dict) -> np.ndarray:
    """Values of one swept parameter from ``{min, max, n}`` or ``{values: [...]}``."""
    if "values" in spec:
        return np.asarray(spec["values"], dtype=float)
    return np.linspace(float(spec["min"]), float(spec["max"]), int(spec["n"]))


def shard_slice(n: int, shard: int, n_shards: int) -> slice:
    """Contiguous block ``shard`` of ``n`` items split into ``n_shards`` nearly equal blocks."""
    if not 0 <= shard < n_shards:
        raise InputError("sweep", "shard", f"must be in [0, {n_shards}), got {shard}")
    edges = np.linspace(0, n, n_shards + 1).round().astype(int)
    return slice(int(edges[shard]), int(edges[shard + 1]))


def with_params(scene: Scene, **values: float) -> Scene:
    """A copy of ``scene`` with some nondimensional parameters replaced (validated)."""
    params = dataclasses.replace(scene.params, **values)
    Parameters.validate(params, scene.source)
    raw = dict(scene.raw)
    raw["parameters"] = {**(raw.get("parameters") or {}), **values}
    return dataclasses.replace(scene, params=params, raw=raw)


def point_observables(scene: Scene, tail: int) -> dict[str, np.ndarray | float]:
    """Run one grid point and reduce it: impact tail, regime, Lyapunov exponent, mean speed."""
    res = run_scene_arrays(scene)
    ev = res.events
    p = scene.params
    n = len(ev["t"])
    sl = slice(max(0, n - tail), n)
    phase = np.full(tail, np.nan)
    v_rel = np.full(tail, np.nan)
    k = sl.stop - sl.start
    sel_phase = ev["phase"][sl]
    sel_v = ev["v_rel"][sl]
    phase[:k] = sel_phase
    v_rel[:k] = sel_v
    at_rest = res.status_code == ST_REST
    reg = ob.classify(
        ev["t"], ev["phase"], ev["v_rel"], ev["kind"], p.e, p.omega_s, at_rest=at_rest
    )
    half = ev["t"][n // 2] if n > 2 else 0.0
    mean_om = (
        ob.mean_rotor_speed(ev["t"], ev["omega_after"], half)
        if scene.has("torsion") and n > 2
        else math.nan
    )
    return {
        "phase": phase,
        "v_rel": v_rel,
        "regime": reg.code,
        "period": reg.period.p if reg.period else 0,
        "lyapunov": reg.lyapunov,
        "chatter_fraction": reg.chatter_fraction,
        "impact_fraction": float(np.mean(ev["kind"][sl] == KIND_IMPACT)) if k else math.nan,
        "mean_omega": mean_om,
        "mean_slip_speed": p.r_phi * mean_om if math.isfinite(mean_om) else math.nan,
        "n_events": n,
    }


REGIME_MEANINGS = {1: "periodic", 2: "chaotic", 3: "chattering", 4: "rest", 5: "irregular"}


def run_sweep(
    scene: Scene,
    axes: Sequence[tuple[str, np.ndarray]],
    shard: int = 0,
    n_shards: int = 1,
    tail: int = 200,
    progress: Callable[[int, int], None] | None = None,
) -> xr.Dataset:
    """Run one shard of a sweep over the grid ``axes`` (name, values) pairs.

    Returns a Dataset with the swept parameters as dimensions (the first one restricted to this
    shard's block) and per point: ``phase(..., impact)``, ``v_rel(..., impact)`` over the last
    ``tail`` events, ``regime``, ``period``, ``lyapunov``, ``chatter_fraction``, ``mean_omega``.
    """
    names = [a for a, _ in axes]
    for name in names:
        if name not in SWEEPABLE:
            raise InputError(scene.source, f"sweep.{name}", f"cannot sweep (known: {SWEEPABLE})")
    values = [np.asarray(v, float) for _, v in axes]
    values[0] = values[0][shard_slice(len(values[0]), shard, n_shards)]
    shape = tuple(len(v) for v in values)
    scalar_names = (
        "regime",
        "period",
        "lyapunov",
        "chatter_fraction",
        "impact_fraction",
        "mean_omega",
        "mean_slip_speed",
    )
    scalars = {k: np.full(shape, np.nan) for k in scalar_names}
    phase = np.full(shape + (tail,), np.nan)
    v_rel = np.full(shape + (tail,), np.nan)
    total = int(np.prod(shape))
    start = time.perf_counter()
    n_events = 0
    events_per_point = np.zeros(shape, dtype=np.int64)
    for count, idx in enumerate(np.ndindex(*shape)):
        point = {names[d]: float(values[d][i]) for d, i in enumerate(idx)}
        obs = point_observables(with_params(scene, **point), tail)
        n_events += int(obs["n_events"])
        events_per_point[idx] = int(obs["n_events"])
        phase[idx] = obs["phase"]
        v_rel[idx] = obs["v_rel"]
        for k in scalar_names:
            scalars[k][idx] = obs[k]
        if progress:
            progress(count + 1, total)
    dims = tuple(names)
    coords = {
        n: (n, v, {"units": "rad" if n == "psi" else "1", "long_name": n})
        for n, v in zip(names, values, strict=True)
    }
    ds = xr.Dataset(
        {
            "phase": (
                dims + ("impact",),
                phase,
                {"long_name": "stator phase at impact (tail)", "units": "rad"},
            ),
            "v_rel": (
                dims + ("impact",),
                v_rel,
                {"long_name": "relative impact velocity (tail)", "units": "1"},
            ),
            "regime": (
                dims,
                scalars["regime"].astype(np.int16),
                {
                    "long_name": "dynamical regime",
                    "units": "1",
                    "flag_values": np.array(list(REGIME_MEANINGS), dtype=np.int16),
                    "flag_meanings": " ".join(REGIME_MEANINGS.values()),
                    "comment": "periodic: see 'period' for the number of impacts per cycle",
                },
            ),
            "period": (
                dims,
                scalars["period"].astype(np.int16),
                {"long_name": "impacts per cycle of a periodic orbit (0: none)", "units": "1"},
            ),
            "lyapunov": (
                dims,
                scalars["lyapunov"],
                {
                    "long_name": "largest Lyapunov exponent of the impact map",
                    "units": "1 per impact",
                },
            ),
            "chatter_fraction": (
                dims,
                scalars["chatter_fraction"],
                {"long_name": "fraction of chattering tails among the events", "units": "1"},
            ),
            "mean_omega": (
                dims,
                scalars["mean_omega"],
                {"long_name": "mean rotor angular velocity (second half of the run)", "units": "1"},
            ),
            "mean_slip_speed": (
                dims,
                scalars["mean_slip_speed"],
                {"long_name": "mean rotor speed in stator units, r_phi * omega", "units": "1"},
            ),
            # per point, so that any join of shards (open_mfdataset too) sums to the sweep's total
            "n_events": (
                dims,
                events_per_point,
                {"long_name": "events (impacts and chattering tails) simulated", "units": "1"},
            ),
        },
        coords=coords,
    )
    ds.attrs.update(base_attrs(f"bouncedisk sweep of scene '{scene.name}' over {', '.join(names)}"))
    attrs = scene_attrs(scene)
    for n in names:
        attrs.pop(n, None)
    attrs.pop("gamma", None)
    ds.attrs.update(attrs)
    ds.attrs.update(
        {
            "swept": ",".join(names),
            "shard": shard,
            "n_shards": n_shards,
            "tail": tail,
            # a shard's count is named as such: open_mfdataset keeps the first file's attributes,
            # and a joined sweep's total is n_events.sum() (or n_impacts of combine_shards)
            "shard_n_impacts": n_events,
            "status": "completed",
            "run_id": new_run_id(f"{scene.name}-sweep{shard}", scene.sha256),
            "wall_time_s": round(time.perf_counter() - start, 6),
        }
    )
    return ds


def combine_shards(shards: Sequence[xr.Dataset]) -> xr.Dataset:
    """Join sweep shards along their swept dimensions."""
    ds = xr.combine_by_coords(list(shards), combine_attrs="drop_conflicts")
    ds.attrs.pop("shard", None)
    ds.attrs.pop("shard_n_impacts", None)
    first = shards[0].attrs
    ds.attrs["run_id"] = new_run_id(
        f"{first.get('scene_name', 'sweep')}-sweep", str(first.get("scene_sha256", "0" * 8))
    )
    ds.attrs["shard_run_ids"] = ",".join(str(s.attrs.get("run_id")) for s in shards)
    ds.attrs["wall_time_s"] = float(sum(float(s.attrs.get("wall_time_s", 0.0)) for s in shards))
    ds.attrs["n_impacts"] = int(
        sum(int(s.attrs.get("shard_n_impacts", s.attrs.get("n_impacts", 0))) for s in shards)
    )
    return ds
