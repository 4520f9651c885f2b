"""A load curve's derived quantities: no-load speed, stall torque and maximum power, found.

docs/model.md "The motor under load". :func:`derived` is the one place the motor's figures are
computed, for the torque–speed curves, the command, the design maps and the sensitivity study.
The stall torque is the root of the ensemble's mean speed ``Ω̄(τ_L)`` in the load: bracketed by
the first load where the speed is ``<= 0`` or that lies past the momentum bound (no speed is
stationary there) and the load before, the bracket clipped to the bound. The maximum power
``max τ_L Ω̄`` over the loads up to the bound is bracketed by the largest sample and its two
neighbours. Either bracket is narrowed by :func:`refine`, which asks a sweep for more loads
inside it (distinct from those it has: :func:`distinct_new`) until it is no wider than the
ensemble's own resolution (the bootstrap interval across members) or a set floor. Each estimate
carries a 95 % interval: the central 95 % of :data:`BOOTSTRAP_RESAMPLES` resamples of the members,
widened to hold its bracket (the mean curve's root or peak lies in it whatever the members do),
and no interval at all from fewer than two members.

A curve that does not cross zero is not given a stall torque: its state says why
(:data:`STALL_STATES`); a power still rising at the largest load is not a maximum
(:data:`PEAK_STATES`); where there is no estimate there is no interval. A load whose runs have
not settled (:func:`settled_loads`) is reported, its reading a finite window's mean.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..analysis.statistics import confidence_interval
from ..io.records import json_number as _num

#: Bootstrap resamples of the members for the derived quantities' intervals (fixed seed).
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 20261123
#: The load curve's derived quantities (docs/formats.md), each with its ``*_ci95``.
DERIVED = ("no_load_speed", "stall_torque", "max_power", "max_power_load")
#: Where the mean speed's root lies, by state (``stall_torque_state``).
STALL_STATES = {
    "found": "the mean speed crosses 0 between two loads",
    "beyond_largest_load": "the mean speed stays positive up to the largest load",
    "below_smallest_load": "the mean speed is <= 0 already at the smallest load (> 0)",
    "backwards_at_no_load": "the mean speed is <= 0 at no load: the motor runs backwards",
    "none": "no finite mean speed",
}
#: Where the output power's maximum lies, by state (``max_power_state``).
PEAK_STATES = {
    "found": "the largest power lies between two smaller ones",
    "beyond_largest_load": "the power is largest at the largest load: still rising",
    "at_smallest_load": "the power is largest at the smallest load",
    "none": "no finite power",
}
#: The momentum bound on the stall torque in units of the friction torque (docs/model.md).
MOMENTUM_BOUND = 1.0
#: Why an interval is missing when the ensemble has one member.
ONE_MEMBER = "one member: an interval needs >= 2 members"
#: Loads added inside a bracket per round of :func:`refine`, and the rounds at most.
REFINE_POINTS = 3
REFINE_ROUNDS = 3
#: Loads closer than this (relative to the larger, or absolutely below 1) are one load.
SAME_LOAD = 1e-9


def settled_loads(
    loads: np.ndarray,
    speed: np.ndarray,
    drift: np.ndarray | None,
    bound: float | None = None,
    scale: float | None = None,
) -> np.ndarray:
    """Which loads' runs have settled (:func:`~bouncedisk.analysis.settling.drifting`), a
    boolean per load.

    ``speed`` and ``drift`` are ``(members, loads)``: each member's mean speed over the window
    and its second half's mean speed less its first half's. A load has settled when the members'
    mean drift is at most ``DRIFT_SHARE`` times the curve's speed scale (its largest absolute mean
    speed up to the momentum ``bound``, or ``scale``: the up branch's for the down branch, whose
    runaway speeds would loosen it), or within three standard errors of 0 (a chaotic motor's
    halves differ by chance). Without ``drift`` (``None``, or not finite at a load) a load counts
    as settled; past the ``bound`` none does (no speed is stationary there, docs/model.md "The
    motor under load"), nor a backward speed at it (the mean friction torque, at most 1, only
    balances the load).
    """
    speed = np.atleast_2d(np.asarray(speed, float))
    past = np.zeros(speed.shape[1], bool)
    if bound is not None:  # at the bound a backward rotor is driven on backwards (<= 1 vs 1)
        with np.errstate(invalid="ignore"):
            past = (np.asarray(loads) > bound) | ((np.asarray(loads) >= bound) & (_mean(speed) < 0))
    if drift is None:
        return ~past
    from ..analysis.settling import drifting

    if scale is None:
        scale = speed_scale(loads, speed, bound)
    return ~drifting(np.atleast_2d(drift), scale) & ~past  # one member: 1 x loads, as speed


def speed_scale(loads: np.ndarray, speed: np.ndarray, bound: float | None = None) -> float:
    """A curve's speed scale: its largest absolute mean speed up to the momentum ``bound``."""
    speed = np.atleast_2d(np.asarray(speed, float))
    mean = np.abs(_mean(speed))
    if bound is not None:
        mean = np.where(np.asarray(loads) > bound, np.nan, mean)
    return float(np.nanmax(mean)) if np.isfinite(mean).any() else 0.0


def _last_before(valid: np.ndarray) -> np.ndarray:
    """For each load ``k``, the last valid load before it, else ``k - 1`` (``-1`` at 0)."""
    out = np.arange(valid.size) - 1
    last = -1
    for k in range(valid.size):
        if last >= 0:
            out[k] = last
        if valid[k]:
            last = k
    return out


def _stall_rows(
    loads: np.ndarray, mean: np.ndarray, settled: np.ndarray, bound: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The stall torque of each row of ``mean`` (mean speed curves, ``(rows, loads)``).

    The root lies between the first load where the speed is ``<= 0`` or that lies past the
    momentum ``bound`` (no speed is stationary there, docs/model.md "The motor under load") and
    the last ``settled`` load before it, the bracket's upper end clipped to the bound. A sign
    change at a settled load is interpolated linearly; an end past the bound gives the middle
    of the clipped bracket (a reading there is no speed to interpolate to).

    Returns
    -------
    root, state, low, high
        ``root`` (``+inf`` beyond the largest load, ``-inf`` below the smallest or backwards,
        ``nan`` with no finite speed), a :data:`STALL_STATES` code per row (:data:`_STALL_CODES`)
        and the bracket's ends (``nan`` unless found).
    """
    rows = mean.shape[0]
    past = np.zeros(loads.size, bool) if bound is None else loads > bound
    with np.errstate(invalid="ignore"):
        ends = (mean <= 0.0) | past[None, :]
        first_ok = mean[:, 0] > 0.0
    ends[:, 0] = False
    found = ends.any(axis=1) & first_ok
    k = np.argmax(ends, axis=1)
    j = np.maximum(_last_before(settled)[k], 0)
    r = np.arange(rows)
    mj, mk = mean[r, j], mean[r, k]
    a, b = loads[j], loads[k]
    top = b if bound is None else np.minimum(b, np.maximum(a, bound))
    with np.errstate(invalid="ignore", divide="ignore"):
        interp = a + mj / (mj - mk) * (b - a)
        root = np.where((mk <= 0.0) & settled[k], interp, 0.5 * (a + top))
    state = np.where(found, 0, np.where(first_ok, 1, np.where(loads[0] == 0.0, 3, 2)))
    state = np.where(np.isfinite(mean).any(axis=1), state, 4)
    root = np.where(found, root, np.where(state == 1, np.inf, -np.inf))
    root = np.where(state == 4, np.nan, root)
    return root, state, np.where(found, a, np.nan), np.where(found, top, np.nan)


def _peak_rows(
    loads: np.ndarray, power: np.ndarray, valid: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The largest power of each row over the ``valid`` loads (settled, distinct), its load's
    index and its :data:`PEAK_STATES` code (:data:`_PEAK_CODES`): found where a load lies on
    either side of it (past the last valid one the power is smaller or not stationary)."""
    p = np.where(valid[None, :] & np.isfinite(power), power, -np.inf)
    k = np.argmax(p, axis=1)
    best = p[np.arange(len(p)), k]
    first = int(np.argmax(valid)) if valid.any() else 0
    state = np.where(k == len(loads) - 1, 1, np.where(k == first, 2, 0))
    state = np.where(np.isfinite(best), state, 3)
    return np.where(np.isfinite(best), best, np.nan), k, state


_STALL_CODES = (
    "found",
    "beyond_largest_load",
    "below_smallest_load",
    "backwards_at_no_load",
    "none",
)
_PEAK_CODES = ("found", "beyond_largest_load", "at_smallest_load", "none")


def stall_bracket(loads: np.ndarray, speed: np.ndarray) -> tuple[str, int]:
    """The state of the mean speed's root and ``k`` with the root in ``[loads[k-1], loads[k]]``
    (``k = -1`` unless the state is ``"found"``; :data:`STALL_STATES`), every load settled."""
    loads, speed = np.asarray(loads, float), np.asarray(speed, float)[None, :]
    ok = np.ones(loads.size, bool)
    _root, state, _a, b = _stall_rows(loads, speed, ok, None)
    name = _STALL_CODES[int(state[0])]
    return name, (int(np.searchsorted(loads, b[0])) if name == "found" else -1)


def first_zero(loads: np.ndarray, speed: np.ndarray) -> float:
    """The stall torque of one mean speed curve, every load settled (:func:`_stall_rows`): the
    root of ``speed`` in the load, linear between the two loads that bracket its first sign
    change; ``nan`` when there is no such bracket (:func:`stall_bracket` says why)."""
    loads, speed = np.asarray(loads, float), np.asarray(speed, float)[None, :]
    ok = np.ones(loads.size, bool)
    root, state, _a, _b = _stall_rows(loads, speed, ok, None)
    return float(root[0]) if state[0] == 0 else math.nan


def peak_bracket(loads: np.ndarray, power: np.ndarray) -> tuple[str, int]:
    """The state of the power's maximum and the index of the largest finite sample (``-1`` when
    there is none; :data:`PEAK_STATES`)."""
    loads = np.asarray(loads, float)
    _p, k, state = _peak_rows(loads, np.asarray(power, float)[None, :], np.ones(loads.size, bool))
    name = _PEAK_CODES[int(state[0])]
    return name, (-1 if name == "none" else int(k[0]))


def peak(loads: np.ndarray, power: np.ndarray) -> tuple[float, float]:
    """The largest sampled ``power`` and its load; ``(nan, nan)`` when no power is finite.

    No interpolation: where the speed collapses just past the peak (a stall), a parabola through
    the largest sample and its neighbours overshoots every sample several-fold, so the loads
    set the resolution (:func:`refine` adds loads around the peak).
    """
    _state, k = peak_bracket(loads, power)
    if k < 0:
        return math.nan, math.nan
    return float(np.asarray(power, float)[k]), float(np.asarray(loads, float)[k])


def _mean(x: np.ndarray, axis: int = 0) -> np.ndarray:
    """The members' mean at each load over the finite values (``nan`` where there is none),
    without numpy's empty-slice warning."""
    finite = np.isfinite(x)
    n = finite.sum(axis=axis)
    total = np.where(finite, x, 0.0).sum(axis=axis)
    return np.where(n > 0, total / np.maximum(n, 1), np.nan)


def _bootstrap(members: int, resamples: int = BOOTSTRAP_RESAMPLES) -> np.ndarray:
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    return rng.integers(0, members, size=(resamples, members))


def _interval(samples: np.ndarray, bracket: tuple[float, float] | None = None) -> list:
    """Central 95 % of bootstrap ``samples`` widened to hold ``bracket``; an end that falls
    beyond the loads asked for (``±inf``, or ``nan``) is unknown (``None``)."""
    x = np.where(np.isnan(samples), np.inf, samples)
    lo = float(np.quantile(x, 0.025, method="lower"))
    hi = float(np.quantile(x, 0.975, method="higher"))
    if bracket is not None:
        lo, hi = min(lo, bracket[0]), max(hi, bracket[1])
    return [_num(lo), _num(hi)]


def _figures(loads, speed, power, works, settled, bound) -> dict[str, np.ndarray]:
    """Stall torque, maximum power, its load and the efficiency there, of each row of the
    members' mean curves (``speed``, ``power``: ``(rows, loads)``), with the states and
    brackets (:func:`_stall_rows`, :func:`_peak_rows`). The efficiency is the ratio of the mean
    output power to the mean torsional input at the maximum's load, both over the members that
    have both (``works``: that pair of ``(rows, loads)`` means, :func:`_paired`), ``η_t = W_L /
    W_t`` of the members' summed works (docs/model.md "Power and energy audit"): ``0`` where the
    maximum power is not positive, undefined where that input is not."""
    root, state, a, b = _stall_rows(loads, speed, settled, bound)
    p, k, pstate = _peak_rows(loads, power, settled)
    rows = np.arange(len(p))
    at = np.where(np.isfinite(p), loads[k], np.nan)
    w_l, w_t = works[0][rows, k], works[1][rows, k]
    ratio = np.where(w_t > 0.0, w_l / np.where(w_t > 0.0, w_t, 1.0), np.nan)
    eta = np.where(p > 0.0, ratio, np.where(np.isfinite(p), 0.0, np.nan))
    lo = loads[np.maximum(k - 1, 0)]
    hi = loads[np.minimum(k + 1, len(loads) - 1)]
    if bound is not None:  # no power is stationary past the bound
        hi = np.minimum(hi, np.maximum(loads[k], bound))
    return {
        "stall_torque": root,
        "stall_state": state,
        "stall_a": a,
        "stall_b": b,
        "max_power": p,
        "max_power_load": at,
        "peak_state": pstate,
        "peak_a": lo,
        "peak_b": hi,
        "efficiency_at_max_power": eta,
    }


def derived(
    loads: np.ndarray,
    speed: np.ndarray,
    power: np.ndarray,
    bound: float | None = None,
    torsion: np.ndarray | None = None,
    drift: np.ndarray | None = None,
    resamples: int = BOOTSTRAP_RESAMPLES,
) -> dict:
    """The motor's figures: no-load speed, stall torque, maximum power, its load and the
    efficiency there, with 95 % intervals, standard errors and states (the one place they are
    computed: the torque–speed curves, the command, the design maps and the study).

    ``speed``, ``power`` (output), ``torsion`` (torsional input power) and ``drift`` are
    ``(members, loads)`` at distinct
    increasing ``loads``. The estimates are those of the members' mean curve over the loads up
    to the momentum ``bound``; their intervals the central 95 % of ``resamples`` bootstrap
    resamples of the members (fixed seed) widened to the bracket (module docstring), their
    standard errors (``standard_errors``) the resamples' spread. The no-load speed is the mean
    speed at ``τ_L = 0`` (Student interval) when the loads start at 0. With one member every
    interval is ``[None, None]`` and ``interval_note`` says why; ``stall_torque_state`` and
    ``max_power_state`` say where the root and the maximum lie (:data:`STALL_STATES`,
    :data:`PEAK_STATES`), ``*_bracket`` between which loads; where there is no estimate there is
    no value and no interval. ``unsettled_loads`` lists the loads whose runs had not settled
    (:func:`settled_loads`; ``drift``: each member's second-half less first-half mean speed):
    their readings are a finite window's, not a stationary speed's.

    ``bound`` is the momentum bound (``τ_L = 1``, docs/model.md "The motor under load"): past
    it no speed is stationary (the rotor decelerates at ``>= τ_L - 1``), so the stall torque's
    bracket ends at it.
    """
    loads = np.asarray(loads, float)
    speed, power = np.atleast_2d(np.asarray(speed, float)), np.atleast_2d(np.asarray(power, float))
    tor = np.full(speed.shape, np.nan) if torsion is None else np.atleast_2d(torsion)
    settled = settled_loads(loads, speed, drift, bound)
    below = settled_loads(loads, speed, None, bound)  # the estimates' loads: up to the bound
    out: dict = {"no_load_speed": None, "no_load_speed_ci95": [None, None]}
    se = {}
    if loads[0] == 0.0:
        mean, lo, hi = confidence_interval(speed[:, 0])
        out["no_load_speed"], out["no_load_speed_ci95"] = _num(mean), [_num(lo), _num(hi)]
        x = speed[np.isfinite(speed[:, 0]), 0]
        se["no_load_speed"] = float(np.std(x, ddof=1) / math.sqrt(x.size)) if x.size > 1 else None
    f = _figures(
        loads,
        _mean(speed)[None, :],
        _mean(power)[None, :],
        tuple(_mean(x)[None, :] for x in _paired(power, tor)),
        below,
        bound,
    )
    state, pstate = _STALL_CODES[int(f["stall_state"][0])], _PEAK_CODES[int(f["peak_state"][0])]
    found, peaked = state == "found", pstate == "found"
    out["stall_torque"] = _num(f["stall_torque"][0]) if found else None
    out["stall_torque_state"] = state
    sbr = (float(f["stall_a"][0]), float(f["stall_b"][0])) if found else None
    out["stall_torque_bracket"] = list(sbr) if sbr else [None, None]
    for name in ("max_power", "max_power_load", "efficiency_at_max_power"):
        out[name] = _num(f[name][0]) if peaked else None
    out["max_power_state"] = pstate
    pbr = (float(f["peak_a"][0]), float(f["peak_b"][0])) if peaked else None
    out["max_power_bracket"] = list(pbr) if pbr else [None, None]
    out["unsettled_loads"] = [float(x) for x in loads[~settled]]
    boot = _boot_figures(loads, speed, power, tor, below, bound, resamples)
    out.update(_derived_intervals(out, boot, sbr, pbr, se, speed.shape[0]))
    return out


def _boot_figures(loads, speed, power, torsion, settled, bound, resamples) -> dict | None:
    """:func:`_figures` of ``resamples`` bootstrap resamples of the members (one array each);
    ``None`` from fewer than two members."""
    if speed.shape[0] < 2:
        return None
    idx = _bootstrap(speed.shape[0], resamples)
    ms, mp = (_mean(x[idx], axis=1) for x in (speed, power))
    works = tuple(_mean(x[idx], axis=1) for x in _paired(power, torsion))
    return _figures(loads, ms, mp, works, settled, bound)


def _paired(power: np.ndarray, torsion: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Output power and torsional input ``(members, loads)``, each ``nan`` where the other
    is: the efficiency's two means are over the same members."""
    both = np.isfinite(power) & np.isfinite(torsion)
    return np.where(both, power, np.nan), np.where(both, torsion, np.nan)


def _derived_intervals(est: dict, boot: dict | None, sbr, pbr, se: dict, k: int) -> dict:
    """The bootstrap intervals and standard errors of :func:`derived` (``[None, None]`` and
    ``None`` where there is no estimate or fewer than two members)."""
    none = [None, None]
    names = ("stall_torque", "max_power", "max_power_load", "efficiency_at_max_power")
    out: dict = {f"{k}_ci95": none for k in names}
    errors = {k: None for k in names}
    if boot is None:
        out["no_load_speed_ci95"] = none
        out["interval_note"] = ONE_MEMBER
        out["standard_errors"] = {**errors, "no_load_speed": None}
        return out
    for name in names:
        if est[name] is None:
            continue
        x = boot[name]
        bracket = sbr if name == "stall_torque" else pbr if name == "max_power_load" else None
        out[f"{name}_ci95"] = _interval(x, bracket)
        x = x[np.isfinite(x)]
        # the resamples' spread of a mean is sqrt((K - 1)/K) of its standard error
        errors[name] = float(np.std(x, ddof=1) * math.sqrt(k / (k - 1))) if x.size > 1 else None
    out["standard_errors"] = {**errors, "no_load_speed": se.get("no_load_speed")}
    return out


def refinement_loads(
    loads: np.ndarray, summary: dict, resolution: float, points: int = REFINE_POINTS
) -> np.ndarray:
    """Loads to add inside the stall torque's and the maximum power's brackets (``points`` each,
    evenly spaced), for the brackets wider than the ensemble's resolution: the width of the
    estimate's bootstrap interval, or ``resolution`` if that is larger. Empty when both are
    resolved (or not found)."""
    new: list[float] = []
    for name, bracket in (
        ("stall_torque", summary.get("stall_torque_bracket")),
        ("max_power_load", summary.get("max_power_bracket")),
    ):
        if not bracket or bracket[0] is None:
            continue
        a, b = bracket
        lo, hi = summary.get(f"{name}_ci95") or (None, None)
        spread = _boot_width(lo, hi, a, b)
        if b - a > max(resolution, spread):
            new.extend(np.linspace(a, b, points + 2)[1:-1])
    return distinct_new(loads, np.asarray(new, float))


def distinct_new(loads: np.ndarray, new: np.ndarray) -> np.ndarray:
    """``new`` sorted, without the loads that are one load (:data:`SAME_LOAD`) with one of
    ``loads`` or with a smaller one of ``new`` (``0.8999999999999999`` beside ``0.9``)."""
    out: list[float] = []
    have = np.asarray(loads, float)
    for x in np.sort(np.asarray(new, float)):
        near = np.abs(np.r_[have, out] - x) <= SAME_LOAD * max(1.0, abs(x))
        if not near.any():
            out.append(float(x))
    return np.array(out)


def _boot_width(lo, hi, a: float, b: float) -> float:
    """The part of an interval's width that is the members' spread, not the bracket's: 0 when
    the interval is the bracket itself."""
    if lo is None or hi is None:
        return 0.0
    return max(0.0, (hi - lo) - (b - a))


def refine(
    curve,
    sweep: Callable[[np.ndarray, float, str], object],
    resolution: float,
    rounds: int = REFINE_ROUNDS,
    points: int = REFINE_POINTS,
):
    """``curve`` with loads added where the stall torque and the maximum power lie.

    ``curve`` is a :class:`~bouncedisk.studies.torque_speed.LoadCurve`; ``sweep(loads, omega0,
    branch)`` returns the curve of the same ensemble at ``loads`` (increasing) on that one
    branch, its members started at the mean speed ``omega0``. Each round asks
    :func:`refinement_loads` for loads inside the brackets; a group of them between two loads
    of the curve is swept up from the load below, started at the up branch's mean speed there,
    and down from the load above, started at the down branch's (standing in for the
    continuation's state; the readings at those two loads are dropped). Until the brackets are
    resolved, or after ``rounds`` rounds.
    """
    for _ in range(rounds):
        loads = np.asarray(curve.loads, float)
        new = refinement_loads(loads, summary_of(curve), resolution, points)
        if new.size == 0:
            break
        for group in _groups(loads, new):
            below = int(np.searchsorted(loads, group[0]) - 1)
            branches, drift = {}, {}
            for branch in curve.branches:
                k = below if branch == "up" else below + 1
                omega0 = float(np.nanmean(curve.matrix(branch, "mean_omega")[:, k]))
                ends = np.concatenate(
                    ([loads[k]], group) if branch == "up" else (group, [loads[k]])
                )
                got = sweep(np.sort(ends), omega0, branch)
                part = slice(1, None) if branch == "up" else slice(None, -1)
                branches[branch] = got.branches[branch][part]
                if getattr(got, "drift", None) is not None:
                    drift[branch] = got.drift[branch][:, part]
            extra = (
                type(curve)(group, branches, drift)
                if len(drift) == len(branches)
                else type(curve)(group, branches)
            )
            curve = merged(curve, extra)
            loads = np.asarray(curve.loads, float)
    return curve


def _groups(loads: np.ndarray, new: np.ndarray) -> list[np.ndarray]:
    """``new`` split into runs that lie between the same two loads of ``loads``."""
    cell = np.searchsorted(loads, new)
    return [new[cell == c] for c in np.unique(cell)]


def summary_of(curve) -> dict:
    """:func:`derived` of a curve's up branch (loads in the friction torque's units: the
    momentum bound is 1), with its torsional input and its runs' drift where the curve has them;
    without the standard errors (the study's, not the summary's)."""
    drift = getattr(curve, "drift", None)
    out = derived(
        curve.loads,
        curve.matrix("up", "mean_omega"),
        curve.power("up"),
        MOMENTUM_BOUND,
        torsion=_torsion(curve),
        drift=None if drift is None else drift.get("up"),
    )
    out.pop("standard_errors", None)
    return out


def _torsion(curve) -> np.ndarray | None:
    try:
        return curve.matrix("up", "power_torsion_in")
    except (AttributeError, KeyError):
        return None


def merged(curve, extra):
    """One curve of the loads of both, sorted by load, with the branches ``curve`` has (and
    their runs' drift where both have it)."""
    loads = np.concatenate((curve.loads, extra.loads))
    order = np.argsort(loads, kind="stable")
    branches = {}
    for b, stats in curve.branches.items():
        every = list(stats) + list(extra.branches[b])
        branches[b] = [every[i] for i in order]
    drift_a, drift_b = getattr(curve, "drift", None), getattr(extra, "drift", None)
    if drift_a is None or drift_b is None:
        return type(curve)(loads[order], branches)
    drift = {b: np.concatenate((drift_a[b], drift_b[b]), axis=1)[:, order] for b in branches}
    return type(curve)(loads[order], branches, drift)
