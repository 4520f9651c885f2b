"""Global sensitivity of the motor's figures of merit: SALib Sobol' sampling and analysis.

The study (docs/user_guide/sensitivity.md) samples ``(e, omega_s, log10_r_phi, psi)`` over the
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

from ..analysis import observables as ob
from ..analysis.bands import member_speeds
from ..analysis.statistics import confidence_interval, run_stats, t_quantile
from ..analysis.sweeps import regime_attrs, shard_slice
from ..io.provenance import base_attrs
from ..io.records import json_number as _num
from ..model.scene import Scene, scene_from_mapping
from .sensitivity_settings import PARAMETERS, StudySettings
from .shards import join_indexed

LEVEL = 0.95
#: Largest half-width of a 95 % interval at which an index counts as resolved (the figure greys
#: out the others).
RESOLVED = 0.10
#: Fewest points for RBD-FAST's first-order indices (10 harmonics; below, Saltelli's estimator).
RBD_FAST_MIN_POINTS = 200
#: Largest share of an output's base samples that may be left out because the output is undefined
#: at one of their ``D + 2`` points (:func:`defined_blocks`); above it the output has no indices.
UNDEFINED_MAX_SHARE = 0.01
#: Figures of merit: name -> (long name, units, needs the ``load`` effect). Speeds and powers are
#: scaled by ``R_φ``: ``R_φ Ω`` is the rotor speed in units of ``Φ0/t_c`` (docs/model.md "Variables and
#: scales"), so they compare motors of the same stator at different ``R_φ``.
OUTPUTS: dict[str, tuple[str, str, bool]] = {
    "no_load_speed": ("no-load rotor speed R_phi * mean Omega (units Phi0/t_c)", "1", False),
    "log10_tau": ("log10 of the run-up time constant of the ensemble-mean run-up", "1", False),
    "chatter_rate": ("complete chattering sequences per unit time", "1", False),
    "stall_torque": (
        "stall torque, root of mean Omega in the load, at most the momentum bound 1 "
        "(friction units)",
        "1",
        True,
    ),
    "max_power": (
        "largest mean output power R_phi * tau_L * mean Omega over the loads up to 1",
        "1",
        True,
    ),
    "efficiency_at_max_power": ("torsional efficiency at the load of the largest power", "1", True),
}
#: The design maps' outputs, and the one that picks the best operating point (first present).
MAP_OUTPUTS = ("no_load_speed", "stall_torque", "efficiency_at_max_power")
BEST_BY = ("max_power", "no_load_speed")
#: The design maps' load step and how far it goes: their curves add every multiple of the step up
#: to :data:`MAP_LOAD_TOP` (just past the momentum bound's stall torque 1, docs/model.md "The
#: motor under load"), so that a stall torque or a power peak is read between loads this close;
#: the study's own sample keeps its configured loads (its points are many).
MAP_LOAD_STEP = 0.05
MAP_LOAD_TOP = 1.1
#: Transient the design maps add to their first run, from rest (units of ``1/R_φ``,
#: :attr:`StudySettings.runup`): at ``R_φ = 0.001`` the run-up is not over after the study's
#: 5, so that the maps' no-load speed would be a run-up's, not the steady one the torque–speed
#: curves read.
MAP_RUNUP = 15.0
#: Fewest members of a design map's points: their intervals pick the best point and those not
#: resolved from it (with 2 members Student's factor is 12.7, with 4 it is 3.2).
MAP_MIN_MEMBERS = 4
#: How the load figures are signed (attribute ``load_direction`` of the points and indices):
#: against each motor's own no-load motion (:class:`MotorModel`) or against positive rotation.
LOAD_DIRECTION = {
    True: "running: the load opposes each motor's no-load motion",
    False: "positive: the load opposes positive rotation",
}
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
    ``e_sigma`` (docs/model.md "Long-run statistics of chaotic motion"), over ``(discard + duration)/R_φ``.
    With ``loads`` (starting at 0) the point is one torque–speed curve, swept up by continuation
    as :func:`bouncedisk.studies.torque_speed.torque_speed` does (:func:`_load_curve`); its first
    run, ``τ_L = 0`` from rest, is also the run-up: it gives the no-load speed, chatter rate and
    regime (after the transient ``discard/R_φ``) and, sampled on a grid, the run-up time constant
    (first-order trend of the members' mean run-up,
    :func:`bouncedisk.analysis.observables.first_order_trend`, jackknife interval over members).
    The whole curve gives the stall torque, maximum power and the torsional efficiency at it
    (:func:`load_figures`; docs/model.md "The motor under load").

    With ``settings.running`` the load figures are those **in the motor's own running
    direction**: where the mean no-load speed is negative the load opposes that motion. The
    stator twist ``sin(w t + ψ)`` is the only place ``ψ`` enters and the axial motion sees
    neither ``ψ`` nor the rotation (docs/model.md "Variables and scales", "Phases of motion"),
    so ``ψ → ψ + π`` maps every run to its mirror, ``Ω → −Ω``, bit for bit up to round-off: a
    backward motor under load is its mirror (at ``ψ + π``, continuing from the mirrored no-load
    states) under the same load. The no-load speed keeps its sign.
    Without loads the no-load figures come from one ensemble
    (:func:`bouncedisk.analysis.statistics.run_stats`) and the run-up from a second.
    """

    def __init__(self, settings: StudySettings):
        self.s = settings
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
            "stop": {"time": (s.discard + s.runup + s.duration) / r},
            "ensemble": {"members": s.members, "seed": s.seed},
            "stats": {"discard": (s.discard + s.runup) / r},
            "outputs": {"events": False, "trajectory": {"dt": 1.0 / (RUNUP_SAMPLES_PER_UNIT * r)}},
            "solver": {"method": "exact", "tol": 1e-12},
        }
        return scene_from_mapping(raw, source="sensitivity point")

    def __call__(self, point: Mapping[str, float]) -> PointValues:
        r = 10.0 ** point["log10_r_phi"]
        if self.s.loads:
            free, curve, (t, om) = _load_curve(self.scene(point, load=True), self.s)
        else:
            free = run_stats(self.scene(point), cores=1)
            t, om = member_speeds(self.scene(point), self.s.members, self.s.seed)
        out = {
            "no_load_speed": interval(r * free.column("mean_omega")),
            "chatter_rate": interval(free.column("chatter_rate")),
            "log10_tau": _runup_tau(t, om),
        }
        if self.s.loads:
            out.update(load_figures(curve, r))
        name, _, _ = free.regime
        return PointValues(out, ob.REGIME_CODES[name])


def _first_run(cfg, init, member: int, t_from: float) -> tuple:
    """One member's run from rest at the curve's first load
    (:func:`bouncedisk.analysis.settling.run_settled`: its statistics, final state and
    drift), with its ``(t, Ω)`` samples on the scene's trajectory grid, the run-up
    (docs/model.md "The motor under load": at ``τ_L = 0`` the load effect changes nothing).

    Returns
    -------
    stats, final, samples, drift
        The member's :class:`~bouncedisk.analysis.ensembles.MemberStats`, its final state, its
        ``(t, Ω)`` samples, shape (samples, 2), and its second half's mean speed less its first.

    Raises
    ------
    CappedRun
        The run stopped at its cap on events before the end of its window.
    """
    from ..analysis.settling import run_settled

    samples: list[np.ndarray] = []
    stats, final, drift = run_settled(cfg, init, member, t_from, keep=samples.append)
    return stats, final, np.concatenate(samples), drift


def _load_curve(scene: Scene, s: StudySettings) -> tuple:
    """The point's no-load ensemble, its load curve (up branch) and run-up ``(t, Ω)``
    (docs/model.md "The motor under load").

    Each member runs ``s.loads[0] = 0`` from rest (:func:`_first_run`), then every further load
    from its final state at the previous one
    (:func:`bouncedisk.studies.torque_speed.member_sweep`'s continuation, same numbers). With
    ``s.running`` and a negative mean no-load speed the curve is the mirror motor's
    (:class:`MotorModel`): ``ψ + π``, each member's no-load statistics and final state with
    ``Ω`` negated; the no-load ensemble returned keeps the sign, the run-up is the mirror's.

    Returns
    -------
    free : EnsembleStats
        The members at ``τ_L = 0``, signed.
    curve : LoadCurve
        Branch ``up`` at ``s.loads``, in the running direction with ``s.running``, with each
        run's drift (whether it settled).
    (t, om) : tuple of ndarray
        The run-up: the times every member reached and the speeds, shape (member, time).

    Raises
    ------
    InputError
        A member stopped at its cap on events (as :func:`~.torque_speed.torque_speed`).
    """
    from ..analysis.ensembles import CappedRun
    from ..analysis.statistics import EnsembleStats, capped_error, ensemble_window
    from ..model.engine_config import engine_config
    from .torque_speed import LoadCurve

    t_from, t_end = ensemble_window(scene)
    cfg = engine_config(scene)
    # the continued loads: discard + duration (units 1/R_phi), without the first run's run-up
    discard, duration = s.discard / cfg.r_phi, (s.discard + s.duration) / cfg.r_phi
    try:
        first = [_first_run(cfg, scene.initial, m, t_from) for m in range(s.members)]
        per_load, drift = _continue_up(cfg, first, s, duration, discard)
    except CappedRun as ex:
        raise capped_error(
            scene, ex, f" (load tau_L = {getattr(ex, 'load', math.nan):.6g})"
        ) from None
    free = EnsembleStats(
        [f[0] for f in first], scene.stats.discard, t_end - t_from, True, scene.scales
    )
    n = min(len(f[2]) for f in first)  # the samples every member reached
    t, om = first[0][2][:n, 0], np.stack([f[2][:n, 1] for f in first])
    if s.running and float(np.mean(free.column("mean_omega"))) < 0.0:
        om = -om  # the mirror's run-up
    ens = [EnsembleStats(x, discard, duration - discard, True, scene.scales) for x in per_load]
    curve = LoadCurve(np.asarray(s.loads, float), {"up": ens}, {"up": drift})
    return free, curve, (t, om)


def _continue_up(cfg, first: list, s: StudySettings, duration: float, discard: float) -> tuple:
    """Every member's statistics at each of ``s.loads`` (a list per load) and their drifts
    ``(members, loads)``: its first run (:func:`_first_run`), then
    :func:`~.torque_speed.member_sweep` up the other loads from its final state; with
    ``s.running`` and a negative mean no-load speed as the mirror motor (:func:`_load_curve`)."""
    from .torque_speed import continued_state, member_sweep

    stats0, finals = [f[0] for f in first], [f[1] for f in first]
    drift0 = [f[3] for f in first]
    if s.running and float(np.mean([x.mean_omega for x in stats0])) < 0.0:
        cfg = dataclasses.replace(cfg, psi=cfg.psi + math.pi)
        stats0 = [
            dataclasses.replace(x, mean_omega=-x.mean_omega, mean_slip=-x.mean_slip) for x in stats0
        ]
        finals = [{**f, "omega": -f["omega"]} for f in finals]
        drift0 = [-d for d in drift0]
    rest = [
        member_sweep(
            cfg, continued_state(f, cfg.omega_s), m, s.loads[1:], discard, duration, ("up",)
        )
        for m, f in enumerate(finals)
    ]
    per_load = [stats0, *(list(at) for at in zip(*(r["up"] for r in rest), strict=True))]
    drift = np.column_stack([drift0, np.array([r["drift"]["up"] for r in rest], float)])
    return per_load, drift


def _runup_tau(t: np.ndarray, om: np.ndarray) -> tuple[float, float, float, float]:
    """log10 τ of the first-order trend of the members' mean run-up ``om`` (member, time)
    (:func:`bouncedisk.analysis.observables.first_order_trend`), with its jackknife standard
    error over members and Student interval."""
    k = len(om)
    full = math.log10(ob.first_order_trend(t, om.mean(axis=0)).tau)
    total = om.sum(axis=0)
    jack = np.array(
        [math.log10(ob.first_order_trend(t, (total - om[i]) / (k - 1)).tau) for i in range(k)]
    )
    se = _jackknife_se(jack)
    half = t_quantile(k - 1, LEVEL) * se
    return full, full - half, full + half, se


def _jackknife_se(leave_one_out: np.ndarray) -> float:
    """Jackknife standard error ``sqrt((K−1)/K Σ (θ_(i) − θ̄)²)`` of ``K`` leave-one-out values."""
    k = len(leave_one_out)
    return math.sqrt((k - 1) / k * float(np.sum((leave_one_out - leave_one_out.mean()) ** 2)))


def load_figures(curve, r: float) -> dict[str, tuple[float, float, float, float]]:
    """Stall torque, maximum power and the torsional efficiency at it, from a load curve's up
    branch (docs/model.md "The motor under load"), each ``(value, low, high, se)``.

    Computed where the torque–speed curves compute them
    (:func:`bouncedisk.studies.load_summary.derived`: the members' mean curve over the loads
    whose runs settled, the stall's bracket ending at the momentum bound, bootstrap intervals
    and standard errors). Where the summary has no value the study still needs a number: a
    motor that runs backwards at no load holds no load forwards (stall torque 0, its state
    ``backwards_at_no_load``), and one whose power is largest at no load delivers none
    (maximum power and efficiency 0); any other state is undefined (``nan``). The power is
    scaled by ``R_φ`` (``R_φ τ_L Ω̄``, units of ``Φ0/t_c``).
    """
    from .load_summary import MOMENTUM_BOUND, derived

    order = np.argsort(np.asarray(curve.loads, float), kind="stable")
    loads = np.asarray(curve.loads, float)[order]
    drift = getattr(curve, "drift", None)
    drift = None if drift is None else drift["up"][:, order]
    d = derived(
        loads,
        curve.matrix("up", "mean_omega")[:, order],
        curve.power("up")[:, order],
        MOMENTUM_BOUND,
        curve.matrix("up", "power_torsion_in")[:, order],
        drift,
    )
    zero = (0.0, 0.0, 0.0, 0.0)
    none = (math.nan, math.nan, math.nan, math.nan)
    out = {}
    for name, scale in (("stall_torque", 1.0), ("max_power", r), ("efficiency_at_max_power", 1.0)):
        if d[name] is not None:
            lo, hi = (math.nan if x is None else x * scale for x in d[f"{name}_ci95"])
            se = d["standard_errors"][name]
            out[name] = (d[name] * scale, lo, hi, math.nan if se is None else se * scale)
        elif name == "stall_torque":
            out[name] = zero if d["stall_torque_state"] == "backwards_at_no_load" else none
        else:
            at_zero = d["max_power_state"] == "at_smallest_load" and loads[0] == 0.0
            out[name] = zero if at_zero else none
    return out


# ----------------------------------------------------------------------------- sampling
def problem(ranges: Mapping[str, tuple[float, float]]) -> dict:
    """SALib's problem definition of ``ranges`` (parameter -> ``(low, high)``)."""
    return {
        "num_vars": len(ranges),
        "names": list(ranges),
        "bounds": [list(b) for b in ranges.values()],
    }


def sample(ranges: Mapping[str, tuple[float, float]], base_samples: int, seed: int) -> np.ndarray:
    """SALib's scrambled Sobol' sample for first-order and total indices, ``N (D + 2)`` rows."""
    from SALib.sample import sobol

    return sobol.sample(problem(ranges), base_samples, calc_second_order=False, seed=seed)


def map_settings(settings: StudySettings) -> StudySettings:
    """The settings of the design maps: the study's, with at least :data:`MAP_MIN_MEMBERS`
    members and loads every :data:`MAP_LOAD_STEP` up to :data:`MAP_LOAD_TOP` added (the study's
    largest load stays, bracketing every stall)."""
    members = max(settings.members, MAP_MIN_MEMBERS)
    if not settings.loads:
        return dataclasses.replace(settings, members=members, running=False, runup=MAP_RUNUP)
    top = min(MAP_LOAD_TOP, max(settings.loads))
    steps = MAP_LOAD_STEP * np.arange(round(top / MAP_LOAD_STEP) + 1)
    loads = np.unique(np.round(np.r_[steps, settings.loads], 12))
    loads = tuple(float(x) for x in loads)
    return dataclasses.replace(
        settings, members=members, loads=loads, running=False, runup=MAP_RUNUP
    )


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
            (
                ("", long_name),
                ("_ci_low", f"lower end of the 95% interval of {o}"),
                ("_ci_high", f"upper end of the 95% interval of {o}"),
                ("_se", f"standard error of {o} (ensemble noise)"),
            )
        ):
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
            "load_direction": LOAD_DIRECTION[bool(settings.running)],
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
    if not shards:
        raise ValueError("no shards to join")
    keys = ("total_points", "seed", "base_samples")
    if any(s.attrs.get(k) != shards[0].attrs.get(k) for s in shards for k in keys):
        raise ValueError(f"the shards are of different studies (their {', '.join(keys)} differ)")
    total = int(shards[0].attrs["total_points"])
    ds = join_indexed(shards, "point", total, "point")
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
        {
            "map_e": e,
            "map_omega_s": settings.map_omega_s,
            "map_n_psi": shape[0],
            "map_n_r_phi": shape[1],
            "map_loads": list(settings.loads),
            "members": settings.members,
            "seed": settings.seed,
        }
    )
    return ds


def join_maps(maps: Sequence[xr.Dataset]) -> xr.Dataset:
    """The design maps along a dimension ``map`` (coordinate ``map_e``)."""
    ds = xr.concat(list(maps), dim="map", combine_attrs="drop_conflicts")
    e = [float(m.attrs["map_e"]) for m in maps]
    ds = ds.assign_coords(map_e=("map", np.array(e), {"long_name": "restitution e of the map"}))
    for key in ("map_n_psi", "map_n_r_phi", "map_omega_s", "map_loads"):
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


def defined_blocks(y: np.ndarray, d: int) -> np.ndarray | None:
    """The points of the base samples whose ``D + 2`` points (Saltelli's ``A``, ``AB_1 … AB_D``,
    ``B``, consecutive rows without second order) all define the output ``y``, as a boolean mask;
    ``None`` when more than :data:`UNDEFINED_MAX_SHARE` of the base samples would be left out
    (every point is kept when ``y`` is defined everywhere)."""
    defined = np.isfinite(np.asarray(y, float)).reshape(-1, d + 2).all(axis=1)
    if np.count_nonzero(~defined) > UNDEFINED_MAX_SHARE * defined.size:
        return None
    return np.repeat(defined, d + 2)


def analyse(points: xr.Dataset, ranges: Mapping, resamples: int, seed: int) -> xr.Dataset:
    """First-order and total Sobol' indices of every output with 95 % bootstrap intervals.

    Both from SALib, on the Saltelli sample's points: ``ST`` by Jansen's estimator
    (``SALib.analyze.sobol``, the pairs of points that differ in one parameter); ``S1`` by
    RBD-FAST on every point as given data (``SALib.analyze.rbd_fast``: each output sorted by one
    parameter, its spectrum's low harmonics, bias-corrected), which uses all ``N (D + 2)``
    points where Saltelli's ``S1`` estimator uses ``N`` pairs: at the same points its intervals
    are 2–3 times narrower (docs/sensitivity_method.md, "Estimators"). Below
    :data:`RBD_FAST_MIN_POINTS` points (a smoke test) ``S1`` is Saltelli's (``SALib.analyze.sobol``):
    RBD-FAST's ten harmonics need many more points than that.

    Variables (output, parameter): ``S1``, ``S1_conf``, ``ST``, ``ST_conf`` (``conf``: half-width
    of the 95 % bootstrap interval), ``resolved`` (both half-widths at most :data:`RESOLVED`);
    per output: ``noise_share`` (:func:`noise_share`), ``variance``, ``mean``, ``n_undefined``
    (points where the output is undefined, e.g. no efficiency where no member's torsional input
    is positive). An output undefined at a few points is analysed on the base samples whose
    ``D + 2`` points all define it (:func:`defined_blocks`, a Saltelli design of fewer base
    samples); where more than :data:`UNDEFINED_MAX_SHARE` of the base samples would go, it has no
    indices (NaN).
    """
    from SALib.analyze import rbd_fast, sobol

    prob = problem(ranges)
    outputs = [o for o in str(points.attrs["outputs"]).split(",") if o]
    x = points["x"].values
    d = len(prob["names"])
    res = {k: np.full((len(outputs), d), np.nan) for k in ("S1", "S1_conf", "ST", "ST_conf")}
    per = {k: np.full(len(outputs), np.nan) for k in ("noise_share", "variance", "mean")}
    undefined = np.zeros(len(outputs), np.int64)
    for i, o in enumerate(outputs):
        y_all = points[o].values
        undefined[i] = int(np.count_nonzero(~np.isfinite(y_all)))
        keep = defined_blocks(y_all, d)
        if keep is None:
            continue
        y, xk = y_all[keep], x[keep]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            total = sobol.analyze(
                prob,
                y,
                calc_second_order=False,
                num_resamples=resamples,
                conf_level=LEVEL,
                seed=seed,
            )
            first = total
            if len(y) >= RBD_FAST_MIN_POINTS:
                first = rbd_fast.analyze(
                    prob, xk, y, num_resamples=resamples, conf_level=LEVEL, seed=seed
                )
        for k in ("S1", "S1_conf"):
            res[k][i] = first[k]
        for k in ("ST", "ST_conf"):
            res[k][i] = total[k]
        per["noise_share"][i] = noise_share(y, points[f"{o}_se"].values[keep])
        per["variance"][i], per["mean"][i] = float(np.var(y, ddof=1)), float(np.mean(y))
    data = _index_variables(res, per, undefined)
    coords = {
        "output": ("output", np.array(outputs, dtype=str)),
        "parameter": ("parameter", np.array(prob["names"], dtype=str)),
    }
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(base_attrs("bouncedisk global sensitivity: Sobol' indices (SALib)"))
    ds.attrs.update(
        {
            "n_points": int(points.sizes["point"]),
            "resamples": resamples,
            "seed": seed,
            "confidence_level": LEVEL,
            "resolved_half_width": RESOLVED,
            "estimators": (
                "S1: RBD-FAST on every point (SALib rbd_fast); ST: Jansen (SALib sobol)"
                if int(points.sizes["point"]) >= RBD_FAST_MIN_POINTS
                else "S1: Saltelli 2010, ST: Jansen (SALib sobol)"
            ),
            "load_direction": str(points.attrs.get("load_direction", LOAD_DIRECTION[False])),
            "cpu_time_s": float(points.attrs.get("cpu_time_s", math.nan)),
            "cpu_s_per_point": float(points.attrs.get("cpu_time_s", math.nan))
            / max(1, int(points.sizes["point"])),
        }
    )
    return ds


#: The indices file's per-output variables: name -> long name.
_PER_OUTPUT = {
    "noise_share": "share of the output's variance that is ensemble noise",
    "variance": "variance of the output over the sample",
    "mean": "mean of the output over the sample",
}


def _index_variables(res: dict, per: dict, undefined: np.ndarray) -> dict:
    """The variables of :func:`analyse`'s dataset from its arrays: the indices with their
    half-widths, ``resolved``, and the per-output figures."""
    dims = ("output", "parameter")
    resolved = (res["S1_conf"] <= RESOLVED) & (res["ST_conf"] <= RESOLVED)
    names = {"S1": "first-order Sobol' index (RBD-FAST)", "ST": "total Sobol' index (Jansen)"}
    data = {}
    for k, long_name in names.items():
        data[k] = (dims, res[k], {"long_name": long_name, "units": "1"})
        half = f"half-width of the 95% bootstrap interval of {k}"
        data[f"{k}_conf"] = (dims, res[f"{k}_conf"], {"long_name": half, "units": "1"})
    data["resolved"] = (
        dims,
        resolved.astype(np.int8),
        {"long_name": f"1 where both half-widths are at most {RESOLVED:g}", "units": "1"},
    )
    for k, long_name in _PER_OUTPUT.items():
        data[k] = ("output", per[k], {"long_name": long_name, "units": "1"})
    data["n_undefined"] = (
        "output",
        undefined,
        {"long_name": "points where the output is undefined", "units": "1"},
    )
    return data


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
    out["load_direction"] = str(indices.attrs.get("load_direction", LOAD_DIRECTION[False]))
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
