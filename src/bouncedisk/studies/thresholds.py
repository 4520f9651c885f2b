"""The classic thresholds of the bouncing ball, measured on the engine by bisection.

docs/model.md "Classic results": the period-n orbit exists from ``Γ_n = nπ(1−e)/(1+e)`` (Holmes
1982) and the period-1 orbit doubles at ``sqrt(Γ_1² + (2(1+e²)/(1+e)²)²)`` (Luck & Mehta
1993). Here each threshold is found from the engine's own runs, without the closed forms'
algebra: a run started on the orbit settles on it (or stays on it) on one side of the threshold
and not on the other, and :func:`bisect` narrows the bracket where that switches. The
reproduction checks (:mod:`bouncedisk.studies.reproduction`) compare these with the closed forms.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..analysis import observables as ob
from ..engine import EngineConfig, InitialState, simulate_arrays
from ..model import stator


def settles_on_period(e: float, gamma: float, n: int, phase: float, events: int) -> bool:
    """Does a run started at ``phase`` with the period-n orbit's velocity ``T/2`` settle on it?

    Parameters
    ----------
    e : float
        Coefficient of restitution.
    gamma : float
        Stator acceleration ``Γ = omega_s²``.
    n : int
        Stator periods per impact of the orbit.
    phase : float
        Stator phase of the first impact.
    events : int
        Impacts simulated.
    """
    w = math.sqrt(gamma)
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=events),
        InitialState(t=phase / w, u=stator.position(phase), v=math.pi * n / w),
    )
    ev = res.events
    per = ob.find_period(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], w, max_period=4)
    return per is not None and per.p == 1 and per.q == n


def bisect(
    holds: Callable[[float], bool], lo: float, hi: float, resolution: float, holds_above: bool
) -> float:
    """Midpoint of the bracket ``[lo, hi]`` where ``holds(Γ)`` switches, narrowed to
    ``resolution``; ``holds_above`` says on which side of the switch ``holds`` is true."""
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        if holds(mid) == holds_above:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def engine_existence_threshold(n: int, e: float, resolution: float = 2e-4) -> float:
    """Γ above which a run started at the period-n orbit's phase settles on it (bisection
    within 10 % of ``Γ_n``)."""
    g_n = ob.period_n_threshold(n, e)

    def settles(gamma: float) -> bool:
        return settles_on_period(e, gamma, n, math.acos(min(1.0, g_n / gamma)) + 1e-3, 20_000)

    return bisect(settles, 0.9 * g_n, 1.1 * g_n, resolution, holds_above=True)


def period_one_is_stable(e: float, gamma: float) -> bool:
    """Does a run started 1e-4 off the period-1 fixed point stay on it (phases within 1e-7)?"""
    w = math.sqrt(gamma)
    phi, vp = ob.period_n_fixed_point(1, e, w)
    phi += 1e-4
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=60_000),
        InitialState(t=phi / w, u=stator.position(phi), v=vp),
    )
    return float(np.ptp(res.events["phase"][-200:])) < 1e-7


def engine_doubling_threshold(e: float, resolution: float = 5e-4) -> float:
    """Γ at which the engine's period-1 orbit loses stability (bisection on long runs within
    0.05 of the closed form)."""
    g_pd = ob.period_doubling_threshold(1, e)

    def stable(gamma: float) -> bool:
        return period_one_is_stable(e, gamma)

    return bisect(stable, g_pd - 0.05, g_pd + 0.05, resolution, holds_above=False)
