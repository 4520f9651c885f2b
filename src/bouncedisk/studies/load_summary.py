"""A load curve's derived quantities: no-load speed, stall torque and maximum power, found.

docs/model.md "The motor under load". The stall torque is the root of the ensemble's mean speed
``Ω̄(τ_L)`` in the load: bracketed by the first sign change of the sampled curve, and the
maximum power ``max τ_L Ω̄`` is bracketed by the largest sample and its two neighbours. Either
bracket is narrowed by :func:`refine`, which asks a sweep for more loads inside it until it is no
wider than the ensemble's own resolution (the bootstrap interval across members) or a set
floor. Each estimate carries a 95 % interval: the central 95 % of :data:`BOOTSTRAP` resamples of
the members, widened to hold its bracket (the mean curve's root or peak lies in it whatever the
members do), and no interval at all from fewer than two members.

A curve that does not cross zero is not given a stall torque: its state says why (:data:`STALL_STATES`),
and a power still rising at the largest load is not a maximum (:data:`PEAK_STATES`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..analysis.statistics import confidence_interval
from ..io.records import json_number as _num

#: Bootstrap resamples of the members for the derived quantities' intervals (fixed seed).
BOOTSTRAP = 2000
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


def stall_bracket(loads: np.ndarray, speed: np.ndarray) -> tuple[str, int]:
    """The state of the mean speed's root and ``k`` with the root in ``[loads[k-1], loads[k]]``
    (``k = -1`` unless the state is ``"found"``; :data:`STALL_STATES`)."""
    speed = np.asarray(speed, float)
    finite = np.isfinite(speed)
    if not finite.any():
        return "none", -1
    if not speed[0] > 0.0:
        state = "backwards_at_no_load" if loads[0] == 0.0 else "below_smallest_load"
        return (state if finite[0] else "none"), -1
    for k in range(1, len(loads)):
        if speed[k] <= 0.0:
            return "found", k
    return "beyond_largest_load", -1


def first_zero(loads: np.ndarray, speed: np.ndarray) -> float:
    """The stall torque: the root of ``speed`` in the load, linear between the two loads that
    bracket its first sign change (docs/model.md "The motor under load": the smallest ``τ_L`` with
    ``Ω̄ <= 0``); ``nan`` when there is no such bracket (:func:`stall_bracket` says why)."""
    state, k = stall_bracket(loads, speed)
    if state != "found":
        return math.nan
    f = speed[k - 1] / (speed[k - 1] - speed[k])
    return float(loads[k - 1] + f * (loads[k] - loads[k - 1]))


def peak_bracket(loads: np.ndarray, power: np.ndarray) -> tuple[str, int]:
    """The state of the power's maximum and the index of the largest finite sample (``-1`` when
    there is none; :data:`PEAK_STATES`)."""
    power = np.asarray(power, float)
    if not np.isfinite(power).any():
        return "none", -1
    k = int(np.nanargmax(power))
    if k == len(loads) - 1:
        return "beyond_largest_load", k
    if k == 0:
        return "at_smallest_load", k
    return "found", k


def peak(loads: np.ndarray, power: np.ndarray) -> tuple[float, float]:
    """The largest sampled ``power`` and its load; ``(nan, nan)`` when no power is finite.

    No interpolation: where the speed collapses just past the peak (a stall), a parabola through
    the largest sample and its neighbours overshoots every sample several-fold, so the loads
    set the resolution (:func:`refine` adds loads around the peak).
    """
    _state, k = peak_bracket(loads, power)
    if k < 0:
        return math.nan, math.nan
    return float(power[k]), float(loads[k])


def _mean(x: np.ndarray) -> np.ndarray:
    """The members' mean at each load over the finite values (``nan`` where there is none),
    without numpy's empty-slice warning."""
    finite = np.isfinite(x)
    n = finite.sum(axis=0)
    total = np.where(finite, x, 0.0).sum(axis=0)
    return np.where(n > 0, total / np.maximum(n, 1), np.nan)


def _bootstrap(members: int) -> np.ndarray:
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    return rng.integers(0, members, size=(BOOTSTRAP, members))


def _stall_sample(loads: np.ndarray, speed: np.ndarray) -> float:
    """A resample's root: ``+inf`` beyond the largest load, ``-inf`` below the smallest."""
    state, _k = stall_bracket(loads, speed)
    if state == "found":
        return first_zero(loads, speed)
    return math.inf if state == "beyond_largest_load" else -math.inf


def _interval(samples: np.ndarray, bracket: tuple[float, float] | None = None) -> list:
    """Central 95 % of bootstrap ``samples`` widened to hold ``bracket``; an end that falls
    beyond the loads asked for (``±inf``, or ``nan``) is unknown (``None``)."""
    x = np.where(np.isnan(samples), np.inf, samples)
    lo = float(np.quantile(x, 0.025, method="lower"))
    hi = float(np.quantile(x, 0.975, method="higher"))
    if bracket is not None:
        lo, hi = min(lo, bracket[0]), max(hi, bracket[1])
    return [_num(lo), _num(hi)]


def derived(
    loads: np.ndarray, speed: np.ndarray, power: np.ndarray, bound: float | None = None
) -> dict:
    """No-load speed, stall torque and maximum-power point with 95 % intervals and states.

    ``speed`` and ``power`` are ``(members, loads)``. The estimates are those of the members'
    mean curve (:func:`first_zero`, :func:`peak`); their intervals the central 95 % of
    :data:`BOOTSTRAP` resamples of the members (fixed seed) widened to the bracket (module
    docstring). The no-load speed is the mean speed at ``τ_L = 0`` (Student interval) when the
    loads start at 0. With one member every interval is ``[None, None]`` and ``interval_note``
    says why; ``stall_torque_state`` and ``max_power_state`` say where the root and the maximum
    lie (:data:`STALL_STATES`, :data:`PEAK_STATES`), ``*_bracket`` between which loads.

    ``bound`` is the momentum bound (``τ_L = 1``, docs/model.md "The motor under load"): past
    it no speed is stationary, the rotor decelerating at ``>= τ_L - 1``, so a run's mean speed
    reaches 0 only at ``1 + Ω_0 / (discard + window/2)`` for a run started at ``Ω_0``: a root
    found past the bound says the motor stalls at it, and its interval reaches down to it.
    """
    loads = np.asarray(loads, float)
    speed, power = np.atleast_2d(np.asarray(speed, float)), np.atleast_2d(np.asarray(power, float))
    out: dict = {"no_load_speed": None, "no_load_speed_ci95": [None, None]}
    if loads[0] == 0.0:
        mean, lo, hi = confidence_interval(speed[:, 0])
        out["no_load_speed"], out["no_load_speed_ci95"] = _num(mean), [_num(lo), _num(hi)]
    mean_speed, mean_power = _mean(speed), _mean(power)
    state, k = stall_bracket(loads, mean_speed)
    out["stall_torque"] = _num(first_zero(loads, mean_speed))
    out["stall_torque_state"] = state
    out["stall_torque_bracket"] = [float(loads[k - 1]), float(loads[k])] if k > 0 else [None, None]
    pstate, j = peak_bracket(loads, mean_power)
    p, at = peak(loads, mean_power)
    out["max_power"], out["max_power_load"] = _num(p), _num(at)
    out["max_power_state"] = pstate
    pbr = (float(loads[j - 1]), float(loads[j + 1])) if pstate == "found" else None
    out["max_power_bracket"] = list(pbr) if pbr else [None, None]
    out.update(_derived_intervals(loads, speed, power, out, pbr, bound))
    return out


def _derived_intervals(loads, speed, power, est: dict, pbr, bound) -> dict:
    """The bootstrap intervals of :func:`derived` (``[None, None]`` where there is no estimate
    or fewer than two members)."""
    none = [None, None]
    out = {f"{k}_ci95": none for k in ("stall_torque", "max_power", "max_power_load")}
    if speed.shape[0] < 2:
        out["no_load_speed_ci95"] = none
        out["interval_note"] = ONE_MEMBER
        return out
    boots = _bootstrap(speed.shape[0])
    ms = np.array([_mean(speed[i]) for i in boots])
    mp = np.array([_mean(power[i]) for i in boots])
    if est["stall_torque"] is not None:
        st_b = np.array([_stall_sample(loads, m) for m in ms])
        lo, hi = _interval(st_b, tuple(est["stall_torque_bracket"]))
        if bound is not None and lo is not None and lo > bound:
            lo = float(bound)
        out["stall_torque_ci95"] = [lo, hi]
    if est["max_power"] is not None:
        pb = np.array([peak(loads, m) for m in mp])
        out["max_power_ci95"] = _interval(pb[:, 0])
        out["max_power_load_ci95"] = _interval(pb[:, 1], pbr)
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
    have = set(np.asarray(loads, float).tolist())
    return np.array(sorted({float(x) for x in new} - have))


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
            branches = {}
            for branch in curve.branches:
                k = below if branch == "up" else below + 1
                omega0 = float(np.nanmean(curve.matrix(branch, "mean_omega")[:, k]))
                ends = np.concatenate(
                    ([loads[k]], group) if branch == "up" else (group, [loads[k]])
                )
                got = sweep(np.sort(ends), omega0, branch).branches[branch]
                branches[branch] = got[1:] if branch == "up" else got[:-1]
            curve = merged(curve, type(curve)(group, branches))
            loads = np.asarray(curve.loads, float)
    return curve


def _groups(loads: np.ndarray, new: np.ndarray) -> list[np.ndarray]:
    """``new`` split into runs that lie between the same two loads of ``loads``."""
    cell = np.searchsorted(loads, new)
    return [new[cell == c] for c in np.unique(cell)]


def summary_of(curve) -> dict:
    """:func:`derived` of a curve's up branch (loads in the friction torque's units: the
    momentum bound is 1)."""
    return derived(curve.loads, curve.matrix("up", "mean_omega"), curve.power("up"), MOMENTUM_BOUND)


def merged(curve, extra):
    """One curve of the loads of both, sorted by load, with the branches ``curve`` has."""
    loads = np.concatenate((curve.loads, extra.loads))
    order = np.argsort(loads, kind="stable")
    branches = {}
    for b, stats in curve.branches.items():
        every = list(stats) + list(extra.branches[b])
        branches[b] = [every[i] for i in order]
    return type(curve)(loads[order], branches)
