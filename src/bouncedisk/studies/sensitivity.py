"""Global sensitivity of the motor's figures of merit: SALib Sobol' sampling and analysis.

The study (README "Sensitivity of the motor") samples ``(e, omega_s, log10_r_phi, psi)`` over the
configured ranges with SALib's Sobol' sequence (Saltelli's scheme, first-order and total indices,
``N (D + 2)`` points), evaluates the figures of merit at every point, and lets SALib estimate the
indices with their bootstrap intervals. Every figure of merit is an ensemble statistic with a 95 %
interval (docs/model.md "Long-run statistics of chaotic motion"); its squared standard error is the
ensemble noise in that point's value, so :func:`analyse` reports which share of each output's
variance over the sample is noise rather than parameters (an index is never read off noise).

Evaluation is split into shards, contiguous blocks of the sample's points
(:func:`bouncedisk.analysis.sweeps.shard_slice`); a point's value depends on nothing but its parameters and
the seed, so the joined shards are bit-identical to a one-job run (:func:`join_shards`).

A model is any callable ``model(point) -> PointValues`` with a tuple ``model.outputs``:
:class:`MotorModel` (the figures of merit) or :class:`IshigamiModel` (the test function with
analytic indices that checks the code path).
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import xarray as xr
from scipy.special import ndtri

from ..analysis import observables as ob
from ..analysis.bands import member_speeds
from ..analysis.statistics import confidence_interval, run_stats, t_quantile
from ..analysis.sweeps import regime_attrs, shard_slice
from ..io.provenance import base_attrs
from ..model.scene import Scene, scene_from_mapping
from .sensitivity_settings import PARAMETERS, StudySettings

LEVEL = 0.95
#: Figures of merit: name -> (long name, units, needs the ``load`` effect). Speeds and powers are
#: scaled by ``R_φ``: ``R_φ Ω`` is the rotor speed in units of ``Φ0/t_c`` (docs/model.md "Variables and
#: scales"), so they compare motors of the same stator at different ``R_φ``.
OUTPUTS: dict[str, tuple[str, str, bool]] = {
    "no_load_speed": ("no-load rotor speed R_phi * mean Omega (units Phi0/t_c)", "1", False),
    "log10_tau": ("log10 of the run-up time constant of the ensemble-mean run-up", "1", False),
    "chatter_rate": ("complete chattering sequences per unit time", "1", False),
    "stall_torque": (
        "stall torque, smallest load with mean Omega <= 0 (friction units)",
        "1",
        True,
    ),
    "max_power": ("largest mean output power R_phi * tau_L * mean Omega over the loads", "1", True),
    "efficiency_at_max_power": ("torsional efficiency at the load of the largest power", "1", True),
}
#: The design maps' outputs, and the one that picks the best operating point (first present).
MAP_OUTPUTS = ("no_load_speed", "stall_torque", "efficiency_at_max_power")
BEST_BY = ("max_power", "no_load_speed")
#: Samples of the run-up per unit of ``1/R_φ`` (the trend's time constant is 1-3 of these).
RUNUP_SAMPLES_PER_UNIT = 20


@dataclasses.dataclass(frozen=True)
class PointValues:
    """The figures of merit at one point: name -> ``(mean, ci_low, ci_high, standard error)``,
    and the regime code (:data:`bouncedisk.analysis.observables.REGIMES`; 0 where it has none)."""

    values: dict[str, tuple[float, float, float, float]]
    regime: int = 0


def interval(values: Sequence[float]) -> tuple[float, float, float, float]:
    """Mean, Student-t 95 % interval and standard error ``s/√K`` of finite member values."""
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    mean, low, high = confidence_interval(x, LEVEL)
    se = float(np.std(x, ddof=1) / math.sqrt(len(x))) if len(x) > 1 else math.nan
    return mean, low, high, se


def _from_ci(
    mean, ci, members: int | None, scale: float = 1.0
) -> tuple[float, float, float, float]:
    """``(mean, low, high, se)`` from a reported value and ``[low, high]`` (``None``: NaN).

    The standard error is the half-width over Student's ``t_{0.975, K−1}`` for a Student
    interval of ``members`` members, over the normal ``z_{0.975}`` for a bootstrap percentile
    interval (``members=None``).
    """
    m = math.nan if mean is None else float(mean) * scale
    lo, hi = (math.nan if v is None else float(v) * scale for v in (ci or (None, None)))
    if members is None:
        q = float(ndtri(0.5 + LEVEL / 2.0))
    else:
        q = t_quantile(max(1, members - 1), LEVEL)
    return m, lo, hi, (hi - lo) / (2.0 * q)


# ----------------------------------------------------------------------------- models
class IshigamiModel:
    """Ishigami's function ``sin x1 + a sin² x2 + b x3⁴ sin x1`` (SALib's test function), whose
    Sobol' indices are known in closed form; ``noise`` adds a known standard error to every value
    (deterministic per point) to check the noise share."""

    outputs = ("ishigami",)

    def __init__(self, names: Sequence[str], a: float = 7.0, b: float = 0.1, noise: float = 0.0):
        self.names, self.a, self.b, self.noise = tuple(names), a, b, noise

    def __call__(self, point: Mapping[str, float]) -> PointValues:
        x1, x2, x3 = (point[n] for n in self.names[:3])
        y = math.sin(x1) + self.a * math.sin(x2) ** 2 + self.b * x3**4 * math.sin(x1)
        if self.noise:
            seed = np.frombuffer(np.array([x1, x2, x3]).tobytes(), np.uint32)
            y += self.noise * np.random.default_rng(seed).standard_normal()
        half = 1.96 * self.noise
        return PointValues({"ishigami": (y, y - half, y + half, self.noise)})


class MotorModel:
    """The motor's figures of merit at a point ``(e, omega_s, log10_r_phi, psi)``.

    Each point is an ensemble of ``members`` runs from rest, differing by restitution noise
    ``e_sigma`` (docs/model.md "Long-run statistics of chaotic motion"), over ``(discard + duration)/R_φ``:
    no-load speed, chatter rate and regime from :func:`bouncedisk.analysis.statistics.run_stats` (after the
    transient ``discard/R_φ``), the run-up time constant from the first-order trend
    (:func:`bouncedisk.analysis.observables.first_order_trend`) of the members' mean run-up with a
    jackknife interval over members, and with ``loads`` the torque–speed curve's stall torque,
    maximum power and the torsional efficiency at it (docs/model.md "The motor under load").
    """

    def __init__(self, settings: StudySettings, torque_speed: Callable | None = None):
        self.s = settings
        self._torque_speed = torque_speed
        if settings.loads and torque_speed is None:
            from .torque_speed import torque_speed as ts  # the load effect (docs/model.md)

            self._torque_speed = ts
        self.outputs = tuple(k for k, v in OUTPUTS.items() if settings.loads or not v[2])

    def scene(self, point: Mapping[str, float], load: bool = False) -> Scene:
        """The ensemble scene of ``point`` (``load``: with the load effect at ``τ_L = 0``)."""
        s, r = self.s, 10.0 ** point["log10_r_phi"]
        params = {"e": point["e"], "omega_s": point["omega_s"], "r_phi": r, "psi": point["psi"]}
        params["e_sigma"] = s.e_sigma
        effects = ["impacts", "contact", "torsion", "restitution_noise"]
        if load:
            effects.append("load")
            params["load_torque"] = 0.0
        raw = {
            "name": "sensitivity",
            "parameters": params,
            "effects": effects,
            "stop": {"time": (s.discard + s.duration) / r},
            "ensemble": {"members": s.members, "seed": s.seed},
            "stats": {"discard": s.discard / r},
            "outputs": {"events": False, "trajectory": {"dt": 1.0 / (RUNUP_SAMPLES_PER_UNIT * r)}},
            "solver": {"method": "exact", "tol": 1e-12},
        }
        return scene_from_mapping(raw, source="sensitivity point")

    def __call__(self, point: Mapping[str, float]) -> PointValues:
        r = 10.0 ** point["log10_r_phi"]
        scene = self.scene(point)
        st = run_stats(scene, cores=1)
        out = {
            "no_load_speed": interval(r * st.column("mean_omega")),
            "chatter_rate": interval(st.column("chatter_rate")),
            "log10_tau": self._runup(scene),
        }
        if self.s.loads:
            out.update(self._load(point, r))
        name, _, _ = st.regime
        return PointValues(out, ob.REGIME_CODES[name])

    def _runup(self, scene: Scene) -> tuple[float, float, float, float]:
        """log10 τ of the members' mean run-up, with a jackknife interval over members."""
        t, om = member_speeds(scene, self.s.members, self.s.seed)
        k = len(om)
        full = math.log10(ob.first_order_trend(t, om.mean(axis=0)).tau)
        total = om.sum(axis=0)
        jack = np.array(
            [math.log10(ob.first_order_trend(t, (total - om[i]) / (k - 1)).tau) for i in range(k)]
        )
        se = math.sqrt((k - 1) / k * float(np.sum((jack - jack.mean()) ** 2)))
        half = t_quantile(k - 1, LEVEL) * se
        return full, full - half, full + half, se

    def _load(self, point: Mapping[str, float], r: float) -> dict:
        """Stall torque, maximum power and the efficiency at it, from the torque–speed curve's
        up branch (loads increasing by continuation; docs/model.md "The motor under load").

        The stall torque and its bootstrap interval are the curve's. The maximum power is the
        largest mean power ``τ_L Ω̄`` over the loads asked for, with its Student interval, and
        the efficiency is taken at that load: the curve's parabolic peak overshoots where the
        speed collapses at the stall (a vertex far above every sample).
        """
        scene = self.scene(point, load=True)
        curve = self._torque_speed(scene, list(self.s.loads), cores=1, branches=("up",))
        s = curve.summary()
        k = self.s.members
        power = np.array([math.nan if p is None else p for p in s["power_out"]], float)
        i = int(np.nanargmax(power)) if np.isfinite(power).any() else 0
        return {
            "stall_torque": _from_ci(s["stall_torque"], s["stall_torque_ci95"], None),
            "max_power": _from_ci(s["power_out"][i], s["power_out_ci95"][i], k, scale=r),
            "efficiency_at_max_power": _from_ci(
                s["efficiency_torsion"][i], s["efficiency_torsion_ci95"][i], k
            ),
        }


# ----------------------------------------------------------------------------- sampling
def problem(ranges: Mapping[str, tuple[float, float]]) -> dict:
    """SALib's problem definition of ``ranges`` (parameter -> ``(low, high)``)."""
    return {"num_vars": len(ranges), "names": list(ranges), "bounds": [list(b) for b in ranges.values()]}  # fmt: skip


def sample(ranges: Mapping[str, tuple[float, float]], base_samples: int, seed: int) -> np.ndarray:
    """SALib's scrambled Sobol' sample for first-order and total indices, ``N (D + 2)`` rows."""
    from SALib.sample import sobol

    return sobol.sample(problem(ranges), base_samples, calc_second_order=False, seed=seed)


def map_sample(settings: StudySettings, e: float) -> tuple[np.ndarray, tuple[int, int]]:
    """The design map's grid over ``(psi, log10_r_phi)`` at ``e`` and ``map_omega_s``, as rows of
    :data:`PARAMETERS` (``psi`` varying slowest), and its shape ``(n_psi, n_r_phi)``."""
    n_psi, n_r = settings.map_points
    psi = np.linspace(*settings.ranges["psi"], n_psi)
    lr = np.linspace(*settings.ranges["log10_r_phi"], n_r)
    pp, rr = np.meshgrid(psi, lr, indexing="ij")
    cols = {"e": e, "omega_s": settings.map_omega_s, "log10_r_phi": rr.ravel(), "psi": pp.ravel()}
    x = np.column_stack([np.broadcast_to(cols[n], pp.size) for n in PARAMETERS])
    return x, (n_psi, n_r)


# ----------------------------------------------------------------------------- evaluation
def evaluate(
    x: np.ndarray,
    names: Sequence[str],
    model: Callable[[Mapping[str, float]], PointValues],
    index: np.ndarray | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> xr.Dataset:
    """The model's outputs at the rows of ``x`` (columns ``names``), dimension ``point``.

    Per output ``o``: ``o``, ``o_ci_low``, ``o_ci_high``, ``o_se``; ``regime``; ``x`` itself.
    ``index`` numbers the points (default ``0 … len(x)−1``). Wall and CPU time are attributes
    (they are not data: a joined study's data do not depend on how it was split).
    """
    x = np.asarray(x, float)
    index = np.arange(len(x)) if index is None else np.asarray(index, np.int64)
    outputs = tuple(model.outputs)
    vals = {o: np.full((len(x), 4), np.nan) for o in outputs}
    regime = np.zeros(len(x), np.int16)
    wall, cpu = time.perf_counter(), time.process_time()
    for i, row in enumerate(x):
        pv = model(dict(zip(names, map(float, row), strict=True)))
        for o in outputs:
            vals[o][i] = pv.values[o]
        regime[i] = pv.regime
        if progress:
            progress(i + 1, len(x))
    data = {"x": (("point", "parameter"), x, {"long_name": "sampled parameters", "units": "1"})}
    for o in outputs:
        long_name, units = OUTPUTS.get(o, (o, "1", False))[:2]
        for j, (suffix, what) in enumerate(
            (("", long_name), ("_ci_low", f"lower end of the 95% interval of {o}"),
             ("_ci_high", f"upper end of the 95% interval of {o}"),
             ("_se", f"standard error of {o} (ensemble noise)"))
        ):  # fmt: skip
            data[o + suffix] = ("point", vals[o][:, j], {"long_name": what, "units": units})
    data["regime"] = ("point", regime, regime_attrs())
    coords = {
        "point": ("point", index, {"long_name": "index of the point in the sample"}),
        "parameter": ("parameter", np.array(names, dtype=str), {"long_name": "sampled parameter"}),
    }
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(base_attrs("bouncedisk global sensitivity study: figures of merit per point"))
    ds.attrs.update(
        {
            "outputs": ",".join(outputs),
            "n_points": len(x),
            "wall_time_s": round(time.perf_counter() - wall, 6),
            "cpu_time_s": round(time.process_time() - cpu, 6),
        }
    )
    return ds


def run_shard(
    settings: StudySettings,
    model: Callable[[Mapping[str, float]], PointValues],
    shard: int,
    progress: Callable[[int, int], None] | None = None,
) -> xr.Dataset:
    """Evaluate shard ``shard`` of ``settings.shards``: a contiguous block of the sample."""
    x = sample(settings.ranges, settings.base_samples, settings.seed)
    block = shard_slice(len(x), shard, settings.shards)
    ds = evaluate(x[block], list(settings.ranges), model, np.arange(len(x))[block], progress)
    ds.attrs.update(
        {
            "shard": shard,
            "n_shards": settings.shards,
            "total_points": len(x),
            "base_samples": settings.base_samples,
            "seed": settings.seed,
            "members": settings.members,
        }
    )
    return ds


def join_shards(shards: Sequence[xr.Dataset]) -> xr.Dataset:
    """Join shards along ``point`` in sample order; every point of the sample exactly once.

    Raises
    ------
    ValueError
        When points are missing or repeated.
    """
    parts = sorted(shards, key=lambda d: int(d["point"].values[0]) if d.sizes["point"] else 0)
    ds = xr.concat(parts, dim="point", combine_attrs="drop_conflicts")
    total = int(parts[0].attrs.get("total_points", ds.sizes["point"]))
    if not np.array_equal(ds["point"].values, np.arange(total)):
        raise ValueError(f"the shards do not hold points 0..{total - 1} once each")
    for key in ("wall_time_s", "cpu_time_s"):
        ds.attrs[key] = float(sum(float(s.attrs.get(key, 0.0)) for s in shards))
    ds.attrs.pop("shard", None)
    ds.attrs["n_points"] = total
    return ds


def design_map(
    settings: StudySettings,
    model: Callable[[Mapping[str, float]], PointValues],
    which: int,
    progress: Callable[[int, int], None] | None = None,
) -> xr.Dataset:
    """The design map at the ``which``-th ``e`` of ``settings.map_e`` (:func:`map_sample`)."""
    if not 0 <= which < len(settings.map_e):
        raise ValueError(f"design map {which}: there are {len(settings.map_e)}")
    e = settings.map_e[which]
    x, shape = map_sample(settings, e)
    ds = evaluate(x, PARAMETERS, model, progress=progress)
    ds.attrs.update(
        {"map_e": e, "map_omega_s": settings.map_omega_s, "map_n_psi": shape[0],
         "map_n_r_phi": shape[1],
         "members": settings.members, "seed": settings.seed}
    )  # fmt: skip
    return ds


def join_maps(maps: Sequence[xr.Dataset]) -> xr.Dataset:
    """The design maps along a dimension ``map`` (coordinate ``map_e``)."""
    ds = xr.concat(list(maps), dim="map", combine_attrs="drop_conflicts")
    e = [float(m.attrs["map_e"]) for m in maps]
    ds = ds.assign_coords(map_e=("map", np.array(e), {"long_name": "restitution e of the map"}))
    for key in ("map_n_psi", "map_n_r_phi", "map_omega_s"):
        ds.attrs[key] = maps[0].attrs[key]
    ds.attrs["cpu_time_s"] = float(sum(float(m.attrs.get("cpu_time_s", 0.0)) for m in maps))
    return ds


# ----------------------------------------------------------------------------- analysis
def noise_share(y: np.ndarray, se: np.ndarray) -> float:
    """Share of the variance of ``y`` over the sample that is ensemble noise:
    ``mean(se²) / var(y)`` (each point's value scatters by its standard error about the
    parameters' value, so the noise adds ``mean(se²)`` to the variance)."""
    var = float(np.var(y, ddof=1))
    noise = float(np.nanmean(np.asarray(se, float) ** 2))
    return noise / var if var > 0 else math.nan


def analyse(points: xr.Dataset, ranges: Mapping, resamples: int, seed: int) -> xr.Dataset:
    """First-order and total Sobol' indices of every output with SALib's bootstrap intervals.

    Variables (output, parameter): ``S1``, ``S1_conf``, ``ST``, ``ST_conf`` (``conf``: half-width
    of the 95 % bootstrap interval); per output: ``noise_share`` (:func:`noise_share`),
    ``variance``, ``mean``, ``n_undefined`` (points where the output is undefined, e.g. no stall
    within the loads asked for: then no indices, NaN).
    """
    from SALib.analyze import sobol

    prob = problem(ranges)
    outputs = [o for o in str(points.attrs["outputs"]).split(",") if o]
    d = len(prob["names"])
    res = {k: np.full((len(outputs), d), np.nan) for k in ("S1", "S1_conf", "ST", "ST_conf")}
    per = {k: np.full(len(outputs), np.nan) for k in ("noise_share", "variance", "mean")}
    undefined = np.zeros(len(outputs), np.int64)
    for i, o in enumerate(outputs):
        y = points[o].values
        undefined[i] = int(np.count_nonzero(~np.isfinite(y)))
        if undefined[i]:
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            si = sobol.analyze(
                prob, y, calc_second_order=False, num_resamples=resamples,
                conf_level=LEVEL, seed=seed,
            )  # fmt: skip
        for k in res:
            res[k][i] = si[k]
        per["noise_share"][i] = noise_share(y, points[f"{o}_se"].values)
        per["variance"][i], per["mean"][i] = float(np.var(y, ddof=1)), float(np.mean(y))
    dims = ("output", "parameter")
    data = {
        "S1": (dims, res["S1"], {"long_name": "first-order Sobol' index", "units": "1"}),
        "S1_conf": (
            dims,
            res["S1_conf"],
            {"long_name": "half-width of the 95% bootstrap interval of S1", "units": "1"},
        ),  # fmt: skip
        "ST": (dims, res["ST"], {"long_name": "total Sobol' index", "units": "1"}),
        "ST_conf": (
            dims,
            res["ST_conf"],
            {"long_name": "half-width of the 95% bootstrap interval of ST", "units": "1"},
        ),  # fmt: skip
        "noise_share": (
            "output",
            per["noise_share"],
            {"long_name": "share of the output's variance that is ensemble noise", "units": "1"},
        ),  # fmt: skip
        "variance": (
            "output",
            per["variance"],
            {"long_name": "variance of the output over the sample", "units": "1"},
        ),  # fmt: skip
        "mean": (
            "output",
            per["mean"],
            {"long_name": "mean of the output over the sample", "units": "1"},
        ),  # fmt: skip
        "n_undefined": (
            "output",
            undefined,
            {"long_name": "points where the output is undefined", "units": "1"},
        ),  # fmt: skip
    }
    coords = {"output": ("output", np.array(outputs, dtype=str)), "parameter": ("parameter", np.array(prob["names"], dtype=str))}  # fmt: skip
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(base_attrs("bouncedisk global sensitivity: Sobol' indices (SALib)"))
    ds.attrs.update(
        {
            "n_points": int(points.sizes["point"]),
            "resamples": resamples,
            "seed": seed,
            "confidence_level": LEVEL,
            "cpu_time_s": float(points.attrs.get("cpu_time_s", math.nan)),
            "cpu_s_per_point": float(points.attrs.get("cpu_time_s", math.nan))
            / max(1, int(points.sizes["point"])),
        }
    )
    return ds


def best_point(ds: xr.Dataset, output: str) -> dict:
    """The point of a design map with the largest ``output``, with its 95 % interval, and the
    points whose interval reaches the best one's (``indistinguishable``: not resolved from it)."""
    y = ds[output].values
    if not np.isfinite(y).any():
        return {"output": output, "index": None}
    i = int(np.nanargmax(y))
    low = ds[f"{output}_ci_low"].values
    high = ds[f"{output}_ci_high"].values
    near = np.flatnonzero(np.isfinite(y) & (high >= low[i]))
    params = dict(zip(ds["parameter"].values.tolist(), ds["x"].values[i].tolist(), strict=True))
    return {
        "output": output,
        "index": i,
        "value": float(y[i]),
        "ci95": [float(low[i]), float(high[i])],
        "parameters": params,
        "indistinguishable": near.tolist(),
    }


def summary(indices: xr.Dataset, maps: Sequence[xr.Dataset] = ()) -> dict:
    """The study as JSON: per output the noise share and each parameter's ``S1`` and ``ST`` as
    ``{"index", "ci95": [low, high]}`` (SALib's bootstrap interval), and the best operating
    point of every design map (:func:`best_point`)."""
    out: dict = {"n_points": int(indices.attrs["n_points"]), "outputs": {}}
    out["cpu_s_per_point"] = float(indices.attrs["cpu_s_per_point"])
    for o in indices["output"].values.tolist():
        row = indices.sel(output=o)
        entry = {
            "noise_share": _num(row["noise_share"]),
            "n_undefined": int(row["n_undefined"]),
        }
        for k in ("S1", "ST"):
            entry[k] = {}
            for p in indices["parameter"].values.tolist():
                v, c = float(row[k].sel(parameter=p)), float(row[f"{k}_conf"].sel(parameter=p))
                entry[k][p] = {"index": _num(v), "ci95": [_num(v - c), _num(v + c)]}
        out["outputs"][o] = entry
    best = next((b for b in BEST_BY if maps and b in maps[0]), None)
    out["best"] = {}
    for m in maps:
        if best is not None:
            out["best"][f"e={m.attrs['map_e']:g}"] = best_point(m, best)
    return out


def _num(v) -> float | None:
    x = float(v)
    return x if math.isfinite(x) else None
