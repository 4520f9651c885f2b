"""Has a run settled? Its window's second half against its first (docs/model.md "The motor under
load"): the one rule that ensemble statistics, load curves and the sensitivity study share.

A member's **drift** is the mean rotor speed over the second half of its averaging window less
the mean over the first half, each sampled about :data:`SETTLE_SAMPLES` times over the window
(:func:`run_settled`) at a step that no cycle locked to the stator aliases (:func:`settle_step`). An ensemble has **settled** where its members' mean drift is at most
:data:`DRIFT_SHARE` of the speed scale, or within three standard errors of 0 (a chaotic motor's
halves differ by chance): :func:`drifting`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from ..engine import EngineConfig, InitialState
from .ensembles import MemberStats, run_member

#: A run has settled when the members' mean drift is at most this share of the speed scale.
DRIFT_SHARE = 0.02
#: Samples of the rotor speed over a window, about, for its halves' means.
SETTLE_SAMPLES = 256
#: The fractional part, in stator periods, of the sampling step: the golden ratio's.
GOLDEN_FRACTION = (math.sqrt(5.0) - 1.0) / 2.0


def settle_step(t_from: float, t_end: float, omega_s: float) -> float:
    """The step of the samples of a window ``[t_from, t_end]``, near a :data:`SETTLE_SAMPLES`-th
    of it: a whole number of stator periods plus :data:`GOLDEN_FRACTION` of one, or, for a
    window of fewer than :data:`SETTLE_SAMPLES` periods, a period over a whole number plus that
    fraction.

    A periodic motion locked to the stator (``p`` impacts every ``q`` periods) sampled at a whole
    number of periods, or at a step close to a period or one of its fractions, is read at phases
    that creep slowly through its cycle: each half's mean is biased by a different part of its
    speed ripple, and the halves differ although the motion is stationary. With the golden
    fraction the samples' stator phases are equidistributed (the halves' means agree to a small
    fraction of the ripple).
    """
    period = 2.0 * math.pi / omega_s
    step = (t_end - t_from) / SETTLE_SAMPLES
    if step >= period:
        return (math.floor(step / period) + GOLDEN_FRACTION) * period
    return period / (math.floor(period / step) + GOLDEN_FRACTION)


def run_settled(
    cfg: EngineConfig,
    init: InitialState,
    member: int,
    t_from: float,
    should_stop: Callable[[], bool] | None = None,
    keep: Callable[[np.ndarray], None] | None = None,
) -> tuple[MemberStats, dict, float]:
    """:func:`~bouncedisk.analysis.ensembles.run_member` with the rotor speed sampled over
    ``[t_from, t_end]`` at :func:`settle_step` (with ``keep``, at ``cfg.traj_dt`` if it has one),
    returning its statistics, final state and drift: the second half's mean sampled speed less
    the first half's. ``keep`` receives every chunk's ``(t, Ω)`` samples."""
    from ..io.records import TrajColumn

    step = settle_step(t_from, cfg.t_end, cfg.omega_s)
    if keep is None:
        cfg = dataclasses.replace(cfg, traj_t0=t_from, traj_t1=math.inf)
    elif cfg.traj_dt > 0.0:
        step = cfg.traj_dt  # the caller's grid
    samples: list[np.ndarray] = []

    def take(c) -> None:
        tw = np.array(c.traj[:, [TrajColumn.T, TrajColumn.OMEGA]])
        samples.append(tw)
        if keep is not None:
            keep(tw)

    run = dataclasses.replace(cfg, traj_dt=step)
    stats, final, _tail = run_member(run, init, member, t_from, should_stop, on_chunk=take)
    tw = np.concatenate(samples) if samples else np.empty((0, 2))
    mid = 0.5 * (t_from + cfg.t_end)
    first = tw[(tw[:, 0] >= t_from) & (tw[:, 0] < mid), 1]
    second = tw[tw[:, 0] >= mid, 1]
    drift = float(second.mean() - first.mean()) if first.size and second.size else math.nan
    return stats, final, drift


def drifting(drift: np.ndarray, scale: float | np.ndarray) -> np.ndarray:
    """Which columns of ``drift`` (members × cases, two dimensions: a 1-D array would be read
    neither way safely) have not settled: the members' mean drift beyond :data:`DRIFT_SHARE`
    times ``scale`` and beyond three standard errors of 0. A column without a finite drift counts
    as settled (nothing says otherwise)."""
    drift = np.asarray(drift, float)
    if drift.ndim != 2:
        raise ValueError(f"drift must be members x cases, got the shape {drift.shape}")
    finite = np.isfinite(drift)
    k = finite.sum(axis=0)
    d = np.where(finite, drift, 0.0).sum(axis=0) / np.maximum(k, 1)
    dev = np.where(finite, drift - d, 0.0)
    se = np.sqrt((dev**2).sum(axis=0) / np.maximum(k - 1, 1) / np.maximum(k, 1))
    with np.errstate(invalid="ignore"):
        return (k > 0) & (np.abs(d) > DRIFT_SHARE * scale) & (np.abs(d) > 3.0 * se)
