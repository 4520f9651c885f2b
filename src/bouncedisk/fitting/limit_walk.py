"""The deterministic limit's valley walk: a joint fit's search at ``σ_e = 0``.

Without restitution noise a periodic motor's load curve is a smooth, exact function of the
parameters, and the readings of a lab's few repeated runs pin it very tightly: the joint
``χ²``'s valley, with ``(ψ, R_φ)`` refitted, can be narrower in ``e`` and ``omega_s`` than any
scan's spacing. The scan runs at the stated noise, where such a valley is not seen, and the
local search stops in a neighbouring one. But along ``e`` the valley floor descends smoothly to
the truth when ``(R_φ, ψ, omega_s)`` follow it.

:func:`deterministic_walk` follows it: from the search's best point with ``σ_e`` set to 0, the
other coordinates (all but ``e``) are refitted by least squares at each step in ``e``, predicted
linearly from the last two steps, past a bump of the floor and with shorter steps where the
valley bends (:func:`_one_way`); a last refit with ``e`` free starts from the walk's best point.
It runs only where the deterministic limit reads a ``χ²`` within :data:`WORTH` times the best
one's (a motor with noise reads far worse there). At ``σ_e = 0`` the members coincide, so one
run serves an ensemble (:func:`.members.rows_records`) and a step costs a few seconds. Every point
is logged: the search's result is the best logged point, never worse than without the walk.

The refit frees every coordinate but ``e`` and ``σ_e``: ``(R_φ, ψ, omega_s)``, and the speed scale
where ``Φ0`` is unknown. A chaotic motor at ``σ_e = 0`` has no such valley: a change of ``2·10⁻⁴``
in ``e`` can move its readings by hundreds of their standard deviations, so the walk finds
nothing there (skipped by the :data:`WORTH` rule, or ended after a few halvings).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import least_squares

from .objective import Evaluation, Objective
from .uncertainty import THRESHOLD

#: The least lowering of ``χ²`` for which the search moves to the walk's best point and measures
#: the model's covariance there (the plain threshold ``χ²₁(0.95)``): a gain within the noise of
#: ``χ²`` is no reason to move the metric. The covariance itself is measured at
#: ``σ_e ≥ 10⁻⁸`` (:func:`.search.metric_point`): at ``σ_e = 0`` a chaotic motor's members
#: coincide and would hold the reading noise only.
WALK_GAIN = THRESHOLD
#: The walk runs where the deterministic limit's ``χ²`` is at most this many times the best's.
WORTH = 2.0
#: The walk's first step in ``e`` (and its longest), as a fraction of the range of ``e``.
STEP = 0.0117
#: Passes of a direction's loop at most (steps tried and halvings together).
MAX_STEPS = 24
#: The shortest step, as a fraction of :data:`STEP` (a direction ends below it).
SHORTEST = 0.25
#: Steps in a row that do not lower ``χ²`` the walk goes on past before it halves its step.
PAST = 1
#: Least-squares evaluations refitting the other coordinates at each step.
NFEV = 10
#: Least-squares evaluations of the last refit, ``e`` free, from the walk's best point.
FINAL_NFEV = 30
#: Relative step of the refit's forward differences (scipy's ``diff_step``: the step in the unit
#: box is this times the coordinate's position there). The valley is about ``2·10⁻⁴`` of the range
#: of ``omega_s`` across: far finer than the local search's ``2·10⁻³``.
DIFF_STEP = 1e-4


def _refit(
    obj: Objective,
    y0: np.ndarray,
    members: int,
    held: tuple[str, ...] = ("e", "e_sigma"),
    nfev: int = NFEV,
) -> tuple[np.ndarray, float]:
    """Every coordinate but ``held`` refitted from ``y0`` by least squares (at most ``nfev``
    evaluations); the end point and its ``χ²`` (logged)."""
    free = [k for k, n in enumerate(obj.names) if n not in held]
    if not np.isfinite(obj.residuals(y0, members)).all():
        return y0, obj.chi2(y0, members)  # a run that did not reach its window: no refit from it
    res = least_squares(
        lambda u: obj.residuals(obj.from_unit(u, y0, free), members),
        obj.to_unit(y0, free),
        bounds=(0.0, 1.0),
        diff_step=DIFF_STEP,
        max_nfev=nfev,
    )
    y = obj.from_unit(res.x, y0, free)
    return y, obj.chi2(y, members)


def _predicted(obj: Objective, cur: np.ndarray, prev: np.ndarray | None, e: float) -> np.ndarray:
    """The next step's start at ``e``: the other coordinates continued linearly from ``prev``
    through ``cur`` (held when there is no ``prev``), clipped to the box."""
    ie = obj.names.index("e")
    out = cur.copy()
    out[ie] = e
    if prev is not None and cur[ie] != prev[ie]:
        out += (cur - prev) * (e - cur[ie]) / (cur[ie] - prev[ie]) * (np.arange(len(cur)) != ie)
    return np.clip(out, obj.lo, obj.hi)


def _one_way(
    obj: Objective, start: np.ndarray, chi2: float, sign: float, members: int
) -> tuple[np.ndarray, float]:
    """The walk from ``start`` (its ``χ²`` ``chi2``) in the direction ``sign`` of ``e``; the
    best point reached and its ``χ²``.

    A step whose refit does not lower the best ``χ²`` is refitted once more from where it ended
    (:data:`NFEV` evaluations rarely converge where the valley bends). The walk goes on past
    :data:`PAST` such steps in a row (the valley floor has bumps short of the truth), then
    returns to its best point with the step halved; it ends when the step is below
    :data:`SHORTEST` of :data:`STEP`, when the next step leaves the range of ``e``, or after
    :data:`MAX_STEPS` passes.
    """
    ie = obj.names.index("e")
    h = STEP * obj.span[ie]
    prev, cur, misses = None, start, 0
    best = (None, start, chi2)  # (the point before the best, the best, its chi2)
    for _ in range(MAX_STEPS):
        e = cur[ie] + sign * h
        if h < SHORTEST * STEP * obj.span[ie] or not obj.lo[ie] <= e <= obj.hi[ie]:
            break
        y, c = _refit(obj, _predicted(obj, cur, prev, e), members)
        if c >= best[2]:
            y, c = _refit(obj, y, members)
        if c < best[2]:
            best, misses = (cur, y, c), 0
        elif misses < PAST:
            misses += 1
        else:
            (prev, cur, _), misses, h = best, 0, h / 2.0
            continue
        prev, cur = cur, y
    return best[1], best[2]


def deterministic_walk(
    obj: Objective, best: Evaluation, members: int, progress: Callable[[str], None] | None = None
) -> Evaluation:
    """The valley walk at ``σ_e = 0`` from ``best`` (module docstring); the best logged point
    after it.

    Parameters
    ----------
    obj : Objective
        The joint objective, its covariance held.
    best : Evaluation
        The search's best point so far.
    members : int
        Ensemble size of every evaluation (the fit's).
    progress : callable, optional
        Receives one line when the walk ends.

    Returns
    -------
    Evaluation
        The best logged point at ``members`` members (``best`` when the walk found nothing
        better).
    """
    start = best.x.copy()
    if "e_sigma" in obj.names:
        start[obj.names.index("e_sigma")] = 0.0
    start, chi2 = _refit(obj, start, members)
    if chi2 > WORTH * best.chi2:
        if progress is not None:
            progress(
                f"deterministic limit: chi2 {chi2:.4g} at e_sigma 0, no walk (best {best.chi2:.4g})"
            )
        return obj.best(members)
    ends = [_one_way(obj, start, chi2, sign, members) for sign in (1.0, -1.0)]
    # where the valley bends the walk stops short of its floor: e joins the refit there
    _refit(obj, min(ends, key=lambda p: p[1])[0], members, ("e_sigma",), FINAL_NFEV)
    out = obj.best(members)
    if progress is not None:
        progress(
            f"deterministic limit: valley walk at e_sigma 0 from chi2 {chi2:.4g}; best "
            f"chi2 {out.chi2:.4g} (before: {best.chi2:.4g})"
        )
    return out
