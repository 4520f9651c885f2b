"""The motor under load: torque–speed curves by continuation (``bouncedisk torque-speed``).

A motor is read from its load characteristic (docs/model.md "The motor under load"): the ensemble's
mean speed, output power and efficiency at each load torque ``τ_L``, with 95 % intervals across
members, and the derived no-load speed, stall torque (the first zero of the mean speed) and
maximum-power point. The loads are swept **up and down by continuation**: each member at each
load starts from its own final state at the previous load, so a motor that can hold two speeds
under one load shows both (the two branches differ there).

Each load's run lasts the scene's ``stop.time − initial.t`` with its ``stats.discard`` left out
of the averages. A continued run starts at time ``θ/w`` (the stator phase ``θ`` of the previous
run's end, exact) with the previous final rotor state: the model is autonomous in the phase, so
nothing but the clock's origin changes, and its rounding does not grow with the sweep's length.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..analysis.ensembles import CappedRun, MemberStats
from ..analysis.settling import run_settled
from ..analysis.statistics import (
    EnsembleStats,
    capped_error,
    confidence_interval,
    ensemble_window,
)
from ..engine import EngineConfig, InitialState
from ..model.engine_config import engine_config
from ..model.errors import InputError
from ..model.limits import MAX_LOAD
from ..model.scene import Scene, require_scene
from ..run.cores import checked_cores, map_on_threads
from .load_summary import (  # first_zero and peak: the summary's API, also from here
    BOOTSTRAP_RESAMPLES,
    DERIVED,
    REFINE_ROUNDS,
    SAME_LOAD,
    _num,
    derived,  # noqa: F401
    distinct_new,
    first_zero,  # noqa: F401
    peak,  # noqa: F401
    refine,
    summary_of,
)

#: Branches of the sweep: loads increasing, then decreasing from the top load's final states.
BRANCHES = ("up", "down")
#: Relative difference of two branches' mean speeds below which they count as one speed.
MATERIAL = 1e-3
#: Largest number of loads one curve may ask for.
MAX_LOADS = 1000
#: Loads of a curve when none are given: from no load to the momentum bound ``τ_L = 1``, in
#: nondimensional units whether the scene is physical or not.
DEFAULT_LOADS = "0:1:11"


def scene_loads(
    scene: Scene, text: str | None, source: str = "<arguments>", field: str = "--loads"
) -> np.ndarray:
    """The nondimensional loads ``τ_L`` of a curve of ``scene`` from ``text`` (:func:`parse_loads`):
    in N·m for a physical scene (as ``physical.load_torque``), else in units of
    ``μ m_r g_eff r_eff``; without ``text`` (``None``) :data:`DEFAULT_LOADS`, nondimensional.
    The command and the pipeline read loads through this one function.

    Raises
    ------
    InputError
        As :func:`parse_loads`, or a load above :data:`MAX_LOAD` once nondimensional.
    """
    if text is None:
        return parse_loads(DEFAULT_LOADS, source, field)
    typed = parse_loads(text, source, field)
    loads, largest, bound = typed, f"tau_L = {typed[-1]:.4g}", f"tau_L = {MAX_LOAD:g}"
    if scene.physical is not None:  # N·m, like physical.load_torque
        torque = scene.physical.scales().torque
        with np.errstate(over="ignore"):  # an overflow is a load over the bound below
            loads = typed / torque
        largest = f"{typed[-1]:.4g} N m"
        bound = f"{MAX_LOAD * torque:.4g} N m (tau_L = {MAX_LOAD:g} for this scene)"
    if not loads[-1] <= MAX_LOAD:
        raise InputError(
            source,
            field,
            f"the largest load is {largest}; loads must be at most {bound}, a hundred times the "
            "momentum bound tau_L = 1",
        )
    return loads


def with_load(scene: Scene) -> Scene:
    """``scene`` with the ``load`` effect (its torque set per load by :func:`torque_speed`): the
    user's effects and parameters, whatever form they were given in, kept as they are."""
    if "load" in scene.effects:
        return scene
    raw = dict(scene.raw)
    given = raw.get("effects")
    if isinstance(given, dict):
        raw["effects"] = {**given, "load": True}
    elif isinstance(given, str):
        raw["effects"] = f"{given},load"
    else:
        raw["effects"] = [*(given or ["impacts", "contact"]), "load"]
    section = "physical" if scene.physical is not None else "parameters"
    raw[section] = {**(raw.get(section) or {}), "load_torque": 0.0}
    return dataclasses.replace(scene, effects=scene.effects | {"load"}, raw=raw)


def parse_loads(text: str, source: str = "<arguments>", field: str = "--loads") -> np.ndarray:
    """Loads from ``START:STOP:N`` (``N`` evenly spaced, ends included) or ``A,B,C``.

    Raises
    ------
    InputError
        Naming ``source`` and ``field``: not numbers, negative or non-finite loads, ``N < 2``,
        ``STOP <= START``, repeated loads, or more than :data:`MAX_LOADS`.
    """
    from ..model.params import number, whole_number

    text = str(text).strip()
    if not text:
        raise InputError(source, field, "is empty; give START:STOP:N or A,B,C")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise InputError(source, field, f"must be START:STOP:N or A,B,C, got {text!r}")
        start = number(source, field, parts[0], nonneg=True)
        stop = number(source, field, parts[1], nonneg=True)
        n = whole_number(source, field, parts[2], minimum=2)
        if n > MAX_LOADS:
            raise InputError(source, field, f"must ask for at most {MAX_LOADS} loads, got {n}")
        if not stop > start:
            raise InputError(source, field, f"STOP must be > START, got {text!r}")
        return np.linspace(start, stop, n)
    items = text.split(",")
    if not all(x.strip() for x in items):
        raise InputError(source, field, f"has an empty item: {text!r}; give START:STOP:N or A,B,C")
    if len(items) > MAX_LOADS:
        raise InputError(source, field, f"must ask for at most {MAX_LOADS} loads")
    loads = np.array([number(source, field, x, nonneg=True) for x in items])
    if len(distinct_new(np.empty(0), loads)) != len(loads):
        raise InputError(source, field, f"repeats a load (within {SAME_LOAD:g}): {text!r}")
    return np.sort(loads)


def checked_loads(loads: object, source: str = "<arguments>", field: str = "loads") -> np.ndarray:
    """A Python call's loads, as :func:`parse_loads` checks the command's: text is parsed as
    ``--loads``; numbers (a sequence, or one) must each be a finite ``τ_L >= 0``, none repeated,
    at most :data:`MAX_LOADS` of them, none above :data:`~bouncedisk.model.limits.MAX_LOAD`;
    returned sorted."""
    from ..model.params import number

    if isinstance(loads, str):
        out = parse_loads(loads, source, field)
    else:
        try:
            values = np.asarray(loads, dtype=object)
        except ValueError:  # ragged nesting
            raise InputError(source, field, "must be a list of numbers") from None
        if values.ndim > 1:
            raise InputError(source, field, f"must be a flat list of numbers, got {loads!r}")
        values = np.ravel(values)
        if not 1 <= len(values) <= MAX_LOADS:
            raise InputError(source, field, f"must hold 1 to {MAX_LOADS} loads, got {len(values)}")
        out = np.sort([number(source, field, x, nonneg=True) for x in values])
        if len(distinct_new(np.empty(0), out)) != len(out):
            raise InputError(source, field, f"repeats a load (within {SAME_LOAD:g})")
    if not out[-1] <= MAX_LOAD:
        raise InputError(source, field, f"must be at most tau_L = {MAX_LOAD:g}, got {out[-1]:g}")
    return out


def checked_branches(branches: object, field: str = "branches") -> tuple[str, ...]:
    """The sweeps a call asks for: one or both of :data:`BRANCHES`, each once (one name or
    several)."""
    try:
        names = (branches,) if isinstance(branches, str) else tuple(branches)
    except TypeError:  # not a name nor a sequence of them (None, a number)
        names = ()
    if (
        not names
        or not all(isinstance(b, str) for b in names)
        or len(set(names)) != len(names)
        or any(b not in BRANCHES for b in names)
    ):
        raise InputError(
            "<arguments>", field, f"must be one or both of {BRANCHES}, each once, got {branches!r}"
        )
    return names


@dataclass(frozen=True)
class LoadCurve:
    """An ensemble's statistics at each load, on both branches (see the module docstring).

    ``loads`` are nondimensional (``τ_L``); ``branches[name][k]`` is the ensemble at ``loads[k]``.
    """

    loads: np.ndarray
    branches: dict[str, list[EnsembleStats]]
    #: Per branch, each member's second-half less first-half mean speed at each load
    #: ``(members, loads)`` (:func:`member_sweep`; ``None``: not measured, every load settled).
    drift: dict[str, np.ndarray] | None = None

    def matrix(self, branch: str, name: str) -> np.ndarray:
        """A per-member quantity as a ``(members, loads)`` array."""
        return np.stack([s.column(name) for s in self.branches[branch]], axis=1)

    def summary(self) -> dict:
        """The JSON object of ``bouncedisk torque-speed --json`` (docs/formats.md): the up branch's
        statistics per load as lists, the derived quantities with intervals, the down branch
        under ``"down"`` and the loads where the branches differ."""
        out: dict = {"loads": [float(x) for x in self.loads]}
        out.update(_per_load(self.branches["up"]))
        out.update(summary_of(self))
        if "down" in self.branches:
            out["down"] = _per_load(self.branches["down"])
            out["branches_differ_at"] = self.branches_differ()
        scales = self.branches["up"][0].scales
        if scales is not None:
            out.update(_physical(out, scales))
        return out

    def power(self, branch: str) -> np.ndarray:
        """Output power ``τ_L Ω̄`` per member and load (``(members, loads)``)."""
        return self.matrix(branch, "power_out")

    def branches_differ(self) -> list[float]:
        """Loads at which the two branches hold different speeds: their 95 % intervals of the
        mean speed do not overlap and the means differ by more than :data:`MATERIAL` of the
        largest mean speed on the curve (a periodic attractor has a zero-width interval, and a
        finite window's average still depends on where in the cycle it starts)."""
        up = [confidence_interval(s.column("mean_omega")) for s in self.branches["up"]]
        down = [confidence_interval(s.column("mean_omega")) for s in self.branches["down"]]
        scale = max(abs(m) for m, _, _ in up + down)
        out = []
        for load, (m_u, lo_u, hi_u), (m_d, lo_d, hi_d) in zip(self.loads, up, down, strict=True):
            apart = hi_u < lo_d or hi_d < lo_u
            if apart and abs(m_u - m_d) > MATERIAL * scale:
                out.append(float(load))
        return out


def _per_load(stats: list[EnsembleStats]) -> dict:
    """Every ``stats`` field as a list over the loads."""
    per = [s.summary() for s in stats]
    keys = [k for k in per[0] if k not in ("members", "discard", "duration")]
    out: dict = {k: [p[k] for p in per] for k in keys}
    out["members"] = per[0]["members"]
    out["discard"] = per[0]["discard"]
    out["duration"] = per[0]["duration"]
    return out


def _nan(x: float | None) -> float:
    return math.nan if x is None else x


def _physical(out: dict, sc) -> dict:
    """SI copies of the curve's axes and derived quantities (N·m, rad/s, W)."""

    def conv(v, unit):
        if isinstance(v, list):
            return [conv(x, unit) for x in v]
        return None if v is None else _num(v * unit)

    si = {"loads_Nm": conv(out["loads"], sc.torque)}
    si["mean_omega_rad_s"] = conv(out["mean_omega"], sc.omega_scale)
    si["mean_omega_rad_s_ci95"] = conv(out["mean_omega_ci95"], sc.omega_scale)
    for name, unit in (
        ("no_load_speed", sc.omega_scale),
        ("stall_torque", sc.torque),
        ("max_power", sc.torsion_power),
        ("max_power_load", sc.torque),
    ):
        suffix = {sc.omega_scale: "_rad_s", sc.torque: "_Nm", sc.torsion_power: "_W"}[unit]
        si[name + suffix] = conv(out[name], unit)
        si[name + suffix + "_ci95"] = conv(out[name + "_ci95"], unit)
    for name in ("unsettled_loads", "branches_differ_at"):  # loads too, listed
        if out.get(name):
            si[name + "_Nm"] = conv(list(out[name]), sc.torque)
    return si


def continued_state(final: dict, omega_s: float) -> InitialState:
    """The initial state that continues a run from its final state (:func:`~bouncedisk.engine.iterate`'s),
    at time ``θ/w`` (module docstring)."""
    t = final["phase"] / omega_s
    if final["in_contact"]:
        return InitialState(t=t, omega=final["omega"])
    return InitialState(t=t, omega=final["omega"], u=final["u"], v=final["v"])


def member_sweep(
    cfg: EngineConfig,
    init: InitialState,
    member: int,
    loads: Sequence[float],
    discard: float,
    duration: float,
    branches: Sequence[str] = BRANCHES,
    should_stop: Callable[[], bool] | None = None,
) -> dict[str, list[MemberStats]]:
    """One member's statistics at each load, swept up then down by continuation.

    Each run lasts ``duration`` with ``discard`` left out of its averages. Under the key
    ``"drift"`` (per branch, a list over the loads) the second half's mean speed less the first
    half's (:func:`run_settled`).
    """
    order = {"up": list(range(len(loads))), "down": list(range(len(loads)))[::-1]}
    out: dict = {"drift": {}}
    state = init
    for branch in branches:
        got: dict[int, tuple] = {}
        for k in order[branch]:
            t0 = state.t
            run = dataclasses.replace(cfg, load_torque=float(loads[k]), t_end=t0 + duration)
            try:
                stats, final, drift = run_settled(run, state, member, t0 + discard, should_stop)
            except CappedRun as ex:
                ex.load = float(loads[k])
                raise
            got[k] = (stats, drift)
            state = continued_state(final, cfg.omega_s)
        out[branch] = [got[k][0] for k in range(len(loads))]
        out["drift"][branch] = [got[k][1] for k in range(len(loads))]
    return out


def torque_speed(
    scene: Scene,
    loads: Sequence[float],
    cores: int = 1,
    branches: Sequence[str] = BRANCHES,
    on_member: Callable[[int, int], None] | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> LoadCurve:
    """The scene's load characteristic: its ensemble at each of ``loads`` (nondimensional
    ``τ_L``, increasing), swept by continuation (module docstring). Members run on ``cores``
    threads, each sweeping its own chain; the numbers do not depend on ``cores``.

    Parameters
    ----------
    scene : Scene
        With ``torsion``, ``stop.time``, ``stats.discard`` and an ensemble: every load runs
        ``stop.time − initial.t`` and averages after ``discard``.
    loads : sequence of float, or str
        Load torques ``τ_L >= 0`` in units of ``μ m_r g_eff r_eff`` (sorted into increasing
        order), or text as ``--loads`` takes it (``"0:0.9:10"``, ``"0,0.3"``):
        :func:`checked_loads`.
    cores : int
        Threads the members run on.
    branches : sequence of str
        ``("up", "down")`` or ``("up",)``: the sweeps to run (:data:`BRANCHES`).
    on_member, should_stop : callable, optional
        Progress ``on_member(done, total)``; ``should_stop()`` polled between chunks.

    Returns
    -------
    LoadCurve
        Per branch and load the ensemble's :class:`~bouncedisk.analysis.statistics.EnsembleStats`.

    Raises
    ------
    InputError
        When the scene has no ``torsion`` effect, does not stop on time, is not the exact
        bouncing model, or a member stops at ``stop.max_events`` before the end of a load's run.
    """
    scene = require_scene(scene)
    loads = checked_loads(loads)
    branches = checked_branches(branches)
    cores = checked_cores(cores)
    t_from, t_end = ensemble_window(scene)
    if "torsion" not in scene.effects:
        raise InputError(scene.source, "effects", "a load curve needs the 'torsion' effect")
    if scene.solver.method != "exact" or scene.model != "bouncing":
        raise InputError(scene.source, "solver.method", "load curves run the exact bouncing model")
    cfg = engine_config(scene)
    discard = scene.stats.discard
    duration = t_end - scene.initial.t
    members = scene.ensemble.members

    def one(m: int) -> dict:
        return member_sweep(cfg, scene.initial, m, loads, discard, duration, branches, should_stop)

    try:
        results = map_on_threads(one, range(members), cores, on_member)
    except CappedRun as ex:
        raise capped_error(
            scene, ex, f" (load tau_L = {getattr(ex, 'load', math.nan):.6g})"
        ) from None
    curve = {
        b: [
            EnsembleStats([r[b][k] for r in results], discard, t_end - t_from, True, scene.scales)
            for k in range(len(loads))
        ]
        for b in branches
    }
    drift = {b: np.array([r["drift"][b] for r in results], float) for b in branches}
    return LoadCurve(loads, curve, drift)


def refined_torque_speed(
    scene: Scene,
    loads: Sequence[float],
    resolution: float,
    rounds: int = REFINE_ROUNDS,
    cores: int = 1,
    branches: Sequence[str] = BRANCHES,
    on_member: Callable[[int, int], None] | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> LoadCurve:
    """:func:`torque_speed` at ``loads``, then at loads added where the stall torque and the
    maximum power lie until their brackets are no wider than the ensemble's resolution or
    ``resolution`` (:func:`bouncedisk.studies.load_summary.refine`, at most ``rounds`` rounds).

    An added group of loads is swept up from the curve's load below it, its members started at
    the up branch's mean speed there, and down from the load above, started at the down
    branch's: each round costs ``REFINE_POINTS + 1`` loads per bracket and branch, not a new
    curve.
    """
    curve = torque_speed(scene, loads, cores, branches, on_member, should_stop)

    def sweep(extra: np.ndarray, omega0: float, branch: str) -> LoadCurve:
        start = dataclasses.replace(scene.initial, omega=omega0, u=None, v=None)
        moved = dataclasses.replace(scene, initial=start)
        return torque_speed(moved, extra, cores, (branch,), None, should_stop)

    return refine(curve, sweep, resolution, rounds)


#: Per-load statistics written to a load-curve file: the ``stats`` quantities that have a mean
#: and an interval (QUANTITIES), and the audit's residuals.
CURVE_QUANTITIES = (
    "mean_omega",
    "mean_slip",
    "impact_rate",
    "chatter_rate",
    "power_out",
    "power_torsion_in",
    "power_axial_in",
    "efficiency_torsion",
)


def to_dataset(scene: Scene, curve: LoadCurve, wall_time_s: float, summary: dict | None = None):
    """The load curve as an xarray Dataset (docs/formats.md): per branch and load the ensemble
    means with their 95 % intervals, per member the speed and output power, the audit residuals,
    and the derived quantities as attributes, with the scene's provenance. ``summary`` is
    ``curve.summary()`` when the caller has it already (its bootstrap is not run twice)."""
    import xarray as xr

    from ..analysis.statistics import AUDIT, QUANTITIES
    from ..io.provenance import base_attrs, new_run_id
    from ..run.runner import scene_attrs

    names = list(curve.branches)
    dims = ("branch", "load_torque")
    data = {}
    for q in CURVE_QUANTITIES:
        long_name = QUANTITIES[q][0]
        cis = [[confidence_interval(s.column(q)) for s in curve.branches[b]] for b in names]
        arr = np.array(cis, dtype=float)  # (branch, load, 3)
        data[q] = (dims, arr[..., 0], {"long_name": f"ensemble mean of the {long_name}"})
        for j, end in ((1, "low"), (2, "high")):
            data[f"{q}_ci95_{end}"] = (
                dims,
                arr[..., j],
                {"long_name": f"{end} end of the 95% interval of {q} across members"},
            )
    for q in ("mean_omega", "power_out"):
        data[f"{q}_member"] = (
            ("branch", "load_torque", "member"),
            np.stack([curve.matrix(b, q).T for b in names]),
            {"long_name": f"{QUANTITIES[q][0]} of each member"},
        )
    for q, long_name in AUDIT.items():
        data[q] = (
            dims,
            np.array([[np.nanmax(s.column(q)) for s in curve.branches[b]] for b in names]),
            {"long_name": long_name},
        )
    data["settled"] = (
        dims,
        _settled(curve, names).astype(np.int8),
        {
            "long_name": "1 where the load's runs settled (second half's mean speed within 2% of "
            "the first half's; none past the momentum bound): a stationary speed"
        },
    )
    for var in data.values():
        var[2].setdefault("units", "1")
    members = np.arange(curve.branches[names[0]][0].column("mean_omega").size)
    coords = {
        "branch": ("branch", names, {"long_name": "direction of the continuation sweep"}),
        "load_torque": (
            "load_torque",
            curve.loads,
            {"long_name": "load torque tau_L (units of mu m_r g_eff r_eff)", "units": "1"},
        ),
        "member": ("member", members, {"long_name": "ensemble member"}),
    }
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(base_attrs(f"bouncedisk load characteristic of scene '{scene.name}'"))
    ds.attrs.update(scene_attrs(scene))
    summary = curve.summary() if summary is None else summary
    for k in DERIVED:
        for key in (k, *(f"{k}{si}" for si in ("_rad_s", "_Nm", "_W"))):
            if key in summary:
                ds.attrs[key] = _nan(summary[key])
                ds.attrs[f"{key}_ci95"] = [_nan(x) for x in summary[f"{key}_ci95"]]
    for key in ("stall_torque_state", "max_power_state", "interval_note"):
        if key in summary:
            ds.attrs[key] = summary[key]
    for key in ("stall_torque_bracket", "max_power_bracket"):
        ds.attrs[key] = [_nan(x) for x in summary[key]]
    ds.attrs["unsettled_loads"] = list(summary.get("unsettled_loads") or []) or "none"
    ds.attrs["stats_discard"], ds.attrs["stats_duration"] = summary["discard"], summary["duration"]
    ds.attrs["branches_differ_at"] = summary.get("branches_differ_at") or "none"
    if scene.physical is not None:
        sc = scene.physical.scales()
        ds.attrs.update({"torque_scale_Nm": sc.torque, "omega_scale_rad_s": sc.omega_scale})
    ds.attrs.update(
        {
            "ensemble_members": int(members.size),
            "ensemble_seed": scene.ensemble.seed,
            "confidence_level": 0.95,
            "bootstrap_resamples": BOOTSTRAP_RESAMPLES,
            "run_id": new_run_id(f"{scene.name}-torque-speed", scene.sha256),
            "wall_time_s": round(wall_time_s, 6),
            "status": "completed",
        }
    )
    return ds


def _settled(curve: LoadCurve, names: list[str]) -> np.ndarray:
    """Per branch and load: have its runs settled (:func:`~.load_summary.settled_loads`)?"""
    from .load_summary import MOMENTUM_BOUND, settled_loads, speed_scale

    scale = speed_scale(curve.loads, curve.matrix(names[0], "mean_omega"), MOMENTUM_BOUND)
    rows = []
    for b in names:
        drift = None if curve.drift is None else curve.drift[b]
        rows.append(
            settled_loads(curve.loads, curve.matrix(b, "mean_omega"), drift, MOMENTUM_BOUND, scale)
        )
    return np.array(rows)


def motor_scene(
    params,
    drive_frequency_hz: float,
    phi0_rad: float,
    rotor: dict,
    preload_n: float,
    members: int,
    time: float,
    discard: float,
    seed: int = 1,
    name: str = "prototype_load",
) -> Scene:
    """A physical scene of a motor for its load curve in SI units: the nondimensional
    ``params`` (e.g. a fit's) with the drive ``(f, Φ0)`` and the ``rotor``
    (``m_r_kg``, ``r_g_m``, ``r_c_m``), converted by
    :meth:`~bouncedisk.model.params.PhysicalParameters.from_nondimensional`; an ensemble of
    ``members`` with the params' restitution noise, ``time`` and ``discard`` nondimensional.
    """
    from ..model.params import PhysicalParameters
    from ..model.scene import scene_from_mapping

    phys = PhysicalParameters.from_nondimensional(
        params,
        drive_frequency_hz,
        phi0_rad,
        rotor["m_r_kg"],
        rotor["r_g_m"],
        rotor["r_c_m"],
        F_preload=preload_n,
    )
    physical = {k: v for k, v in phys.as_dict().items()}
    raw = {
        "name": name,
        "description": "load characteristic of a motor given by nondimensional parameters",
        "physical": physical,
        "effects": ["impacts", "contact", "torsion", "restitution_noise", "load"],
        "stop": {"time": float(time)},
        "stats": {"discard": float(discard)},
        "ensemble": {"members": int(members), "seed": int(seed)},
    }
    return scene_from_mapping(raw, f"<{name}>")


def readings_from_rest(
    scene: Scene, loads: Sequence[float], cores: int = 1, independent: bool = False
) -> list[EnsembleStats]:
    """What a lab reads at each load: the scene's ensemble started from its initial condition
    (at rest) under that load, each member's mean speed over the scene's stats window
    (``[initial.t + discard, stop.time]``; docs/formats.md, a load curve's ``window_s``).

    Unlike :func:`torque_speed` there is no continuation: every reading starts afresh. Member
    ``m`` uses the noise stream ``(seed, m)`` at every load (common random numbers), or with
    ``independent`` the stream ``(seed + j + 1, m)`` at the ``j``-th load: separate runs, as a
    lab's readings at different loads are.
    """
    from ..analysis.ensembles import run_ensemble

    t_from, t_end = ensemble_window(scene)
    cfg = engine_config(scene)
    out = []
    for j, load in enumerate(loads):
        seed = cfg.seed + j + 1 if independent else cfg.seed
        run = dataclasses.replace(cfg, load_torque=float(load), seed=seed)
        try:
            members = run_ensemble(run, scene.initial, scene.ensemble.members, t_from, cores=cores)
        except CappedRun as ex:
            raise capped_error(scene, ex, f" (load tau_L = {float(load):.6g})") from None
        out.append(EnsembleStats(members, scene.stats.discard, t_end - t_from, True, scene.scales))
    return out
