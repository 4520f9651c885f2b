"""Global-then-local search of the synthetic likelihood (:mod:`.objective`).

1. A Sobol scan of the whole search box and a seeded :func:`scipy.optimize.differential_evolution`
   seeded with the scan's best points, on cheap ensembles (``global_members``) and the robust loss
   ``Σ log(1 + r²)`` with provisional scales (a block bootstrap of the data).
2. A pilot ensemble (``pilot_members``) at the best point measures the model's across-member
   covariance ``C``; the objective switches to it.
3. :func:`scipy.optimize.least_squares` on the whitened residuals, in coordinates scaled to the
   search box, from the best few global points re-evaluated with ``members``; then ``C`` is
   measured again at the new best point and the search polished.

Every evaluation is logged, and the result is the best logged point at the final ensemble size
under the final metric: the search never returns a point worse than one it evaluated.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import differential_evolution, least_squares
from scipy.stats import qmc

from .objective import Evaluation, Objective
from .statistics import regularized_cov, stat_floor


@dataclass(frozen=True)
class SearchSettings:
    """Sizes of the search stages (see the module docstring)."""

    seed: int = 12345
    scan: int = 256
    global_members: int = 1
    popsize: int = 10
    maxiter: int = 12
    members: int = 12
    pilot_members: int = 32
    local_nfev: int = 40
    starts: int = 3


def _say(progress: Callable[[str], None] | None, msg: str) -> None:
    if progress is not None:
        progress(msg)


#: Coordinates set by matching the trend (:func:`matched_point`), not searched globally.
MATCHED = ("log10_r_phi", "log10_speed_scale")


def matched_point(obj: Objective, x: np.ndarray, members: int, steps: int = 2) -> np.ndarray:
    """Move ``log10 R_φ`` (and the free speed scale) so the trend matches the data's.

    MODEL.md's scaling: ``x = R_φ Ω`` evolves at a rate ``∝ R_φ`` while the axial motion does
    not depend on ``R_φ``, so the time constant goes like ``1/R_φ`` and the steady speed barely
    moves with it; with Φ0 unknown the speed in rad/s is proportional to the speed scale.
    ``steps`` such corrections, each one evaluation; the point with the best robust loss is kept.
    """
    names = obj.names
    x = np.clip(np.asarray(x, float), obj.lo, obj.hi)
    best, best_loss = x, obj.robust(x, members)
    for _ in range(steps):
        m = obj.ensemble(x, members).mean
        x = x.copy()
        if "log10_r_phi" in names:
            j = names.index("log10_r_phi")
            x[j] += (m[1] - obj.target[1]) / np.log(10.0)
        if "log10_speed_scale" in names and m[0] * obj.target[0] > 0:
            j = names.index("log10_speed_scale")
            x[j] += np.log10(obj.target[0] / m[0])
        x = np.clip(x, obj.lo, obj.hi)
        loss = obj.robust(x, members)
        if loss < best_loss:
            best, best_loss = x, loss
    return best


def global_stage(
    obj: Objective, s: SearchSettings, progress: Callable[[str], None] | None = None
) -> list[Evaluation]:
    """Scan with matched trends, then differential evolution, on cheap ensembles.

    The scan is a Sobol sample of the whole box whose points are moved by
    :func:`matched_point`; the best matched points seed the evolution's population.
    Returns the logged cheap evaluations, best first (by ``χ²`` under the provisional metric).
    """
    d = len(obj.names)
    scan = qmc.scale(qmc.Sobol(d, seed=s.seed).random(s.scan), obj.lo, obj.hi)
    matched = []
    for i in range(0, len(scan), 64):
        matched += obj.map(lambda x: matched_point(obj, x, s.global_members), scan[i : i + 64])
        _say(progress, f"scan: {len(matched)}/{s.scan} points (trend-matched R_phi)")
    losses = np.array([obj.robust(x, s.global_members) for x in matched])
    _say(progress, f"scan: best robust loss {losses.min():.4g}")
    # the evolution runs over the coordinates other than those matched to the trend
    free = [j for j, n in enumerate(obj.names) if n not in MATCHED]
    init = np.array(matched)[np.argsort(losses)[: max(5, s.popsize * len(free))]][:, free]
    gen = [0]
    anchor = np.array(matched)[int(np.argmin(losses))]

    def full(z):
        x = anchor.copy()
        x[free] = z
        return x

    def loss(z):
        xm = matched_point(obj, full(z), s.global_members, steps=1)
        return obj.robust(xm, s.global_members)

    def callback(xk, convergence=None):
        gen[0] += 1
        best = min(ev.chi2 for ev in obj.log if ev.members == s.global_members)
        _say(progress, f"global search: generation {gen[0]}/{s.maxiter}, best chi2 {best:.4g}")

    differential_evolution(
        loss,
        [(obj.lo[j], obj.hi[j]) for j in free],
        seed=s.seed,
        maxiter=s.maxiter,
        tol=0.0,
        atol=0.0,
        polish=False,
        init=init,
        updating="deferred",
        workers=obj.map,
        callback=callback,
    )
    pts = [ev for ev in obj.log if ev.members == s.global_members]
    return sorted(pts, key=lambda ev: ev.chi2)


def measure_cov(obj: Objective, x: np.ndarray, members: int) -> np.ndarray:
    """Regularized across-member covariance of the statistics at ``x`` (``members`` members)."""
    ens = obj.ensemble(x, members)
    return regularized_cov(ens.cov, stat_floor(obj.target))


def local_stage(
    obj: Objective,
    starts: list[np.ndarray],
    s: SearchSettings,
    nfev: int,
    progress: Callable[[str], None] | None = None,
) -> Evaluation:
    """Least squares on the whitened residuals from the best of ``starts`` (box-scaled)."""
    for x in starts:
        obj.chi2(x, s.members)
    x0 = obj.best(s.members).x
    span = obj.span

    def fun(u):
        return obj.residuals(obj.lo + u * span, s.members)

    def logged(u):
        x = obj.lo + u * span
        obj.chi2(x, s.members)
        return fun(u)

    u0 = np.clip((x0 - obj.lo) / span, 0.0, 1.0)
    least_squares(logged, u0, bounds=(0.0, 1.0), diff_step=2e-3, max_nfev=nfev, x_scale=1.0)
    best = obj.best(s.members)
    _say(progress, f"local search: chi2 {best.chi2:.4g} ({len(obj.cache)} ensembles evaluated)")
    return best


def search(
    obj: Objective, s: SearchSettings, progress: Callable[[str], None] | None = None
) -> Evaluation:
    """The whole search (module docstring); returns the best logged point at ``s.members``."""
    ranked = global_stage(obj, s, progress)
    obj.set_cov(measure_cov(obj, ranked[0].x, s.pilot_members))
    _say(progress, f"pilot: model covariance from {s.pilot_members} members")
    # the pilot ensemble's first `members` members are the local stage's ensemble too
    starts = [ev.x for ev in _distinct(ranked, obj.span, s.starts)]
    best = local_stage(obj, starts, s, s.local_nfev, progress)
    obj.set_cov(measure_cov(obj, best.x, s.pilot_members))
    best = local_stage(obj, [best.x], s, max(8, s.local_nfev // 3), progress)
    return best


def _distinct(ranked: list[Evaluation], span: np.ndarray, k: int) -> list[Evaluation]:
    """The best ``k`` points at least 5 % of the range apart (in some coordinate)."""
    out: list[Evaluation] = []
    for ev in ranked:
        if all(np.max(np.abs(ev.x - o.x) / span) > 0.05 for o in out):
            out.append(ev)
        if len(out) == k:
            break
    return out
