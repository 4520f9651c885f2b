"""Uncertainty of the fit: local curvature, profile likelihoods, intervals, identifiability.

``χ²`` (:mod:`.objective`) is ``−2 log`` of the synthetic likelihood, so a 95 % profile
interval of a parameter is where its profile ``min over the others χ²`` stays within
``χ²₁(0.95) = 3.84`` of the overall minimum. Each profile steps out from the estimate on both
sides; at every step the other coordinates are re-optimized by Gauss–Newton steps with the
Jacobian of the whitened residuals at the estimate (chord method, each step one evaluation of
the exact residuals) starting from the previous step's optimum. A side that reaches its search
bound below the threshold is open; a parameter whose profile stays below the threshold over its
whole search range is **not identified**. Correlations come from the inverse of ``JᵀJ``;
well-identified combinations are its eigenvectors (MODEL.md's scaling predicts one combination of
``(e, omega_s, ψ)`` from the steady speed and ``R_φ`` from the time constant).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2 as chi2_dist

from .objective import Objective

#: Δχ² of a 95 % profile interval (one parameter).
THRESHOLD = float(chi2_dist.ppf(0.95, 1))


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
        obj.chi2(xp, members)
        obj.chi2(xm, members)
        jac[:, j] = (obj.residuals(xp, members) - obj.residuals(xm, members)) / (xp[j] - xm[j])
    return jac


def curvature(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covariance (pseudo-inverse of ``JᵀJ``), correlation, and standard deviations."""
    info = jac.T @ jac
    cov = np.linalg.pinv(info, rcond=1e-10)
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
    w, v = np.linalg.eigh(js.T @ js)
    order = np.argsort(w)[::-1]
    sd = 1.0 / np.sqrt(np.maximum(w[order], 1e-300))
    return sd, v[:, order].T


def _side(obj, x0, j, sign, step, chi0, members, jac, max_steps):
    """Points of one side of the profile of coordinate ``j``: (values, χ², points)."""
    others = [k for k in range(len(x0)) if k != j]
    jo = jac[:, others]
    pinv = np.linalg.pinv(jo, rcond=1e-8)
    out = []
    x = x0.copy()
    v = x0[j]
    for _ in range(max_steps):
        if (sign > 0 and v >= obj.hi[j]) or (sign < 0 and v <= obj.lo[j]):
            break
        v = float(np.clip(v + sign * step, obj.lo[j], obj.hi[j]))
        # linear prediction of the others, then two chord Gauss-Newton steps
        x = x.copy()
        x[others] -= pinv @ jac[:, j] * (v - x[j])
        x[j] = v
        x = np.clip(x, obj.lo, obj.hi)
        best_x, best_c = x, obj.chi2(x, members)
        for _ in range(2):
            y = best_x.copy()
            y[others] -= pinv @ obj.residuals(best_x, members)
            y = np.clip(y, obj.lo, obj.hi)
            c = obj.chi2(y, members)
            if c < best_c:
                best_x, best_c = y, c
        x = best_x
        out.append((v, best_c, x.copy()))
        if best_c - chi0 > 2.0 * THRESHOLD:
            break
        if best_c - chi0 < 0.25 * THRESHOLD:
            step *= 2.0
    return out


def profile(
    obj: Objective, x0: np.ndarray, j: int, members: int, jac: np.ndarray, sd: float,
    max_steps: int = 6,
) -> Profile:  # fmt: skip
    """Profile likelihood of coordinate ``j`` about the estimate ``x0`` (module docstring)."""
    chi0 = obj.chi2(x0, members)
    step = float(np.clip(sd if np.isfinite(sd) else np.inf, 0.01 * obj.span[j], 0.2 * obj.span[j]))
    lo = _side(obj, x0, j, -1.0, step, chi0, members, jac, max_steps)
    hi = _side(obj, x0, j, +1.0, step, chi0, members, jac, max_steps)
    pts = lo[::-1] + [(float(x0[j]), chi0, x0.copy())] + hi
    values = np.array([p[0] for p in pts])
    chis = np.array([p[1] for p in pts])
    points = np.array([p[2] for p in pts])
    return Profile(obj.names[j], values, chis, points, *_interval(values, chis, obj, j))


def _interval(values, chis, obj, j):
    """95 % interval from a profile: crossings of the threshold, or the bounds if open."""
    base = chis.min()
    k0 = int(np.argmin(chis))
    below = chis - base <= THRESHOLD

    def crossing(k_in, k_out):
        a, b = chis[k_in] - base, chis[k_out] - base
        f = (THRESHOLD - a) / (b - a) if b != a else 0.0
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
) -> tuple[list[Profile], np.ndarray, np.ndarray, np.ndarray]:
    """Profiles of the coordinates ``which`` (default all), with the curvature at ``x0``.

    Returns the profiles, the Jacobian, the correlation matrix and the local standard deviations.
    """
    jac = jacobian(obj, x0, members)
    _cov, corr, sd = curvature(jac)
    out = []
    for j, name in enumerate(obj.names):
        if which is not None and name not in which:
            continue
        out.append(profile(obj, x0, j, members, jac, sd[j]))
        if progress is not None:
            p = out[-1]
            progress(f"profile {name}: {len(p.values)} points, 95% [{p.ci_low:.4g}, "
                     f"{p.ci_high:.4g}]{'' if p.identified else ' (not identified)'}")  # fmt: skip
    return out, jac, corr, sd
