"""Uncertainty of the fit: local curvature, profile likelihoods, intervals, identifiability.

``χ²`` (:mod:`.objective`) is ``−2 log`` of the synthetic likelihood, so a 95 % profile
interval of a parameter is where its profile ``min over the others χ²`` stays within
``χ²₁(0.95) = 3.84`` of the overall minimum. Each profile steps out from the estimate on both
sides; at every step the other coordinates are re-optimized by Gauss–Newton steps with the
Jacobian of the whitened residuals at the estimate (chord method, each step one evaluation of
the exact residuals) starting from the previous step's optimum. A side that reaches its search
bound below the threshold is open; a parameter whose profile stays below the threshold over its
whole search range is **not identified**. Correlations come from the inverse of ``JᵀJ``;
well-identified combinations are its eigenvectors (docs/model.md's scaling predicts one combination of
``(e, omega_s, ψ)`` from the steady speed and ``R_φ`` from the time constant).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2 as chi2_dist

from . import detlinalg
from .objective import Objective, snap

#: Δχ² of a 95 % profile interval (one parameter).
THRESHOLD = float(chi2_dist.ppf(0.95, 1))
#: Smallest first step of a profile, as a fraction of the search range (the local sd otherwise).
MIN_STEP = 0.002


@dataclass
class Profile:
    """Profile of one coordinate: values, ``χ²`` and the other coordinates at each value."""

    name: str
    values: np.ndarray
    chi2: np.ndarray
    points: np.ndarray  # (n, d) search coordinates of each profile point
    ci_low: float
    ci_high: float
    open_low: bool
    open_high: bool
    identified: bool
    threshold: float = THRESHOLD  # Δχ² used (scaled when the fit is poor, :func:`birge`)
    multimodal: bool = False  # acceptable points outside the profile's interval widened it


def jacobian(obj: Objective, x: np.ndarray, members: int, rel_step: float = 0.01) -> np.ndarray:
    """Central-difference Jacobian of the whitened residuals, per unit of each coordinate."""
    d = len(x)
    r0 = obj.residuals(x, members)
    jac = np.empty((len(r0), d))
    for j in range(d):
        h = rel_step * obj.span[j]
        xp, xm = x.copy(), x.copy()
        xp[j] = min(obj.hi[j], x[j] + h)
        xm[j] = max(obj.lo[j], x[j] - h)
        xp, xm = snap(xp), snap(xm)
        obj.chi2(xp, members)
        obj.chi2(xm, members)
        jac[:, j] = (obj.residuals(xp, members) - obj.residuals(xm, members)) / (xp[j] - xm[j])
    return jac


def curvature(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covariance (pseudo-inverse of ``JᵀJ``), correlation, and standard deviations."""
    info = detlinalg.gram(jac)
    cov = detlinalg.pinv_sym(info, 1e-10)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    return cov, corr, sd


def combinations(jac: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-combinations of the coordinates scaled to their search ranges.

    Returns the standard deviation of each combination (as a fraction of the ranges; below 1:
    the curve constrains it) and the unit vectors (rows), best determined first.
    """
    js = jac * span[None, :]
    w, v = detlinalg.sym_eig(detlinalg.gram(js))
    order = np.argsort(-w, kind="stable")
    sd = 1.0 / np.sqrt(np.maximum(w[order], 1e-300))
    return sd, v[:, order].T


def _side(obj, x0, j, sign, step, chi0, members, jac, max_steps, thr=THRESHOLD):
    """Points of one side of the profile of coordinate ``j``: (values, χ², points)."""
    others = [k for k in range(len(x0)) if k != j]
    jo = jac[:, others]
    pinv = detlinalg.pinv(jo, 1e-8)
    out = []
    x = x0.copy()
    v = x0[j]
    for _ in range(max_steps):
        if (sign > 0 and v >= obj.hi[j]) or (sign < 0 and v <= obj.lo[j]):
            break
        v = float(snap(np.clip(v + sign * step, obj.lo[j], obj.hi[j])))
        # linear prediction of the others, then two chord Gauss-Newton steps
        x = x.copy()
        x[others] -= detlinalg.matvec(pinv, jac[:, j]) * (v - x[j])
        x[j] = v
        x = np.clip(x, obj.lo, obj.hi)
        best_x, best_c = x, obj.chi2(x, members)
        for _ in range(2):
            y = best_x.copy()
            y[others] -= detlinalg.matvec(pinv, obj.residuals(best_x, members))
            y = np.clip(y, obj.lo, obj.hi)
            c = obj.chi2(y, members)
            if c < best_c:
                best_x, best_c = y, c
        x = snap(best_x)
        out.append((v, best_c, x.copy()))
        if best_c - chi0 > 2.0 * thr:
            break
        if best_c - chi0 < 0.25 * thr:
            step *= 2.0
    return out


def reference_chi2(chi2: float, level: float | None) -> float:
    """The ``χ²`` a ``Δχ²`` is measured from: the lowest one read, or the level on fresh
    members (:func:`chi2_level`) when that is higher."""
    return chi2 if level is None else max(chi2, level)


def profile(
    obj: Objective,
    x0: np.ndarray,
    j: int,
    members: int,
    jac: np.ndarray,
    sd: float,
    max_steps: int = 6,
    thr: float = THRESHOLD,
    level: float | None = None,
) -> Profile:
    """Profile likelihood of coordinate ``j`` about the estimate ``x0`` (module docstring);
    ``Δχ²`` is measured from ``level`` (:func:`chi2_level`) when that is above ``x0``'s."""
    chi0 = obj.chi2(x0, members)
    ref = reference_chi2(chi0, level)
    step = float(
        np.clip(sd if np.isfinite(sd) else np.inf, MIN_STEP * obj.span[j], 0.2 * obj.span[j])
    )
    lo = _side(obj, x0, j, -1.0, step, ref, members, jac, max_steps, thr)
    hi = _side(obj, x0, j, +1.0, step, ref, members, jac, max_steps, thr)
    pts = lo[::-1] + [(float(x0[j]), chi0, x0.copy())] + hi
    values = np.array([p[0] for p in pts])
    chis = np.array([p[1] for p in pts])
    points = np.array([p[2] for p in pts])
    low, high, open_low, open_high, identified = _interval(values, chis, obj, j, thr, ref)
    if np.isfinite(sd) and sd > 0:
        # never narrower than the local quadratic's interval ±sqrt(thr)·sd: the members'
        # Monte-Carlo noise makes a re-optimized profile point err upward only (a worse
        # optimum found), which narrows the interval; the curvature smooths over it
        half = float(np.sqrt(thr) * sd)
        low = max(float(obj.lo[j]), min(low, float(x0[j]) - half))
        high = min(float(obj.hi[j]), max(high, float(x0[j]) + half))
    return Profile(
        obj.names[j], values, chis, points, low, high, open_low, open_high, identified, thr
    )


def _interval(values, chis, obj, j, thr=THRESHOLD, level=None):
    """95 % interval from a profile: crossings of the threshold above its minimum (or above
    ``level`` when higher), or the bounds if open."""
    base = reference_chi2(chis.min(), level)
    k0 = int(np.argmin(chis))
    below = chis - base <= thr

    def crossing(k_in, k_out):
        # linear in sqrt(Δχ²): exact for a quadratic profile, so a coarse step past the
        # threshold does not shrink the interval (linear in Δχ² would, by up to sqrt(b/thr))
        a, b = np.sqrt(max(chis[k_in] - base, 0.0)), np.sqrt(max(chis[k_out] - base, 0.0))
        f = (np.sqrt(thr) - a) / (b - a) if b != a else 0.0
        return float(values[k_in] + f * (values[k_out] - values[k_in]))

    k = k0
    while k > 0 and below[k - 1]:
        k -= 1
    open_low = k == 0  # never crossed: open to the search bound
    low = float(obj.lo[j]) if open_low else (crossing(k, k - 1) if k > 0 else float(values[0]))
    k = k0
    while k < len(values) - 1 and below[k + 1]:
        k += 1
    n = len(values) - 1
    open_high = k == n
    high = float(obj.hi[j]) if open_high else (crossing(k, k + 1) if k < n else float(values[-1]))
    identified = not (open_low and open_high)
    return low, high, bool(open_low), bool(open_high), identified


def all_profiles(
    obj: Objective,
    x0: np.ndarray,
    members: int,
    which: list[str] | None = None,
    progress: Callable[[str], None] | None = None,
    thr: float = THRESHOLD,
    extra: np.ndarray | None = None,
    level: float | None = None,
) -> tuple[list[Profile], np.ndarray, np.ndarray, np.ndarray]:
    """Profiles of the coordinates ``which`` (default all), with the curvature at ``x0``.

    Each interval is then widened to hold every point the search evaluated (with ``members``
    members, under the current metric) whose ``χ²`` is within ``thr`` of the best: the
    landscape in ``(e, omega_s)`` is rugged, a profile that walks from the estimate sees one
    basin only, and an acceptable point in another basin means the interval is (at least) the
    hull of both (:func:`widen`); ``extra`` are further acceptable points (the scan's, judged
    by the data's own resampling scales, :func:`scan_acceptable`). ``level`` (:func:`chi2_level`)
    replaces the best logged ``χ²`` as the base of that widening when it is higher. Returns the
    profiles, the Jacobian, the correlation matrix and the local standard deviations.
    """
    jac = jacobian(obj, x0, members)
    _cov, corr, sd = curvature(jac)
    out = []
    for j, name in enumerate(obj.names):
        if which is not None and name not in which:
            continue
        out.append(profile(obj, x0, j, members, jac, sd[j], thr=thr, level=level))
        if progress is not None:
            p = out[-1]
            progress(f"profile {name}: {len(p.values)} points")
    # after every profile: a profile may have found a better point than the estimate
    out = [widen(obj, p, members, extra, level) for p in out]
    if progress is not None:
        for p in out:
            progress(
                f"interval {p.name}: 95% [{p.ci_low:.4g}, {p.ci_high:.4g}]"
                f"{'' if p.identified else ' (not identified)'}"
                f"{' (several basins)' if p.multimodal else ''}"
            )
    return out, jac, corr, sd


#: An interval reaching within this fraction of the range of both search bounds covers the range.
EDGE = 0.02


def acceptable_points(
    obj: Objective, members: int, thr: float, level: float | None = None
) -> np.ndarray:
    """Every evaluated point (``members`` members) within ``thr`` of the best ``χ²`` now, or of
    ``level`` (:func:`chi2_level`) when that is higher."""
    pts = {tuple(ev.x): ev.x for ev in obj.log if ev.members == members}
    xs = np.array(list(pts.values()))
    chis = np.array([obj.chi2_now(x, members) for x in xs])
    return xs[chis <= reference_chi2(chis.min(), level) + thr]


#: Fresh member blocks read at the best point for its unbiased ``χ²`` (:func:`chi2_level`).
LEVEL_BLOCKS = 3


def chi2_level(obj: Objective, x: np.ndarray, members: int, blocks: int = LEVEL_BLOCKS) -> float:
    """The ``χ²`` level at the best point ``x``: the mean over ``blocks`` blocks of fresh members
    (:meth:`.objective.Objective.fresh_chi2`), at least the point's own ``χ²``.

    The best point was selected, out of every point the search evaluated on the same ``members``
    members, for the lowest ``χ²``; with a rugged landscape (chaotic members: the common random
    numbers do not make ``χ²`` smooth) that selection lowers it by several units (measured on a
    random motor: 21.5 on the search's members, 25.9, 30.4 and 25.0 on fresh blocks). An
    acceptable point must be within the threshold of the level, not of the lucky value, or the
    generating point itself is rejected.
    """
    fresh = [obj.fresh_chi2(x, members, b) for b in range(1, blocks + 1)]
    return max(float(np.mean(fresh)), obj.chi2_now(x, members))


def birge_scale(chi2_min: float, n_stats: int, n_params: int) -> float:
    """The scale factor of the data's variances when the best fit is poor: ``χ²/dof`` with
    ``dof = n_stats − n_params`` when that exceeds 1, else 1 (the Particle Data Group's scale
    factor; Birge). Every threshold of the intervals is scaled by it: :func:`birge`,
    :func:`fit_limit`. The fit file says so (``fit_adequate = 0``, ``interval_scale``)."""
    return max(1.0, chi2_min / max(1, n_stats - n_params))


def fit_limit(best_chi2: float, n_stats: int, n_params: int) -> float:
    """``χ²`` below which a point reproduces ``n_stats`` statistics: the 95 % point of
    ``χ²(n)``, scaled by :func:`birge_scale`."""
    return birge_scale(best_chi2, n_stats, n_params) * float(chi2_dist.ppf(0.95, n_stats))


def consistent_points(
    obj: Objective, points: np.ndarray, members: int, best_chi2: float
) -> np.ndarray:
    """The re-read candidates (:func:`.search.confirm_points`) that reproduce the data within the
    members' own spread there: :meth:`.objective.Objective.own_chi2` below
    :func:`fit_limit`. A goodness-of-fit test, not a ``Δχ²`` one: the held covariance does not
    describe another regime (in a chaotic recovery case the generating point reads ``χ²`` 39 on
    21 statistics under it), so the intervals are widened to these points too."""
    if len(points) == 0:
        return np.empty((0, len(obj.names)))
    limit = fit_limit(best_chi2, obj.n_stats, len(obj.names))
    keep = [x for x in points if obj.own_chi2(x, members) <= limit]
    return np.array(keep).reshape(-1, len(obj.names))


def widen(
    obj: Objective,
    p: Profile,
    members: int,
    extra: np.ndarray | None = None,
    level: float | None = None,
) -> Profile:
    """The interval of ``p`` widened to every acceptable evaluated point (union of basins).

    A parameter is **not identified** only when its profile is flat over the search range:
    open on both sides, or widened to within :data:`EDGE` of both search bounds. Otherwise the
    (possibly one-sided) interval is reported as an identified interval.
    """
    j = obj.names.index(p.name)
    xs = acceptable_points(obj, members, p.threshold, level)
    if extra is not None and len(extra):
        xs = np.vstack([xs, extra])
    v = xs[:, j]
    lo, hi = min(p.ci_low, float(v.min())), max(p.ci_high, float(v.max()))
    multimodal = lo < p.ci_low or hi > p.ci_high
    edge = EDGE * obj.span[j]
    covers = lo <= obj.lo[j] + edge and hi >= obj.hi[j] - edge
    identified = p.identified and not covers
    return Profile(
        p.name,
        p.values,
        p.chi2,
        p.points,
        lo,
        hi,
        p.open_low,
        p.open_high,
        identified,
        p.threshold,
        multimodal,
    )


def birge(chi2_min: float, n_stats: int, n_params: int) -> float:
    """Δχ² threshold of a 95 % interval, :data:`THRESHOLD` scaled by :func:`birge_scale`.

    A best ``χ²`` far above its degrees of freedom means the model's point does not reproduce
    the data within the stated variances; the usual remedy is to scale the variances by
    ``χ²/dof``, i.e. the threshold by the same factor.
    """
    return THRESHOLD * birge_scale(chi2_min, n_stats, n_params)


def realization_limit(n: int) -> float:
    """``χ²`` below which one model realization is consistent with the data on ``n`` statistics.

    A cheap evaluation compares one realization with another (the data's): twice the variance,
    so the limit is twice the 95 % point of ``χ²(n)``. Used for the scan's points
    (:func:`scan_acceptable`) and the joint candidates (:func:`.search.joint_missed`).
    """
    return 2.0 * float(chi2_dist.ppf(0.95, n))


def scan_acceptable(obj: Objective, members: int) -> np.ndarray:
    """Scan points that reproduce the data's statistics within the data's own scales.

    The scan's cheap evaluations of the run-ups (``members`` members, ``χ²`` under the provisional metric: the
    data's block-bootstrap spread, at least a few % of each statistic) whose ``χ²`` is within the
    (``χ²/dof``-scaled) 95 % threshold of the scan's best, or below twice the 95 % point of
    ``χ²(n_stats)`` (one model realization against the data's: twice the variance). Distinct basins in this set mean the
    curve does not single out one of them.
    """
    evs = [ev for ev in obj.log if ev.members == members and ev.parts == "runup"]
    if not evs:
        return np.empty((0, len(obj.names)))
    chis = np.array([ev.chi2 for ev in evs])
    thr = birge(float(chis.min()), len(obj.target), len(obj.names))
    limit = max(chis.min() + thr, realization_limit(len(obj.target)))
    return np.array([ev.x for ev, c in zip(evs, chis, strict=True) if c <= limit])


#: A fit whose best ``χ²`` has a p-value below this (``χ²`` with one degree per statistic) is
#: inadequate: it does not reproduce the data, and no parameter is reported identified by it.
ADEQUATE_P = 1e-3


def adequate(chi2_min: float, n_stats: int) -> bool:
    """Whether the best point reproduces the data's statistics (p-value above :data:`ADEQUATE_P`)."""
    return bool(chi2_dist.sf(chi2_min, n_stats) > ADEQUATE_P)


def identified(chi2_min: float, n_stats: int) -> tuple[bool, str]:
    """Whether a fit may report intervals at all (the fit file's ``identified``) and why.

    An inadequate fit (:func:`adequate` false) does not reproduce the data: its profiles are
    about a point the data reject, so its intervals are not reported (NaN), whatever their widths.
    """
    if adequate(chi2_min, n_stats):
        return True, (
            f"the best point reproduces the data (chi2 {chi2_min:.4g} on {n_stats} "
            f"statistics, p >= {ADEQUATE_P:g})"
        )
    return False, (
        f"inadequate fit: chi2 {chi2_min:.4g} on {n_stats} statistics (p = "
        f"{float(chi2_dist.sf(chi2_min, n_stats)):.2g} < {ADEQUATE_P:g}); the best "
        "point found does not reproduce the data, so no interval is reported"
    )
